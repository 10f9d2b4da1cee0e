#include "integrator.h"

#include <math.h>
#include <string.h>

#include "bsdf.h"
#include "roulette.h"
#include "sampling.h"

/* ---- the path's state ------------------------------------------------------ */

/* No sample of a path weighs more than WEIGHT_RATIO_MAX times what BSDF
 * sampling with the albedo roulette would give the same path: at each
 * vertex a guide's mixture takes a BSDF share of at least
 * weight_ratio / WEIGHT_RATIO_MAX (GuideVertex.alpha_floor), and the
 * learned roulette a survival of at least that times the albedo
 * roulette's. A learner's young guesses (a region's mixture fitted to a
 * few hundred bounces that never met the sun's patch, its roulette's
 * second moment underestimated alike) compound along a path: on a sun
 * through a window (tests/data/sun-window, 8 passes, 16 seeds) one sample
 * in a few thousand weighed 20-100x, and the image's MSE was 2.2x bsdf's;
 * bounded at 4 it is 0.64x bsdf's, and from 32 passes on the corridor,
 * the dark corridor, the north room, the sunlit house and the staircase
 * are within noise of unbounded (2 loses 25% on the corridor; 8 leaves
 * the sun window 1.6x worse than 4). docs/render.md, "Bounded weights". */
#define WEIGHT_RATIO_MAX 4.0f

/* Between vertices. */
typedef struct PathState {
    Vec3 o, d;
    Vec3 beta;
    /* What beta would be under BSDF sampling (the product of albedos):
     * Russian roulette follows it, not beta, so that a guided path is not
     * killed for carrying a small weight where its pdf was large. Any
     * survival probability is unbiased once divided out. */
    Vec3 rr_beta;
    bool specular_bounce; /* the last bounce was drawn by its BSDF alone: emission counts fully */
    float prev_pdf;
    float prev_portal_share; /* the vertex before's (GuideVertex.portal_share) */
    Vec3 prev_p;
    Vec3 guide_estimate; /* the guide's slot for its roulette (PathGuideOps.survival) */
    /* the absorbing dielectric the path is inside (Material.sigma_a), or 0:
     * set where a path enters one through its front, cleared where it
     * leaves through the back */
    Vec3 sigma_a;
    bool absorbing;
    /* The path's weight over what BSDF sampling with the albedo roulette
     * would give the same path: the product, over its bounces, of the
     * BSDF's density over the one drawn from, and over its roulettes, of
     * the albedo roulette's survival over the one used (and of 1/split
     * where it split). Kept at most WEIGHT_RATIO_MAX (above). */
    float weight_ratio;
} PathState;

/* A diffuse or glossy vertex, as far as drawing its bounce needs. */
typedef struct BounceVertex {
    const Material *m;
    GuideVertex g;     /* the guide's distribution there */
    Vec3 origin, p;
    GuideSegment *seg; /* recording: the vertex's record */
    int thread;
    /* a normal or bump map bent the shading normal (the BSDF's lobe.n)
     * away from ng, the geometric normal on wo's side: what is below ng
     * gets nothing, so no light comes through the surface */
    bool shaded;
    Vec3 ng;
} BounceVertex;

/* A learning vertex waiting for the rest of its branch. */
typedef struct PendingRecord {
    GuideVertex v;  /* as its bounce was drawn */
    Vec3 beta;      /* path throughput of the bounce (before the roulette, where it cut the path) */
    Vec3 radiance;  /* radiance gathered before the bounce */
    bool bounced;   /* a direction above the surface was drawn */
    bool cut;       /* the albedo roulette cut the path here */
    float distance; /* how far the bounce's ray went (INFINITY: it left the scene) */
} PendingRecord;

#define MAX_PENDING 32

/* A vertex where the learned roulette split the path: its bounce is drawn
 * again, `remaining` more times, once the branches before have ended. */
typedef struct SplitPoint {
    BounceVertex v;
    PathState ps;      /* at the vertex, beta already divided by the split factor */
    int depth;
    int remaining;
    int mark;          /* the branch's first record in pending[] */
    bool learn;        /* the vertex learns: each branch gets a record */
} SplitPoint;

/* One camera path as it is traced: where it is, what it gathered, the
 * records of its learning vertices (known once their branch has ended) and
 * the split points its other branches wait at. */
typedef struct Path {
    const Integrator *it;
    const PathCtx *pc;
    PathState ps;
    Vec3 radiance;
    Vec3 *seen;
    int depth;
    int branches;
    int pending_count, split_count;
    PendingRecord *last_bounce; /* the record whose bounce the next ray follows, if any */
    PendingRecord pending[MAX_PENDING];
    SplitPoint splits[SPLIT_STACK];
} Path;

/* ---- what a finished branch tells the guide -------------------------------- */

static Vec3 per_throughput(Vec3 c, Vec3 beta)
{
    return v3(beta.x > 0.0f ? c.x / beta.x : 0.0f, beta.y > 0.0f ? c.y / beta.y : 0.0f,
              beta.z > 0.0f ? c.z / beta.z : 0.0f);
}

/* The records pending[from..to) of a finished branch: what each bounce
 * brought back is the radiance gathered since it, `radiance` now. */
static void finish_records(PathGuide *g, const PendingRecord *pending, int from, int to, Vec3 radiance, int tile)
{
    for (int i = from; i < to; i++) {
        const PendingRecord *pr = &pending[i];
        float t = luminance(pr->beta);
        BounceOutcome o = {.radiance = luminance(per_throughput(v3_sub(radiance, pr->radiance), pr->beta)),
                           .weight = t * t, .bounced = pr->bounced, .cut = pr->cut, .distance = pr->distance};
        g->ops->learn(g, tile, &pr->v, &o);
    }
}

/* ---- surfaces --------------------------------------------------------------- */

/* A textured material's albedo at a hit, its texture's value there. */
static Vec3 textured_albedo(const Integrator *it, const Material *m, const Hit *h, int thread)
{
    Vec3 c = texture_set_eval_at(it->textures, m->texture, h->tri, h->b1, h->b2, thread);
    Vec3 top = m->type == SG_MATERIAL_GLOSSY ? v3_sub(v3(1, 1, 1), m->ks) : v3(1, 1, 1); /* kd + ks <= 1 */
    return v3(sg_minf(sg_maxf(c.x, 0.0f), top.x), sg_minf(sg_maxf(c.y, 0.0f), top.y),
              sg_minf(sg_maxf(c.z, 0.0f), top.z));
}

/* The material's albedo at a hit: kd, or its texture's value there (the
 * untextured case inline: it is every vertex of most scenes). */
static inline Vec3 surface_albedo(const Integrator *it, const Material *m, const Hit *h, int thread)
{
    return m->texture ? textured_albedo(it, m, h, thread) : m->kd;
}

/* ---- cut-outs ------------------------------------------------------------------ */

/* How many cut-out surfaces one ray may pass before the next counts as solid. */
#define MAX_CUTOUT_LAYERS 64

/* A number in [0, 1) of the ray and the hit's distance alone (pbrt-v4
 * hashes the ray too): the same ray meets a surface of constant alpha, or
 * passes it, every time; layers along one ray decide apart. */
static float ray_hash(Vec3 o, Vec3 d, float t)
{
    const float f[7] = {o.x, o.y, o.z, d.x, d.y, d.z, t};
    uint64_t h = 0x9e3779b97f4a7c15ULL;
    for (int i = 0; i < 7; i++) {
        uint32_t bits;
        memcpy(&bits, &f[i], sizeof bits);
        h = (h ^ bits) * 0xbf58476d1ce4e5b9ULL;
        h ^= h >> 31;
    }
    h *= 0x94d049bb133111ebULL;
    h ^= h >> 29;
    return (float)(h >> 40) * 0x1p-24f;
}

/* Whether the ray from o along d passes through its hit h: a cut-out's
 * alpha texture below 0.5 there, or its constant alpha by the ray's hash. */
static bool passes_through(const Integrator *it, const Hit *h, Vec3 o, Vec3 d, int thread)
{
    const Material *m = &it->materials[it->geo->tris[h->tri].material];
    if (!m->cutout)
        return false;
    if (m->alpha_texture)
        return texture_set_eval_at(it->textures, m->alpha_texture, h->tri, h->b1, h->b2, thread).x < 0.5f;
    return ray_hash(o, d, h->t) >= m->alpha;
}

/* The first hit along the ray that it does not pass through (scenes
 * without cut-outs: intersect itself). Past a cut-out the ray goes on
 * along the same line, just beyond the hit: an origin moved off the
 * surface would shift the line and so where a shadow ray's reach ends. */
static Hit intersect_solid(const Integrator *it, Vec3 o, Vec3 d, float tfar, int thread)
{
    Hit h = intersect(it->geo, o, d, tfar);
    if (!it->geo->has_cutouts)
        return h;
    for (int i = 0; h.found && i < MAX_CUTOUT_LAYERS && passes_through(it, &h, o, d, thread); i++) {
        float tnear = h.t * (1.0f + 0x1p-16f) + it->geo->scale * 0x1p-24f;
        h = intersect_between(it->geo, o, d, tnear, tfar);
    }
    return h;
}

static bool occluded_solid(const Integrator *it, Vec3 o, Vec3 d, float tfar, int thread)
{
    return it->geo->has_cutouts ? intersect_solid(it, o, d, tfar, thread).found : occluded(it->geo, o, d, tfar);
}

/* Emission toward the path (one-sided, toward the winding normal), MIS
 * weighted against the light sample of the vertex before. */
static void add_emission(Path *p, const Hit *h, const Material *m, float cos_o, GuideSegment *seg)
{
    const Integrator *it = p->it;
    float w = 1.0f;
    if (!p->ps.specular_bounce) {
        Vec3 dp = v3_sub(h->p, p->ps.prev_p);
        float pl = light_set_pdf(it->lights, it->geo->tris[h->tri].light, v3_dot(dp, dp), -cos_o);
        w = sg_power_heuristic(p->ps.prev_pdf, pl);
    }
    p->radiance = v3_add(p->radiance, v3_scale(v3_mul(p->ps.beta, m->emission), w));
    if (seg)
        it->guide->ops->record_emission(seg, m->emission, w);
}

/* A ray that left the scene: the sky's and the sun disk's radiance, MIS
 * weighted against the light samples of the vertex before. The guide
 * records it as emission seen far along the ray. */
static void add_escaped(Path *p)
{
    const Integrator *it = p->it;
    Vec3 le = light_set_escaped(it->lights, p->ps.prev_p, p->ps.d, p->ps.specular_bounce ? -1.0f : p->ps.prev_pdf,
                                p->ps.prev_portal_share);
    p->radiance = v3_add(p->radiance, v3_mul(p->ps.beta, le));
    if (p->pc->record) {
        Vec3 far = v3_add(p->ps.o, v3_scale(p->ps.d, 1e3f * it->geo->scale));
        Vec3 back = v3_scale(p->ps.d, -1.0f);
        GuideSegment *seg = it->guide->ops->record_vertex(it->guide, p->pc->thread, far, back, back);
        if (seg)
            it->guide->ops->record_emission(seg, le, 1.0f);
    }
}

/* A mirror's, smooth conductor's or glass's bounce, drawn from its BSDF
 * alone (bsdf.h); false where the path ends. */
static bool specular_bounce(Path *p, const Material *m, const Hit *h, Vec3 wo, Vec3 n, bool entering,
                            GuideSegment *seg)
{
    const Integrator *it = p->it;
    SgRng *rng = p->pc->rng;
    PathState *ps = &p->ps;
    SpecularBounce b;
    if (m->delta) {
        Vec3 albedo = m->type == SG_MATERIAL_CONDUCTOR ? surface_albedo(it, m, h, p->pc->thread) : m->kd;
        bsdf_sample_delta(m, albedo, wo, n, entering, bsdf_delta_chooses(m) ? sg_rng_float(rng) : 0.0f, &b);
    } else {
        float uc = sg_rng_float(rng), u1 = sg_rng_float(rng), u2 = sg_rng_float(rng);
        if (!bsdf_sample_rough_glass(m, wo, n, entering, uc, u1, u2, &b))
            return false;
    }
    ps->d = b.wi;
    ps->o = offset_origin(it->geo, h->p, b.transmitted ? v3_scale(n, -1.0f) : n);
    if (b.transmitted && m->type == SG_MATERIAL_DIELECTRIC) { /* into or out of what it encloses */
        ps->absorbing = entering && m->absorbs;
        ps->sigma_a = ps->absorbing ? m->sigma_a : v3(0, 0, 0);
    }
    ps->beta = v3_mul(ps->beta, b.weight);
    ps->rr_beta = v3_mul(ps->rr_beta, b.rr_weight);
    ps->specular_bounce = true;
    if (seg)
        it->guide->ops->record_bounce(seg, b.wi, b.pdf, b.weight, b.delta, b.eta, b.delta ? 0.0f : m->roughness);
    return true;
}

/* ---- shading normals ------------------------------------------------------------ */

/* A shading-normal vertex's direction under its geometric surface. */
static inline bool below_geometry(const BounceVertex *v, Vec3 wi) { return v->shaded && !(v3_dot(wi, v->ng) > 0.0f); }

/* The triangle's tangent dp/du and bitangent dp/dv from its texture
 * coordinates, and the coordinates at the hit; without usable ones, a
 * frame around the normal ng and (0, 0). */
static void surface_frame(const Integrator *it, const Hit *h, Vec3 ng, Vec3 *dpdu, Vec3 *dpdv, float *u, float *v)
{
    float uv[3][2];
    *u = *v = 0.0f;
    if (texture_set_triangle_uvs(it->textures, h->tri, uv)) {
        const uint32_t *id = it->geo->indices + 3 * (size_t)h->tri;
        Vec3 p0 = it->geo->vertices[id[0]], p1 = it->geo->vertices[id[1]], p2 = it->geo->vertices[id[2]];
        float b0 = 1.0f - h->b1 - h->b2;
        *u = b0 * uv[0][0] + h->b1 * uv[1][0] + h->b2 * uv[2][0];
        *v = b0 * uv[0][1] + h->b1 * uv[1][1] + h->b2 * uv[2][1];
        float du02 = uv[0][0] - uv[2][0], dv02 = uv[0][1] - uv[2][1];
        float du12 = uv[1][0] - uv[2][0], dv12 = uv[1][1] - uv[2][1];
        float det = du02 * dv12 - dv02 * du12;
        if (fabsf(det) > 1e-12f) {
            Vec3 dp02 = v3_sub(p0, p2), dp12 = v3_sub(p1, p2);
            *dpdu = v3_scale(v3_sub(v3_scale(dp02, dv12), v3_scale(dp12, dv02)), 1.0f / det);
            *dpdv = v3_scale(v3_sub(v3_scale(dp12, du02), v3_scale(dp02, du12)), 1.0f / det);
            if (v3_length(v3_cross(*dpdu, *dpdv)) > 0.0f)
                return;
        }
    }
    v3_basis(ng, dpdu, dpdv);
}

/* The shading normal of a normal- or bump-mapped material at h, on the
 * side of n (the geometric normal facing wo). A map that would turn it
 * away from wo gives the geometric normal there (a light leak otherwise). */
static Vec3 shading_normal(const Integrator *it, const Material *m, const Hit *h, Vec3 n, Vec3 wo, int thread)
{
    Vec3 ng = it->geo->tris[h->tri].normal; /* the winding's side: maps are made for it */
    Vec3 dpdu, dpdv, ns;
    float u, v;
    surface_frame(it, h, ng, &dpdu, &dpdv, &u, &v);
    if (m->normal_texture) { /* tangent space: x along dp/du, z the normal (pbrt-v4, Mitsuba) */
        Vec3 c = texture_set_eval_at(it->textures, m->normal_texture, h->tri, h->b1, h->b2, thread);
        Vec3 x = v3_sub(dpdu, v3_scale(ng, v3_dot(ng, dpdu)));
        x = v3_length(x) > 0.0f ? v3_normalize(x) : dpdu;
        Vec3 y = v3_cross(ng, x);
        ns = v3_add(v3_add(v3_scale(x, 2.0f * c.x - 1.0f), v3_scale(y, 2.0f * c.y - 1.0f)),
                    v3_scale(ng, 2.0f * c.z - 1.0f));
    } else { /* the displaced surface's normal, by differences (pbrt-v4's step without ray differentials) */
        const float step = 0.0005f;
        float d0 = texture_set_eval(it->textures, m->bump_texture, u, v, thread).x;
        float d_u = texture_set_eval(it->textures, m->bump_texture, u + step, v, thread).x;
        float d_v = texture_set_eval(it->textures, m->bump_texture, u, v + step, thread).x;
        Vec3 tu = v3_add(dpdu, v3_scale(ng, m->bump_scale * (d_u - d0) / step));
        Vec3 tv = v3_add(dpdv, v3_scale(ng, m->bump_scale * (d_v - d0) / step));
        ns = v3_cross(tu, tv);
        if (v3_dot(ns, ng) < 0.0f) /* uv mirrored: the winding decides the side */
            ns = v3_scale(ns, -1.0f);
    }
    float len = v3_length(ns);
    if (!(len > 0.0f) || !isfinite(len))
        return n;
    ns = v3_scale(ns, 1.0f / len);
    if (v3_dot(n, ng) < 0.0f)
        ns = v3_scale(ns, -1.0f);
    return v3_dot(ns, wo) > 1e-3f && v3_dot(ns, n) > 1e-3f ? ns : n;
}

/* ---- a diffuse or glossy vertex ---------------------------------------------- */

/* Next-event estimation: one point on the lights, its shadow ray, and what
 * it brings (before the MIS weight). */
typedef struct LightSample {
    bool lit;         /* the sampled point is visible (whatever its cosine) */
    Vec3 c;           /* f cos Le / pdf, 0 where the point gives nothing */
    Vec3 wi;
    float pdf, cos_x; /* pdf 0: no contribution */
    bool delta;       /* a point, spot or sun without a disk: no MIS weight */
    /* a sky with portals was sampled: its strategies' densities (blocked too) */
    bool sky;
    float pdf_portals, pdf_sky;
} LightSample;

/* Next-event estimation toward a point, spot, distant or infinite light
 * (index among the sources). A delta light's sample is marked so: no
 * bounce can find it, so the caller gives it no MIS weight. */
static LightSample sample_light_source(const Integrator *it, const BounceVertex *v, uint32_t source,
                                       bool lit_below_horizon, float u0, float u1, float u2, PathStats *st)
{
    LightSample ls = {0};
    LightSourcePoint lp;
    /* the light as seen from the surface point itself: from the offset
     * origin a point light would be nearer by the offset (0.2 % brighter
     * at a scene's size / 65536 from a lamp 1.5 away) */
    if (!light_source_sample(it->lights, source, v->p, v->g.portal_share, u0, u1, u2, &lp))
        return ls;
    ls.sky = lp.pdf_portals > 0.0f || lp.pdf_sky > 0.0f;
    ls.pdf_portals = lp.pdf_portals;
    ls.pdf_sky = lp.pdf_sky;
    float cos_x = below_geometry(v, lp.wi) ? 0.0f : v3_dot(lp.wi, v->g.bsdf.lobe.n);
    if (!(cos_x > 0.0f || lit_below_horizon))
        return ls;
    st->rays++;
    Vec3 shadow = lp.wi;
    float reach = INFINITY;
    if (!isinf(lp.dist)) {
        Vec3 to = v3_sub(v3_add(v->p, v3_scale(lp.wi, lp.dist)), v->origin);
        reach = v3_length(to);
        shadow = v3_scale(to, 1.0f / reach);
        reach *= 1.0f - 1e-4f;
    }
    if (occluded_solid(it, v->origin, shadow, reach, v->thread))
        return ls;
    ls.lit = true;
    if (cos_x > 0.0f && lp.pdf > 0.0f) {
        Vec3 f = bsdf_eval(&v->g.bsdf, lp.wi);
        ls.c = v3_scale(v3_mul(f, lp.le), cos_x / lp.pdf);
        ls.wi = lp.wi;
        ls.cos_x = cos_x;
        ls.pdf = lp.pdf;
        ls.delta = lp.delta;
    }
    return ls;
}

static LightSample sample_light(const Integrator *it, const BounceVertex *v, bool lit_below_horizon, SgRng *rng,
                                PathStats *st)
{
    LightSample ls = {0};
    float ul = sg_rng_float(rng), ut = sg_rng_float(rng);
    float ua = sg_rng_float(rng), ub = sg_rng_float(rng);
    uint32_t t, light;
    Vec3 y;
    const Geometry *geo = it->geo;
    if (!light_set_pick(it->lights, ul, &light))
        return ls;
    if (light >= it->lights->count)
        return sample_light_source(it, v, light - it->lights->count, lit_below_horizon, ut, ua, ub, st);
    light_set_sample_area(it->lights, light, geo->vertices, geo->indices, ut, ua, ub, &t, &y);
    Vec3 n = v->g.bsdf.lobe.n;
    Vec3 to = v3_sub(y, v->origin);
    float dist2 = v3_dot(to, to);
    float dist = sqrtf(dist2);
    Vec3 wi = v3_scale(to, 1.0f / dist);
    float cos_l = -v3_dot(wi, geo->tris[t].normal);
    float cos_x = below_geometry(v, wi) ? 0.0f : v3_dot(wi, n);
    if (!(dist > 0.0f && cos_l > 0.0f && (cos_x > 0.0f || lit_below_horizon)))
        return ls;
    st->rays++;
    if (occluded_solid(it, v->origin, wi, dist * (1.0f - 1e-4f), v->thread))
        return ls;
    ls.lit = true;
    if (cos_x > 0.0f) {
        const Material *lm = &it->materials[geo->tris[t].material];
        float pl = light_set_pdf(it->lights, geo->tris[t].light, dist2, cos_l);
        Vec3 f = bsdf_eval(&v->g.bsdf, wi);
        ls.c = v3_scale(v3_mul(f, lm->emission), cos_x / pl);
        ls.wi = wi;
        ls.cos_x = cos_x;
        ls.pdf = pl;
    }
    return ls;
}

/* Draws the vertex's bounce into the path state; false where the path
 * ends (below the surface). `pr`: the vertex's learning record, if any. */
static bool take_bounce(const PathGuide *guide, BounceVertex *v, PathState *ps, SgRng *rng, PendingRecord *pr,
                        PathStats *st)
{
    float u[3];
    u[0] = sg_rng_float(rng);
    u[1] = sg_rng_float(rng);
    u[2] = sg_rng_float(rng);
    float pdf;
    v->g.pdf_bsdf = -1.0f;
    Vec3 wi = guide->ops->sample(&v->g, u, &pdf);
    st->bounces++;
    st->lobe_bounces += v->g.by_guide;
    float cos_x = v3_dot(wi, v->g.bsdf.lobe.n);
    bool above = cos_x > 0.0f && pdf > 0.0f && !below_geometry(v, wi);
    if (pr) {
        pr->v = v->g;
        pr->bounced = above;
        pr->distance = INFINITY;
    }
    if (!above)
        return false; /* below the surface: f = 0, the path ends */
    Vec3 f = bsdf_eval(&v->g.bsdf, wi);
    Vec3 weight = v3_scale(f, cos_x / pdf);
    ps->beta = v3_mul(ps->beta, weight);
    if (v->g.pdf_bsdf > 0.0f)
        ps->weight_ratio *= v->g.pdf_bsdf / pdf;
    if (v->seg)
        guide->ops->record_bounce(v->seg, wi, pdf, weight, false, 1.0f, v->m->roughness);
    ps->d = wi;
    ps->o = v->origin;
    ps->prev_pdf = v->g.mis_pdf >= 0.0f ? v->g.mis_pdf : pdf;
    ps->prev_portal_share = v->g.portal_share;
    ps->prev_p = v->p;
    ps->specular_bounce = false;
    return true;
}

/* The roulette at a vertex whose light sample is done and whose bounce is
 * not drawn yet: it decides on the bounce alone, and a path cut here keeps
 * its direct light and pays for no direction, pdf or guide lobe it would
 * not follow. The learned roulette where the vertex knows what its bounce
 * brings back (GuideVertex.rms), may split the path; elsewhere by albedo.
 * False where the path is cut. */
static bool vertex_roulette(Path *p, const BounceVertex *v, PendingRecord *pr, bool *decided)
{
    PathState *ps = &p->ps;
    SgRng *rng = p->pc->rng;
    ps->rr_beta = v3_mul(ps->rr_beta, bsdf_albedo(&v->g.bsdf));
    if (p->pc->pixel_deviation > 0.0f && v->g.rms >= 0.0f) {
        float worth = luminance(ps->beta) * v->g.rms / p->pc->pixel_deviation;
        float q_albedo = 1.0f; /* the albedo roulette's survival here */
        if (p->depth >= ROULETTE_DEPTH) {
            *decided = true;
            q_albedo = roulette_albedo_survival(ps->rr_beta);
            ps->rr_beta = v3(1, 1, 1);
        }
        bool may_split = p->split_count < SPLIT_STACK && p->pc->may_split;
        float min_survival = q_albedo * ps->weight_ratio * (1.0f / WEIGHT_RATIO_MAX);
        RouletteVerdict rv = roulette_learned(worth, p->depth, p->branches, may_split, min_survival, rng);
        ps->weight_ratio *= q_albedo * rv.scale;
        if (rv.branches == 0) {
            if (pr) /* what a surviving bounce brings is what the guide estimates */
                p->pending_count--;
            return false;
        }
        ps->beta = v3_scale(ps->beta, rv.scale);
        if (rv.branches > 1) { /* the others wait, from this vertex on */
            p->splits[p->split_count++] = (SplitPoint){*v, *ps, p->depth, rv.branches - 1,
                                                       pr ? (int)(pr - p->pending) : p->pending_count, pr != NULL};
            p->branches += rv.branches - 1;
        }
    } else {
        const PathGuide *g = p->it->guide;
        float q = g->ops->survival ? g->ops->survival(&v->g, ps->beta, &ps->guide_estimate) : -1.0f;
        if (p->depth < ROULETTE_DEPTH)
            return true;
        *decided = true;
        if (!(q >= 0.0f ? roulette_survive(g, q, &ps->beta, &ps->rr_beta, rng, v->seg)
                        : roulette_albedo(g, &ps->beta, &ps->rr_beta, rng, v->seg))) {
            if (pr) /* the guide hears of a bounce cut before it was drawn */
                *pr = (PendingRecord){.v = v->g, .beta = pr->beta, .radiance = p->radiance, .cut = true};
            return false;
        }
    }
    return true;
}

/* A diffuse or glossy vertex: the guide's distribution there, the light
 * sample weighted by MIS against it, the roulette, then the bounce. False
 * where the path ends; *decided: a roulette has decided here. */
static bool scatter(Path *p, const Hit *h, const Material *m, Vec3 wo, Vec3 n, bool front, GuideSegment *seg,
                    bool *decided)
{
    const Integrator *it = p->it;
    const PathCtx *pc = p->pc;
    PathGuide *guide = it->guide;
    const PathGuideOps *gops = guide->ops;
    /* field by field: zeroing the whole vertex (its BSDF's microfacet
     * fields, unused by most) costs per bounce; the guide's state starts
     * zeroed as guides expect */
    BounceVertex v;
    v.m = m;
    v.p = h->p;
    v.seg = seg;
    v.thread = pc->thread;
    memset(v.g.state, 0, sizeof v.g.state);
    Vec3 albedo = surface_albedo(it, m, h, pc->thread);
    v.shaded = m->normal_texture || m->bump_texture;
    Vec3 ns = v.shaded ? shading_normal(it, m, h, n, wo, pc->thread) : n;
    if (m->type == SG_MATERIAL_DIFFUSE_TRANSMISSION) { /* one side per vertex (bsdf.h) */
        DiffuseTransmission dt = bsdf_diffuse_transmission(ns, albedo, m->kt);
        if (bsdf_diffuse_side(&dt, sg_rng_float(pc->rng), &albedo)) {
            n = v3_scale(n, -1.0f);
            ns = v3_scale(ns, -1.0f);
            front = !front;
        }
    }
    v.ng = n;
    bsdf_init(&v.g.bsdf, m, ns, wo, albedo);
    v.g.learn = false;
    v.g.rms = -1.0f;
    v.g.by_guide = false;
    v.g.mis_pdf = -1.0f;
    v.g.portal_share = -1.0f;
    v.g.sky.taken = false;
    v.g.alpha_floor = sg_minf(1.0f, p->ps.weight_ratio * (1.0f / WEIGHT_RATIO_MAX));
    /* n is the winding normal or its opposite: the other bin of the pair */
    GuideHit gh = {.p = h->p, .n = n, .m = m, .thread = pc->thread,
                   .normal_bin = it->geo->tris[h->tri].normal_bin ^ (front ? 0u : 1u),
                   .may_learn = pc->learn_tile >= 0 && p->pending_count < MAX_PENDING};
    if (gops->vertex_begin)
        gops->vertex_begin(guide, &gh, pc->rng, &v.g);
    PendingRecord *pr = NULL;
    if (v.g.learn) { /* the weight of a bounce the roulette cuts; the rest is set when it is drawn */
        pr = &p->pending[p->pending_count++];
        *pr = (PendingRecord){.beta = p->ps.beta};
    }
    v.origin = offset_origin(it->geo, h->p, n);

    LightSample ls = sample_light(it, &v, gops->lit_below_horizon, pc->rng, pc->st);
    if (gops->vertex_end)
        gops->vertex_end(guide, &gh, ls.lit, pc->rng, &v.g);
    if (pr && ls.sky) /* for the learner of the portal share: before MIS, the whole estimate's spread */
        v.g.sky = (SkyLightSample){.taken = true, .contribution = luminance(v3_mul(p->ps.beta, ls.c)) * ls.pdf,
                                   .pdf_portals = ls.pdf_portals, .pdf_sky = ls.pdf_sky,
                                   .share = v.g.portal_share};
    if (ls.pdf > 0.0f) {
        float w = ls.delta ? 1.0f : sg_power_heuristic(ls.pdf, gops->pdf(&v.g, ls.wi, ls.cos_x));
        Vec3 c = v3_scale(ls.c, w);
        p->radiance = v3_add(p->radiance, v3_mul(p->ps.beta, c));
        if (seg)
            gops->record_direct(seg, c);
    }
    if (!vertex_roulette(p, &v, pr, decided))
        return false;
    if (pr) { /* the bounce's throughput and what came before it */
        pr->beta = p->ps.beta;
        pr->radiance = p->radiance;
    }
    p->last_bounce = pr;
    return take_bounce(guide, &v, &p->ps, pc->rng, pr, pc->st);
}

/* ---- the path ------------------------------------------------------------------ */

/* The path's next vertex: what it sees there, and its bounce. False where
 * the branch ends. */
static bool path_vertex(Path *p)
{
    const Integrator *it = p->it;
    const PathCtx *pc = p->pc;
    Hit h = intersect_solid(it, p->ps.o, p->ps.d, INFINITY, pc->thread);
    pc->st->rays++;
    if (p->last_bounce) { /* where the learning vertex's bounce led */
        if (h.found)
            p->last_bounce->distance = h.t;
        p->last_bounce = NULL;
    }
    if (p->ps.absorbing && h.found) { /* Beer-Lambert along the segment inside */
        Vec3 tau = v3_scale(p->ps.sigma_a, -h.t);
        Vec3 tr = v3(expf(tau.x), expf(tau.y), expf(tau.z));
        p->ps.beta = v3_mul(p->ps.beta, tr);
        p->ps.rr_beta = v3_mul(p->ps.rr_beta, tr);
    }
    if (!h.found) {
        if (it->lights->has_escaping)
            add_escaped(p);
        if (p->depth == 0)
            *p->seen = p->radiance;
        return false;
    }
    Vec3 ng = it->geo->tris[h.tri].normal;
    float cos_o = v3_dot(p->ps.d, ng);
    bool front = cos_o < 0.0f;
    if (p->depth == 0 && pc->first_pass && cos_o > 0.0f)
        pc->st->backface++;
    const Material *m = &it->materials[it->geo->tris[h.tri].material];
    Vec3 wo = v3_scale(p->ps.d, -1.0f);
    Vec3 n = front ? ng : v3_scale(ng, -1.0f); /* facing wo */
    PathGuide *guide = it->guide;
    GuideSegment *seg = pc->record ? guide->ops->record_vertex(guide, pc->thread, h.p, wo, n) : NULL;

    if (m->emissive && front)
        add_emission(p, &h, m, cos_o, seg);
    if (p->depth == 0)
        *p->seen = p->radiance; /* emission the camera sees directly */
    if (p->depth + 1 >= it->max_depth)
        return false;

    bool decided = false; /* a roulette has decided at this vertex */
    if (m->delta || m->type == SG_MATERIAL_DIELECTRIC) {
        if (!specular_bounce(p, m, &h, wo, n, front, seg))
            return false;
    } else if (m->black || !scatter(p, &h, m, wo, n, front, seg, &decided)) {
        return false;
    }
    /* after a specular bounce: the albedo roulette */
    if (p->depth >= ROULETTE_DEPTH && !decided && !roulette_albedo(guide, &p->ps.beta, &p->ps.rr_beta, pc->rng, seg))
        return false;
    return v3_max_component(p->ps.beta) > 0.0f;
}

/* The branch has ended: what its vertices brought back is known; the next
 * branch of the deepest split starts from that vertex's bounce. False
 * where that bounce ends it at once. */
static bool path_resume_split(Path *p)
{
    SplitPoint *sp = &p->splits[p->split_count - 1];
    finish_records(p->it->guide, p->pending, sp->mark, p->pending_count, p->radiance, p->pc->learn_tile);
    p->pending_count = sp->mark;
    BounceVertex v = sp->v;
    v.g.sky.taken = false; /* the vertex's light sample was recorded with its first branch */
    p->ps = sp->ps;
    p->depth = sp->depth;
    PendingRecord *pr = NULL;
    if (sp->learn && p->pending_count < MAX_PENDING) {
        pr = &p->pending[p->pending_count++];
        *pr = (PendingRecord){.beta = p->ps.beta, .radiance = p->radiance};
    }
    if (--sp->remaining == 0)
        p->split_count--;
    p->last_bounce = pr;
    bool alive = take_bounce(p->it->guide, &v, &p->ps, p->pc->rng, pr, p->pc->st) &&
                 v3_max_component(p->ps.beta) > 0.0f;
    p->depth++;
    return alive;
}

Vec3 integrator_trace(const Integrator *it, Vec3 o, Vec3 d, const PathCtx *pc, Vec3 *seen)
{
    /* field by field: the records and split points are written before read */
    Path p;
    p.it = it;
    p.pc = pc;
    p.ps = (PathState){o, d, v3(1, 1, 1), v3(1, 1, 1), true /* the camera ray counts as one */, 0.0f, -1.0f, o,
                       v3(0, 0, 0), v3(0, 0, 0), false, 1.0f};
    p.radiance = v3(0, 0, 0);
    p.seen = seen;
    p.depth = 0;
    p.branches = 1;
    p.pending_count = p.split_count = 0;
    p.last_bounce = NULL;
    bool alive = true;
    for (;;) {
        if (alive)
            while (path_vertex(&p))
                p.depth++;
        if (!p.split_count)
            break;
        alive = path_resume_split(&p);
    }
    finish_records(it->guide, p.pending, 0, p.pending_count, p.radiance, pc->learn_tile);
    if (pc->record)
        it->guide->ops->record_path_end(it->guide, pc->thread);
    pc->st->branches += (uint64_t)(p.branches - 1);
    return p.radiance;
}

Vec3 integrator_seen(const Integrator *it, Vec3 o, Vec3 d, int thread, PathStats *st)
{
    Hit h = intersect_solid(it, o, d, INFINITY, thread); /* past cut-outs, as the camera ray goes */
    st->rays++;
    st->views++;
    if (!h.found) /* as add_escaped sees it from the camera: the camera ray counts as a specular bounce */
        return it->lights->has_escaping ? light_set_escaped(it->lights, o, d, -1.0f, -1.0f) : v3(0, 0, 0);
    const Material *m = &it->materials[it->geo->tris[h.tri].material];
    /* as add_emission at the first hit: front faces only, MIS weight 1 */
    return m->emissive && v3_dot(d, it->geo->tris[h.tri].normal) < 0.0f ? m->emission : v3(0, 0, 0);
}
