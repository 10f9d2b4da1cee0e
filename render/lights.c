#include "lights.h"

#include <math.h>
#include <stdlib.h>

#include "sampling.h"

/* ---- light sources ------------------------------------------------------------ */

static Vec3 vec3_of(const double d[3]) { return v3((float)d[0], (float)d[1], (float)d[2]); }

/* pbrt-v4's smooth spot falloff: 0 outside the cone, 1 inside its core. */
static float spot_falloff(const LightSource *l, float cos_theta)
{
    if (l->cos_falloff_start <= l->cos_cone)
        return cos_theta >= l->cos_cone ? 1.0f : 0.0f;
    float t = (cos_theta - l->cos_cone) / (l->cos_falloff_start - l->cos_cone);
    t = fminf(fmaxf(t, 0.0f), 1.0f);
    return t * t * (3.0f - 2.0f * t);
}

/* ---- portals ---------------------------------------------------------------- */

static bool portal_init(Portal *p, const Vec3 c[4])
{
    p->p0 = c[0];
    p->e1 = v3_sub(c[1], c[0]);
    p->e2 = v3_sub(c[3], c[0]);
    Vec3 n = v3_cross(p->e1, p->e2);
    p->area = v3_length(n);
    if (!(p->area > 0.0f) || !isfinite(p->area))
        return false;
    p->n = v3_scale(n, 1.0f / p->area);
    p->g11 = v3_dot(p->e1, p->e1);
    p->g12 = v3_dot(p->e1, p->e2);
    p->g22 = v3_dot(p->e2, p->e2);
    float det = p->g11 * p->g22 - p->g12 * p->g12;
    if (!(det > 0.0f))
        return false;
    p->inv_det = 1.0f / det;
    return true;
}

/* The solid-angle density at x of a point uniform on the portal, toward
 * unit w: 0 where w misses it. */
static float portal_pdf(const Portal *p, Vec3 x, Vec3 w)
{
    float wn = v3_dot(w, p->n);
    if (wn == 0.0f)
        return 0.0f;
    float t = v3_dot(v3_sub(p->p0, x), p->n) / wn;
    if (!(t > 0.0f))
        return 0.0f;
    Vec3 d = v3_sub(v3_add(x, v3_scale(w, t)), p->p0);
    float a = v3_dot(d, p->e1), b = v3_dot(d, p->e2);
    float u = (a * p->g22 - b * p->g12) * p->inv_det, v = (b * p->g11 - a * p->g12) * p->inv_det;
    if (!(u >= 0.0f && u <= 1.0f && v >= 0.0f && v <= 1.0f))
        return 0.0f;
    return t * t / (p->area * fabsf(wn));
}

/* The sky's own density of direction w (no pick). */
static float sky_pdf(const LightSource *l, Vec3 w)
{
    return l->map ? environment_pdf(l->map, w) : 1.0f / (4.0f * SG_PI);
}

/* The portals' densities at x toward w, summed (a portal is picked
 * uniformly: over their count, the portal strategy's density). */
static float portals_pdf_sum(const LightSource *l, Vec3 x, Vec3 w)
{
    float portals = 0.0f;
    for (uint32_t k = 0; k < l->portal_count; k++)
        portals += portal_pdf(&l->portals[k], x, w);
    return portals;
}

static inline float share_or_default(float portal_share) { return portal_share < 0.0f ? PORTAL_SHARE : portal_share; }

/* A sky's NEE density at x toward w: its map's, mixed with its portals'. */
static float infinite_pdf(const LightSource *l, Vec3 x, Vec3 w, float portal_share)
{
    float pdf = sky_pdf(l, w);
    if (!l->portal_count)
        return pdf;
    float s = share_or_default(portal_share);
    return (1.0f - s) * pdf + s * portals_pdf_sum(l, x, w) / (float)l->portal_count;
}

bool light_source_set_portals(LightSet *ls, uint32_t i, const Vec3 (*corners)[4], uint32_t count)
{
    LightSource *l = &ls->sources[i];
    Portal *p = count ? calloc(count, sizeof *p) : NULL;
    if (count && !p)
        return false;
    for (uint32_t k = 0; k < count; k++)
        if (!portal_init(&p[k], corners[k])) {
            free(p);
            return false;
        }
    free(l->portals);
    l->portals = p;
    l->portal_count = count;
    return true;
}

/* Whether unit w points into the sun's disk: by the sine, which keeps its
 * precision for a disk of a quarter degree where the cosine has none. */
static bool in_sun_disk(const LightSource *l, Vec3 w)
{
    Vec3 axis = v3_scale(l->direction, -1.0f);
    Vec3 c = v3_cross(w, axis);
    return v3_dot(w, axis) > 0.0f && v3_dot(c, c) <= l->sun_sin2 * (1.0f + 1e-5f);
}

/* The source's power over pi (the area lights' unit: area times
 * luminance), in a scene of bounding radius `radius`. */
static double source_power(const LightSource *l, double radius)
{
    double lum = luminance(l->rgb);
    switch (l->kind) {
    case SG_LIGHT_POINT:
        return 4.0 * lum;
    case SG_LIGHT_SPOT:
        return 2.0 * lum * (1.0 - 0.5 * ((double)l->cos_falloff_start + l->cos_cone));
    case SG_LIGHT_DISTANT: /* the irradiance over the scene's disk */
        if (l->sun_sin2 > 0.0f)
            lum *= M_PI * l->sun_sin2; /* radiance to irradiance */
        return lum * radius * radius;
    case SG_LIGHT_INFINITE:
        return 4.0 * M_PI * radius * radius * (l->map ? luminance(l->map->mean) : lum);
    }
    return 0.0;
}

static bool sources_init(LightSet *ls, const SgScene *s, const double centre[3], const char *path, SgError *err)
{
    ls->source_count = s->light_source_count;
    if (!ls->source_count)
        return true;
    if (!(ls->sources = calloc(ls->source_count, sizeof *ls->sources)))
        return sg_fail(err, "%s: out of memory for the lights", path);
    for (uint32_t i = 0; i < ls->source_count; i++) {
        const SgLightSource *in = &s->light_sources[i];
        LightSource *l = &ls->sources[i];
        l->kind = in->kind;
        l->rgb = v3(in->rgb[0], in->rgb[1], in->rgb[2]);
        double local[3] = {in->position[0] - centre[0], in->position[1] - centre[1], in->position[2] - centre[2]};
        l->position = vec3_of(local);
        l->direction = v3_normalize(vec3_of(in->direction));
        l->cos_cone = (float)in->cos_cone;
        l->cos_falloff_start = (float)in->cos_falloff_start;
        if (in->kind == SG_LIGHT_DISTANT && in->angular_radius > 0.0) {
            double radius = fmin(in->angular_radius, M_PI / 2), sr = sin(radius), half = sin(0.5 * radius);
            l->sun_sin2 = (float)(sr * sr);
            l->sun_one_minus_cos = (float)(2.0 * half * half);
            l->rgb = v3_scale(l->rgb, (float)(1.0 / (M_PI * sr * sr))); /* the disk's radiance */
            ls->has_escaping = true;
        }
        if (in->kind == SG_LIGHT_INFINITE) {
            ls->has_escaping = true;
            if (in->has_portal) {
                Vec3 c[1][4];
                for (int k = 0; k < 4; k++) {
                    double q[3] = {in->portal[k][0] - centre[0], in->portal[k][1] - centre[1],
                                   in->portal[k][2] - centre[2]};
                    c[0][k] = vec3_of(q);
                }
                if (!light_source_set_portals(ls, i, (const Vec3(*)[4])c, 1))
                    return sg_fail(err, "%s: a sky's portal is degenerate (its corners must span a window)", path);
            }
            if (in->image_path || in->image_pixels) {
                if (!(l->map = calloc(1, sizeof *l->map)))
                    return sg_fail(err, "%s: out of memory for the lights", path);
                if (!environment_load(l->map, in, err))
                    return false;
            }
        }
    }
    return true;
}

Vec3 light_set_escaped(const LightSet *ls, Vec3 x, Vec3 d, float bsdf_pdf, float portal_share)
{
    Vec3 sum = v3(0, 0, 0);
    if (!ls->has_escaping)
        return sum;
    for (uint32_t i = 0; i < ls->source_count; i++) {
        const LightSource *l = &ls->sources[i];
        Vec3 le;
        if (l->kind == SG_LIGHT_INFINITE)
            le = l->map ? environment_radiance(l->map, d) : l->rgb;
        else if (l->kind == SG_LIGHT_DISTANT && l->sun_sin2 > 0.0f && in_sun_disk(l, d))
            le = l->rgb;
        else
            continue;
        float w = bsdf_pdf < 0.0f ? 1.0f : sg_power_heuristic(bsdf_pdf, light_source_pdf(ls, i, x, d, portal_share));
        sum = v3_add(sum, v3_scale(le, w));
    }
    return sum;
}

float light_source_pdf(const LightSet *ls, uint32_t i, Vec3 x, Vec3 d, float portal_share)
{
    const LightSource *l = &ls->sources[i];
    float pick = (float)l->pick_pdf;
    if (l->kind == SG_LIGHT_INFINITE)
        return pick * infinite_pdf(l, x, d, portal_share);
    if (l->kind == SG_LIGHT_DISTANT && l->sun_sin2 > 0.0f)
        return in_sun_disk(l, d) ? pick / (2.0f * SG_PI * l->sun_one_minus_cos) : 0.0f;
    return 0.0f;
}

bool light_source_sample(const LightSet *ls, uint32_t i, Vec3 origin, float portal_share, float u0, float u1,
                         float u2, LightSourcePoint *out)
{
    const LightSource *l = &ls->sources[i];
    float pick = (float)l->pick_pdf;
    *out = (LightSourcePoint){.dist = INFINITY, .pdf = pick};
    switch (l->kind) {
    case SG_LIGHT_POINT:
    case SG_LIGHT_SPOT: {
        Vec3 to = v3_sub(l->position, origin);
        float dist2 = v3_dot(to, to);
        if (!(dist2 > 0.0f))
            return false;
        out->dist = sqrtf(dist2);
        out->wi = v3_scale(to, 1.0f / out->dist);
        float k = 1.0f / dist2;
        if (l->kind == SG_LIGHT_SPOT)
            k *= spot_falloff(l, -v3_dot(out->wi, l->direction));
        out->le = v3_scale(l->rgb, k);
        out->delta = true;
        return k > 0.0f;
    }
    case SG_LIGHT_DISTANT:
        if (!(l->sun_sin2 > 0.0f)) {
            out->wi = v3_scale(l->direction, -1.0f);
            out->le = l->rgb;
            out->delta = true;
            return true;
        }
        {
            /* uniform in the cone around the sun's direction: 1 - cos t
             * uniform, the sine from it without cancellation */
            float s = u1 * l->sun_one_minus_cos;
            float cos_t = 1.0f - s, sin_t = sqrtf(fmaxf(0.0f, s * (2.0f - s)));
            float phi = 2.0f * SG_PI * u2;
            out->wi = sg_to_world(v3(sin_t * cosf(phi), sin_t * sinf(phi), cos_t), v3_scale(l->direction, -1.0f));
        }
        out->le = l->rgb;
        out->pdf = pick / (2.0f * SG_PI * l->sun_one_minus_cos);
        return true;
    case SG_LIGHT_INFINITE: {
        /* through a window (where it has portals), or from the whole sky */
        float sky, share = share_or_default(portal_share);
        if (l->portal_count && u0 < share) {
            float s = u0 / share * (float)l->portal_count;
            uint32_t k = (uint32_t)s < l->portal_count ? (uint32_t)s : l->portal_count - 1;
            const Portal *p = &l->portals[k];
            Vec3 to = v3_sub(v3_add(p->p0, v3_add(v3_scale(p->e1, u1), v3_scale(p->e2, u2))), origin);
            float len = v3_length(to);
            if (!(len > 0.0f))
                return false;
            out->wi = v3_scale(to, 1.0f / len);
        } else if (l->map) {
            out->wi = environment_sample(l->map, u1, u2, &sky);
        } else {
            float z = 1.0f - 2.0f * u1, r = sqrtf(fmaxf(0.0f, 1.0f - z * z)), phi = 2.0f * SG_PI * u2;
            out->wi = v3(r * cosf(phi), r * sinf(phi), z);
            sky = 1.0f / (4.0f * SG_PI);
        }
        out->le = l->map ? environment_radiance(l->map, out->wi) : l->rgb;
        /* without portals the sample's own density; with them the mixture's */
        if (!l->portal_count) {
            out->pdf = pick * sky;
            return out->pdf > 0.0f;
        }
        float portals = portals_pdf_sum(l, origin, out->wi);
        out->pdf_portals = portals / (float)l->portal_count;
        out->pdf_sky = sky_pdf(l, out->wi);
        out->pdf = pick * ((1.0f - share) * out->pdf_sky + share * portals / (float)l->portal_count);
        return out->pdf > 0.0f;
    }
    }
    return false;
}

double light_set_power(const LightSet *ls) { return ls->total_power; }

/* ---- the set ---------------------------------------------------------------------- */

/* Pick probabilities by power: the area lights' (power[], summing to
 * area_power), then the sources'. Without sources the arithmetic is the
 * one area lights always had, so their images do not change. */
static bool finish_picking(LightSet *ls, const double *power, double area_power, const SgScene *s)
{
    double dx = s->bounds_max[0] - s->bounds_min[0], dy = s->bounds_max[1] - s->bounds_min[1],
           dz = s->bounds_max[2] - s->bounds_min[2];
    double radius = 0.5 * sqrt(dx * dx + dy * dy + dz * dz);
    double total = area_power;
    for (uint32_t i = 0; i < ls->source_count; i++)
        total += source_power(&ls->sources[i], radius);
    ls->total_power = total;
    double acc = 0.0;
    for (uint32_t l = 0; l < ls->count; l++) {
        ls->lights[l].pick_pdf = total > 0 ? power[l] / total : 0.0;
        acc += ls->lights[l].pick_pdf;
        ls->cdf[l] = acc;
    }
    for (uint32_t i = 0; i < ls->source_count; i++) {
        ls->sources[i].pick_pdf = total > 0 ? source_power(&ls->sources[i], radius) / total : 0.0;
        acc += ls->sources[i].pick_pdf;
        ls->cdf[ls->count + i] = acc;
    }
    return true;
}

/* Which light the guide follows (SgGuideLight's order): in proportion to
 * follow_weight where given, else to power (the area lights' area_power,
 * area times luminance; the others' power over pi in the same unit). */
static bool follow_init(LightSet *ls, const SgScene *s, const double *follow_weight, const double *area_power,
                        const char *path, SgError *err)
{
    ls->follow_count = sg_scene_guide_light_count(s);
    if (!ls->follow_count)
        return true;
    ls->follow_cdf = calloc(ls->follow_count, sizeof *ls->follow_cdf);
    double *w = calloc(ls->follow_count, sizeof *w);
    if (!ls->follow_cdf || !w) {
        free(w);
        return sg_fail(err, "%s: out of memory for the light table", path);
    }
    for (uint32_t l = 0; l < ls->follow_count; l++)
        w[l] = follow_weight ? follow_weight[l] : l < ls->count ? area_power[l] : sg_scene_guide_light(s, l).power / M_PI;
    double wsum = 0.0, acc = 0.0;
    for (uint32_t l = 0; l < ls->follow_count; l++)
        wsum += w[l] > 0 ? w[l] : 0.0;
    for (uint32_t l = 0; l < ls->follow_count; l++) {
        acc += wsum > 0 && w[l] > 0 ? w[l] / wsum : 0.0;
        ls->follow_cdf[l] = acc;
    }
    free(w);
    return true;
}

bool light_set_init(LightSet *ls, const SgScene *s, const Vec3 *vertices, const Material *materials,
                    const double *follow_weight, const double centre[3], const char *path, SgError *err)
{
    if (!sources_init(ls, s, centre, path, err))
        return false;
    ls->count = s->light_count;
    uint32_t n_all = ls->count + ls->source_count;
    if (!n_all)
        return true;
    ls->cdf = calloc(n_all, sizeof *ls->cdf);
    if (!ls->cdf)
        return sg_fail(err, "%s: out of memory for the light table", path);
    if (!ls->count)
        return finish_picking(ls, NULL, 0.0, s) && follow_init(ls, s, follow_weight, NULL, path, err);
    ls->lights = calloc(ls->count, sizeof *ls->lights);
    uint32_t total_tris = 0;
    for (uint32_t l = 0; l < s->light_count; l++)
        total_tris += s->lights[l].triangle_count;
    ls->tris = calloc(total_tris ? total_tris : 1, sizeof *ls->tris);
    ls->tri_cdf = calloc(total_tris ? total_tris : 1, sizeof *ls->tri_cdf);
    if (!ls->lights || !ls->tris || !ls->tri_cdf)
        return sg_fail(err, "%s: out of memory for the light table", path);
    double total_power = 0.0;
    double *power = calloc(ls->count, sizeof *power);
    if (!power)
        return sg_fail(err, "%s: out of memory", path);
    uint32_t k = 0;
    for (uint32_t l = 0; l < s->light_count; l++) {
        const SgLight *L = &s->lights[l];
        LightTable *lt = &ls->lights[l];
        lt->first = k;
        double area = 0.0;
        for (uint32_t i = 0; i < L->triangle_count; i++) {
            uint32_t t = s->light_triangles[L->first_triangle + i];
            if (t >= s->triangle_count) {
                free(power);
                return sg_fail(err, "%s: light %u names triangle %u of %u", path, l, t,
                               s->triangle_count);
            }
            const Vec3 *v = vertices;
            const uint32_t *id = s->indices + 3 * t;
            float a = 0.5f * v3_length(v3_cross(v3_sub(v[id[1]], v[id[0]]), v3_sub(v[id[2]], v[id[0]])));
            area += a;
            ls->tris[k] = t;
            ls->tri_cdf[k] = area;
            k++;
        }
        lt->count = k - lt->first;
        for (uint32_t i = lt->first; i < k; i++)
            ls->tri_cdf[i] = area > 0 ? ls->tri_cdf[i] / area : (double)(i - lt->first + 1) / lt->count;
        lt->inv_area = area > 0 ? (float)(1.0 / area) : 0.0f;
        /* power from what the renderer will emit: the material's emission */
        Vec3 e = v3(0, 0, 0);
        if (L->triangle_count) {
            uint32_t t0 = s->light_triangles[L->first_triangle];
            e = materials[s->triangle_material[t0]].emission;
        }
        power[l] = area > 0 ? area * luminance(e) : 0.0;
        total_power += power[l];
    }
    finish_picking(ls, power, total_power, s);
    bool ok = follow_init(ls, s, follow_weight, power, path, err);
    free(power);
    return ok;
}

void light_set_free(LightSet *ls)
{
    for (uint32_t i = 0; i < ls->source_count; i++) {
        if (ls->sources[i].map) {
            environment_free(ls->sources[i].map);
            free(ls->sources[i].map);
        }
        free(ls->sources[i].portals);
    }
    free(ls->sources);
    free(ls->lights);
    free(ls->cdf);
    free(ls->tris);
    free(ls->tri_cdf);
    free(ls->follow_cdf);
    *ls = (LightSet){0};
}
