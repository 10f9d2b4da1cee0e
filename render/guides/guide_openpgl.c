/* openpgl: the peer, Open PGL's learned guiding integrated as Cycles does
 * (render/guides/openpgl_field.h wraps the library): one field for the scene,
 * trained after each of its training passes (SG_OPENPGL_TRAINING_PASSES,
 * Cycles' training samples, unless the options say) from the paths that
 * pass recorded, then frozen (or frozen as a field file gives it); at a diffuse or glossy vertex the field's
 * distribution there (cosine product applied) is mixed with the BSDF by
 * one-sample MIS. */
#include <stdio.h>
#include <stdlib.h>

#include "openpgl_field.h"
#include "path_guide.h"
#include "progress.h"

/* Open PGL's share of a diffuse bounce: Cycles' default surface guiding
 * probability. */
#define OPENPGL_GUIDING_PROBABILITY 0.5f

typedef struct OpenPgl {
    PathGuide base;
    SgPglField *field;
    int training_passes;
    bool recording; /* this pass trains the field */
    bool frozen;    /* it learns no more */
    double training_seconds;
} OpenPgl;

typedef struct PglVertex {
    SgPglField *field; /* NULL: the BSDF alone */
    int thread;        /* whose distribution was prepared */
    float alpha;       /* the BSDF's share */
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

static void pgl_pass_end(PathGuide *g, int pass)
{
    (void)pass;
    OpenPgl *o = (OpenPgl *)g;
    if (!o->recording)
        return;
    double t0 = sg_seconds(); /* the next pass samples what this one taught */
    sg_pgl_field_update(o->field);
    o->training_seconds += sg_seconds() - t0;
}

static void pgl_vertex_end(PathGuide *g, const GuideHit *h, bool lit, SgRng *rng, GuideVertex *v)
{
    (void)lit;
    OpenPgl *o = (OpenPgl *)g;
    PglVertex *pv = pgl_vertex(v);
    /* Cycles' share for the guide: its guiding probability times the
     * BSDF's diffuse share (a glossy lobe is not guided) */
    float share = OPENPGL_GUIDING_PROBABILITY * v->bsdf.lobe.diffuse_weight;
    float u = sg_rng_float(rng);
    bool on = share > 0.0f && sg_pgl_guide_at(o->field, h->thread, h->p, h->n, u);
    *pv = (PglVertex){.field = on ? o->field : NULL, .thread = h->thread, .alpha = 1.0f - share};
}

static float pgl_pdf(const GuideVertex *v, Vec3 w, float cos_n)
{
    const PglVertex *pv = pgl_vertex_c(v);
    if (!pv->field)
        return guide_bsdf_pdf(v, w, cos_n);
    return pv->alpha * bsdf_pdf(&v->bsdf, w) + (1.0f - pv->alpha) * sg_pgl_guide_pdf(pv->field, pv->thread, w);
}

static Vec3 pgl_sample(GuideVertex *v, const float u[3], float *pdf)
{
    const PglVertex *pv = pgl_vertex(v);
    if (!pv->field)
        return guide_bsdf_sample(v, u, pdf);
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
    s->training_passes = sg_pgl_field_updates(o->field);
    s->training_seconds = o->training_seconds;
}

/* A field file's part: the updates behind the field, then Open PGL's own bytes. */
static bool pgl_field_store(const PathGuide *g, FieldBytes *out)
{
    const OpenPgl *o = (const OpenPgl *)g;
    unsigned char *data;
    size_t size;
    SgError e = {0};
    if (!sg_pgl_field_save(o->field, &data, &size, &e))
        return false;
    int32_t updates = sg_pgl_field_updates(o->field);
    bool ok = field_bytes_put(out, &updates, sizeof updates) && field_bytes_put(out, data, size);
    free(data);
    return ok;
}

static bool pgl_field_load(PathGuide *g, FieldReader *in, SgError *err)
{
    OpenPgl *o = (OpenPgl *)g;
    int32_t updates;
    if (!field_reader_get(in, &updates, sizeof updates) || updates < 0)
        return sg_fail(err, "its Open PGL field is truncated");
    if (!sg_pgl_field_restore(o->field, in->data + in->at, in->size - in->at, updates, err))
        return false;
    in->at = in->size;
    o->frozen = true;
    return true;
}

static void pgl_freeze(PathGuide *g) { ((OpenPgl *)g)->frozen = true; }

static void pgl_describe(const PathGuide *g, const GuideStats *s, SgRenderReport *report)
{
    snprintf(report->guide, sizeof report->guide, ", field trained on %d passes (%.2f s%s), guide drew %.1f%% of bounces",
             s->training_passes, s->training_seconds, ((const OpenPgl *)g)->frozen ? ", frozen" : "",
             100.0 * s->lobe_share);
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
             .help = "the peer, Open PGL's learned guiding as Cycles uses it\n(no cache; builds with `make openpgl`)",
             .learns = true,
             .training_passes = SG_OPENPGL_TRAINING_PASSES,
             .available = sg_pgl_require},
    .create = pgl_create,
};
