/* The guide interface (render/guides/path_guide.h) from outside: a guide written
 * here, in this one file, as the next paper's would be, runs in the path
 * tracer through sg_renderer_create_with_guide. It must give the furnace's
 * exact answer; the same guide lying about its pdf must not; and the
 * integrator must make the calls in the order and number the interface
 * promises (passes, paths, recording, learning). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>

#include "../render/guides/path_guide.h"
#include "../render/renderer.h"
#include "support_render.h"

/* ---- the guide: half the bounces uniform over the hemisphere ----------- */

typedef struct Calls {
    _Atomic long pass_begin, pass_end, side_job, paths_learning;
    _Atomic long vertex_begin, vertex_end, vertex_may_learn, learn, learn_bounced, learn_cut;
    _Atomic long record_vertex, record_bounce, record_path_end;
    long order_errors; /* pass_end before pass_begin, a pass out of order (one thread: between passes) */
    int last_pass_begun;
} Calls;

typedef struct UniformGuide {
    PathGuide base;
    Calls *calls;
    float pdf_error; /* 1: honest; else the guide reports its pdf times this */
    bool recording;
} UniformGuide;

typedef struct UniformVertex {
    bool mixed;
    float pdf_error;
} UniformVertex;

/* Passed to create through a global: PathGuideCreate takes only the setup
 * (the renderer's tests run one at a time in this process). */
static Calls g_calls;
static float g_pdf_error = 1.0f;

#define UNIFORM_SHARE 0.5f

static void uniform_pass_begin(PathGuide *g, int pass, uint64_t key, GuidePass *plan)
{
    (void)key;
    UniformGuide *u = (UniformGuide *)g;
    if (pass != u->calls->last_pass_begun + 1)
        u->calls->order_errors++;
    u->calls->last_pass_begun = pass;
    u->calls->pass_begin++;
    u->recording = pass < 2; /* the first two passes record */
    plan->record = u->recording;
    plan->side_job = true;
}
static void uniform_side_job(PathGuide *g) { ((UniformGuide *)g)->calls->side_job++; }
static void uniform_pass_end(PathGuide *g, int pass)
{
    UniformGuide *u = (UniformGuide *)g;
    if (pass != u->calls->last_pass_begun)
        u->calls->order_errors++;
    u->calls->pass_end++;
}
static bool uniform_path_learns(const PathGuide *g, size_t pixel)
{
    bool learns = pixel % 2 == 0;
    ((const UniformGuide *)g)->calls->paths_learning += learns;
    return learns;
}
static void uniform_vertex_begin(PathGuide *g, const GuideHit *h, SgRng *rng, GuideVertex *v)
{
    (void)rng;
    UniformGuide *u = (UniformGuide *)g;
    u->calls->vertex_begin++;
    u->calls->vertex_may_learn += h->may_learn;
    v->learn = h->may_learn;
}
static void uniform_vertex_end(PathGuide *g, const GuideHit *h, bool lit, SgRng *rng, GuideVertex *v)
{
    (void)h, (void)lit, (void)rng;
    UniformGuide *u = (UniformGuide *)g;
    u->calls->vertex_end++;
    UniformVertex *uv = (UniformVertex *)v->state;
    uv->mixed = true;
    uv->pdf_error = u->pdf_error;
}
static float uniform_pdf(const GuideVertex *v, Vec3 w, float cos_n)
{
    const UniformVertex *uv = (const UniformVertex *)v->state;
    float pdf = (1.0f - UNIFORM_SHARE) * bsdf_pdf(&v->bsdf, w) +
                UNIFORM_SHARE * (cos_n > 0.0f ? 1.0f / (2.0f * (float)M_PI) : 0.0f);
    return pdf * uv->pdf_error;
}
static Vec3 uniform_sample(GuideVertex *v, const float u[3], float *pdf)
{
    Vec3 w;
    v->by_guide = !(u[0] < 1.0f - UNIFORM_SHARE);
    if (!v->by_guide) {
        w = bsdf_sample(&v->bsdf, u[0] / (1.0f - UNIFORM_SHARE), u[1], u[2]);
    } else { /* uniform over the hemisphere around n */
        Vec3 n = v->bsdf.lobe.n;
        float z = u[1], r = sqrtf(fmaxf(0.0f, 1.0f - z * z)), phi = 2.0f * (float)M_PI * u[2];
        Vec3 t = fabsf(n.x) > 0.5f ? v3(0, 1, 0) : v3(1, 0, 0);
        Vec3 b1 = v3_normalize(v3_cross(n, t)), b2 = v3_cross(n, b1);
        w = v3_add(v3_add(v3_scale(b1, r * cosf(phi)), v3_scale(b2, r * sinf(phi))), v3_scale(n, z));
    }
    *pdf = uniform_pdf(v, w, v3_dot(w, v->bsdf.lobe.n));
    return w;
}
static void uniform_learn(PathGuide *g, int tile, const GuideVertex *v, const BounceOutcome *o)
{
    (void)tile, (void)v;
    Calls *c = ((UniformGuide *)g)->calls;
    c->learn++;
    c->learn_bounced += o->bounced;
    c->learn_cut += o->cut;
}
static GuideSegment *uniform_record_vertex(PathGuide *g, int thread, Vec3 p, Vec3 wo, Vec3 n)
{
    (void)thread, (void)p, (void)wo, (void)n;
    UniformGuide *u = (UniformGuide *)g;
    u->calls->record_vertex++;
    return (GuideSegment *)u; /* any non-NULL handle: this guide keeps no segments */
}
static void uniform_record_emission(GuideSegment *s, Vec3 le, float mis) { (void)s, (void)le, (void)mis; }
static void uniform_record_direct(GuideSegment *s, Vec3 c) { (void)s, (void)c; }
static void uniform_record_bounce(GuideSegment *s, Vec3 wi, float pdf, Vec3 weight, bool delta, float eta,
                                  float roughness)
{
    (void)wi, (void)pdf, (void)weight, (void)delta, (void)eta, (void)roughness;
    ((UniformGuide *)s)->calls->record_bounce++;
}
static void uniform_record_survival(GuideSegment *s, float q) { (void)s, (void)q; }
static void uniform_record_path_end(PathGuide *g, int thread)
{
    (void)thread;
    ((UniformGuide *)g)->calls->record_path_end++;
}
static void uniform_destroy(PathGuide *g) { free(g); }

static const PathGuideOps uniform_ops = {
    .name = "uniform-test",
    .destroy = uniform_destroy,
    .pass_begin = uniform_pass_begin,
    .side_job = uniform_side_job,
    .pass_end = uniform_pass_end,
    .path_learns = uniform_path_learns,
    .vertex_begin = uniform_vertex_begin,
    .vertex_end = uniform_vertex_end,
    .pdf = uniform_pdf,
    .sample = uniform_sample,
    .learn = uniform_learn,
    .record_vertex = uniform_record_vertex,
    .record_emission = uniform_record_emission,
    .record_direct = uniform_record_direct,
    .record_bounce = uniform_record_bounce,
    .record_survival = uniform_record_survival,
    .record_path_end = uniform_record_path_end,
};

static PathGuide *uniform_create(const PathGuideSetup *setup, SgError *err)
{
    UniformGuide *u = path_guide_alloc(sizeof *u, &uniform_ops, setup, err);
    if (!u)
        return NULL;
    u->calls = &g_calls;
    u->pdf_error = g_pdf_error;
    return &u->base;
}

/* ---- the furnace: a closed box, albedo 0.5, emission 0.5, L = 1 --------- */

typedef struct FurnaceResult {
    double mean, std_error, guide_share;
} FurnaceResult;

static FurnaceResult furnace(float pdf_error, int passes, int threads)
{
    g_calls = (Calls){.last_pass_begun = -1};
    g_pdf_error = pdf_error;
    SgScene *s = sgt_furnace_scene();
    SgRenderOptions o;
    sg_render_options_default(&o, s);
    o.threads = threads;
    o.max_depth = 64; /* 0.5^64: the truncation is far below the noise */
    SgError err = {0};
    SgRenderer *r = sg_renderer_create_with_guide(s, &o, uniform_create, &err);
    cr_assert_not_null(r, "%s", err.message);
    SgtSampleMean m = sgt_passes_mean(r, passes, (size_t)o.width * o.height);
    FurnaceResult fr = {.mean = m.mean, .std_error = m.std_error, .guide_share = sgt_stats(r).lobe_share};
    sg_renderer_free(r);
    sgt_scene_free(s);
    return fr;
}

Test(path_guide, a_guide_from_outside_gives_the_furnace_answer)
{
    FurnaceResult fr = furnace(1.0f, 48, 2);
    cr_log_info("uniform-test guide furnace: %.5f +- %.5f, guide drew %.4f", fr.mean, fr.std_error, fr.guide_share);
    cr_assert(fabs(fr.mean - 1.0) < 4.0 * fr.std_error, "furnace %.5f, expected 1 +- %.5f", fr.mean,
              4.0 * fr.std_error);
    cr_assert(fr.std_error < 0.01, "standard error %.4f", fr.std_error);
    cr_assert(fr.guide_share > 0.48 && fr.guide_share < 0.52, "the guide drew %.4f of the bounces, not half",
              fr.guide_share);
}

/* The furnace can tell: a pdf reported 10% high weighs every bounce 10%
 * low, and the answer drops far outside its error bars. */
Test(path_guide, a_guide_that_misreports_its_pdf_fails_the_furnace)
{
    FurnaceResult fr = furnace(1.1f, 24, 2);
    cr_log_info("lying guide furnace: %.5f +- %.5f", fr.mean, fr.std_error);
    cr_assert(fabs(fr.mean - 1.0) > 10.0 * fr.std_error, "a pdf 10%% too high went unnoticed: %.5f +- %.5f",
              fr.mean, fr.std_error);
}

Test(path_guide, the_integrator_makes_the_calls_the_interface_promises)
{
    const int passes = 5, pixels = 32 * 24;
    furnace(1.0f, passes, 2);
    Calls *c = &g_calls;
    cr_assert_eq(c->order_errors, 0, "passes begun or ended out of order");
    cr_assert_eq(c->pass_begin, passes);
    cr_assert_eq(c->pass_end, passes);
    cr_assert_eq(c->side_job, passes, "side job ran %ld times in %d passes", (long)c->side_job, passes);
    cr_assert_eq(c->paths_learning, (long)passes * pixels / 2, "path_learns asked %ld times",
                 (long)c->paths_learning);
    cr_assert_eq(c->vertex_begin, c->vertex_end, "every vertex begun is ended");
    cr_assert_gt(c->vertex_begin, (long)passes * pixels, "every camera ray hits a wall");
    /* half the paths learn; each of their vertices is heard once its branch ends */
    cr_assert_gt(c->vertex_may_learn, c->vertex_begin / 3);
    cr_assert_lt(c->vertex_may_learn, c->vertex_begin * 2 / 3);
    cr_assert_eq(c->learn, c->vertex_may_learn, "learn() heard %ld of %ld learning vertices", (long)c->learn,
                 (long)c->vertex_may_learn);
    cr_assert_gt(c->learn_cut, 0, "the roulette cut some bounces");
    cr_assert_eq(c->learn_bounced + c->learn_cut, c->learn, "a furnace bounce is drawn above the surface");
    /* two recording passes: every path of those ends once, every vertex is recorded */
    cr_assert_eq(c->record_path_end, 2L * pixels);
    cr_assert_gt(c->record_vertex, 2L * pixels);
    cr_assert_lt(c->record_bounce, c->record_vertex, "the last vertex of a path has no bounce");
}
