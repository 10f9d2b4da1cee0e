#include "renderer.h"

#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bsdf.h"
#include "camera.h"
#include "geometry.h"
#include "lights.h"
#include "material.h"
#include "memory.h"
#include "path_guide.h"
#include "pixel_noise.h"
#include "progress.h"
#include "rng.h"
#include "sampling.h"
#include "textures.h"
#include "threads.h"
#include "vecmath.h"

#define TILE 16

struct SgRenderer {
    SgRenderOptions opt;
    Geometry geo;
    SgThreadPool *pool;   /* its workers live across the passes */

    uint32_t material_count;
    Material *materials;
    TextureSet *textures; /* NULL: no material is textured */

    LightSet lights;
    PathGuide *guide;     /* how bounces are drawn: one of path_guide.h's */
    /* Learned roulette: per pixel, the sums of the luminance of its samples
     * past the camera ray's own hit (emission seen directly is not what
     * roulette acts on) and of their squares; and the noise a path may add
     * there, made before each pass (0: unknown). */
    PixelNoise *noise;
    int tiles_x, tiles_y;

    Camera camera;

    int spp;
    double *sum;           /* width * height * 3 */
    float *last;           /* width * height * 3 */
    _Atomic uint64_t nonfinite;
    _Atomic uint64_t rays;
    _Atomic uint64_t backface_hits;
    _Atomic uint64_t branches;
    _Atomic uint64_t bounces, lobe_bounces;
};

const char *sg_sampling_name(SgSampling s)
{
    switch (s) {
    case SG_SAMPLING_BSDF: return "bsdf";
    case SG_SAMPLING_SKELETON: return "skeleton";
    case SG_SAMPLING_GUIDED: return "guided";
    case SG_SAMPLING_OPENPGL: return "openpgl";
    case SG_SAMPLING_COUNT: break;
    }
    return "?";
}

bool sg_sampling_parse(const char *name, SgSampling *s)
{
    for (int i = 0; i < SG_SAMPLING_COUNT; i++)
        if (strcmp(name, sg_sampling_name((SgSampling)i)) == 0) {
            *s = (SgSampling)i;
            return true;
        }
    return false;
}

void sg_render_options_default(SgRenderOptions *o, const SgScene *scene)
{
    memset(o, 0, sizeof *o);
    o->width = scene && scene->has_camera && scene->camera.width > 0 ? scene->camera.width : 320;
    o->height = scene && scene->has_camera && scene->camera.height > 0 ? scene->camera.height : 240;
    o->max_depth = scene && scene->render.max_depth > 0 ? scene->render.max_depth : 8;
    o->sampling = SG_SAMPLING_BSDF;
    o->lobe_exponent = 16.0f;
    o->alpha = SG_ALPHA_LEARNED;
    o->roulette = SG_ROULETTE_LEARNED;
    o->shard_count = 1;
}

const char *sg_roulette_name(SgRoulette r) { return r == SG_ROULETTE_ALBEDO ? "albedo" : "learned"; }

bool sg_roulette_parse(const char *name, SgRoulette *r)
{
    if (!strcmp(name, "learned"))
        *r = SG_ROULETTE_LEARNED;
    else if (!strcmp(name, "albedo"))
        *r = SG_ROULETTE_ALBEDO;
    else
        return false;
    return true;
}

/* ---- setup ---------------------------------------------------------------- */

/* `create`: the guide's constructor, NULL: the one o->sampling names. */
static SgRenderer *renderer_create(const SgScene *s, const SgRenderOptions *o, PathGuideCreate create, SgError *err)
{
    const char *path = s->path[0] ? s->path : "scene";
    if (!s->triangle_count || !s->positions || !s->indices)
        return sg_fail(err, "%s: no triangles to render", path), NULL;
    if (!s->has_camera)
        return sg_fail(err, "%s: no camera", path), NULL;
    if (o->width <= 0 || o->height <= 0 || o->width > 65536 || o->height > 65536)
        return sg_fail(err, "%s: bad image size %dx%d", path, o->width, o->height), NULL;
    if (o->max_depth < 1)
        return sg_fail(err, "%s: max depth must be at least 1", path), NULL;
    if (!(o->lobe_exponent >= 0.0f && o->lobe_exponent <= 1e5f))
        return sg_fail(err, "%s: lobe exponent must be in [0, 1e5]", path), NULL;
    if (!(o->shard_count >= 1 && o->shard_count <= SG_SHARDS_MAX && o->shard >= 0 && o->shard < o->shard_count))
        return sg_fail(err, "%s: shard %d of %d: want 0 <= shard < count <= %d", path, o->shard, o->shard_count,
                       SG_SHARDS_MAX), NULL;
    if (o->roulette != SG_ROULETTE_LEARNED && o->roulette != SG_ROULETTE_ALBEDO)
        return sg_fail(err, "%s: unknown roulette %d", path, (int)o->roulette), NULL;

    /* sum (double) + last pass + the caller's image (float) per pixel, and
     * the renderer's and Embree's copies of the triangles (~150 bytes each):
     * refuse up front what the machine cannot hold rather than be killed */
    char what[96];
    snprintf(what, sizeof what, "a %dx%d image", o->width, o->height);
    if (!sg_memory_check(48.0 * o->width * o->height + 150.0 * s->triangle_count, path, what, err))
        return NULL;
    SgRenderer *r = calloc(1, sizeof *r);
    if (!r)
        return sg_fail(err, "%s: out of memory", path), NULL;
    r->opt = *o;
    r->tiles_x = (o->width + TILE - 1) / TILE;
    r->tiles_y = (o->height + TILE - 1) / TILE;

    if (!s->material_count) {
        sg_renderer_free(r);
        return sg_fail(err, "%s: no materials", path), NULL;
    }
    if (!geometry_init(&r->geo, s, path, err)) {
        sg_renderer_free(r);
        return NULL;
    }
    r->material_count = s->material_count;
    r->materials = calloc(s->material_count, sizeof *r->materials);
    size_t pixels = (size_t)o->width * o->height;
    r->sum = calloc(pixels * 3, sizeof *r->sum);
    r->last = calloc(pixels * 3, sizeof *r->last);
    if (!r->materials || !r->sum || !r->last) {
        sg_renderer_free(r);
        return sg_fail(err, "%s: out of memory", path), NULL;
    }
    for (uint32_t m = 0; m < s->material_count; m++)
        material_init(&r->materials[m], &s->materials[m]);
    if (!light_set_init(&r->lights, s, r->geo.vertices, r->materials, r->opt.guide.light_weight, path, err)) {
        sg_renderer_free(r);
        return NULL;
    }
    camera_init(&r->camera, &s->camera, r->geo.centre, o->width, o->height);
    r->pool = sg_thread_pool_create(o->threads);
    if (textures_needed(s) && !(r->textures = texture_set_create(s, r->geo.indices, sg_thread_pool_size(r->pool),
                                                                  o->texture_cache_mb, path, err))) {
        sg_renderer_free(r);
        return NULL;
    }
    PathGuideSetup gs = {.opt = &r->opt, .geo = &r->geo, .lights = &r->lights,
                         .threads = sg_thread_pool_size(r->pool), .tiles = (uint32_t)(r->tiles_x * r->tiles_y),
                         .path = path};
    r->guide = create ? create(&gs, err) : path_guide_create(o->sampling, &gs, err);
    if (!r->guide) {
        sg_renderer_free(r);
        return NULL;
    }
    /* the learned roulette needs what a bounce brings back: a guide that learns it */
    if (o->roulette == SG_ROULETTE_LEARNED && r->guide->estimates_radiance) {
        r->noise = pixel_noise_create(o->width, o->height);
        if (!r->noise) {
            sg_renderer_free(r);
            return sg_fail(err, "%s: out of memory", path), NULL;
        }
    }
    if (!geometry_build(&r->geo, path, err)) {
        sg_renderer_free(r);
        return NULL;
    }

    return r;
}

SgRenderer *sg_renderer_create(const SgScene *s, const SgRenderOptions *o, SgError *err)
{
    return renderer_create(s, o, NULL, err);
}

SgRenderer *sg_renderer_create_with_guide(const SgScene *s, const SgRenderOptions *o, PathGuideCreate create,
                                          SgError *err)
{
    return renderer_create(s, o, create, err);
}

void sg_renderer_free(SgRenderer *r)
{
    if (!r)
        return;
    geometry_free(&r->geo);
    sg_thread_pool_free(r->pool);
    path_guide_free(r->guide);
    free(r->materials);
    texture_set_free(r->textures);
    light_set_free(&r->lights);
    pixel_noise_free(r->noise);
    free(r->sum);
    free(r->last);
    free(r);
}

/* ---- tracing -------------------------------------------------------------- */

static inline float power_heuristic(float a, float b)
{
    float a2 = a * a, b2 = b * b;
    return a2 + b2 > 0.0f ? a2 / (a2 + b2) : 0.0f;
}

typedef struct PathStats {
    uint64_t rays;
    uint64_t backface;
    uint64_t branches;     /* made by splitting, beyond the path itself */
    uint64_t bounces;      /* diffuse and glossy bounces drawn */
    uint64_t lobe_bounces; /* of which the guide drew the direction */
} PathStats;

/* What one camera path needs besides the renderer. */
typedef struct PathCtx {
    SgRng *rng;
    PathStats *st;
    int thread;
    bool first_pass;
    bool record;           /* the guide records this pass's paths (record_*) */
    int learn_tile;        /* >= 0: the path learns, its records go to this tile */
    float pixel_deviation; /* the pixel's noise for the learned roulette; 0: albedo roulette */
} PathCtx;

/* A learning vertex waiting for the rest of its branch. */
typedef struct PendingRecord {
    GuideVertex v;  /* as its bounce was drawn */
    Vec3 beta;      /* path throughput of the bounce (before the roulette, where it cut the path) */
    Vec3 radiance;  /* radiance gathered before the bounce */
    bool bounced;   /* a direction above the surface was drawn */
    bool cut;       /* the albedo roulette cut the path here */
} PendingRecord;

#define MAX_PENDING 32

/* Learned roulette (efficiency-aware, after Rath et al. 2022; its
 * splitting half is below, SPLIT_GAIN): from the third vertex on (as
 * albedo roulette), after its next-event estimate, a path's bounce
 * survives with probability
 *     q = min(1, ROULETTE_GAIN |beta| sqrt(M2(region)) / sigma(pixel)),
 * M2 the region's second moment of what a bounce brings back per unit
 * throughput (GuideVertex.rms, from a guide that learns it), sigma the
 * noise the pixel has anyway (render/pixel_noise.h).
 * Cutting adds variance |beta|^2 M2 (1/q - 1) and saves the rest of the
 * path's cost; this q balances the two against the pixel's variance per
 * cost (the ratio of a whole path's cost to its rest folded into
 * ROULETTE_GAIN: 2.8 against 2 and 1.4 measured corridor 5.3x / 4.8x / 4.7x
 * bsdf's efficiency, the Cornell box within noise of 0.97x at all three;
 * 0.7 made fireflies on Sponza). Paths heading into the dark die; paths
 * toward the light live on, where albedo roulette would cut them. Never
 * below ROULETTE_MIN_SURVIVAL, so that a region whose estimate is wrongly
 * low cannot make fireflies. */
#define ROULETTE_DEPTH 2
#define ROULETTE_GAIN 2.8f
#define ROULETTE_MIN_SURVIVAL 0.05f

/* Splitting, the other half of efficiency-aware roulette: where a
 * bounce's worth |beta| sqrt(M2) / sigma(pixel) (as for the learned
 * roulette) times SPLIT_GAIN exceeds 1, the bounce is drawn that many times
 * (randomly rounded), each branch weighted by the inverse of the unrounded
 * factor: the expected weight stays 1. It pays where a bounce's light is
 * most of the pixel's noise and the path to it was costly, at the first
 * vertices. SPLIT_GAIN is well below ROULETTE_GAIN: at 0.9 (equal-time
 * relMSE against bsdf, 1.5 s at 160x120, 4-8 seeds) the Cornell box went
 * from 0.93 to 0.98 and from 0.98 to 1.06 at 6 s, Sponza from 2.9 to 3.5,
 * the bathroom from 2.1 to 2.3, the corridor from 5.2 to 4.9 and the
 * staircase from 1.38 to 1.32; at 1.4 and 2.8 every scene lost (more
 * branches than their light was worth). Not before pass SPLIT_FROM_PASS:
 * on the corridor, splitting on the first passes' estimates (the pixels'
 * noise from a few samples, regions' M2 from their fallbacks) cost a fifth
 * of the efficiency at 0.45 s (3.8x bsdf against 4.6x without splitting,
 * 4.4x splitting from pass 16), where the Cornell box at 1.5 s lost 2%
 * (1.05x from the first pass, 1.03x from pass 16, 0.98x without). A path
 * splits into at most SPLIT_BRANCHES_MAX branches, SPLIT_MAX at one
 * vertex. */
#define SPLIT_GAIN 0.9f
#define SPLIT_FROM_PASS 16
#define SPLIT_MAX 4
#define SPLIT_BRANCHES_MAX 16
#define SPLIT_STACK 12

/* Russian roulette after a few bounces, on the product of albedos:
 * unbiased (the survivor is divided by its survival probability). */
static bool albedo_roulette(const PathGuide *g, Vec3 *beta, Vec3 *rr_beta, SgRng *rng, GuideSegment *seg)
{
    float q = sg_minf(0.95f, v3_max_component(*rr_beta));
    if (seg) /* a learned field learns what survivors carry */
        g->ops->record_survival(seg, q);
    if (!(sg_rng_float(rng) < q))
        return false;
    *beta = v3_scale(*beta, 1.0f / q);
    *rr_beta = v3_scale(*rr_beta, 1.0f / q);
    return true;
}

static Vec3 per_throughput(Vec3 c, Vec3 beta)
{
    return v3(beta.x > 0.0f ? c.x / beta.x : 0.0f, beta.y > 0.0f ? c.y / beta.y : 0.0f,
              beta.z > 0.0f ? c.z / beta.z : 0.0f);
}

/* The records of a finished branch, pending[from..to): what each bounce
 * brought back is the radiance gathered since it, `radiance` now. */
static void finish_records(PathGuide *g, const PendingRecord *pending, int from, int to, Vec3 radiance, int tile)
{
    for (int i = from; i < to; i++) {
        const PendingRecord *pr = &pending[i];
        float t = luminance(pr->beta);
        BounceOutcome o = {.radiance = luminance(per_throughput(v3_sub(radiance, pr->radiance), pr->beta)),
                           .weight = t * t, .bounced = pr->bounced, .cut = pr->cut};
        g->ops->learn(g, tile, &pr->v, &o);
    }
}

/* A path's state between vertices. */
typedef struct PathState {
    Vec3 o, d;
    Vec3 beta;
    /* What beta would be under BSDF sampling (the product of albedos):
     * Russian roulette follows it, not beta, so that a guided path is not
     * killed for carrying a small weight where its pdf was large. Any
     * survival probability is unbiased once divided out. */
    Vec3 rr_beta;
    bool specular_bounce;
    float prev_pdf;
    Vec3 prev_p;
} PathState;

/* A diffuse or glossy vertex, as far as drawing its bounce needs. */
typedef struct BounceVertex {
    const Material *m;
    GuideVertex g;     /* the guide's distribution there */
    Vec3 origin, p;
    GuideSegment *seg; /* recording: the vertex's record */
} BounceVertex;

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
    Vec3 wi = guide->ops->sample(&v->g, u, &pdf);
    st->bounces++;
    st->lobe_bounces += v->g.by_guide;
    float cos_x = v3_dot(wi, v->g.bsdf.lobe.n);
    bool above = cos_x > 0.0f && pdf > 0.0f;
    if (pr) {
        pr->v = v->g;
        pr->bounced = above;
    }
    if (!above)
        return false; /* below the surface: f = 0, the path ends */
    Vec3 f = bsdf_eval(&v->g.bsdf, wi);
    Vec3 weight = v3_scale(f, cos_x / pdf);
    ps->beta = v3_mul(ps->beta, weight);
    if (v->seg)
        guide->ops->record_bounce(v->seg, wi, pdf, weight, false, 1.0f, v->m->roughness);
    ps->d = wi;
    ps->o = v->origin;
    ps->prev_pdf = pdf;
    ps->prev_p = v->p;
    ps->specular_bounce = false;
    return true;
}

/* A textured material's albedo at a hit, its texture's value there. */
static Vec3 textured_albedo(const SgRenderer *r, const Material *m, const Hit *h, int thread)
{
    Vec3 c = texture_set_eval_at(r->textures, m->texture, h->tri, h->b1, h->b2, thread);
    Vec3 top = m->type == SG_MATERIAL_GLOSSY ? v3_sub(v3(1, 1, 1), m->ks) : v3(1, 1, 1); /* kd + ks <= 1 */
    return v3(sg_minf(sg_maxf(c.x, 0.0f), top.x), sg_minf(sg_maxf(c.y, 0.0f), top.y),
              sg_minf(sg_maxf(c.z, 0.0f), top.z));
}

/* The material's albedo at a hit: kd, or its texture's value there (the
 * untextured case inline: it is every vertex of most scenes). */
static inline Vec3 surface_albedo(const SgRenderer *r, const Material *m, const Hit *h, int thread)
{
    return m->texture ? textured_albedo(r, m, h, thread) : m->kd;
}

/* A mirror's, smooth conductor's or glass's bounce (a delta distribution:
 * no guide). */
static void specular_bounce(const SgRenderer *r, const Material *m, const Hit *h, Vec3 wo, Vec3 n, bool entering,
                            PathState *ps, SgRng *rng, GuideSegment *seg, int thread)
{
    Vec3 p = h->p;
    ps->specular_bounce = true;
    if (m->type == SG_MATERIAL_MIRROR || m->type == SG_MATERIAL_CONDUCTOR) {
        Vec3 tint = m->ks;
        if (m->type == SG_MATERIAL_CONDUCTOR) { /* its Fresnel at this angle */
            Vec3 eta, k;
            bsdf_conductor_index(m, surface_albedo(r, m, h, thread), &eta, &k);
            tint = sg_fresnel_conductor3(v3_dot(wo, n), eta, k);
        }
        ps->d = v3_normalize(sg_reflect(wo, n));
        ps->beta = v3_mul(ps->beta, tint);
        ps->rr_beta = v3_mul(ps->rr_beta, tint);
        ps->o = offset_origin(&r->geo, p, n);
        if (seg)
            r->guide->ops->record_bounce(seg, ps->d, 1.0f, tint, true, 1.0f, 0.0f);
        return;
    }
    float eta = entering ? 1.0f / m->ior : m->ior; /* eta_i / eta_t */
    float cos_i = v3_dot(wo, n);
    float sin2_t = eta * eta * fmaxf(0.0f, 1.0f - cos_i * cos_i);
    float fresnel = 1.0f, cos_t = 0.0f;
    if (sin2_t < 1.0f) {
        cos_t = sqrtf(1.0f - sin2_t);
        float rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
        float rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
        fresnel = 0.5f * (rs * rs + rp * rp);
    }
    Vec3 weight = v3(1, 1, 1);
    bool refracted = !(sg_rng_float(rng) < fresnel);
    if (!refracted) {
        ps->d = v3_normalize(sg_reflect(wo, n));
        ps->o = offset_origin(&r->geo, p, n);
    } else {
        ps->d = v3_normalize(v3_add(v3_scale(wo, -eta), v3_scale(n, eta * cos_i - cos_t)));
        ps->o = offset_origin(&r->geo, p, v3_scale(n, -1.0f));
        ps->beta = v3_scale(ps->beta, eta * eta); /* radiance is compressed entering glass */
        weight = v3(eta * eta, eta * eta, eta * eta);
    }
    if (seg)
        r->guide->ops->record_bounce(seg, ps->d, 1.0f, weight, true, refracted ? 1.0f / eta : 1.0f, 0.0f);
}

/* A rough dielectric's bounce: drawn from its BSDF alone, reflected or
 * transmitted (render/microfacet.h). Like smooth glass it samples no light
 * (a light is rarely reached through glass by a shadow ray) and asks no
 * guide, so the emission the bounce finds counts fully (specular_bounce:
 * no other strategy could have found it). False where the path ends. */
static bool rough_dielectric_bounce(const SgRenderer *r, const Material *m, const Hit *h, Vec3 wo, Vec3 n,
                                    bool entering, PathState *ps, SgRng *rng, GuideSegment *seg)
{
    float eta = entering ? m->ior : 1.0f / m->ior; /* beyond the surface over wo's side */
    Vec3 wo_l = sg_to_local(wo, n);
    wo_l.z = sg_maxf(wo_l.z, 1e-6f); /* wo faces n; keep it above at grazing angles */
    float uc = sg_rng_float(rng), u1 = sg_rng_float(rng), u2 = sg_rng_float(rng);
    Vec3 wi_l;
    float weight, pdf;
    if (!sg_ggx_dielectric_sample(wo_l, eta, m->ax, m->ay, uc, u1, u2, &wi_l, &weight, &pdf))
        return false;
    Vec3 wi = v3_normalize(sg_to_world(wi_l, n));
    bool refracted = wi_l.z < 0.0f;
    ps->d = wi;
    ps->o = offset_origin(&r->geo, h->p, refracted ? v3_scale(n, -1.0f) : n);
    ps->beta = v3_scale(ps->beta, weight);
    /* the roulette follows what is lost, not the compression of radiance */
    ps->rr_beta = v3_scale(ps->rr_beta, refracted ? weight * eta * eta : weight);
    ps->specular_bounce = true;
    if (seg)
        r->guide->ops->record_bounce(seg, wi, pdf, v3(weight, weight, weight), false, refracted ? eta : 1.0f,
                                     m->roughness);
    return true;
}

/* Next-event estimation at a diffuse or glossy vertex: one point on the
 * lights, its shadow ray, and what it brings (before the MIS weight). */
typedef struct LightSample {
    bool lit;         /* the sampled point is visible (whatever its cosine) */
    Vec3 c;           /* f cos Le / pdf, 0 where the point gives nothing */
    Vec3 wi;
    float pdf, cos_x; /* pdf 0: no contribution */
} LightSample;

static LightSample sample_light(const SgRenderer *r, const BounceVertex *v, bool lit_below_horizon, SgRng *rng,
                                PathStats *st)
{
    LightSample ls = {0};
    float ul = sg_rng_float(rng), ut = sg_rng_float(rng);
    float ua = sg_rng_float(rng), ub = sg_rng_float(rng);
    uint32_t t;
    Vec3 y;
    if (!light_set_sample(&r->lights, r->geo.vertices, r->geo.indices, ul, ut, ua, ub, &t, &y))
        return ls;
    Vec3 n = v->g.bsdf.lobe.n;
    Vec3 to = v3_sub(y, v->origin);
    float dist2 = v3_dot(to, to);
    float dist = sqrtf(dist2);
    Vec3 wi = v3_scale(to, 1.0f / dist);
    float cos_l = -v3_dot(wi, r->geo.tris[t].normal);
    float cos_x = v3_dot(wi, n);
    if (!(dist > 0.0f && cos_l > 0.0f && (cos_x > 0.0f || lit_below_horizon)))
        return ls;
    st->rays++;
    if (occluded(&r->geo, v->origin, wi, dist * (1.0f - 1e-4f)))
        return ls;
    ls.lit = true;
    if (cos_x > 0.0f) {
        const Material *lm = &r->materials[r->geo.tris[t].material];
        float pl = light_set_pdf(&r->lights, r->geo.tris[t].light, dist2, cos_l);
        Vec3 f = bsdf_eval(&v->g.bsdf, wi);
        ls.c = v3_scale(v3_mul(f, lm->emission), cos_x / pl);
        ls.wi = wi;
        ls.cos_x = cos_x;
        ls.pdf = pl;
    }
    return ls;
}

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

/* One camera path. Where it learns (pc->learn_tile >= 0) every diffuse or
 * glossy vertex the guide asks for becomes a record of what its bounce
 * brought back, known once its branch has ended. `seen` gets the emission
 * the camera ray itself hit. */
static Vec3 trace_path(SgRenderer *r, Vec3 o, Vec3 d, const PathCtx *pc, Vec3 *seen)
{
    PathGuide *guide = r->guide;
    const PathGuideOps *gops = guide->ops;
    SgRng *rng = pc->rng;
    PathStats *st = pc->st;
    PendingRecord pending[MAX_PENDING];
    int pending_count = 0;
    SplitPoint splits[SPLIT_STACK];
    int split_count = 0, branches = 1;
    Vec3 radiance = v3(0, 0, 0);
    PathState ps = {o, d, v3(1, 1, 1), v3(1, 1, 1), true /* the camera ray counts as one */, 0.0f, o};
    int depth = 0;
    bool alive = true;

    for (;;) {
        for (; alive; depth++) {
            bool roulette_done = false; /* a roulette has decided at this vertex */
            Hit h = intersect(&r->geo, ps.o, ps.d, INFINITY);
            st->rays++;
            if (!h.found)
                break;
            Vec3 ng = r->geo.tris[h.tri].normal;
            float cos_o = v3_dot(ps.d, ng);
            if (depth == 0 && pc->first_pass && cos_o > 0.0f)
                st->backface++;
            const Material *m = &r->materials[r->geo.tris[h.tri].material];
            Vec3 wo = v3_scale(ps.d, -1.0f);
            Vec3 n = cos_o < 0.0f ? ng : v3_scale(ng, -1.0f); /* facing wo */
            GuideSegment *seg = pc->record ? gops->record_vertex(guide, pc->thread, h.p, wo, n) : NULL;

            /* emission (one-sided, toward the winding normal) */
            if (m->emissive && cos_o < 0.0f) {
                float w = 1.0f;
                if (!ps.specular_bounce) {
                    Vec3 dp = v3_sub(h.p, ps.prev_p);
                    float pl = light_set_pdf(&r->lights, r->geo.tris[h.tri].light, v3_dot(dp, dp), -cos_o);
                    w = power_heuristic(ps.prev_pdf, pl);
                }
                radiance = v3_add(radiance, v3_scale(v3_mul(ps.beta, m->emission), w));
                if (seg)
                    gops->record_emission(seg, m->emission, w);
            }
            if (depth == 0)
                *seen = radiance; /* emission the camera sees directly */
            if (depth + 1 >= r->opt.max_depth)
                break;

            if (m->delta) {
                specular_bounce(r, m, &h, wo, n, cos_o < 0.0f, &ps, rng, seg, pc->thread);
            } else if (m->type == SG_MATERIAL_DIELECTRIC) {
                if (!rough_dielectric_bounce(r, m, &h, wo, n, cos_o < 0.0f, &ps, rng, seg))
                    break;
            } else {
                if (m->black)
                    break;
                /* field by field: zeroing the whole vertex (its BSDF's
                 * microfacet fields, unused by most) costs per bounce; the
                 * guide's state starts zeroed as guides expect */
                BounceVertex v;
                v.m = m;
                v.p = h.p;
                v.seg = seg;
                memset(v.g.state, 0, sizeof v.g.state);
                bsdf_init(&v.g.bsdf, m, n, wo, surface_albedo(r, m, &h, pc->thread));
                v.g.learn = false;
                v.g.rms = -1.0f;
                v.g.by_guide = false;
                /* n is the winding normal or its opposite: the other bin of the pair */
                GuideHit gh = {.p = h.p, .n = n, .m = m, .thread = pc->thread,
                               .normal_bin = r->geo.tris[h.tri].normal_bin ^ (cos_o < 0.0f ? 0u : 1u),
                               .may_learn = pc->learn_tile >= 0 && pending_count < MAX_PENDING};
                if (gops->vertex_begin)
                    gops->vertex_begin(guide, &gh, rng, &v.g);
                PendingRecord *pr = NULL;
                if (v.g.learn) {
                    pr = &pending[pending_count++];
                    /* before the roulette: the weight of a bounce it cuts; the
                     * rest is set when the bounce is drawn */
                    *pr = (PendingRecord){.beta = ps.beta};
                }
                v.origin = offset_origin(&r->geo, h.p, n);

                LightSample ls = sample_light(r, &v, gops->lit_below_horizon, rng, st);
                if (gops->vertex_end)
                    gops->vertex_end(guide, &gh, ls.lit, rng, &v.g);
                if (ls.pdf > 0.0f) {
                    float w = power_heuristic(ls.pdf, gops->pdf(&v.g, ls.wi, ls.cos_x));
                    Vec3 c = v3_scale(ls.c, w);
                    radiance = v3_add(radiance, v3_mul(ps.beta, c));
                    if (seg)
                        gops->record_direct(seg, c);
                }

                /* Roulette after next-event estimation and before the bounce is
                 * drawn: it decides on the bounce alone, and a path cut here
                 * keeps its direct light and pays for no direction, pdf or
                 * guide lobe it would not follow. */
                ps.rr_beta = v3_mul(ps.rr_beta, bsdf_albedo(&v.g.bsdf));
                if (pc->pixel_deviation > 0.0f && v.g.rms >= 0.0f) {
                    /* learned: by what the bounce brings back, against the pixel's noise */
                    float worth = luminance(ps.beta) * v.g.rms / pc->pixel_deviation;
                    float q = ROULETTE_GAIN * worth, split = SPLIT_GAIN * worth;
                    if (depth >= ROULETTE_DEPTH) {
                        roulette_done = true;
                        ps.rr_beta = v3(1, 1, 1);
                    }
                    if (depth >= ROULETTE_DEPTH && q < 1.0f) {
                        q = sg_maxf(q, ROULETTE_MIN_SURVIVAL);
                        if (!(sg_rng_float(rng) < q)) {
                            if (pr) /* what a surviving bounce brings is what the guide estimates */
                                pending_count--;
                            break;
                        }
                        ps.beta = v3_scale(ps.beta, 1.0f / q);
                    } else if (split > 1.0f && split_count < SPLIT_STACK && r->spp >= SPLIT_FROM_PASS) {
                        split = sg_minf(split, sg_minf((float)SPLIT_MAX, (float)(1 + SPLIT_BRANCHES_MAX - branches)));
                        int n_branches = (int)split + (sg_rng_float(rng) < split - floorf(split));
                        ps.beta = v3_scale(ps.beta, 1.0f / split);
                        if (n_branches > 1) { /* the others wait, from this vertex on */
                            splits[split_count++] = (SplitPoint){v, ps, depth, n_branches - 1,
                                                                 pr ? (int)(pr - pending) : pending_count,
                                                                 pr != NULL};
                            branches += n_branches - 1;
                        }
                    }
                } else if (depth >= ROULETTE_DEPTH) {
                    roulette_done = true;
                    if (!albedo_roulette(guide, &ps.beta, &ps.rr_beta, rng, seg)) {
                        if (pr) /* the guide hears of a bounce cut before it was drawn */
                            *pr = (PendingRecord){.v = v.g, .beta = pr->beta, .radiance = radiance, .cut = true};
                        break;
                    }
                }
                if (pr) { /* the bounce's throughput and what came before it */
                    pr->beta = ps.beta;
                    pr->radiance = radiance;
                }
                if (!take_bounce(guide, &v, &ps, rng, pr, st))
                    break;
            }

            /* after a specular bounce: the same roulette */
            if (depth >= ROULETTE_DEPTH && !roulette_done && !albedo_roulette(guide, &ps.beta, &ps.rr_beta, rng, seg))
                break;
            if (!(v3_max_component(ps.beta) > 0.0f))
                break;
        }
        if (!split_count)
            break;
        /* the branch has ended: what its vertices brought back is known;
         * the next branch of the deepest split starts from its bounce */
        SplitPoint *sp = &splits[split_count - 1];
        finish_records(guide, pending, sp->mark, pending_count, radiance, pc->learn_tile);
        pending_count = sp->mark;
        BounceVertex v = sp->v;
        ps = sp->ps;
        depth = sp->depth;
        PendingRecord *pr = NULL;
        if (sp->learn && pending_count < MAX_PENDING) {
            pr = &pending[pending_count++];
            *pr = (PendingRecord){.beta = ps.beta, .radiance = radiance};
        }
        if (--sp->remaining == 0)
            split_count--;
        alive = take_bounce(guide, &v, &ps, rng, pr, st) && v3_max_component(ps.beta) > 0.0f;
        depth++;
    }
    finish_records(guide, pending, 0, pending_count, radiance, pc->learn_tile);
    if (pc->record)
        gops->record_path_end(guide, pc->thread);
    st->branches += (uint64_t)(branches - 1);
    return radiance;
}

typedef struct PassCtx {
    SgRenderer *r;
    int tiles_x;
    uint64_t pass;        /* in the whole render (shards: render/renderer.h) */
    uint64_t pass_key;
    uint64_t jitter_key;  /* the seed's: the same for every pass */
    bool first_pass;
    GuidePass plan;       /* what the guide said of this pass */
} PassCtx;

static uint64_t mix64(uint64_t x)
{
    x ^= x >> 30;
    x *= 0xbf58476d1ce4e5b9ULL;
    x ^= x >> 27;
    x *= 0x94d049bb133111ebULL;
    x ^= x >> 31;
    return x;
}

/* Where in its pixel pass n's camera ray goes: the n-th point of the R2
 * sequence (Roberts 2018, the plastic number's powers) shifted by an
 * offset drawn per pixel and seed (a Cranley-Patterson rotation). Each pass
 * alone is a uniform jitter, so each pass stays an unbiased estimate; over
 * the passes a pixel's points cover it evenly, so an edge seen directly (a
 * light's silhouette, whose in-or-out noise is otherwise most of the image's
 * squared error) converges faster than with independent jitter. */
static void pixel_jitter(uint64_t key, size_t pix, uint64_t pass, float *jx, float *jy)
{
    uint64_t h = mix64(key ^ ((uint64_t)pix * 0x9e3779b97f4a7c15ULL));
    double x = (double)(h >> 40) * (1.0 / 16777216.0) + (double)pass * 0.75487766624669276;
    double y = (double)(h & 0xffffff) * (1.0 / 16777216.0) + (double)pass * 0.56984029099805327;
    *jx = (float)(x - floor(x));
    *jy = (float)(y - floor(y));
    if (!(*jx < 1.0f)) /* rounding to float */
        *jx = 0.0f;
    if (!(*jy < 1.0f))
        *jy = 0.0f;
}

static void render_tile(PassCtx *pc, uint64_t index, int thread)
{
    SgRenderer *r = pc->r;
    const int w = r->opt.width, hgt = r->opt.height;
    int tx = (int)(index % (uint64_t)pc->tiles_x), ty = (int)(index / (uint64_t)pc->tiles_x);
    PathStats st = {0};
    uint64_t nonfinite = 0;
    for (int y = ty * TILE; y < (ty + 1) * TILE && y < hgt; y++)
        for (int x = tx * TILE; x < (tx + 1) * TILE && x < w; x++) {
            size_t pix = (size_t)y * w + x;
            SgRng rng;
            sg_rng_seed(&rng, pc->pass_key, pix);
            float jx, jy;
            pixel_jitter(pc->jitter_key, pix, pc->pass, &jx, &jy);
            Vec3 dir = camera_ray(&r->camera, x, y, jx, jy);
            bool learns = r->guide->ops->path_learns && r->guide->ops->path_learns(r->guide, pix);
            PathCtx path = {.rng = &rng, .st = &st, .thread = thread, .first_pass = pc->first_pass,
                            .record = pc->plan.record, .learn_tile = learns ? (int)index : -1,
                            .pixel_deviation = r->noise ? pixel_noise_deviation(r->noise, pix) : 0.0f};
            Vec3 seen = v3(0, 0, 0);
            Vec3 L = trace_path(r, r->camera.pos, dir, &path, &seen);
            if (!isfinite(L.x) || !isfinite(L.y) || !isfinite(L.z)) {
                nonfinite++;
                L = v3(0, 0, 0);
                seen = L;
            }
            r->last[3 * pix] = L.x;
            r->last[3 * pix + 1] = L.y;
            r->last[3 * pix + 2] = L.z;
            r->sum[3 * pix] += L.x;
            r->sum[3 * pix + 1] += L.y;
            r->sum[3 * pix + 2] += L.z;
            if (r->noise)
                pixel_noise_add(r->noise, pix, luminance(v3_sub(L, seen)));
        }
    atomic_fetch_add(&r->rays, st.rays);
    if (st.backface)
        atomic_fetch_add(&r->backface_hits, st.backface);
    if (st.branches)
        atomic_fetch_add(&r->branches, st.branches);
    atomic_fetch_add(&r->bounces, st.bounces);
    if (st.lobe_bounces)
        atomic_fetch_add(&r->lobe_bounces, st.lobe_bounces);
    if (nonfinite)
        atomic_fetch_add(&r->nonfinite, nonfinite);
}

/* A pass's jobs: where the guide has a side job (the learner learning
 * from the pass before), job 0 (taken first, it runs beside the tiles),
 * then one job per tile. */
static void pass_job(void *vctx, uint64_t index, int thread)
{
    PassCtx *pc = vctx;
    if (pc->plan.side_job) {
        if (index == 0) {
            pc->r->guide->ops->side_job(pc->r->guide);
            return;
        }
        index--;
    }
    render_tile(pc, index, thread);
}

void sg_renderer_pass(SgRenderer *r)
{
    /* every pass at first, then at powers of two and every 16th: the
     * pixels' noise settles, and the passes wait for this */
    if (r->noise && r->spp > 1 && (r->spp < 8 || !(r->spp & (r->spp - 1)) || r->spp % 16 == 0))
        pixel_noise_estimate(r->noise, r->spp, r->pool);
    /* the whole render's pass this one is (this one, unsharded) */
    uint64_t pass = (uint64_t)r->opt.shard + (uint64_t)r->spp * (uint64_t)r->opt.shard_count;
    PassCtx pc = {.r = r,
                  .tiles_x = (r->opt.width + TILE - 1) / TILE,
                  .pass = pass,
                  .pass_key = mix64(r->opt.seed * 0x9e3779b97f4a7c15ULL + pass + 1),
                  .jitter_key = mix64(r->opt.seed ^ 0x6a09e667f3bcc909ULL),
                  .first_pass = r->spp == 0};
    const PathGuideOps *gops = r->guide->ops;
    if (gops->pass_begin)
        gops->pass_begin(r->guide, r->spp, pc.pass_key, &pc.plan);
    int tiles_y = (r->opt.height + TILE - 1) / TILE;
    sg_thread_pool_run(r->pool, (uint64_t)pc.tiles_x * tiles_y + pc.plan.side_job, pass_job, &pc);
    if (gops->pass_end)
        gops->pass_end(r->guide, r->spp);
    r->spp++;
}

int sg_renderer_spp(const SgRenderer *r) { return r->spp; }

void sg_renderer_image(const SgRenderer *r, float *rgb)
{
    size_t n = (size_t)r->opt.width * r->opt.height * 3;
    double inv = r->spp > 0 ? 1.0 / r->spp : 0.0;
    for (size_t i = 0; i < n; i++)
        rgb[i] = (float)(r->sum[i] * inv);
}

const float *sg_renderer_last_pass(const SgRenderer *r) { return r->last; }
uint64_t sg_renderer_nonfinite(const SgRenderer *r) { return atomic_load(&((SgRenderer *)r)->nonfinite); }
double sg_renderer_guided_fraction(const SgRenderer *r)
{
    GuideStats gs;
    path_guide_stats(r->guide, &gs);
    return gs.guided_fraction;
}

size_t sg_renderer_texture_cache(const SgRenderer *r, size_t *images)
{
    *images = 0;
    return r->textures ? texture_set_cache_bytes(r->textures, images) : 0;
}

uint64_t sg_renderer_rays(const SgRenderer *r) { return atomic_load(&((SgRenderer *)r)->rays); }

double sg_renderer_branches_per_path(const SgRenderer *r)
{
    double paths = (double)r->opt.width * r->opt.height * r->spp;
    return paths > 0.0 ? (double)atomic_load(&((SgRenderer *)r)->branches) / paths : 0.0;
}

int sg_renderer_training_passes(const SgRenderer *r)
{
    GuideStats gs;
    path_guide_stats(r->guide, &gs);
    return gs.training_passes;
}

double sg_renderer_training_seconds(const SgRenderer *r)
{
    GuideStats gs;
    path_guide_stats(r->guide, &gs);
    return gs.training_seconds;
}

double sg_renderer_lobe_share(const SgRenderer *r)
{
    uint64_t bounces = atomic_load(&((SgRenderer *)r)->bounces);
    return bounces ? (double)atomic_load(&((SgRenderer *)r)->lobe_bounces) / (double)bounces : 0.0;
}

double sg_renderer_backface_fraction(const SgRenderer *r)
{
    double n = (double)r->opt.width * r->opt.height;
    return r->spp > 0 ? (double)atomic_load(&((SgRenderer *)r)->backface_hits) / n : 0.0;
}
