/* guided: a one-sample mixture of the BSDF (probability alpha) and a
 * cosine-power lobe toward the skeleton's importance point (folded above
 * the surface), unbiased. With a fixed --alpha the mixture is the same
 * everywhere; by default it is learned per region of the scene while
 * rendering (render/mixture_learning.h): learning paths report what their
 * bounces brought back, the learner re-chooses between passes (beside the
 * next pass, as a side job), and its regional second moments feed the
 * learned roulette (GuideVertex.rms). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "mixture_learning.h"
#include "path_guide.h"
#include "importance_lookup.h"

typedef struct Mixture {
    PathGuide base;
    ImportanceLookup skeleton;
    SgMixtureCandidate fixed;        /* the options' alpha and exponent */
    bool alpha_learned;              /* the options ask for a learned alpha */
    SgMixtureLearner *learner;       /* NULL: a fixed alpha, or no light */
    const SgMixtureView *view;       /* the learner's, read at every bounce */
    bool roulette_learns;            /* the learned roulette reads what every vertex brought back */
    bool frozen;                     /* the learner learns no more: its view is what it holds */
    uint64_t pixels;
    /* this pass's learning paths: one in `stride`, by pixel and pass */
    uint64_t stride, below, pass_key;
} Mixture;

typedef struct MixtureVertex {
    ImportanceQuery query;
    SgFoldedLobe lobe; /* the lobe drawn from: the skeleton's or the learned axis's */
    const float *histogram; /* or the region's learned histogram (its cumulative distribution) */
    SgMixtureCandidate mix;
    uint32_t region;
    bool asked;    /* the guide was queried */
    bool mixture;  /* there is an axis: the bounce draws from the mixture */
    bool skeleton; /* the skeleton gave an axis (skeleton_axis) */
    Vec3 skeleton_axis;
    /* the vertex and the direction drawn, as the learner needs them */
    Vec3 position, direction;
    float pdf_bsdf, pdf;
} MixtureVertex;
_Static_assert(sizeof(MixtureVertex) <= GUIDE_VERTEX_STATE, "MixtureVertex fits GuideVertex.state");

static inline MixtureVertex *mixture_vertex(GuideVertex *v) { return (MixtureVertex *)v->state; }
static inline const MixtureVertex *mixture_vertex_c(const GuideVertex *v) { return (const MixtureVertex *)v->state; }

/* ---- which paths learn ---------------------------------------------------- */

/* All in the first passes, then a share that halves as the passes double
 * (1/2, 1/4, ... down to 1/64), chosen by pixel and pass so that every
 * pixel takes turns. Learning costs a cache query at every bounce; what it
 * learns matters most early. */
#define LEARN_WARMUP_PASSES 2
#define LEARN_STRIDE_MAX 64

/* At most this many learning paths per pass (~20 MB of records), whatever
 * the image size: a large image learns from a share of its pixels. */
#define LEARN_PATHS_MAX 16384
/* A training pass (render --field-out) is for learning alone: every path
 * learns, up to this many a pass (~80 MB of records in each of the two
 * buffers). On Sponza (320x240, 48 spp from the field) training with every
 * path rather than the render's share lowered relMSE 1.8x, the learned
 * axis another 1.8x (docs/render.md). */
#define LEARN_TRAINING_PATHS_MAX 131072

static void mixture_pass_begin(PathGuide *g, int pass, uint64_t pass_key, GuidePass *plan)
{
    Mixture *x = (Mixture *)g;
    uint64_t stride = 1, most = plan->training ? LEARN_TRAINING_PATHS_MAX : LEARN_PATHS_MAX;
    while (x->pixels / stride > most)
        stride *= 2;
    if (pass >= LEARN_WARMUP_PASSES && !plan->training)
        for (int p = 2; p <= pass && stride < LEARN_STRIDE_MAX; p *= 2)
            stride *= 2;
    x->stride = stride;
    x->below = UINT64_MAX / stride;
    x->pass_key = pass_key;
    plan->side_job = x->learner && !x->frozen;
}

/* Fibonacci hashing (the high bits of pixel times 2^64/golden ratio spread
 * consecutive pixels evenly), the pixels shifted by the pass: one in
 * `stride` (a power of two), a different set each pass, for an imul. */
static bool mixture_path_learns(const PathGuide *g, size_t pixel)
{
    const Mixture *x = (const Mixture *)g;
    return x->learner && !x->frozen &&
           (x->stride == 1 || ((uint64_t)pixel + x->pass_key) * 0x9e3779b97f4a7c15ULL < x->below);
}

/* Each pass's records are learned during the next (the side job) and used
 * from the one after: the update does not hold up the threads. */
static void mixture_side_job(PathGuide *g) { sg_mixture_learn(((Mixture *)g)->learner); }

static void mixture_pass_end(PathGuide *g, int pass)
{
    (void)pass;
    Mixture *x = (Mixture *)g;
    if (x->learner && !x->frozen)
        sg_mixture_end_pass(x->learner);
}

/* ---- a vertex ------------------------------------------------------------- */

static void mixture_vertex_begin(PathGuide *g, const GuideHit *h, SgRng *rng, GuideVertex *v)
{
    Mixture *x = (Mixture *)g;
    MixtureVertex *mv = mixture_vertex(v);
    mv->mix = x->fixed;
    mv->region = SG_NO_REGION;
    mv->mixture = false;
    mv->histogram = NULL;
    mv->skeleton = false;
    mv->position = h->p;
    mv->direction = v3(0, 0, 0);
    if (!x->learner) /* a fixed --alpha is the user's: no floor under it */
        v->alpha_floor = 0.0f;
    bool lobe_region = x->fixed.alpha < 1.0f;
    if (x->learner) {
        /* the region's learned alpha; where it is the BSDF alone the guide
         * is asked only by paths that learn */
        const SgMixtureView *view = x->view;
        mv->region = sg_mixture_region_at(view, h->p, h->normal_bin);
        uint8_t state = view->state[mv->region];
        mv->mix = view->of_state[state & SG_MIXTURE_STATE_CANDIDATE];
        lobe_region = state & SG_MIXTURE_STATE_LOBE;
        v->learn = h->may_learn && !(state & SG_MIXTURE_STATE_SETTLED);
        v->rms = sg_mixture_radiance(view, mv->region);
        v->portal_share = sg_mixture_portal_share(view, mv->region);
        if ((state & SG_MIXTURE_STATE_AXIS) && mv->mix.learned_histogram) { /* no cache query either */
            uint32_t e = view->histogram_of[mv->region];
            mv->mixture = e != SG_NO_REGION;
            mv->histogram = mv->mixture ? &view->histogram[(size_t)e * SG_MIXTURE_BINS] : NULL;
        } else if (state & SG_MIXTURE_STATE_AXIS) { /* the region's learned axis or point: no cache query */
            const float *a = &view->axis[3 * (size_t)mv->region];
            Vec3 axis = mv->mix.learned_point ? sg_mixture_point_axis(&view->point[4 * (size_t)mv->region], a, h->p)
                                              : v3(a[0], a[1], a[2]);
            mv->mixture = true;
            mv->lobe = sg_folded_lobe(axis, h->n, mv->mix.exponent);
        }
    }
    mv->asked = (lobe_region || v->learn) && importance_lookup_begin(&x->skeleton, h->p, h->n, rng, &mv->query);
}

static void mixture_vertex_end(PathGuide *g, const GuideHit *h, bool lit, SgRng *rng, GuideVertex *v)
{
    (void)lit, (void)rng;
    Mixture *x = (Mixture *)g;
    MixtureVertex *mv = mixture_vertex(v);
    Vec3 axis;
    if (mv->asked && importance_lookup_end(&x->skeleton, &mv->query, h->p, h->n, &axis)) {
        mv->skeleton = true;
        mv->skeleton_axis = axis;
        if (mv->mix.learned_axis)
            return; /* the skeleton's axis only for the learner */
        /* alpha 1 (a learning path): the BSDF, with the lobe's densities
         * at hand for the learner */
        mv->mixture = true;
        mv->lobe = sg_folded_lobe(axis, h->n, mv->mix.exponent);
    }
}

/* The region's BSDF share, or more where the path's weight asks for it. */
static inline float mixture_alpha(const GuideVertex *v, const MixtureVertex *mv)
{
    return sg_maxf(mv->mix.alpha, v->alpha_floor);
}

static float mixture_pdf(const GuideVertex *v, Vec3 w, float cos_n)
{
    const MixtureVertex *mv = mixture_vertex_c(v);
    if (!mv->mixture)
        return guide_bsdf_pdf(v, w, cos_n);
    float alpha = mixture_alpha(v, mv);
    if (mv->histogram)
        return alpha * bsdf_pdf(&v->bsdf, w) + (1.0f - alpha) * sg_mixture_histogram_pdf(mv->histogram, w);
    float pdf_bsdf, c1, c2;
    return bsdf_mixture_pdf(&v->bsdf, &mv->lobe, alpha, w, cos_n, &pdf_bsdf, &c1, &c2);
}

static Vec3 mixture_sample(GuideVertex *v, const float u[3], float *pdf)
{
    MixtureVertex *mv = mixture_vertex(v);
    if (!mv->mixture) {
        Vec3 w = guide_bsdf_sample(v, u, pdf);
        if (v->learn) { /* the learner's record: the BSDF drew it */
            mv->direction = w;
            mv->pdf_bsdf = mv->pdf = *pdf;
        }
        return w;
    }
    float alpha = mixture_alpha(v, mv);
    v->by_guide = !(u[0] < alpha);
    if (mv->histogram) {
        Vec3 w = v->by_guide ? sg_mixture_histogram_sample(mv->histogram, u[1], u[2])
                             : bsdf_sample(&v->bsdf, u[0] / alpha, u[1], u[2]);
        mv->pdf_bsdf = bsdf_pdf(&v->bsdf, w);
        mv->pdf = *pdf = alpha * mv->pdf_bsdf + (1.0f - alpha) * sg_mixture_histogram_pdf(mv->histogram, w);
        mv->direction = w;
        v->pdf_bsdf = mv->pdf_bsdf;
        return w;
    }
    Vec3 w = bsdf_mixture_sample(&v->bsdf, &mv->lobe, alpha, u[0], u[1], u[2]);
    /* with the BSDF's part the learner needs */
    float c1, c2;
    mv->pdf = *pdf = bsdf_mixture_pdf(&v->bsdf, &mv->lobe, alpha, w, v3_dot(w, v->bsdf.lobe.n), &mv->pdf_bsdf, &c1, &c2);
    mv->direction = w;
    v->pdf_bsdf = mv->pdf_bsdf;
    return w;
}

/* A learning vertex's record: what its bounce brought back (every bounce:
 * the learned roulette's second moments) and, where the mixture drew it,
 * how (the candidates' second moments). A bounce the albedo roulette cut
 * before the mixture could draw it counts, for the lobe, as one that
 * brought nothing back; elsewhere it is no sample of what survivors bring. */
static void mixture_learn(PathGuide *g, int tile, const GuideVertex *v, const BounceOutcome *o)
{
    Mixture *x = (Mixture *)g;
    const MixtureVertex *mv = mixture_vertex_c(v);
    /* every learning bounce: where the skeleton gave no axis its
     * candidates are the BSDF, and the learned axis needs them all */
    bool lobe = o->bounced || o->cut;
    if (!lobe && !x->roulette_learns && !v->sky.taken)
        return; /* only the learned roulette reads what left a vertex */
    SgMixtureRecord rec = {.region = mv->region, .radiance = o->cut ? -1.0f : o->radiance, .lobe = lobe,
                           .weight = o->weight};
    if (v->sky.taken) {
        rec.sky = true;
        rec.sky_contribution = v->sky.contribution;
        rec.sky_pdf_portals = v->sky.pdf_portals;
        rec.sky_pdf_sky = v->sky.pdf_sky;
        rec.sky_share = v->sky.share < 0.0f ? PORTAL_SHARE : v->sky.share;
    }
    if (lobe) {
        if (!o->cut) {
            Vec3 n = v->bsdf.lobe.n, d = mv->direction;
            rec.pdf_bsdf = mv->pdf_bsdf;
            rec.pdf = mv->pdf;
            rec.direction = d;
            rec.normal = n;
            rec.position = mv->position;
            rec.distance = o->distance;
            rec.no_skeleton = !mv->skeleton;
            if (mv->skeleton)
                sg_folded_cosines(mv->skeleton_axis, n, d, &rec.cos_axis, &rec.cos_mirror);
        }
        rec.estimate = o->radiance;
    }
    sg_mixture_record(x->learner, (uint32_t)tile, &rec);
}

static void mixture_stats(const PathGuide *g, GuideStats *s)
{
    const Mixture *x = (const Mixture *)g;
    s->guided_fraction = x->learner ? sg_mixture_guided_fraction(x->learner) : -1.0;
    s->learned_axis_fraction = x->learner ? sg_mixture_learned_axis_fraction(x->learner) : 0.0;
}

static void mixture_destroy(PathGuide *g)
{
    Mixture *x = (Mixture *)g;
    sg_mixture_learner_free(x->learner);
    importance_lookup_free(&x->skeleton);
    free(x);
}

/* A field file's part: the learner's view (none with a fixed alpha). */
static bool mixture_field_store(const PathGuide *g, FieldBytes *out)
{
    const Mixture *x = (const Mixture *)g;
    if (!x->learner)
        return true;
    size_t size = sg_mixture_view_size(x->learner);
    unsigned char *view = size ? malloc(size) : NULL;
    if (!view)
        return false;
    sg_mixture_view_save(x->learner, view);
    bool ok = field_bytes_put(out, view, size);
    free(view);
    return ok;
}

static bool mixture_field_load(PathGuide *g, FieldReader *in, SgError *err)
{
    Mixture *x = (Mixture *)g;
    x->frozen = true;
    size_t size = in->size - in->at;
    if (!x->learner)
        return size == 0 || sg_fail(err, "a learned mixture, for a render with a fixed alpha");
    if (!sg_mixture_view_restore(x->learner, in->data + in->at, size))
        return sg_fail(err, "its learned mixture is for another grid of regions");
    in->at = in->size;
    return true;
}

static void mixture_freeze(PathGuide *g) { ((Mixture *)g)->frozen = true; }

static void mixture_describe(const PathGuide *g, const GuideStats *s, SgRenderReport *report)
{
    const Mixture *x = (const Mixture *)g;
    if (x->alpha_learned && x->frozen)
        snprintf(report->alpha, sizeof report->alpha, "learned, frozen");
    else if (x->alpha_learned)
        snprintf(report->alpha, sizeof report->alpha, "learned (lobe in %.0f%% of bounces, %.0f%% around a learned axis)",
                 100.0 * fmax(0.0, s->guided_fraction), 100.0 * s->learned_axis_fraction);
    int n = snprintf(report->guide, sizeof report->guide, ", alpha %s, lobe drew %.1f%% of bounces", report->alpha,
                     100.0 * s->lobe_share);
    /* where a sky has portals: how its light samples were shared between them and its map */
    double use[SG_PORTAL_SHARES];
    if (x->learner && !x->frozen && sg_mixture_portal_share_use(x->learner, use) && n > 0 &&
        (size_t)n < sizeof report->guide) {
        n += snprintf(report->guide + n, sizeof report->guide - (size_t)n, ", lit sky samples' portal share");
        for (int k = 0; k < SG_PORTAL_SHARES && n > 0 && (size_t)n < sizeof report->guide; k++)
            n += snprintf(report->guide + n, sizeof report->guide - (size_t)n, "%s%g %.0f%%", k ? ", " : " ",
                          (double)sg_portal_shares[k], 100.0 * use[k]);
    }
}

static const PathGuideOps mixture_ops = {
    .name = "guided",
    .destroy = mixture_destroy,
    .pass_begin = mixture_pass_begin,
    .side_job = mixture_side_job,
    .pass_end = mixture_pass_end,
    .path_learns = mixture_path_learns,
    .vertex_begin = mixture_vertex_begin,
    .vertex_end = mixture_vertex_end,
    .pdf = mixture_pdf,
    .sample = mixture_sample,
    .learn = mixture_learn,
    .stats = mixture_stats,
    .describe = mixture_describe,
    .field_store = mixture_field_store,
    .field_load = mixture_field_load,
    .freeze = mixture_freeze,
};

/* The learner's grid covers the triangles' bounds (local coordinates):
 * 32 cells along the longest side, a few thousand regions in a room. */
#define LEARNER_CELLS 32

static PathGuide *mixture_create(const PathGuideSetup *setup, SgError *err)
{
    const SgRenderOptions *o = setup->opt;
    const char *path = setup->path;
    if (o->alpha != SG_ALPHA_LEARNED && !(o->alpha > 0.0f && o->alpha <= 1.0f))
        return sg_fail(err, "%s: the mixture weight alpha must be in (0, 1] to stay unbiased", path), NULL;
    Mixture *x = path_guide_alloc(sizeof *x, &mixture_ops, setup, err);
    if (!x)
        return NULL;
    x->fixed = (SgMixtureCandidate){o->alpha, o->lobe_exponent, false, false, false};
    x->alpha_learned = o->alpha == SG_ALPHA_LEARNED;
    x->roulette_learns = o->roulette == SG_ROULETTE_LEARNED;
    x->pixels = (uint64_t)o->width * (uint64_t)o->height;
    x->stride = 1;
    if (!importance_lookup_init(&x->skeleton, &o->importance, setup->geo->centre, setup->geo->scale, setup->lights, path,
                             err)) {
        mixture_destroy(&x->base);
        return NULL;
    }
    if (o->alpha == SG_ALPHA_LEARNED && setup->lights->follow_count) {
        Vec3 lo, hi;
        geometry_bounds(setup->geo, &lo, &hi);
        SgError e;
        x->learner = sg_mixture_learner_create(lo, hi, LEARNER_CELLS, setup->tiles, SG_MIXTURE_INITIAL, &e);
        if (!x->learner) {
            mixture_destroy(&x->base);
            return sg_fail(err, "%s: %s", path, e.message), NULL;
        }
        x->view = sg_mixture_view(x->learner);
        x->base.estimates_radiance = true;
    }
    return &x->base;
}

const PathGuideKind guide_guided_kind = {
    .mode = {.name = "guided",
             .help = "unbiased mixture of BSDF and a lobe toward the skeleton's\nimportance point (default with a cache)",
             .uses_cache = true,
             .default_with_cache = true,
             .lobe_exponent = 16.0f,
             .learns = true,
             .learned_roulette = true,
             /* the peer's training budget: as many samples a pixel
              * as Open PGL's (Cycles' schedule), so that the race
              * compares guides trained alike (on Sponza 128 passes left
              * guided 1.39x less efficient per sample, the bathroom
              * 1.15x: docs/render.md, "Training as long as the peer") */
             .training_passes = SG_OPENPGL_TRAINING_PASSES,
             .stops_learning_itself = true},
    .create = mixture_create,
};
