/* The renderer: the scene set up for tracing, and progressive passes over
 * the image in tiles shared out on a thread pool. What a pass does per
 * pixel lives beside it: where its sample goes (pixel_sampler.h), the path
 * (integrator.h), where the sample lands (film.h). */
#include "renderer.h"

#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "camera.h"
#include "field_file.h"
#include "film.h"
#include "geometry.h"
#include "guides/path_guide.h"
#include "hash.h"
#include "integrator.h"
#include "lights.h"
#include "openings.h"
#include "material.h"
#include "memory.h"
#include "pixel_noise.h"
#include "pixel_sampler.h"
#include "progress.h"
#include "roulette.h"
#include "edge_rays.h"
#include "textures.h"
#include "threads.h"
#include "vecmath.h"

#define TILE 16
/* Training passes draw random numbers of their own: the render that
 * follows them must not repeat the samples its guide learned from. */
#define TRAINING_SEED_SALT 0x5851f42d4c957f2dULL

struct SgRenderer {
    SgRenderOptions opt;
    Geometry geo;
    SgThreadPool *pool;   /* its workers live across the passes */

    uint32_t material_count;
    Material *materials;
    TextureSet *textures; /* NULL: no material is textured */

    LightSet lights;
    uint32_t openings; /* windows found for the sky (openings.h) */
    PathGuide *guide;     /* how bounces are drawn: one of path_guide.h's */
    Integrator integrator;
    /* Learned roulette: per pixel, the sums of the luminance of its samples
     * past the camera ray's own hit (emission seen directly is not what
     * roulette acts on) and of their squares; and the noise a path may add
     * there, made before each pass (NULL: the albedo roulette runs). */
    PixelNoise *noise;
    int noise_spp;        /* the passes in its sums (training's included) */
    EdgeRays *seen;      /* extra camera rays where the light seen directly varies (NULL: none) */
    bool surveyed;        /* seen's survey is done (before the first pass) */
    int seen_passes;      /* the passes in seen's sums (training's included) */
    int tiles_x, tiles_y;
    uint64_t scene_hash;  /* what a field learns from: the scene's geometry and lights (not its camera) */
    uint64_t view_hash;   /* the camera and the image size: what the pixels' noise in a field is for */
    int training_passes;  /* a learned mode's training */
    bool training;        /* the passes now are training's */
    /* learning within the render (no field read, no training apart): the
     * guide learns from the first pass, the film keeps its passes in groups
     * that end at each checkpoint (learning_checkpoint), and learning stops
     * at the mode's training passes or, for a mode that judges it itself,
     * when it stops paying (learning_pays) */
    bool learning;
    bool judges_learning; /* the mode's stops_learning_itself */
    int budget_passes;    /* the render's passes in all (0: not known) */
    double budget_seconds;/* its seconds in all (0: not known) */
    double seconds;       /* the passes' time so far */
    int learned_passes;   /* the passes whose paths the guide learned from, when it stopped */

    Camera camera;

    int spp;
    Film film;
    _Atomic uint64_t nonfinite;
    _Atomic uint64_t rays;
    _Atomic uint64_t backface_hits;
    _Atomic uint64_t branches;
    _Atomic uint64_t bounces, lobe_bounces;
    _Atomic uint64_t views;                /* extra camera rays (in rays too) */
    uint64_t path_rays, path_samples;     /* all passes', training's too: a sample's cost in rays */
};

void sg_render_options_default(SgRenderOptions *o, const SgScene *scene)
{
    memset(o, 0, sizeof *o);
    o->width = scene && scene->has_camera && scene->camera.width > 0 ? scene->camera.width : 320;
    o->height = scene && scene->has_camera && scene->camera.height > 0 ? scene->camera.height : 240;
    o->max_depth = scene && scene->render.max_depth > 0 ? scene->render.max_depth : SG_MAX_DEPTH_DEFAULT;
    o->sampling = SG_SAMPLING_BSDF;
    o->lobe_exponent = 16.0f;
    o->alpha = SG_ALPHA_LEARNED;
    o->roulette = SG_ROULETTE_LEARNED;
    o->shard_count = 1;
    o->edge_rays = EDGE_RAYS_MAX;
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

/* A sky without a portal of its own gets the openings the precompute
 * found (r->opt.importance.cache) as its portals. */
static bool attach_openings(SgRenderer *r, const SgScene *s, const char *path, SgError *err)
{
    Vec3(*corners)[4];
    uint32_t n;
    if (!openings_find(r->opt.importance.cache, s->bounds_min, s->bounds_max, r->geo.centre, &corners, &n))
        return sg_fail(err, "%s: out of memory for the openings", path);
    bool ok = true;
    for (uint32_t i = 0; ok && i < r->lights.source_count; i++)
        if (r->lights.sources[i].kind == SG_LIGHT_INFINITE && !r->lights.sources[i].portal_count && n)
            ok = light_source_set_portals(&r->lights, i, (const Vec3(*)[4])corners, n);
    r->openings = n;
    free(corners);
    return ok || sg_fail(err, "%s: out of memory for the openings", path);
}

/* Whether scene s can be rendered with options o, and the machine can
 * hold the render (false, naming the scene, where not). */
static bool renderable(const SgScene *s, const SgRenderOptions *o, const char *path, SgError *err)
{
    if (!s->triangle_count || !s->positions || !s->indices)
        return sg_fail(err, "%s: no triangles to render", path);
    if (!s->has_camera)
        return sg_fail(err, "%s: no camera", path);
    if (o->width <= 0 || o->height <= 0 || o->width > 65536 || o->height > 65536)
        return sg_fail(err, "%s: bad image size %dx%d", path, o->width, o->height);
    if (o->max_depth < 1)
        return sg_fail(err, "%s: max depth must be at least 1", path);
    if (!(o->lobe_exponent >= 0.0f && o->lobe_exponent <= 1e5f))
        return sg_fail(err, "%s: lobe exponent must be in [0, 1e5]", path);
    if (!sg_shard_valid(o->shard, o->shard_count))
        return sg_fail(err, "%s: shard %d of %d: want 0 <= shard < count <= %d", path, o->shard, o->shard_count,
                       SG_SHARDS_MAX);
    if (o->roulette != SG_ROULETTE_LEARNED && o->roulette != SG_ROULETTE_ALBEDO)
        return sg_fail(err, "%s: unknown roulette %d", path, (int)o->roulette);
    if (o->edge_rays < 0 || o->edge_rays > EDGE_RAYS_MAX)
        return sg_fail(err, "%s: edge rays must be in [0, %d]", path, EDGE_RAYS_MAX);

    /* sum (double) + last pass + the caller's image (float) per pixel, and
     * the renderer's and Embree's copies of the triangles (~150 bytes each):
     * refuse up front what the machine cannot hold rather than be killed */
    char what[96];
    snprintf(what, sizeof what, "a %dx%d image", o->width, o->height);
    /* + the square of each sample's luminance (8 bytes), and while a guide
     * learns within the render, ~10 groups of its passes at 16 bytes each */
    bool learns_here = sg_sampling_mode(o->sampling) && sg_sampling_mode(o->sampling)->learns;
    double per_pixel = 56.0 + (o->edge_rays ? 44.0 : 0.0) + (learns_here ? 160.0 : 0.0);
    return sg_memory_check(per_pixel * o->width * o->height + 150.0 * s->triangle_count, path, what, err);
}

/* The materials, the lights and (a sky without a portal) the openings. */
static bool shading_init(SgRenderer *r, const SgScene *s, const char *path, SgError *err)
{
    r->material_count = s->material_count;
    r->materials = calloc(s->material_count, sizeof *r->materials);
    if (!r->materials)
        return sg_fail(err, "%s: out of memory", path);
    for (uint32_t m = 0; m < s->material_count; m++)
        material_init(&r->materials[m], &s->materials[m]);
    if (!light_set_init(&r->lights, s, r->geo.vertices, r->materials, r->opt.importance.light_weight, r->geo.centre,
                        path, err))
        return false;
    if (r->opt.importance.cache && !r->opt.no_openings && r->lights.has_escaping && !attach_openings(r, s, path, err))
        return false;
    if (!(light_set_power(&r->lights) > 0.0))
        return sg_fail(err, "%s: no light the renderer can use (no emissive surface of non-zero area, "
                            "no LightSource or \"lights\" entry that sends light)", path);
    return true;
}

/* The view a field's pixel noise is for: the camera and the image size. */
static uint64_t view_identity(const SgCamera *c, int width, int height)
{
    uint64_t h = SG_HASH_INIT;
    h = sg_hash_bytes(h, c->position, sizeof c->position);
    h = sg_hash_bytes(h, c->look_at, sizeof c->look_at);
    h = sg_hash_bytes(h, c->up, sizeof c->up);
    h = sg_hash_bytes(h, &c->fov_deg, sizeof c->fov_deg);
    h = sg_hash_bytes(h, &width, sizeof width);
    return sg_hash_bytes(h, &height, sizeof height);
}

/* `create`: the guide's constructor, NULL: the one o->sampling names. */
static SgRenderer *renderer_create(const SgScene *s, const SgRenderOptions *o, PathGuideCreate create, SgError *err)
{
    const char *path = s->path[0] ? s->path : "scene";
    if (!renderable(s, o, path, err))
        return NULL;
    SgRenderer *r = calloc(1, sizeof *r);
    if (!r)
        return sg_fail(err, "%s: out of memory", path), NULL;
    r->opt = *o;
    /* a field serves any view of the scene: a guide learned elsewhere, or
     * for other materials, leaves the image unbiased, only less helped */
    r->scene_hash = s->geometry_hash;
    r->view_hash = view_identity(&s->camera, o->width, o->height);
    const SgSamplingMode *mode = sg_sampling_mode(o->sampling);
    r->training_passes = o->training_passes > 0 ? o->training_passes : mode ? mode->training_passes : 0;
    r->learning = mode && mode->learns;
    r->judges_learning = mode && mode->stops_learning_itself && o->training_passes <= 0;
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
    if (!film_init(&r->film, o->width, o->height) ||
        (o->edge_rays && !(r->seen = edge_rays_create(o->width, o->height, o->edge_rays)))) {
        sg_renderer_free(r);
        return sg_fail(err, "%s: out of memory", path), NULL;
    }
    if (!shading_init(r, s, path, err)) {
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
    PathGuideSetup gs = {.opt = &r->opt, .training_passes = r->training_passes, .geo = &r->geo, .lights = &r->lights,
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
    r->integrator = (Integrator){.geo = &r->geo, .materials = r->materials, .textures = r->textures,
                                 .lights = &r->lights, .guide = r->guide, .max_depth = o->max_depth};

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
    edge_rays_free(r->seen);
    film_free(&r->film);
    free(r);
}

typedef struct PassCtx {
    SgRenderer *r;
    int tiles_x;
    PixelSampler sampler; /* the pass in the whole render (shards: render/renderer.h) */
    bool first_pass;
    GuidePass plan;       /* what the guide said of this pass */
    double sample_rays;   /* a sample's cost in rays, from the passes before */
} PassCtx;

static void render_tile(PassCtx *pc, uint64_t index, int thread)
{
    SgRenderer *r = pc->r;
    const int w = r->opt.width, hgt = r->opt.height;
    int tx = (int)(index % (uint64_t)pc->tiles_x), ty = (int)(index / (uint64_t)pc->tiles_x);
    const PathGuideOps *gops = r->guide->ops;
    PathStats st = {0};
    uint64_t nonfinite = 0;
    for (int y = ty * TILE; y < (ty + 1) * TILE && y < hgt; y++)
        for (int x = tx * TILE; x < (tx + 1) * TILE && x < w; x++) {
            size_t pix = (size_t)y * w + x;
            SgRng rng;
            float jx, jy;
            pixel_sampler_start(&pc->sampler, pix, &rng, &jx, &jy);
            Vec3 dir = camera_ray(&r->camera, x, y, jx, jy);
            bool learns = gops->path_learns && gops->path_learns(r->guide, pix);
            PathCtx path = {.rng = &rng, .st = &st, .thread = thread, .first_pass = pc->first_pass,
                            .record = pc->plan.record, .may_split = r->noise_spp >= SPLIT_FROM_PASS,
                            .learn_tile = learns ? (int)index : -1,
                            .pixel_deviation = r->noise ? pixel_noise_deviation(r->noise, pix) : 0.0f};
            Vec3 seen = v3(0, 0, 0);
            Vec3 L = integrator_trace(&r->integrator, r->camera.pos, dir, &path, &seen);
            /* what the roulette acts on: the light past the camera ray's own hit, not the edge rays' views */
            Vec3 rest = v3_sub(L, seen);
            if (r->seen)
                L = edge_rays_sample(r->seen, &r->integrator, &r->camera, &pc->sampler, pc->sample_rays, x, y, L,
                                     seen, thread, &st);
            if (!film_add(&r->film, pix, &L)) {
                nonfinite++;
                rest = v3(0, 0, 0);
            }
            if (r->noise)
                pixel_noise_add(r->noise, pix, luminance(rest));
        }
    atomic_fetch_add(&r->rays, st.rays);
    if (st.backface)
        atomic_fetch_add(&r->backface_hits, st.backface);
    if (st.branches)
        atomic_fetch_add(&r->branches, st.branches);
    atomic_fetch_add(&r->bounces, st.bounces);
    if (st.lobe_bounces)
        atomic_fetch_add(&r->lobe_bounces, st.lobe_bounces);
    if (st.views)
        atomic_fetch_add(&r->views, st.views);
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

/* Before the first pass the survey looks for the light seen directly, so
 * that its silhouettes are known from the first pass on (edge_rays.h). */
static void survey_views(SgRenderer *r)
{
    uint64_t rays = edge_rays_survey(r->seen, &r->integrator, &r->camera, r->opt.seed, r->pool);
    atomic_fetch_add(&r->rays, rays);
    atomic_fetch_add(&r->views, rays);
    r->surveyed = true;
}

/* ---- learning within the render ------------------------------------------ */

/* Guided judges its learning within a render at its checkpoints from the
 * 32nd pass on: before, the groups' variances are read against an image of
 * too few passes, which favours the older groups (on the corridor at 8
 * passes the newest group looked 9 % less efficient than the one before;
 * against the image of 256 passes it was 3 % more). */
#define LEARNING_JUDGED_FROM 32
/* A learning pass costs this much more than a frozen one beyond its rays:
 * every path's records and the learner's update (the corridor: 507
 * training passes in 77.9 s, 64 frozen in 7.2 s, 0.154 s against 0.113 s). */
#define LEARNING_PASS_OVERHEAD 0.4

/* Whether a further stretch of learning, as long as all of it so far (the
 * checkpoints double), pays within the budget. Its L passes cost
 * LEARNING_PASS_OVERHEAD L passes more than frozen ones would; if it makes
 * the passes after it `gain` times as efficient, as the last stretch made
 * them over the one before (variance times rays per pass), the R passes
 * left gain about (gain - 1)(R - L/2) passes' worth. So it pays while
 * (gain - 1)(R - L/2) > LEARNING_PASS_OVERHEAD L. */
static bool learning_pays(SgRenderer *r)
{
    int learned = r->spp;
    double remaining = INFINITY;
    if (r->budget_passes > 0)
        remaining = r->budget_passes - learned;
    if (r->budget_seconds > 0.0) /* at the pace of the passes so far */
        remaining = fmin(remaining, (r->budget_seconds - r->seconds) / (r->seconds / learned));
    if (!(remaining >= 2.0 * learned)) /* no room for the stretch and as many passes after it to use it */
        return false;
    if (learned < LEARNING_JUDGED_FROM)
        return true;
    double variance[FILM_GROUPS_MAX + 1], cost[FILM_GROUPS_MAX + 1];
    int n = film_group_variances(&r->film, variance, cost);
    if (n < 2)
        return true;
    double before = variance[n - 2] * cost[n - 2], now = variance[n - 1] * cost[n - 1];
    double gain = now > 0.0 ? before / now : (before > 0.0 ? INFINITY : 1.0);
    return (gain - 1.0) * (remaining - 0.5 * learned) > LEARNING_PASS_OVERHEAD * learned;
}

/* After a pass of a render that learns: the film's groups end where the
 * learner's checkpoints are (passes 1, 2, 4, 8, ...) and where its learning
 * stops; a mode that judges its learning stops there when a further stretch
 * would not pay. */
static void learning_checkpoint(SgRenderer *r)
{
    int spp = r->spp;
    bool checkpoint = !(spp & (spp - 1));
    bool last = spp >= r->training_passes;
    if (!checkpoint && !last)
        return;
    film_close_group(&r->film);
    if (last || (r->judges_learning && !learning_pays(r)))
        sg_renderer_stop_learning(r);
}

void sg_renderer_set_budget(SgRenderer *r, int passes, double seconds)
{
    r->budget_passes = passes > 0 ? passes : 0;
    r->budget_seconds = seconds > 0.0 ? seconds : 0.0;
}

bool sg_renderer_learning(const SgRenderer *r) { return r->learning && !r->training; }

void sg_renderer_stop_learning(SgRenderer *r)
{
    if (!r->learning || r->training)
        return;
    film_close_group(&r->film);
    if (r->guide->ops->freeze)
        r->guide->ops->freeze(r->guide);
    r->learning = false;
    r->learned_passes = r->spp;
}

int sg_renderer_learned_passes(const SgRenderer *r) { return r->learned_passes; }

void sg_renderer_pass(SgRenderer *r)
{
    if (r->seen && !r->surveyed)
        survey_views(r);
    if (r->seen && (r->seen_passes < 8 || !(r->seen_passes & (r->seen_passes - 1)) || r->seen_passes % 16 == 0))
        edge_rays_estimate(r->seen, r->seen_passes);
    roulette_prepare_pass(r->noise, r->noise_spp, r->pool);
    /* the whole render's pass this one is (this one, unsharded) */
    uint64_t pass = sg_shard_pass(r->opt.shard, r->opt.shard_count, (uint64_t)r->spp);
    PassCtx pc = {.r = r, .tiles_x = r->tiles_x, .first_pass = r->spp == 0,
                  .sample_rays = r->path_samples ? (double)r->path_rays / (double)r->path_samples : 1.0};
    uint64_t rays_before = atomic_load(&r->rays), views_before = atomic_load(&r->views);
    double t0 = sg_seconds();
    pixel_sampler_init(&pc.sampler, r->training ? r->opt.seed ^ TRAINING_SEED_SALT : r->opt.seed, pass);
    const PathGuideOps *gops = r->guide->ops;
    /* every path learns while the guide learns: apart (training) or within
     * the render (its passes kept in the image, so none is wasted) */
    pc.plan.training = r->training || r->learning;
    if (gops->pass_begin)
        gops->pass_begin(r->guide, r->spp, pc.sampler.pass_key, &pc.plan);
    sg_thread_pool_run(r->pool, (uint64_t)r->tiles_x * r->tiles_y + pc.plan.side_job, pass_job, &pc);
    if (gops->pass_end)
        gops->pass_end(r->guide, r->spp);
    r->path_rays += (atomic_load(&r->rays) - rays_before) - (atomic_load(&r->views) - views_before);
    r->path_samples += (uint64_t)r->opt.width * r->opt.height;
    r->seen_passes++;
    r->spp++;
    if (r->noise)
        r->noise_spp++;
    r->seconds += sg_seconds() - t0;
    /* a pass's cost in rays, not seconds: a decision taken on it is the same
     * whatever the machine's load or thread count */
    film_end_pass(&r->film, (double)(atomic_load(&r->rays) - rays_before));
    if (r->learning && !r->training)
        learning_checkpoint(r);
}

int sg_renderer_spp(const SgRenderer *r) { return r->spp; }

void sg_renderer_image(const SgRenderer *r, float *rgb) { film_image(&r->film, rgb); }

const float *sg_renderer_last_pass(const SgRenderer *r) { return r->film.last; }

/* per sample of the passes so far (0 before any) */
static double per_sample(const SgRenderer *r, uint64_t count)
{
    double samples = (double)r->opt.width * r->opt.height * r->spp;
    return samples > 0.0 ? (double)count / samples : 0.0;
}

void sg_renderer_stats(const SgRenderer *r, SgRenderStats *stats)
{
    SgRenderer *m = (SgRenderer *)r; /* the counters are atomics */
    GuideStats gs;
    path_guide_stats(r->guide, &gs);
    memset(stats, 0, sizeof *stats);
    stats->spp = r->spp;
    stats->rays = atomic_load(&m->rays);
    stats->nonfinite = atomic_load(&m->nonfinite);
    double pixels = (double)r->opt.width * r->opt.height;
    stats->backface_fraction = r->spp > 0 ? (double)atomic_load(&m->backface_hits) / pixels : 0.0;
    stats->guided_fraction = gs.guided_fraction;
    uint64_t bounces = atomic_load(&m->bounces);
    stats->lobe_share = bounces ? (double)atomic_load(&m->lobe_bounces) / (double)bounces : 0.0;
    stats->training_passes = gs.training_passes;
    stats->training_updates = gs.training_updates;
    stats->training_seconds = gs.training_seconds;
    stats->branches_per_path = per_sample(r, atomic_load(&m->branches));
    stats->edge_rays_per_sample = per_sample(r, atomic_load(&m->views));
    if (r->textures)
        stats->texture_cache_bytes = texture_set_cache_bytes(r->textures, &stats->texture_image_bytes);
}

void sg_renderer_report(const SgRenderer *r, SgRenderReport *report)
{
    GuideStats gs;
    path_guide_stats(r->guide, &gs);
    SgRenderStats stats;
    sg_renderer_stats(r, &stats);
    gs.lobe_share = stats.lobe_share;
    report->roulette = r->noise ? SG_ROULETTE_LEARNED : SG_ROULETTE_ALBEDO;
    snprintf(report->alpha, sizeof report->alpha, "%g", r->opt.alpha);
    report->guide[0] = '\0';
    report->openings = r->openings;
    if (r->guide->ops->describe)
        r->guide->ops->describe(r->guide, &gs, report);
}

/* ---- a learned mode's training and field files ------------------------------ */

int sg_renderer_train_begin(SgRenderer *r, SgError *err)
{
    if (!r->guide->ops->freeze)
        return sg_fail(err, "--sampling %s learns nothing: it has no field to train", sg_sampling_name(r->opt.sampling)),
               -1;
    r->training = true;
    return r->training_passes;
}

void sg_renderer_train_end(SgRenderer *r) { r->training = false; }

bool sg_renderer_train(SgRenderer *r, SgError *err)
{
    int passes = sg_renderer_train_begin(r, err);
    for (int p = 0; p < passes; p++)
        sg_renderer_pass(r);
    sg_renderer_train_end(r);
    return passes >= 0;
}

void sg_renderer_freeze(SgRenderer *r)
{
    if (r->guide->ops->freeze)
        r->guide->ops->freeze(r->guide);
    r->learning = false;
    film_clear(&r->film);
    r->spp = 0;
    atomic_store(&r->nonfinite, 0);
    atomic_store(&r->rays, 0);
    atomic_store(&r->backface_hits, 0);
    atomic_store(&r->branches, 0);
    atomic_store(&r->bounces, 0);
    atomic_store(&r->lobe_bounces, 0);
    atomic_store(&r->views, 0);
    /* the edge rays start afresh, as in a render from the field's file */
    if (r->seen)
        edge_rays_clear(r->seen);
    r->surveyed = false;
    r->seen_passes = 0;
    r->path_rays = r->path_samples = 0;
    /* the roulette starts from all it knows of the pixels */
    if (r->noise && r->noise_spp > 1)
        pixel_noise_estimate(r->noise, r->noise_spp, r->pool);
}

void sg_render_options_summary(const SgRenderOptions *o, char *buf, size_t size)
{
    char alpha[32];
    if (o->alpha == SG_ALPHA_LEARNED)
        snprintf(alpha, sizeof alpha, "learned");
    else
        snprintf(alpha, sizeof alpha, "%.9g", o->alpha);
    /* openpgl: the mode draws the paths the field learns from; no openings:
     * the sky's light samples shape what a learner sees */
    bool pgl = o->sampling == SG_SAMPLING_OPENPGL;
    snprintf(buf, size, "max depth %d, exponent %.9g, alpha %s, roulette %s%s%s%s",
             o->max_depth, o->lobe_exponent, alpha, sg_roulette_name(o->roulette), pgl ? ", openpgl " : "",
             pgl ? sg_openpgl_mode_name(o->openpgl_mode) : "", o->no_openings ? ", no openings" : "");
}

/* What a field is for: the mode, the scene, the cache, and the options
 * that shape what is learned (not the seed, the shard or the passes). */
static void field_identity(const SgRenderer *r, FieldIdentity *id)
{
    const SgRenderOptions *o = &r->opt;
    memset(id, 0, sizeof *id);
    snprintf(id->mode, sizeof id->mode, "%s", sg_sampling_name(o->sampling));
    id->scene_hash = r->scene_hash;
    id->cache_hash = o->importance.cache ? sg_cache_checksum(o->importance.cache) : 0;
    sg_render_options_summary(o, id->recipe, sizeof id->recipe);
}

bool sg_renderer_write_field(const SgRenderer *r, const char *path, SgError *err)
{
    if (!r->guide->ops->field_store)
        return sg_fail(err, "%s: --sampling %s learns nothing: it has no field to store", path,
                       sg_sampling_name(r->opt.sampling));
    FieldIdentity id;
    field_identity(r, &id);
    id.training_spp = (uint32_t)r->training_passes;
    return field_file_save(path, &id, r->guide, r->noise, r->noise_spp, r->view_hash, err);
}

bool sg_renderer_read_field(SgRenderer *r, const char *path, SgError *err)
{
    if (!r->guide->ops->field_load)
        return sg_fail(err, "%s: --sampling %s learns nothing: it takes no field", path,
                       sg_sampling_name(r->opt.sampling));
    if (r->spp || r->noise_spp)
        return sg_fail(err, "%s: a field is read before the first pass", path);
    FieldIdentity want;
    field_identity(r, &want);
    if (!field_file_load(path, &want, r->guide, r->noise, &r->noise_spp, r->view_hash, err))
        return false;
    if (r->noise && r->noise_spp > 1)
        pixel_noise_estimate(r->noise, r->noise_spp, r->pool);
    r->learning = false;
    return true;
}
