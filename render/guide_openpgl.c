/* openpgl: the peer, Open PGL's learned guiding integrated as Cycles does
 * (render/openpgl_guide.h wraps the library): one field for the scene,
 * trained after each of the first SG_OPENPGL_TRAINING_PASSES passes from
 * the paths that pass recorded; at a diffuse or glossy vertex the field's
 * distribution there (cosine product applied) is mixed with the BSDF by
 * one-sample MIS. */
#include <stdlib.h>

#include "openpgl_guide.h"
#include "path_guide.h"
#include "progress.h"

/* Open PGL's share of a diffuse bounce: Cycles' default surface guiding
 * probability. */
#define OPENPGL_GUIDING_PROBABILITY 0.5f

typedef struct OpenPgl {
    PathGuide base;
    SgPglField *field;
    bool recording; /* this pass trains the field */
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
    o->recording = pass < SG_OPENPGL_TRAINING_PASSES;
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
};

PathGuide *guide_openpgl_create(const PathGuideSetup *setup, SgError *err)
{
    OpenPgl *o = calloc(1, sizeof *o);
    if (!o)
        return sg_fail(err, "%s: out of memory", setup->path), NULL;
    o->base.ops = &pgl_ops;
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
