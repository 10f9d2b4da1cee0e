/* skeleton: the paper's rule as written (section 3.4): where a vertex is
 * not directly lit, the bounce is drawn from a cosine-power lobe toward the
 * importance point of the skeleton node nearest it, and from the BSDF
 * where it is lit. Biased (the lobe's density is not weighed against the
 * BSDF's); kept to reproduce the paper. */
#include <stdio.h>
#include <stdlib.h>

#include "path_guide.h"
#include "importance_lookup.h"

typedef struct SkeletonRule {
    PathGuide base;
    ImportanceLookup skeleton;
    float exponent;
} SkeletonRule;

typedef struct RuleVertex {
    ImportanceQuery query;
    bool asked;      /* the query was begun */
    bool lobe;       /* the bounce follows the lobe alone */
    SgFoldedLobe folded;
} RuleVertex;
_Static_assert(sizeof(RuleVertex) <= GUIDE_VERTEX_STATE, "RuleVertex fits GuideVertex.state");

static inline RuleVertex *rule_vertex(GuideVertex *v) { return (RuleVertex *)v->state; }
static inline const RuleVertex *rule_vertex_c(const GuideVertex *v) { return (const RuleVertex *)v->state; }

static void rule_vertex_begin(PathGuide *g, const GuideHit *h, SgRng *rng, GuideVertex *v)
{
    SkeletonRule *s = (SkeletonRule *)g;
    RuleVertex *rv = rule_vertex(v);
    rv->lobe = false;
    rv->asked = importance_lookup_begin(&s->skeleton, h->p, h->n, rng, &rv->query);
}

static void rule_vertex_end(PathGuide *g, const GuideHit *h, bool lit, SgRng *rng, GuideVertex *v)
{
    (void)rng;
    SkeletonRule *s = (SkeletonRule *)g;
    RuleVertex *rv = rule_vertex(v);
    Vec3 axis;
    /* the query is finished even where the vertex is lit (the cache line it loaded is then wasted) */
    if (rv->asked && importance_lookup_end(&s->skeleton, &rv->query, h->p, h->n, &axis) && !lit) {
        rv->lobe = true;
        rv->folded = sg_folded_lobe(axis, h->n, s->exponent);
    }
}

static float rule_pdf(const GuideVertex *v, Vec3 w, float cos_n)
{
    const RuleVertex *rv = rule_vertex_c(v);
    return rv->lobe ? sg_pdf_cosine_power(rv->folded.axis, rv->folded.exponent, w) : guide_bsdf_pdf(v, w, cos_n);
}

static Vec3 rule_sample(GuideVertex *v, const float u[3], float *pdf)
{
    const RuleVertex *rv = rule_vertex(v);
    if (!rv->lobe)
        return guide_bsdf_sample(v, u, pdf);
    Vec3 w = sg_sample_cosine_power(rv->folded.axis, rv->folded.exponent, u[1], u[2]);
    v->by_guide = true;
    *pdf = sg_pdf_cosine_power(rv->folded.axis, rv->folded.exponent, w);
    return w;
}

static void rule_destroy(PathGuide *g)
{
    SkeletonRule *s = (SkeletonRule *)g;
    importance_lookup_free(&s->skeleton);
    free(s);
}

static void rule_describe(const PathGuide *g, const GuideStats *s, SgRenderReport *report)
{
    (void)g;
    snprintf(report->guide, sizeof report->guide, ", lobe drew %.1f%% of bounces", 100.0 * s->lobe_share);
}

static const PathGuideOps rule_ops = {
    .name = "skeleton",
    .lit_below_horizon = true, /* "directly lit" is the light sample's visibility, whatever its cosine */
    .destroy = rule_destroy,
    .vertex_begin = rule_vertex_begin,
    .vertex_end = rule_vertex_end,
    .pdf = rule_pdf,
    .sample = rule_sample,
    .describe = rule_describe,
};

static PathGuide *rule_create(const PathGuideSetup *setup, SgError *err)
{
    const SgRenderOptions *o = setup->opt;
    SkeletonRule *s = path_guide_alloc(sizeof *s, &rule_ops, setup, err);
    if (!s)
        return NULL;
    s->exponent = o->lobe_exponent;
    if (!importance_lookup_init(&s->skeleton, &o->importance, setup->geo->centre, setup->geo->scale, setup->lights,
                             setup->path, err)) {
        rule_destroy(&s->base);
        return NULL;
    }
    return &s->base;
}

const PathGuideKind guide_skeleton_kind = {
    .mode = {.name = "skeleton",
             .help = "the paper's rule as written (biased; for reproduction)",
             .uses_cache = true,
             .lobe_exponent = 4.0f, /* the paper's p_skel for its corridor */
             .biased = true},
    .create = rule_create,
};
