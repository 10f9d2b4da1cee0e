#include "sampling.h"

#include <math.h>

Vec3 sg_to_world(Vec3 local, Vec3 axis)
{
    Vec3 t, b;
    v3_basis(axis, &t, &b);
    return v3_add(v3_add(v3_scale(t, local.x), v3_scale(b, local.y)), v3_scale(axis, local.z));
}

Vec3 sg_sample_cosine_hemisphere(Vec3 n, float u1, float u2)
{
    /* Malley: uniform on the disk, projected up. */
    float r = sqrtf(u1);
    float phi = 2.0f * SG_PI * u2;
    float z = sqrtf(fmaxf(0.0f, 1.0f - u1));
    return sg_to_world(v3(r * cosf(phi), r * sinf(phi), z), n);
}

float sg_pdf_cosine_hemisphere(Vec3 n, Vec3 w)
{
    return fmaxf(0.0f, v3_dot(n, w)) * SG_INV_PI;
}

Vec3 sg_sample_cosine_power(Vec3 a, float p, float u1, float u2)
{
    /* cos theta = u^(1/(p+1)), with u = 1 - u1 in (0, 1]. In logs so that
     * sin theta keeps its digits when the lobe is narrow (p up to 1e4+). */
    double l = log1p(-(double)u1) / ((double)p + 1.0); /* log cos theta, <= 0 */
    double cos_t = exp(l);
    double sin_t = sqrt(fmax(0.0, -expm1(2.0 * l)));
    double phi = 2.0 * M_PI * (double)u2;
    Vec3 local = v3((float)(sin_t * cos(phi)), (float)(sin_t * sin(phi)), (float)cos_t);
    return sg_to_world(local, a);
}

float sg_pdf_cosine_power(Vec3 a, float p, Vec3 w)
{
    float c = v3_dot(a, w);
    if (c <= 0.0f)
        return 0.0f;
    return (p + 1.0f) * (0.5f * SG_INV_PI) * powf(fminf(c, 1.0f), p);
}

SgGlossyLobe sg_glossy_lobe(Vec3 n, Vec3 wo, float exponent, float diffuse_weight)
{
    SgGlossyLobe lobe;
    lobe.n = n;
    lobe.r = v3_normalize(sg_reflect(wo, n));
    lobe.exponent = exponent;
    lobe.diffuse_weight = diffuse_weight;
    return lobe;
}

Vec3 sg_sample_glossy(const SgGlossyLobe *lobe, float u0, float u1, float u2)
{
    if (u0 < lobe->diffuse_weight)
        return sg_sample_cosine_hemisphere(lobe->n, u1, u2);
    return sg_sample_cosine_power(lobe->r, lobe->exponent, u1, u2);
}

float sg_pdf_glossy(const SgGlossyLobe *lobe, Vec3 w)
{
    float pd = lobe->diffuse_weight;
    float pdf = 0.0f;
    if (pd > 0.0f)
        pdf += pd * sg_pdf_cosine_hemisphere(lobe->n, w);
    if (pd < 1.0f)
        pdf += (1.0f - pd) * sg_pdf_cosine_power(lobe->r, lobe->exponent, w);
    return pdf;
}

Vec3 sg_sample_mixture(const SgMixture *m, float u0, float u1, float u2)
{
    if (u0 < m->alpha)
        return sg_sample_glossy(&m->bsdf, u0 / m->alpha, u1, u2);
    return sg_sample_cosine_power(m->axis, m->lobe_exponent, u1, u2);
}

float sg_pdf_mixture(const SgMixture *m, Vec3 w)
{
    float pdf = 0.0f;
    if (m->alpha > 0.0f)
        pdf += m->alpha * sg_pdf_glossy(&m->bsdf, w);
    if (m->alpha < 1.0f)
        pdf += (1.0f - m->alpha) * sg_pdf_cosine_power(m->axis, m->lobe_exponent, w);
    return pdf;
}
