/* openpgl: the peer, Open PGL's learned guiding integrated as Cycles does
 * (render/guides/openpgl_field.h wraps the library): one field for the scene,
 * trained during its training passes (SG_OPENPGL_TRAINING_PASSES unless the
 * options say) on Cycles' schedule: 128 updates, each from the paths of up
 * to 4 passes (openpgl_passes_per_update), then frozen (or frozen as a field
 * file gives it). At a
 * diffuse or glossy vertex the field's distribution there (cosine product
 * applied) and the BSDF share the bounce as Cycles' two modes do
 * (--openpgl-mode):
 *   ris  (Cycles' default) one candidate from the BSDF, one from the
 *        guide, one kept in proportion to its estimated contribution,
 *        f cos ((1 - P) / 2pi + P p_Li) over the candidates' mean density
 *        (P Cycles' surface guiding probability, p_Li the incoming
 *        radiance's density); MIS against the lights by that mean density;
 *        every vertex whose lobes' roughness reaches Cycles' threshold
 *   mis  Cycles' older mode: a one-sample mixture, the guide's share P
 *        times the BSDF's diffuse share (glossy lobes are never guided).
 * Where Open PGL keeps radiance caches and --roulette learned, Open PGL's
 * guided (adjoint-driven) roulette decides the paths' survival. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "openpgl_field.h"
#include "path_guide.h"
#include "progress.h"

/* Cycles' default surface guiding probability: the guide's share of a
 * diffuse bounce (mis), the guide's weight in RIS's target (ris). */
#define OPENPGL_GUIDING_PROBABILITY 0.5f
/* Cycles' guiding roughness threshold (0.05, squared as Cycles squares the
 * user's value): a vertex whose lobes' mean GGX alpha is below it is not
 * guided in RIS. */
#define OPENPGL_ROUGHNESS_THRESHOLD (0.05f * 0.05f)
/* The guided roulette's floor: a region whose cache is wrongly dark cannot
 * make fireflies (render/roulette.h's ROULETTE_MIN_SURVIVAL). */
#define OPENPGL_MIN_SURVIVAL 0.05f

typedef struct OpenPgl {
    PathGuide base;
    SgPglField *field;
    int training_passes;
    int trained_passes;   /* passes whose paths reached the field */
    int batch;            /* passes recorded since the last update */
    SgOpenPglMode mode;
    bool guided_roulette; /* Open PGL's guided roulette runs (radiance caches, --roulette learned) */
    bool recording; /* this pass trains the field */
    bool frozen;    /* it learns no more */
    double training_seconds;
} OpenPgl;

typedef struct PglVertex {
    SgPglField *field; /* NULL: the BSDF alone */
    int thread;        /* whose distribution was prepared */
    bool ris;          /* resampled (else the mixture) */
    float alpha;       /* mis: the BSDF's share */
    float u_guide[2];  /* ris: the guide candidate's random numbers */
    float u_pick;      /* ris: the choice between the candidates */
    bool has_adjoint;  /* the guided roulette knows what a bounce brings */
    Vec3 adjoint;      /* per unit throughput: albedo times irradiance / pi, MIS-weighted */
    Vec3 expected;     /* the same with all the light: what the path brings from here */
} PglVertex;
_Static_assert(sizeof(PglVertex) <= GUIDE_VERTEX_STATE, "PglVertex fits GuideVertex.state");

static inline PglVertex *pgl_vertex(GuideVertex *v) { return (PglVertex *)v->state; }
static inline const PglVertex *pgl_vertex_c(const GuideVertex *v) { return (const PglVertex *)v->state; }

static void pgl_pass_begin(PathGuide *g, int pass, uint64_t pass_key, GuidePass *plan)
{
    (void)pass_key;
    OpenPgl *o = (OpenPgl *)g;
    o->recording = !o->frozen && pass < o->training_passes;
    plan->record = o->recording;
}

/* Cycles' schedule: its scheduler starts with one sample between updates
 * and grows the work, and Cycles caps it at 4 samples per update while
 * guiding trains: 1, 2, then 4 passes per update. */
static int openpgl_passes_per_update(int update) { return update == 0 ? 1 : update == 1 ? 2 : 4; }

static void pgl_pass_end(PathGuide *g, int pass)
{
    OpenPgl *o = (OpenPgl *)g;
    if (!o->recording)
        return;
    o->trained_passes++;
    o->batch++;
    if (o->batch < openpgl_passes_per_update(sg_pgl_field_updates(o->field)) && pass + 1 < o->training_passes)
        return;
    double t0 = sg_seconds(); /* the next pass samples what these taught */
    sg_pgl_field_update(o->field);
    o->training_seconds += sg_seconds() - t0;
    o->batch = 0;
}

/* Cycles' roughness of a vertex: the square root of its lobes' mean
 * squared GGX alpha, weighted by how often each is sampled (a diffuse lobe
 * counts 1; a Phong lobe its Beckmann-equivalent alpha, sqrt(2 / (p + 2))). */
static float vertex_roughness(const Bsdf *b)
{
    float a2;
    if (b->kind == BSDF_PHONG)
        a2 = b->lobe.exponent > 0.0f ? 2.0f / (b->lobe.exponent + 2.0f) : 1.0f;
    else
        a2 = b->ax * b->ay;
    float d = b->lobe.diffuse_weight;
    return sqrtf(d + (1.0f - d) * a2);
}

static void pgl_vertex_end(PathGuide *g, const GuideHit *h, bool lit, SgRng *rng, GuideVertex *v)
{
    (void)lit;
    OpenPgl *o = (OpenPgl *)g;
    PglVertex *pv = pgl_vertex(v);
    bool ris = o->mode == SG_OPENPGL_RIS;
    /* mis: Cycles' share for the guide, its guiding probability times the
     * BSDF's diffuse share (a glossy lobe is not guided); ris: every
     * vertex rough enough */
    float share = OPENPGL_GUIDING_PROBABILITY * v->bsdf.lobe.diffuse_weight;
    bool wanted = ris ? vertex_roughness(&v->bsdf) >= OPENPGL_ROUGHNESS_THRESHOLD : share > 0.0f;
    float u = sg_rng_float(rng);
    bool ready = (wanted || o->guided_roulette) && sg_pgl_guide_at(o->field, h->thread, h->p, h->n, u);
    bool on = wanted && ready;
    *pv = (PglVertex){.field = on ? o->field : NULL, .thread = h->thread, .ris = ris, .alpha = 1.0f - share};
    if (on && ris) {
        pv->u_guide[0] = sg_rng_float(rng);
        pv->u_guide[1] = sg_rng_float(rng);
        pv->u_pick = sg_rng_float(rng);
    }
    Vec3 e_mis, e_all;
    if (ready && o->guided_roulette && sg_pgl_guide_irradiance(o->field, h->thread, h->n, true, &e_mis) &&
        sg_pgl_guide_irradiance(o->field, h->thread, h->n, false, &e_all)) {
        Vec3 a = v3_scale(bsdf_albedo(&v->bsdf), SG_INV_PI);
        pv->has_adjoint = true;
        pv->adjoint = v3_mul(a, e_mis);
        pv->expected = v3_mul(a, e_all);
    }
}

/* Open PGL's guided roulette: the pixel's estimate is what the cache
 * expects the path to bring from its first vertex that has one. */
static float pgl_survival(const GuideVertex *v, Vec3 beta, Vec3 *estimate)
{
    const PglVertex *pv = pgl_vertex_c(v);
    if (!pv->has_adjoint)
        return -1.0f;
    if (v3_max_component(*estimate) <= 0.0f)
        *estimate = v3_mul(beta, pv->expected);
    return sg_pgl_guided_survival(beta, pv->adjoint, *estimate, OPENPGL_MIN_SURVIVAL);
}

static float pgl_pdf(const GuideVertex *v, Vec3 w, float cos_n)
{
    const PglVertex *pv = pgl_vertex_c(v);
    if (!pv->field)
        return guide_bsdf_pdf(v, w, cos_n);
    /* ris: the candidates' mean density, as Cycles weighs the light sample */
    float a = pv->ris ? 0.5f : pv->alpha;
    return a * bsdf_pdf(&v->bsdf, w) + (1.0f - a) * sg_pgl_guide_pdf(pv->field, pv->thread, w);
}

/* A RIS candidate: its direction, the candidates' mean density there and
 * its resampling weight (target / that density). */
typedef struct RisCandidate {
    Vec3 w;
    float target, mean_pdf, weight;
} RisCandidate;

static void ris_weigh(const GuideVertex *v, const PglVertex *pv, RisCandidate *c, float guide_pdf)
{
    Vec3 n = v->bsdf.lobe.n;
    float cos_n = v3_dot(c->w, n);
    c->mean_pdf = 0.5f * (bsdf_pdf(&v->bsdf, c->w) + guide_pdf);
    c->target = 0.0f;
    if (cos_n > 0.0f) {
        Vec3 f = bsdf_eval(&v->bsdf, c->w);
        float fc = (f.x + f.y + f.z) * (1.0f / 3.0f) * cos_n;
        float p = OPENPGL_GUIDING_PROBABILITY;
        if (fc > 0.0f)
            c->target = fc * ((1.0f - p) * (0.5f * SG_INV_PI) +
                              p * sg_pgl_guide_radiance_pdf(pv->field, pv->thread, c->w));
    }
    c->weight = c->target > 0.0f && c->mean_pdf > 0.0f ? c->target / c->mean_pdf : 0.0f;
}

/* Cycles' RIS: of a BSDF candidate and a guide candidate, one is kept in
 * proportion to its weight; the estimator's density is target 2 / the
 * weights' sum (unbiased: generalized RIS with balance-heuristic weights,
 * every direction with f > 0 having a target > 0). */
static Vec3 pgl_sample_ris(GuideVertex *v, const PglVertex *pv, const float u[3], float *pdf)
{
    RisCandidate c[2];
    float guide_pdf;
    c[0].w = bsdf_sample(&v->bsdf, u[0], u[1], u[2]);
    ris_weigh(v, pv, &c[0], sg_pgl_guide_pdf(pv->field, pv->thread, c[0].w));
    c[1].w = sg_pgl_guide_sample(pv->field, pv->thread, pv->u_guide[0], pv->u_guide[1], &guide_pdf);
    ris_weigh(v, pv, &c[1], guide_pdf);
    float sum = c[0].weight + c[1].weight;
    if (!(sum > 0.0f)) { /* neither brings anything: the path ends */
        v->by_guide = false;
        *pdf = 0.0f;
        return c[0].w;
    }
    int k = pv->u_pick * sum < c[0].weight ? 0 : 1;
    v->by_guide = k == 1;
    v->mis_pdf = c[k].mean_pdf;
    *pdf = c[k].target * 2.0f / sum;
    return c[k].w;
}

static Vec3 pgl_sample(GuideVertex *v, const float u[3], float *pdf)
{
    const PglVertex *pv = pgl_vertex(v);
    if (!pv->field)
        return guide_bsdf_sample(v, u, pdf);
    if (pv->ris)
        return pgl_sample_ris(v, pv, u, pdf);
    Vec3 w;
    v->by_guide = !(u[0] < pv->alpha);
    if (!v->by_guide) {
        w = bsdf_sample(&v->bsdf, u[0] / pv->alpha, u[1], u[2]);
    } else {
        float guide_pdf;
        w = sg_pgl_guide_sample(pv->field, pv->thread, u[1], u[2], &guide_pdf);
    }
    *pdf = pgl_pdf(v, w, v3_dot(w, v->bsdf.lobe.n));
    return w;
}

static GuideSegment *pgl_record_vertex(PathGuide *g, int thread, Vec3 p, Vec3 wo, Vec3 n)
{
    return (GuideSegment *)sg_pgl_segment_next(((OpenPgl *)g)->field, thread, p, wo, n);
}
static void pgl_record_emission(GuideSegment *s, Vec3 le, float mis_weight)
{
    sg_pgl_segment_emission((SgPglSegment *)s, le, mis_weight);
}
static void pgl_record_direct(GuideSegment *s, Vec3 c) { sg_pgl_segment_scattered((SgPglSegment *)s, c); }
static void pgl_record_bounce(GuideSegment *s, Vec3 wi, float pdf, Vec3 weight, bool delta, float eta,
                              float roughness)
{
    sg_pgl_segment_bounce((SgPglSegment *)s, wi, pdf, weight, delta, eta, roughness);
}
static void pgl_record_survival(GuideSegment *s, float q) { sg_pgl_segment_survival((SgPglSegment *)s, q); }
static void pgl_record_path_end(PathGuide *g, int thread) { sg_pgl_path_end(((OpenPgl *)g)->field, thread); }

static void pgl_stats(const PathGuide *g, GuideStats *s)
{
    const OpenPgl *o = (const OpenPgl *)g;
    s->training_passes = o->trained_passes;
    s->training_updates = sg_pgl_field_updates(o->field);
    s->training_seconds = o->training_seconds;
}

/* A field file's part: the updates and passes behind the field, then Open
 * PGL's own bytes. */
static bool pgl_field_store(const PathGuide *g, FieldBytes *out)
{
    const OpenPgl *o = (const OpenPgl *)g;
    unsigned char *data;
    size_t size;
    SgError e = {0};
    if (!sg_pgl_field_save(o->field, &data, &size, &e))
        return false;
    int32_t counts[2] = {sg_pgl_field_updates(o->field), o->trained_passes};
    bool ok = field_bytes_put(out, counts, sizeof counts) && field_bytes_put(out, data, size);
    free(data);
    return ok;
}

static bool pgl_field_load(PathGuide *g, FieldReader *in, SgError *err)
{
    OpenPgl *o = (OpenPgl *)g;
    int32_t counts[2];
    if (!field_reader_get(in, counts, sizeof counts) || counts[0] < 0 || counts[1] < counts[0])
        return sg_fail(err, "its Open PGL field is truncated");
    if (!sg_pgl_field_restore(o->field, in->data + in->at, in->size - in->at, counts[0], err))
        return false;
    o->trained_passes = counts[1];
    in->at = in->size;
    o->frozen = true;
    return true;
}

static void pgl_freeze(PathGuide *g) { ((OpenPgl *)g)->frozen = true; }

static void pgl_describe(const PathGuide *g, const GuideStats *s, SgRenderReport *report)
{
    const OpenPgl *o = (const OpenPgl *)g;
    snprintf(report->guide, sizeof report->guide,
             ", %s, field trained on %d passes in %d updates (%.2f s%s), guide drew %.1f%% of bounces%s",
             sg_openpgl_mode_name(o->mode), s->training_passes, s->training_updates, s->training_seconds, o->frozen ? ", frozen" : "",
             100.0 * s->lobe_share, o->guided_roulette ? ", Open PGL's guided roulette" : "");
    if (o->guided_roulette)
        report->roulette = SG_ROULETTE_LEARNED;
}

static void pgl_destroy(PathGuide *g)
{
    OpenPgl *o = (OpenPgl *)g;
    sg_pgl_field_free(o->field);
    free(o);
}

static const PathGuideOps pgl_ops = {
    .name = "openpgl",
    .destroy = pgl_destroy,
    .pass_begin = pgl_pass_begin,
    .pass_end = pgl_pass_end,
    .vertex_end = pgl_vertex_end,
    .survival = pgl_survival,
    .pdf = pgl_pdf,
    .sample = pgl_sample,
    .record_vertex = pgl_record_vertex,
    .record_emission = pgl_record_emission,
    .record_direct = pgl_record_direct,
    .record_bounce = pgl_record_bounce,
    .record_survival = pgl_record_survival,
    .record_path_end = pgl_record_path_end,
    .stats = pgl_stats,
    .describe = pgl_describe,
    .field_store = pgl_field_store,
    .field_load = pgl_field_load,
    .freeze = pgl_freeze,
};

static PathGuide *pgl_create(const PathGuideSetup *setup, SgError *err)
{
    OpenPgl *o = path_guide_alloc(sizeof *o, &pgl_ops, setup, err);
    if (!o)
        return NULL;
    o->training_passes = setup->training_passes;
    o->mode = setup->opt->openpgl_mode;
    o->guided_roulette = setup->opt->roulette == SG_ROULETTE_LEARNED && sg_pgl_has_radiance_caches();
    Vec3 lo, hi;
    geometry_bounds(setup->geo, &lo, &hi);
    SgError e = {0};
    o->field = sg_pgl_field_create(lo, hi, setup->threads, &e);
    if (!o->field) {
        free(o);
        return sg_fail(err, "%s: --sampling openpgl: %s", setup->path, e.message), NULL;
    }
    return &o->base;
}

const PathGuideKind guide_openpgl_kind = {
    .mode = {.name = "openpgl",
             .help = "the peer, Open PGL's learned guiding as Cycles uses it\n(no cache; builds with `make openpgl`; --openpgl-mode)",
             .learns = true,
             .learned_roulette = true, /* Open PGL's guided roulette, where it keeps radiance caches */
             .training_passes = SG_OPENPGL_TRAINING_PASSES,
             .available = sg_pgl_require},
    .create = pgl_create,
};
