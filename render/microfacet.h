/* Trowbridge-Reitz (GGX) microfacets as pbrt-v4 defines them, in a local
 * frame whose z is the surface normal: the distribution of normals D, the
 * masking G (Smith, height-correlated), sampling by visible normals (Heitz
 * 2018, "Sampling the GGX distribution of visible normals"), and the
 * Fresnel terms of a dielectric and of a conductor (complex index). */
#ifndef SG_RENDER_MICROFACET_H
#define SG_RENDER_MICROFACET_H

#include <complex.h>
#include <math.h>
#include <stdbool.h>

#include "sampling.h"
#include "vecmath.h"

/* Below this alpha pbrt-v4 treats a surface as smooth (a delta lobe). */
#define SG_GGX_SMOOTH_ALPHA 1e-3f

/* D(h) for h.z > 0 (0 otherwise). */
static inline float sg_ggx_d(Vec3 h, float ax, float ay)
{
    if (!(h.z > 0.0f))
        return 0.0f;
    float x = h.x / ax, y = h.y / ay;
    float d = x * x + y * y + h.z * h.z;
    return 1.0f / (SG_PI * ax * ay * d * d);
}

/* Smith's Lambda(w). */
static inline float sg_ggx_lambda(Vec3 w, float ax, float ay)
{
    float z2 = w.z * w.z;
    if (!(z2 > 0.0f))
        return INFINITY;
    float t2 = (ax * ax * w.x * w.x + ay * ay * w.y * w.y) / z2;
    return 0.5f * (sqrtf(1.0f + t2) - 1.0f);
}

static inline float sg_ggx_g1(Vec3 w, float ax, float ay) { return 1.0f / (1.0f + sg_ggx_lambda(w, ax, ay)); }

static inline float sg_ggx_g(Vec3 wo, Vec3 wi, float ax, float ay)
{
    return 1.0f / (1.0f + sg_ggx_lambda(wo, ax, ay) + sg_ggx_lambda(wi, ax, ay));
}

/* A microfacet normal visible from wo (wo.z > 0), from u1, u2 in [0, 1). */
Vec3 sg_ggx_sample_visible(Vec3 wo, float ax, float ay, float u1, float u2);

/* Density of wi = reflect(wo, h) when h is drawn by sg_ggx_sample_visible:
 * D_wo(h) / (4 wo.h) = G1(wo) D(h) / (4 wo.z), over the whole sphere (a
 * reflection below the surface has its density too; 0 where no h gives wi). */
static inline float sg_ggx_pdf_reflect(Vec3 wo, Vec3 wi, float ax, float ay)
{
    Vec3 h = v3_add(wo, wi);
    float l = v3_length(h);
    if (!(l > 0.0f))
        return 0.0f;
    h = v3_scale(h, 1.0f / l);
    if (!(h.z > 0.0f) || !(v3_dot(wo, h) > 0.0f))
        return 0.0f;
    return sg_ggx_g1(wo, ax, ay) * sg_ggx_d(h, ax, ay) / (4.0f * wo.z);
}

/* Unpolarized Fresnel reflectance of a dielectric of relative index eta
 * (inside over outside) seen at cos_i from outside (cos_i < 0: from inside). */
static inline float sg_fresnel_dielectric(float cos_i, float eta)
{
    cos_i = sg_minf(sg_maxf(cos_i, -1.0f), 1.0f);
    if (cos_i < 0.0f) {
        eta = 1.0f / eta;
        cos_i = -cos_i;
    }
    float sin2_t = (1.0f - cos_i * cos_i) / (eta * eta);
    if (sin2_t >= 1.0f)
        return 1.0f; /* total internal reflection */
    float cos_t = sqrtf(1.0f - sin2_t);
    float r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    float r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return 0.5f * (r_parl * r_parl + r_perp * r_perp);
}

/* Unpolarized Fresnel reflectance of a conductor of complex index eta + i k
 * at cos_i in [0, 1] (pbrt-v4's FrComplex). */
static inline float sg_fresnel_conductor(float cos_i, float eta, float k)
{
    cos_i = sg_minf(sg_maxf(cos_i, 0.0f), 1.0f);
    float complex e = eta + k * I;
    float complex sin2_t = (1.0f - cos_i * cos_i) / (e * e);
    float complex cos_t = csqrtf(1.0f - sin2_t);
    float complex r_parl = (e * cos_i - cos_t) / (e * cos_i + cos_t);
    float complex r_perp = (cos_i - e * cos_t) / (cos_i + e * cos_t);
    float a = cabsf(r_parl), b = cabsf(r_perp);
    return 0.5f * (a * a + b * b);
}

static inline Vec3 sg_fresnel_conductor3(float cos_i, Vec3 eta, Vec3 k)
{
    return v3(sg_fresnel_conductor(cos_i, eta.x, k.x), sg_fresnel_conductor(cos_i, eta.y, k.y),
              sg_fresnel_conductor(cos_i, eta.z, k.z));
}

/* A rough dielectric interface (pbrt-v4's DielectricBxDF with alpha > 0),
 * in the frame of the normal on wo's side (wo.z > 0); eta is the index
 * beyond the surface over the index on wo's side. It reflects F(wo.h) and
 * transmits the rest through the microfacet h (the generalized half vector
 * of wo and wi); transmitted radiance is scaled by 1 / eta^2 (it is
 * compressed entering a denser medium). f and pdf cover the whole sphere. */
float sg_ggx_dielectric_f(Vec3 wo, Vec3 wi, float eta, float ax, float ay);
float sg_ggx_dielectric_pdf(Vec3 wo, Vec3 wi, float eta, float ax, float ay);
/* Draws wi from the density above: a visible microfacet from u1, u2, then
 * reflection with probability F, refraction otherwise (uc). Returns false
 * where the drawn microfacet sends wi to the wrong side (the path ends:
 * that mass is what the pdf misses from 1). *weight = f |wi.z| / pdf, which
 * for this sampler is G(wo, wi) / G1(wo), over eta^2 when transmitted;
 * *pdf its density (for a guide's record). */
bool sg_ggx_dielectric_sample(Vec3 wo, float eta, float ax, float ay, float uc, float u1, float u2, Vec3 *wi,
                              float *weight, float *pdf);

/* Cosine-weighted hemispherical average of the dielectric Fresnel
 * reflectance seen from inside a medium of index eta (light leaving a
 * coat, diffusely lit): 2 int_0^1 F(-mu) mu dmu, by quadrature. */
float sg_fresnel_diffuse_internal(float eta);

#endif
