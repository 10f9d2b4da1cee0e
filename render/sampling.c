#include "sampling.h"

#include <math.h>

Vec3 sg_to_world(Vec3 local, Vec3 axis)
{
    Vec3 t, b;
    v3_basis(axis, &t, &b);
    return v3_add(v3_add(v3_scale(t, local.x), v3_scale(b, local.y)), v3_scale(axis, local.z));
}

Vec3 sg_to_local(Vec3 world, Vec3 axis)
{
    Vec3 t, b;
    v3_basis(axis, &t, &b);
    return v3(v3_dot(world, t), v3_dot(world, b), v3_dot(world, axis));
}

Vec3 sg_sample_cosine_hemisphere(Vec3 n, float u1, float u2)
{
    /* Malley: uniform on the disk, projected up. */
    float r = sqrtf(u1);
    float phi = 2.0f * SG_PI * u2;
    float z = sqrtf(sg_maxf(0.0f, 1.0f - u1));
    return sg_to_world(v3(r * cosf(phi), r * sinf(phi), z), n);
}

Vec3 sg_sample_cosine_power(Vec3 a, float p, float u1, float u2)
{
    /* cos theta = u^(1/(p+1)), with u = 1 - u1 in (0, 1]. */
    float phi = 2.0f * SG_PI * u2;
    if (p <= 64.0f) {
        /* wide lobe: single precision keeps sin theta to ~1e-4 relative */
        float cos_t = powf(1.0f - u1, 1.0f / (p + 1.0f));
        float sin_t = sqrtf(sg_maxf(0.0f, 1.0f - cos_t * cos_t));
        return sg_to_world(v3(sin_t * cosf(phi), sin_t * sinf(phi), cos_t), a);
    }
    /* narrow lobe: in logs, so that sin theta keeps its digits (p up to 1e4+) */
    double l = log1p(-(double)u1) / ((double)p + 1.0); /* log cos theta, <= 0 */
    float cos_t = (float)exp(l);
    float sin_t = (float)sqrt(fmax(0.0, -expm1(2.0 * l)));
    return sg_to_world(v3(sin_t * cosf(phi), sin_t * sinf(phi), cos_t), a);
}

Vec3 sg_sample_folded_lobe(Vec3 a, Vec3 n, float p, float u1, float u2)
{
    Vec3 w = sg_sample_cosine_power(a, p, u1, u2);
    float c = v3_dot(w, n);
    return c < 0.0f ? v3_sub(w, v3_scale(n, 2.0f * c)) : w;
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
