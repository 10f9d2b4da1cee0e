/* Chi-square tests of every direction sampler of the renderer against its
 * own pdf (the way pbrt-v4 and Mitsuba 3 test theirs): 1e6 samples
 * histogrammed over theta/phi bins of the sphere, expected counts from the
 * pdf integrated over each bin, bins expecting fewer than 5 pooled, and the
 * test fails when the chi-square p-value is below 0.01 (Sidak-corrected for
 * the number of chi-square tests in this file, counted from the one list
 * that also declares them, CHI2_CASES). A sample where the pdf is zero fails. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "../render/bsdf.h"
#include "../render/guides/mixture_learning.h"
#include "../render/environment.h"
#include "../render/lights.h"
#include "../render/sampling.h"
#include "rng.h"
#include "scene_builder.h"

#define THETA_BINS 80
#define PHI_BINS 160
#define SAMPLES 1000000

/* How many chi-square tests this file runs: counted from CHI2_CASES below. */
static int chi2_test_count(void);

typedef Vec3 (*SampleFn)(const void *ctx, float u0, float u1, float u2);
typedef float (*PdfFn)(const void *ctx, Vec3 w);

/* ---- chi-square survival function: Q(k/2, x/2), regularized upper
 * incomplete gamma, by its series (x < a + 1) or continued fraction. */
static double upper_gamma_q(double a, double x)
{
    if (x <= 0.0)
        return 1.0;
    double log_prefix = -x + a * log(x) - lgamma(a);
    if (x < a + 1.0) {
        double term = 1.0 / a, sum = term;
        for (int n = 1; n < 100000; n++) {
            term *= x / (a + n);
            sum += term;
            if (fabs(term) < fabs(sum) * 1e-15)
                break;
        }
        return 1.0 - sum * exp(log_prefix);
    }
    /* Lentz's method for the continued fraction of Q. */
    const double tiny = 1e-300;
    double b = x + 1.0 - a, c = 1.0 / tiny, d = 1.0 / b, h = d;
    for (int i = 1; i < 100000; i++) {
        double an = -i * (i - a);
        b += 2.0;
        d = an * d + b;
        if (fabs(d) < tiny) d = tiny;
        c = b + an / c;
        if (fabs(c) < tiny) c = tiny;
        d = 1.0 / d;
        double delta = d * c;
        h *= delta;
        if (fabs(delta - 1.0) < 1e-15)
            break;
    }
    return exp(log_prefix) * h;
}

static double chi2_survival(double chi2, int dof)
{
    return upper_gamma_q(0.5 * dof, 0.5 * chi2);
}

Test(render_sampling, chi2_survival_matches_known_values)
{
    /* Tabulated: P(chi2_1 > 3.841) = 0.05, P(chi2_10 > 23.209) = 0.01,
     * P(chi2_100 > 135.807) = 0.01, P(chi2_2 > x) = exp(-x/2). */
    cr_assert_float_eq(chi2_survival(3.841459, 1), 0.05, 1e-6);
    cr_assert_float_eq(chi2_survival(23.20925, 10), 0.01, 1e-6);
    cr_assert_float_eq(chi2_survival(135.8067, 100), 0.01, 1e-5);
    cr_assert_float_eq(chi2_survival(7.0, 2), exp(-3.5), 1e-12);
}

/* ---- histogram test ---------------------------------------------------- */

static Vec3 sphere_dir(double theta, double phi)
{
    return v3((float)(sin(theta) * cos(phi)), (float)(sin(theta) * sin(phi)), (float)cos(theta));
}

/* Integral of the pdf over one bin by Simpson's rule in theta and phi
 * (steps sub per side, even), with the sin(theta) Jacobian. */
static double integrate_bin(PdfFn pdf, const void *ctx, double t0, double t1, double p0,
                            double p1, int sub)
{
    /* Evaluate just inside the bin: a pdf that jumps on a bin edge (a lobe
     * folded at the surface, with the normal on a coordinate axis) is then
     * integrated from the correct side. */
    const double inset = 1e-9;
    double width_t = t1 - t0, width_p = p1 - p0;
    t0 += inset;
    t1 -= inset;
    p0 += inset;
    p1 -= inset;
    double ht = (t1 - t0) / sub, hp = (p1 - p0) / sub, sum = 0.0;
    for (int i = 0; i <= sub; i++) {
        double wt = (i == 0 || i == sub) ? 1 : (i % 2 ? 4 : 2);
        double theta = t0 + i * ht;
        for (int j = 0; j <= sub; j++) {
            double wp = (j == 0 || j == sub) ? 1 : (j % 2 ? 4 : 2);
            double phi = p0 + j * hp;
            sum += wt * wp * pdf(ctx, sphere_dir(theta, phi)) * sin(theta);
        }
    }
    return sum * ht * hp / 9.0 * (width_t * width_p) / ((t1 - t0) * (p1 - p0));
}

typedef struct Chi2Result {
    double p_value;
    double pdf_integral;
    long zero_pdf_samples;
    long nonfinite_samples;
    int dof;
} Chi2Result;

static int compare_expected(const void *a, const void *b)
{
    const double *x = a, *y = b;
    return (x[0] > y[0]) - (x[0] < y[0]);
}

/* may_absorb: the sampler may return no direction (the zero vector; a
 * rough dielectric's microfacet that sends wi to the wrong side), and the
 * pdf then integrates to less than 1: the missing mass is one more cell. */
static Chi2Result chi2_test(SampleFn sample, PdfFn pdf, const void *ctx, uint64_t seed, int sub, bool may_absorb)
{
    Chi2Result res = {0};
    const int bins = THETA_BINS * PHI_BINS;
    double *observed = calloc(bins, sizeof *observed);
    long absorbed = 0;
    SgRng rng;
    sg_rng_seed(&rng, seed, 7);
    for (long s = 0; s < SAMPLES; s++) {
        float u0 = sg_rng_float(&rng), u1 = sg_rng_float(&rng), u2 = sg_rng_float(&rng);
        Vec3 w = sample(ctx, u0, u1, u2);
        if (may_absorb && w.x == 0.0f && w.y == 0.0f && w.z == 0.0f) {
            absorbed++;
            continue;
        }
        if (!isfinite(w.x) || !isfinite(w.y) || !isfinite(w.z) ||
            fabsf(v3_length(w) - 1.0f) > 1e-4f) {
            res.nonfinite_samples++;
            continue;
        }
        if (!(pdf(ctx, w) > 0.0f))
            res.zero_pdf_samples++;
        double theta = acos(fmax(-1.0, fmin(1.0, (double)w.z)));
        double phi = atan2((double)w.y, (double)w.x);
        if (phi < 0)
            phi += 2.0 * M_PI;
        int ti = (int)(theta / M_PI * THETA_BINS), pi = (int)(phi / (2.0 * M_PI) * PHI_BINS);
        ti = ti < 0 ? 0 : ti >= THETA_BINS ? THETA_BINS - 1 : ti;
        pi = pi < 0 ? 0 : pi >= PHI_BINS ? PHI_BINS - 1 : pi;
        observed[ti * PHI_BINS + pi] += 1.0;
    }
    /* pairs (expected, observed), sorted by expected to pool the small ones */
    double *pairs = malloc(2 * sizeof(double) * (bins + 1));
    for (int ti = 0; ti < THETA_BINS; ti++)
        for (int pi = 0; pi < PHI_BINS; pi++) {
            double e = integrate_bin(pdf, ctx, M_PI * ti / THETA_BINS, M_PI * (ti + 1) / THETA_BINS,
                                     2 * M_PI * pi / PHI_BINS, 2 * M_PI * (pi + 1) / PHI_BINS, sub);
            res.pdf_integral += e;
            pairs[2 * (ti * PHI_BINS + pi)] = e * SAMPLES;
            pairs[2 * (ti * PHI_BINS + pi) + 1] = observed[ti * PHI_BINS + pi];
        }
    int cells_in = bins;
    if (may_absorb) {
        pairs[2 * bins] = fmax(0.0, 1.0 - res.pdf_integral) * SAMPLES;
        pairs[2 * bins + 1] = (double)absorbed;
        cells_in++;
    }
    qsort(pairs, cells_in, 2 * sizeof(double), compare_expected);
    double chi2 = 0.0, pool_e = 0.0, pool_o = 0.0;
    int cells = 0;
    for (int i = 0; i < cells_in; i++) {
        double e = pairs[2 * i], o = pairs[2 * i + 1];
        if (e < 5.0 || (pool_e > 0.0 && pool_e < 5.0)) {
            pool_e += e;
            pool_o += o;
            if (pool_e < 5.0)
                continue;
            e = pool_e;
            o = pool_o;
            pool_e = pool_o = 0.0;
        }
        chi2 += (o - e) * (o - e) / e;
        cells++;
    }
    if (pool_e > 0.0) { /* leftover pool: fold into the statistic as one cell */
        chi2 += (pool_o - pool_e) * (pool_o - pool_e) / fmax(pool_e, 1e-12);
        cells++;
    }
    res.dof = cells - 1;
    res.p_value = chi2_survival(chi2, res.dof);
    free(pairs);
    free(observed);
    return res;
}

static void assert_chi2_of(const char *name, SampleFn sample, PdfFn pdf, const void *ctx, uint64_t seed, int sub,
                           bool may_absorb)
{
    Chi2Result r = chi2_test(sample, pdf, ctx, seed, sub, may_absorb);
    double alpha = 1.0 - pow(1.0 - 0.01, 1.0 / chi2_test_count()); /* Sidak */
    cr_log_info("%s: p = %.4f (dof %d), pdf integral %.6f", name, r.p_value, r.dof,
                r.pdf_integral);
    cr_assert_eq(r.nonfinite_samples, 0, "%s: %ld non-unit or non-finite samples", name,
                 r.nonfinite_samples);
    cr_assert_eq(r.zero_pdf_samples, 0, "%s: %ld samples where the pdf is zero", name,
                 r.zero_pdf_samples);
    if (may_absorb) /* what the pdf misses, the sampler must have absorbed: the extra cell checks it */
        cr_assert(r.pdf_integral < 1.0 + 2e-3 && r.pdf_integral > 0.5, "%s: pdf integrates to %.6f", name,
                  r.pdf_integral);
    else
        cr_assert(fabs(r.pdf_integral - 1.0) < 2e-3, "%s: pdf integrates to %.6f", name, r.pdf_integral);
    cr_assert(r.p_value >= alpha, "%s: chi-square p = %.3g < %.3g (dof %d)", name, r.p_value,
              alpha, r.dof);
}

static void assert_chi2(const char *name, SampleFn sample, PdfFn pdf, const void *ctx, uint64_t seed, int sub)
{
    assert_chi2_of(name, sample, pdf, ctx, seed, sub, false);
}

/* ---- the routines under test -------------------------------------------- */

typedef struct AxisCtx {
    Vec3 axis;
    float exponent;
} AxisCtx;

static Vec3 cosine_sample(const void *c, float u0, float u1, float u2)
{
    (void)u0;
    return sg_sample_cosine_hemisphere(((const AxisCtx *)c)->axis, u1, u2);
}
static float cosine_pdf(const void *c, Vec3 w)
{
    return sg_pdf_cosine_hemisphere(((const AxisCtx *)c)->axis, w);
}
static Vec3 power_sample(const void *c, float u0, float u1, float u2)
{
    (void)u0;
    const AxisCtx *a = c;
    return sg_sample_cosine_power(a->axis, a->exponent, u1, u2);
}
static float power_pdf(const void *c, Vec3 w)
{
    const AxisCtx *a = c;
    return sg_pdf_cosine_power(a->axis, a->exponent, w);
}
static Vec3 glossy_sample(const void *c, float u0, float u1, float u2)
{
    return sg_sample_glossy(c, u0, u1, u2);
}
static float glossy_pdf(const void *c, Vec3 w) { return sg_pdf_glossy(c, w); }
/* The guided bounce's mixture (render/bsdf.h): a BSDF and a folded lobe. */
typedef struct MixtureCtx {
    Bsdf bsdf;
    SgFoldedLobe lobe;
    float alpha;
} MixtureCtx;

static MixtureCtx mixture_of(Bsdf bsdf, Vec3 axis, float exponent, float alpha)
{
    return (MixtureCtx){bsdf, sg_folded_lobe(axis, bsdf.lobe.n, exponent), alpha};
}
/* the Phong BSDF of a glossy lobe (its sampler and pdf need nothing else) */
static Bsdf phong(SgGlossyLobe lobe) { return (Bsdf){.lobe = lobe, .kind = BSDF_PHONG}; }

static Vec3 mixture_sample(const void *c, float u0, float u1, float u2)
{
    const MixtureCtx *m = c;
    return bsdf_mixture_sample(&m->bsdf, &m->lobe, m->alpha, u0, u1, u2);
}
static float mixture_pdf(const void *c, Vec3 w)
{
    const MixtureCtx *m = c;
    float pdf_bsdf, c1, c2;
    return bsdf_mixture_pdf(&m->bsdf, &m->lobe, m->alpha, w, v3_dot(w, m->bsdf.lobe.n), &pdf_bsdf, &c1, &c2);
}

static Vec3 tilted(float x, float y, float z) { return v3_normalize(v3(x, y, z)); }

static void cosine_hemisphere_tilted_case(void)
{
    AxisCtx c = {tilted(0.3f, -0.5f, 0.8f), 0};
    assert_chi2("cosine tilted", cosine_sample, cosine_pdf, &c, 1, 8);
}

static void cosine_hemisphere_facing_minus_z_case(void)
{
    /* the basis construction's singular direction */
    AxisCtx c = {v3(0, 0, -1), 0};
    assert_chi2("cosine -z", cosine_sample, cosine_pdf, &c, 2, 8);
}

static void power_case(float exponent, uint64_t seed, int sub)
{
    char name[64];
    snprintf(name, sizeof name, "cosine power %g", exponent);
    AxisCtx c = {tilted(-0.4f, 0.2f, 0.6f), exponent};
    assert_chi2(name, power_sample, power_pdf, &c, seed, sub);
}


/* The first bin i with u < cdf[i], else the last: by a plain scan. */
static uint32_t scan_bin(const double *cdf, uint32_t n, double u)
{
    for (uint32_t i = 0; i < n; i++)
        if (u < cdf[i])
            return i;
    return n - 1;
}

Test(render_sampling, piecewise_search_finds_the_scans_bin)
{
    /* every size up to past a histogram's 256 bins, with bins of no weight
     * (a repeated sum), sums short of 1 (u past them all) and u on the
     * sums themselves, where an off-by-one would show */
    enum { N_MAX = 300 };
    double cdf[N_MAX], cdff_wide[N_MAX];
    float cdff[N_MAX];
    SgRng rng;
    sg_rng_seed(&rng, 41, 1);
    for (uint32_t n = 1; n <= N_MAX; n++) {
        double sum = 0.0;
        for (uint32_t i = 0; i < n; i++) {
            sum += sg_rng_float(&rng) < 0.3f ? 0.0 : (double)sg_rng_float(&rng);
            cdf[i] = sum;
        }
        double top = sum > 0.0 ? sum : 1.0, scale = sg_rng_float(&rng) < 0.5f ? 1.0 : 0.9;
        for (uint32_t i = 0; i < n; i++) {
            cdf[i] = cdf[i] / top * scale;
            cdff[i] = (float)cdf[i];
            cdff_wide[i] = cdff[i]; /* exact: the float search's sums, for the scan */
        }
        for (int k = 0; k < 64; k++) {
            double u = k < 32 ? (double)sg_rng_float(&rng) : cdf[(uint32_t)k % n];
            cr_assert_eq(sg_piecewise_pick(cdf, n, u), scan_bin(cdf, n, u), "n %u, u %.17g", n, u);
            cr_assert_eq(sg_piecewise_pickf(cdff, n, (float)u), scan_bin(cdff_wide, n, (double)(float)u),
                         "n %u, u %.9g (float)", n, u);
        }
    }
}

Test(render_sampling, cosine_power_10000_narrow_lobe)
{
    /* Too narrow for 80 theta bins: test it with the lobe's own moments.
     * E[cos theta] = (p+1)/(p+2), E[1 - cos theta] = 1/(p+2) exactly. */
    const float p = 10000.0f;
    Vec3 a = tilted(0.1f, 0.9f, -0.3f);
    SgRng rng;
    sg_rng_seed(&rng, 8, 1);
    double sum = 0.0, sum2 = 0.0;
    const int n = SAMPLES;
    for (int i = 0; i < n; i++) {
        Vec3 w = sg_sample_cosine_power(a, p, sg_rng_float(&rng), sg_rng_float(&rng));
        double one_minus = 1.0 - (double)v3_dot(w, a);
        sum += one_minus;
        sum2 += one_minus * one_minus;
        cr_assert(sg_pdf_cosine_power(a, p, w) > 0.0f);
    }
    double mean = sum / n, var = sum2 / n - mean * mean;
    double expected = 1.0 / (p + 2.0);
    /* float directions: 1 - cos is resolved to ~6e-8 per sample, far below
     * the tolerance; the statistical error is sqrt(var/n). */
    cr_assert(fabs(mean - expected) < 4.0 * sqrt(var / n) + 1e-7,
              "E[1-cos] = %.4g, expected %.4g", mean, expected);
}

typedef struct FoldCtx {
    Vec3 axis, n;
    float exponent;
} FoldCtx;
static Vec3 folded_sample(const void *c, float u0, float u1, float u2)
{
    (void)u0;
    const FoldCtx *f = c;
    return sg_sample_folded_lobe(f->axis, f->n, f->exponent, u1, u2);
}
static float folded_pdf(const void *c, Vec3 w)
{
    const FoldCtx *f = c;
    return sg_pdf_folded_lobe(f->axis, f->n, f->exponent, w);
}

static void folded_lobe_grazing_axis_case(void)
{
    /* axis 10 degrees above the surface: half the lobe is folded back */
    FoldCtx c = {tilted(0.98f, 0.0f, 0.17f), v3(0, 0, 1), 8.0f};
    assert_chi2("folded lobe 8 grazing", folded_sample, folded_pdf, &c, 14, 8);
}

static void folded_lobe_axis_below_tilted_normal_case(void)
{
    FoldCtx c = {tilted(-0.3f, 0.5f, -0.2f), tilted(0.1f, 0.7f, 0.3f), 3.0f};
    assert_chi2("folded lobe 3 below", folded_sample, folded_pdf, &c, 15, 8);
}

static void glossy_diffuse_plus_phong_case(void)
{
    Vec3 n = tilted(0.2f, 0.1f, 0.9f);
    Vec3 wo = tilted(0.9f, -0.2f, 0.3f); /* grazing: part of the lobe is below */
    SgGlossyLobe lobe = sg_glossy_lobe(n, wo, 20.0f, 0.4f);
    assert_chi2("glossy kd+ks", glossy_sample, glossy_pdf, &lobe, 9, 8);
}

static void glossy_pure_phong_200_case(void)
{
    Vec3 n = v3(0, 0, 1);
    Vec3 wo = tilted(-0.5f, 0.3f, 0.7f);
    SgGlossyLobe lobe = sg_glossy_lobe(n, wo, 200.0f, 0.0f);
    assert_chi2("glossy phong 200", glossy_sample, glossy_pdf, &lobe, 10, 16);
}

static void mixture_half_case(void)
{
    Vec3 n = tilted(0.0f, -0.3f, 1.0f);
    MixtureCtx m = mixture_of(phong(sg_glossy_lobe(n, tilted(0.3f, 0.3f, 0.9f), 0.0f, 1.0f)),
                              tilted(0.7f, 0.1f, 0.2f), 30.0f, 0.5f);
    assert_chi2("mixture 0.5 diffuse + lobe 30", mixture_sample, mixture_pdf, &m, 11, 8);
}

static void mixture_glossy_small_alpha_case(void)
{
    Vec3 n = v3(0, 1, 0);
    MixtureCtx m = mixture_of(phong(sg_glossy_lobe(n, tilted(0.5f, 0.5f, 0.1f), 50.0f, 0.3f)),
                              tilted(-0.6f, 0.3f, -0.5f), 4.0f, 0.1f);
    assert_chi2("mixture 0.1 glossy + lobe 4", mixture_sample, mixture_pdf, &m, 12, 8);
}

static void mixture_lobe_axis_below_surface_keeps_support_case(void)
{
    /* The lobe points into the surface: the mixture still samples the
     * whole upper hemisphere through its BSDF part. */
    Vec3 n = v3(1, 0, 0);
    MixtureCtx m = mixture_of(phong(sg_glossy_lobe(n, tilted(1, 1, 0), 0.0f, 1.0f)), tilted(-1, 0.2f, 0.1f),
                              10.0f, 0.5f);
    assert_chi2("mixture lobe below", mixture_sample, mixture_pdf, &m, 13, 8);
}

/* ---- the microfacet BSDFs (render/bsdf.h) ------------------------------- */

static Vec3 bsdf_sample_fn(const void *c, float u0, float u1, float u2) { return bsdf_sample(c, u0, u1, u2); }
static float bsdf_pdf_fn(const void *c, Vec3 w) { return bsdf_pdf(c, w); }

/* A conductor (gold's index) or a coated diffuse of GGX alpha (ax, ay). */
static Bsdf microfacet_bsdf(SgMaterialType type, float ax, float ay, Vec3 n, Vec3 wo)
{
    SgMaterial sm;
    sg_material_default(&sm, "test");
    sm.type = type;
    sm.roughness[0] = ax;
    sm.roughness[1] = ay;
    const float eta[3] = {0.143f, 0.375f, 1.44f}, k[3] = {3.98f, 2.39f, 1.60f}, kd[3] = {0.6f, 0.4f, 0.2f};
    memcpy(sm.eta, eta, sizeof eta);
    memcpy(sm.k, k, sizeof k);
    memcpy(sm.diffuse, kd, sizeof kd);
    Material m;
    material_init(&m, &sm);
    Bsdf b;
    bsdf_init(&b, &m, n, wo, m.kd);
    return b;
}

static void conductor_case(float ax, float ay, Vec3 n, Vec3 wo, uint64_t seed, int sub)
{
    char name[64];
    snprintf(name, sizeof name, "conductor GGX %g x %g", ax, ay);
    Bsdf b = microfacet_bsdf(SG_MATERIAL_CONDUCTOR, ax, ay, n, wo);
    assert_chi2(name, bsdf_sample_fn, bsdf_pdf_fn, &b, seed, sub);
}

static void coated_case(float alpha, Vec3 n, Vec3 wo, uint64_t seed, int sub)
{
    char name[64];
    snprintf(name, sizeof name, "coated diffuse GGX %g", alpha);
    Bsdf b = microfacet_bsdf(SG_MATERIAL_COATED_DIFFUSE, alpha, alpha, n, wo);
    assert_chi2(name, bsdf_sample_fn, bsdf_pdf_fn, &b, seed, sub);
}

static void mixture_conductor_case(void)
{
    /* the guide's lobe beside a rough conductor's GGX lobe */
    Vec3 n = tilted(0.2f, 0.0f, 1.0f);
    MixtureCtx m = mixture_of(microfacet_bsdf(SG_MATERIAL_CONDUCTOR, 0.2f, 0.2f, n, tilted(-0.5f, 0.4f, 0.7f)),
                              tilted(0.6f, -0.2f, 0.5f), 16.0f, 0.5f);
    assert_chi2("mixture 0.5 conductor 0.2 + lobe 16", mixture_sample, mixture_pdf, &m, 22, 16);
}

/* Diffuse transmission (render/bsdf.h): both hemispheres. */
static Vec3 diffuse_transmission_sample(const void *c, float u0, float u1, float u2)
{
    return bsdf_diffuse_sample(c, u0, u1, u2);
}
static float diffuse_transmission_pdf(const void *c, Vec3 w) { return bsdf_diffuse_pdf(c, w); }

static void diffuse_transmission_case(Vec3 r, Vec3 t, Vec3 n, uint64_t seed)
{
    DiffuseTransmission d = bsdf_diffuse_transmission(n, r, t);
    assert_chi2("diffuse transmission", diffuse_transmission_sample, diffuse_transmission_pdf, &d, seed, 8);
}

/* A rough dielectric (render/microfacet.h) in its own frame: wo above,
 * eta > 1 entering glass, < 1 leaving it (total internal reflection). */
typedef struct DielectricCtx {
    Vec3 wo;
    float eta, ax, ay;
} DielectricCtx;

static Vec3 dielectric_sample(const void *c, float u0, float u1, float u2)
{
    const DielectricCtx *d = c;
    Vec3 wi;
    float weight, pdf;
    if (!sg_ggx_dielectric_sample(d->wo, d->eta, d->ax, d->ay, u0, u1, u2, &wi, &weight, &pdf))
        return v3(0, 0, 0);
    /* the weight the renderer multiplies by is f |cos| / pdf */
    float expected = sg_ggx_dielectric_f(d->wo, wi, d->eta, d->ax, d->ay) * fabsf(wi.z) / pdf;
    cr_expect(fabsf(weight - expected) <= 1e-3f * fmaxf(1.0f, expected), "weight %g, f cos / pdf %g", weight,
              expected);
    return wi;
}

static float dielectric_pdf(const void *c, Vec3 w)
{
    const DielectricCtx *d = c;
    return sg_ggx_dielectric_pdf(d->wo, w, d->eta, d->ax, d->ay);
}

static void dielectric_case(float eta, float ax, float ay, Vec3 wo, uint64_t seed, int sub)
{
    char name[64];
    snprintf(name, sizeof name, "dielectric %g GGX %g x %g", eta, ax, ay);
    DielectricCtx d = {wo, eta, ax, ay};
    assert_chi2_of(name, dielectric_sample, dielectric_pdf, &d, seed, sub, true);
}

/* ---- the chi-square tests: one list declares them and counts them ------ */

/* ---- the sky and the sun (render/environment.h, render/lights.h) ------------ */

static Vec3 environment_sample_fn(const void *c, float u0, float u1, float u2)
{
    (void)u2;
    float pdf;
    return environment_sample(c, u0, u1, &pdf);
}
static float environment_pdf_fn(const void *c, Vec3 w) { return environment_pdf(c, w); }

/* A map with a smooth gradient, a dark band and a bright small sun, in
 * either layout, turned so that its pole is not the world's z. */
static void environment_case(SgEnvironmentLayout layout, int width, int height, uint64_t seed, int sub)
{
    float *rgb = malloc(sizeof(float) * 3 * width * height);
    for (int y = 0; y < height; y++)
        for (int x = 0; x < width; x++) {
            float *t = rgb + 3 * ((size_t)y * width + x);
            float g = 0.2f + (float)x / width + 0.5f * (float)y / height;
            if (y == height / 3)
                g = 0.0f; /* never drawn where it is black */
            if (x == width / 4 && y == height / 5)
                g = 40.0f;
            t[0] = g, t[1] = 0.8f * g, t[2] = 0.5f * g + 0.05f;
        }
    const double turn[3][3] = {{0.8, 0, -0.6}, {0, 1, 0}, {0.6, 0, 0.8}};
    Environment e;
    SgError err = {0};
    cr_assert(environment_init(&e, rgb, width, height, layout, (const float[3]){1, 1, 1}, turn, "test", &err), "%s",
              err.message);
    free(rgb);
    assert_chi2(layout == SG_ENVIRONMENT_LATLONG ? "lat-long sky" : "equal-area sky", environment_sample_fn,
                environment_pdf_fn, &e, seed, sub);
    environment_free(&e);
}

/* A light source's light samples from the origin, with a portal share. */
typedef struct SourceAt {
    const LightSet *ls;
    float portal_share;
} SourceAt;

static Vec3 source_sample_fn(const void *c, float u0, float u1, float u2)
{
    const SourceAt *at = c;
    LightSourcePoint lp;
    cr_assert(light_source_sample(at->ls, 0, v3(0, 0, 0), at->portal_share, u2, u0, u1, &lp));
    return lp.wi;
}
static float source_pdf_fn(const void *c, Vec3 w)
{
    const SourceAt *at = c;
    return light_source_pdf(at->ls, 0, v3(0, 0, 0), w, at->portal_share);
}

/* A constant sky seen through a portal (a 1 x 0.6 window 2 above, tilted)
 * from the origin: the portal's density mixed with the sky's, with the
 * default share (< 0) or the one given. */
static void portal_case(float portal_share, uint64_t seed, int sub)
{
    LightSource src = {.kind = SG_LIGHT_INFINITE, .rgb = v3(1, 1, 1), .pick_pdf = 1.0};
    LightSet ls = {.source_count = 1, .sources = &src, .has_escaping = true};
    const Vec3 corners[1][4] = {{v3(-0.5f, 2.0f, -0.3f), v3(0.5f, 2.2f, -0.3f), v3(0.5f, 2.2f, 0.3f),
                                 v3(-0.5f, 2.0f, 0.3f)}};
    cr_assert(light_source_set_portals(&ls, 0, corners, 1));
    SourceAt at = {&ls, portal_share};
    assert_chi2("sky through a portal", source_sample_fn, source_pdf_fn, &at, seed, sub);
    free(src.portals);
}

/* A constant sky (uniform sphere) or a sun of angular radius `radius`. */
static void source_case(SgLightSourceKind kind, float radius, uint64_t seed, int sub)
{
    LightSource src = {.kind = kind, .rgb = v3(1, 1, 1), .direction = tilted(0.3f, -1.0f, 0.2f),
                       .sun_sin2 = sinf(radius) * sinf(radius),
                       .sun_one_minus_cos = 2.0f * sinf(0.5f * radius) * sinf(0.5f * radius), .pick_pdf = 1.0};
    LightSet ls = {.source_count = 1, .sources = &src, .has_escaping = true};
    SourceAt at = {&ls, -1.0f};
    assert_chi2(kind == SG_LIGHT_INFINITE ? "constant sky" : "sun disk", source_sample_fn, source_pdf_fn, &at, seed,
                sub);
}

static Vec3 histogram_sample_fn(const void *c, float u0, float u1, float u2)
{
    (void)u2;
    return sg_mixture_histogram_sample(c, u0, u1);
}
static float histogram_pdf_fn(const void *c, Vec3 w) { return sg_mixture_histogram_pdf(c, w); }

/* A guided region's learned histogram of directions (equal-area bins):
 * two bright bins, a gradient, and a row of bins no light came from. */
static void histogram_case(uint64_t seed, int sub)
{
    float cdf[SG_MIXTURE_BINS];
    double sum = 0.0;
    for (int b = 0; b < SG_MIXTURE_BINS; b++) {
        int x = b % SG_MIXTURE_HIST_RES, y = b / SG_MIXTURE_HIST_RES;
        double w = y == 3 ? 0.0 : 0.1 + 0.05 * x + (b == 37 || b == 200 ? 30.0 : 0.0);
        cdf[b] = (float)(sum += w);
    }
    for (int b = 0; b < SG_MIXTURE_BINS; b++)
        cdf[b] = (float)(cdf[b] / sum);
    cdf[SG_MIXTURE_BINS - 1] = 1.0f;
    assert_chi2("learned histogram", histogram_sample_fn, histogram_pdf_fn, cdf, seed, sub);
}

#define CHI2_CASES(X) \
    X(cosine_hemisphere_tilted, cosine_hemisphere_tilted_case()) \
    X(cosine_hemisphere_facing_minus_z, cosine_hemisphere_facing_minus_z_case()) \
    X(cosine_power_0_uniform, power_case(0.0f, 3, 8)) \
    X(cosine_power_1, power_case(1.0f, 4, 8)) \
    X(cosine_power_10, power_case(10.0f, 5, 8)) \
    X(cosine_power_100, power_case(100.0f, 6, 16)) \
    X(cosine_power_1000, power_case(1000.0f, 7, 32)) \
    X(folded_lobe_grazing_axis, folded_lobe_grazing_axis_case()) \
    X(folded_lobe_axis_below_tilted_normal, folded_lobe_axis_below_tilted_normal_case()) \
    X(glossy_diffuse_plus_phong, glossy_diffuse_plus_phong_case()) \
    X(glossy_pure_phong_200, glossy_pure_phong_200_case()) \
    X(mixture_half, mixture_half_case()) \
    X(mixture_glossy_small_alpha, mixture_glossy_small_alpha_case()) \
    X(mixture_lobe_axis_below_surface_keeps_support, mixture_lobe_axis_below_surface_keeps_support_case()) \
    X(conductor_ggx_0_3, conductor_case(0.3f, 0.3f, tilted(0.1f, -0.2f, 1.0f), tilted(0.4f, 0.3f, 0.8f), 16, 8)) \
    X(conductor_ggx_1_0_grazing, conductor_case(1.0f, 1.0f, v3(0, 0, 1), tilted(0.95f, 0.0f, 0.1f), 17, 8)) \
    X(conductor_ggx_anisotropic_grazing, \
      conductor_case(0.08f, 0.4f, v3(0, 1, 0), tilted(0.3f, 0.15f, -0.9f), 18, 16)) \
    X(conductor_ggx_0_05_narrow, conductor_case(0.05f, 0.05f, v3(0, 0, 1), tilted(-0.3f, 0.2f, 0.9f), 19, 32)) \
    X(coated_diffuse_ggx_0_2, coated_case(0.2f, tilted(-0.2f, 0.1f, 1.0f), tilted(0.5f, 0.5f, 0.6f), 20, 16)) \
    X(mixture_conductor, mixture_conductor_case()) \
    X(coated_diffuse_ggx_0_1_grazing, coated_case(0.1f, v3(0, 0, 1), tilted(0.97f, 0.1f, 0.08f), 21, 16)) \
    X(dielectric_entering_ggx_0_3, dielectric_case(1.5f, 0.3f, 0.3f, tilted(0.4f, 0.3f, 0.8f), 23, 8)) \
    X(dielectric_leaving_ggx_0_2_total_reflection, \
      dielectric_case(1.0f / 1.5f, 0.2f, 0.2f, tilted(0.8f, -0.1f, 0.5f), 24, 16)) \
    X(dielectric_entering_ggx_0_6_grazing, dielectric_case(1.33f, 0.6f, 0.6f, tilted(0.95f, 0.1f, 0.12f), 25, 32)) \
    X(dielectric_anisotropic_ggx, dielectric_case(1.5f, 0.05f, 0.3f, tilted(-0.3f, 0.5f, 0.8f), 26, 32)) \
    X(sky_equal_area_map, environment_case(SG_ENVIRONMENT_EQUAL_AREA, 24, 24, 27, 16)) \
    X(sky_latlong_map, environment_case(SG_ENVIRONMENT_LATLONG, 32, 16, 28, 16)) \
    X(sky_constant, source_case(SG_LIGHT_INFINITE, 0.0f, 29, 4)) \
    X(sun_disk_10_degrees, source_case(SG_LIGHT_DISTANT, 0.17453f, 30, 32)) \
    X(sky_through_portal, portal_case(-1.0f, 31, 32)) \
    X(sky_through_portal_nearly_always, portal_case(0.99f, 34, 32)) \
    X(sky_through_portal_half_the_time, portal_case(0.5f, 35, 32)) \
    X(learned_histogram, histogram_case(32, 16)) \
    X(diffuse_transmission_tilted, \
      diffuse_transmission_case(v3(0.3f, 0.3f, 0.3f), v3(0.5f, 0.4f, 0.6f), tilted(0.3f, -0.5f, 0.8f), 36)) \
    X(diffuse_transmission_mostly_reflecting, \
      diffuse_transmission_case(v3(0.9f, 0.8f, 0.9f), v3(0.05f, 0.05f, 0.05f), v3(0, 1, 0), 37))

#define CHI2_TEST(name, call) \
    Test(render_sampling, name) { call; }
CHI2_CASES(CHI2_TEST)

#define CHI2_COUNT(name, call) +1
static int chi2_test_count(void) { return 0 CHI2_CASES(CHI2_COUNT); }
