/* Sampling routines of the renderer: directions, each with its pdf (solid
 * angle measure, over the whole sphere; vectors are unit length), and
 * piecewise-constant distributions over bins (lights by power, a sky's
 * texels, the learner's histograms). Every sample routine draws from the
 * density its pdf function returns: the chi-square tests in
 * tests/test_render_sampling.c hold them to it. */
#ifndef SG_RENDER_SAMPLING_H
#define SG_RENDER_SAMPLING_H

#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#include "vecmath.h"

#ifdef __cplusplus
extern "C" {
#endif

#define SG_PI 3.14159265358979323846f
#define SG_INV_PI 0.31830988618379067154f

/* Veach's power heuristic (beta 2): the MIS weight of a sample drawn with
 * pdf a against another strategy's pdf b at the same direction. */
static inline float sg_power_heuristic(float a, float b)
{
    float a2 = a * a, b2 = b * b;
    return a2 + b2 > 0.0f ? a2 / (a2 + b2) : 0.0f;
}

/* Maps a local direction (z = axis) into the frame around unit `axis`. */
Vec3 sg_to_world(Vec3 local, Vec3 axis);
/* The inverse: a world direction in that frame (v3_basis(axis), axis). */
Vec3 sg_to_local(Vec3 world, Vec3 axis);

/* Cosine-weighted hemisphere around unit n: pdf = max(0, w.n) / pi. */
Vec3 sg_sample_cosine_hemisphere(Vec3 n, float u1, float u2);
static inline float sg_pdf_cosine_hemisphere(Vec3 n, Vec3 w);

/* Cosine-power lobe around unit axis a, exponent p >= 0 (0 = uniform
 * hemisphere): pdf = (p + 1) / (2 pi) max(0, w.a)^p. Accurate up to p = 1e4
 * and beyond (sin theta is computed without cancellation). */
Vec3 sg_sample_cosine_power(Vec3 a, float p, float u1, float u2);
static inline float sg_pdf_cosine_power(Vec3 a, float p, Vec3 w);

/* The cosine-power lobe folded onto the hemisphere of n: a lobe sample
 * below the surface is mirrored across it, so that no sample is wasted
 * where a reflective BSDF is zero. pdf(w) = lobe(a, w) + lobe(a', w) for
 * w.n > 0 (a' = a mirrored across the surface), 0 below. */
Vec3 sg_sample_folded_lobe(Vec3 a, Vec3 n, float p, float u1, float u2);
static inline float sg_pdf_folded_lobe(Vec3 a, Vec3 n, float p, Vec3 w);

/* The folded lobe's density made ready for a vertex, where it is evaluated
 * at several directions (the guided bounce: the light sample's and its own):
 * a.n, the normalization and the way to raise to p are computed once. */
typedef struct SgFoldedLobe {
    Vec3 axis;
    float axis_n;   /* a.n: the mirrored axis's cosine is w.a - 2 (a.n)(w.n) */
    float exponent;
    float norm;     /* (p + 1) / (2 pi) */
    int squarings;  /* p = 2^squarings, or -1 */
} SgFoldedLobe;

static inline SgFoldedLobe sg_folded_lobe(Vec3 a, Vec3 n, float p);
/* pdf at w, given wn = w.n; c1, c2 get w's cosines with a and a'. */
static inline float sg_pdf_folded_lobe_at(const SgFoldedLobe *l, Vec3 w, float wn, float *c1, float *c2);

/* The non-delta BSDF of the renderer's diffuse and glossy materials:
 *   f(wo, wi) = kd / pi + ks (p + 2) / (2 pi) max(0, wi.r)^p,  r = reflect(wo, n),
 * for wi above the surface (n faces wo), zero below. kd + ks <= 1 per channel
 * conserves energy (normalized Phong; Lafortune & Willems 1994).
 * Sampling: the diffuse part with probability `diffuse_weight`, the Phong
 * lobe around r otherwise; a lobe sample below the surface is a valid
 * direction with f = 0 (so the pdf below is a density on the whole sphere). */
typedef struct SgGlossyLobe {
    Vec3 n;               /* shading normal, on wo's side */
    Vec3 r;               /* mirror direction of wo about n */
    float exponent;       /* Phong exponent (0 if no glossy part) */
    float diffuse_weight; /* probability of sampling the diffuse part, in [0, 1] */
} SgGlossyLobe;

SgGlossyLobe sg_glossy_lobe(Vec3 n, Vec3 wo, float exponent, float diffuse_weight);
Vec3 sg_sample_glossy(const SgGlossyLobe *lobe, float u0, float u1, float u2);
static inline float sg_pdf_glossy(const SgGlossyLobe *lobe, Vec3 w);

/* k when p = 2^k with 0 <= k <= 6 (c^p is then k squarings), else -1. */
static inline int sg_exponent_squarings(float p)
{
    int32_t bits;
    memcpy(&bits, &p, sizeof bits);
    int k = (bits >> 23) - 127; /* p = 2^k when the mantissa is zero (p > 0) */
    return (bits & 0x007fffff) == 0 && k >= 0 && k <= 6 ? k : -1;
}

/* c^p for c in [0, 1]: by squaring when p is a small whole number (the
 * usual lobe exponents; a power of two, as the learner's 4, 16 and 64, in
 * log2(p) products), powf otherwise. */
static inline float sg_pow_exponent(float c, float p)
{
    int k = sg_exponent_squarings(p);
    if (k >= 0) {
        for (; k; k--)
            c *= c;
        return c;
    }
    if (p >= 0.0f && p <= 64.0f && p == (float)(int)p) {
        float r = 1.0f, b = c;
        for (int e = (int)p; e; e >>= 1) {
            if (e & 1)
                r *= b;
            b *= b;
        }
        return r;
    }
    return powf(c, p);
}
/* Reflection of wo (pointing away from the surface) about n. */
static inline Vec3 sg_reflect(Vec3 wo, Vec3 n)
{
    return v3_sub(v3_scale(n, 2.0f * v3_dot(wo, n)), wo);
}

/* The densities are inline: every bounce evaluates two or three. */
static inline float sg_pdf_cosine_hemisphere(Vec3 n, Vec3 w)
{
    return sg_maxf(0.0f, v3_dot(n, w)) * SG_INV_PI;
}

static inline float sg_pdf_cosine_power(Vec3 a, float p, Vec3 w)
{
    float c = v3_dot(a, w);
    if (c <= 0.0f)
        return 0.0f;
    return (p + 1.0f) * (0.5f * SG_INV_PI) * sg_pow_exponent(sg_minf(c, 1.0f), p);
}

static inline float sg_pdf_glossy(const SgGlossyLobe *lobe, Vec3 w)
{
    float pd = lobe->diffuse_weight;
    float pdf = 0.0f;
    if (pd > 0.0f)
        pdf += pd * sg_pdf_cosine_hemisphere(lobe->n, w);
    if (pd < 1.0f)
        pdf += (1.0f - pd) * sg_pdf_cosine_power(lobe->r, lobe->exponent, w);
    return pdf;
}

static inline SgFoldedLobe sg_folded_lobe(Vec3 a, Vec3 n, float p)
{
    return (SgFoldedLobe){a, v3_dot(a, n), p, (p + 1.0f) * (0.5f * SG_INV_PI), sg_exponent_squarings(p)};
}

/* w's cosines with a and with a' = a - 2 (a.n) n, the axis mirrored across
 * the surface: a'.w = a.w - 2 (a.n)(n.w). */
static inline void sg_folded_cosines(Vec3 a, Vec3 n, Vec3 w, float *c1, float *c2)
{
    *c1 = v3_dot(a, w);
    *c2 = *c1 - 2.0f * v3_dot(a, n) * v3_dot(w, n);
}

/* The mirrored axis a' = a - 2 (a.n) n gives a'.w = a.w - 2 (a.n)(n.w). */
static inline float sg_pdf_folded_lobe_at(const SgFoldedLobe *l, Vec3 w, float wn, float *c1, float *c2)
{
    *c1 = v3_dot(l->axis, w);
    *c2 = *c1 - 2.0f * l->axis_n * wn;
    if (!(wn > 0.0f))
        return 0.0f;
    float a = sg_minf(sg_maxf(*c1, 0.0f), 1.0f), b = sg_minf(sg_maxf(*c2, 0.0f), 1.0f);
    if (l->squarings >= 0) { /* p >= 1: a cosine below zero adds 0^p = 0 */
        for (int k = l->squarings; k; k--) {
            a *= a;
            b *= b;
        }
        return l->norm * (a + b);
    }
    return l->norm * ((*c1 > 0.0f ? sg_pow_exponent(a, l->exponent) : 0.0f) +
                      (*c2 > 0.0f ? sg_pow_exponent(b, l->exponent) : 0.0f));
}

static inline float sg_pdf_folded_lobe(Vec3 a, Vec3 n, float p, Vec3 w)
{
    SgFoldedLobe l = sg_folded_lobe(a, n, p);
    float c1, c2;
    return sg_pdf_folded_lobe_at(&l, w, v3_dot(w, n), &c1, &c2);
}

/* ---- piecewise-constant distributions -------------------------------------
 * A distribution over n bins held as its running sums: cdf[i] is the weight
 * of bins 0..i, cdf[n - 1] the total (1 where normalized). Doubles for the
 * lights and the sky, floats for the learner's histograms: one search. */
typedef struct SgPiecewise1D {
    const double *cdf;
    uint32_t n;
} SgPiecewise1D;

/* A 2D distribution over width x height cells, row by row: the rows'
 * running sums (normalized), then within each row its cells' (normalized). */
typedef struct SgPiecewise2D {
    const double *row_cdf; /* height */
    const double *col_cdf; /* height x width */
    uint32_t width, height;
} SgPiecewise2D;

/* The bin i with cdf[i - 1] <= u < cdf[i] (binary search; the last bin
 * where u is past every sum). */
#define SG_PIECEWISE_SEARCH(cdf, n, u)          \
    do {                                        \
        uint32_t lo_ = 0, hi_ = (n) - 1;        \
        while (lo_ < hi_) {                     \
            uint32_t mid_ = (lo_ + hi_) / 2;    \
            if ((u) < (cdf)[mid_])              \
                hi_ = mid_;                     \
            else                                \
                lo_ = mid_ + 1;                 \
        }                                       \
        return lo_;                             \
    } while (0)

static inline uint32_t sg_piecewise_pick(const double *cdf, uint32_t n, double u) { SG_PIECEWISE_SEARCH(cdf, n, u); }
static inline uint32_t sg_piecewise_pickf(const float *cdf, uint32_t n, float u) { SG_PIECEWISE_SEARCH(cdf, n, u); }

/* Bin i's weight. */
static inline double sg_piecewise_mass(const double *cdf, uint32_t i) { return cdf[i] - (i ? cdf[i - 1] : 0.0); }
static inline float sg_piecewise_massf(const float *cdf, uint32_t i) { return cdf[i] - (i ? cdf[i - 1] : 0.0f); }

/* The bin u falls in, and in *within where in it u fell ([0, 1]; 0.5 in a
 * bin of no weight). */
static inline uint32_t sg_piecewise1d_sample(SgPiecewise1D d, double u, double *within)
{
    uint32_t i = sg_piecewise_pick(d.cdf, d.n, u);
    double lo = i ? d.cdf[i - 1] : 0.0, span = d.cdf[i] - lo;
    *within = span > 0.0 ? (u - lo) / span : 0.5;
    return i;
}

static inline uint32_t sg_piecewise_samplef(const float *cdf, uint32_t n, float u, float *within)
{
    uint32_t i = sg_piecewise_pickf(cdf, n, u);
    float lo = i ? cdf[i - 1] : 0.0f, span = cdf[i] - lo;
    *within = span > 0.0f ? (u - lo) / span : 0.5f;
    return i;
}

/* The cell (x, y) (u1 picks the row, u2 the cell within it), and where in
 * it the two fell (fx, fy, as sg_piecewise1d_sample's `within`). */
static inline void sg_piecewise2d_sample(const SgPiecewise2D *d, double u1, double u2, uint32_t *x, uint32_t *y,
                                         double *fx, double *fy)
{
    *y = sg_piecewise1d_sample((SgPiecewise1D){d->row_cdf, d->height}, u1, fy);
    *x = sg_piecewise1d_sample((SgPiecewise1D){d->col_cdf + (size_t)*y * d->width, d->width}, u2, fx);
}

#ifdef __cplusplus
}
#endif
#endif
