#include "microfacet.h"

Vec3 sg_ggx_sample_visible(Vec3 wo, float ax, float ay, float u1, float u2)
{
    /* stretch wo to the hemisphere configuration (alpha 1) */
    Vec3 vh = v3_normalize(v3(ax * wo.x, ay * wo.y, wo.z));
    float len2 = vh.x * vh.x + vh.y * vh.y;
    Vec3 t1 = len2 > 0.0f ? v3_scale(v3(-vh.y, vh.x, 0.0f), 1.0f / sqrtf(len2)) : v3(1, 0, 0);
    Vec3 t2 = v3_cross(vh, t1);
    /* a point on the disk, its second half squeezed by the projected hemisphere */
    float r = sqrtf(u1), phi = 2.0f * SG_PI * u2;
    float p1 = r * cosf(phi), p2 = r * sinf(phi);
    float s = 0.5f * (1.0f + vh.z);
    p2 = (1.0f - s) * sqrtf(sg_maxf(0.0f, 1.0f - p1 * p1)) + s * p2;
    float p3 = sqrtf(sg_maxf(0.0f, 1.0f - p1 * p1 - p2 * p2));
    Vec3 nh = v3_add(v3_add(v3_scale(t1, p1), v3_scale(t2, p2)), v3_scale(vh, p3));
    /* and back to the ellipsoid */
    return v3_normalize(v3(ax * nh.x, ay * nh.y, sg_maxf(1e-6f, nh.z)));
}

float sg_fresnel_diffuse_internal(float eta)
{
    const int n = 1024;
    double sum = 0.0;
    for (int i = 0; i < n; i++) { /* midpoint rule in mu */
        float mu = (i + 0.5f) / n;
        sum += sg_fresnel_dielectric(-mu, eta) * mu;
    }
    return (float)(2.0 * sum / n);
}

/* The microfacet that takes wo to wi, as f and pdf both need it: its
 * normal h (the generalized half vector: wo + wi in reflection, wo + eta wi
 * in transmission, turned to z > 0), wo.h, wi.h, the Fresnel reflectance
 * at wo.h and, in transmission, the square of wi.h + wo.h / eta (the
 * change of variables from h to wi). False where none does (wi in the
 * plane, or a microfacet seen from behind by wo or wi). */
typedef struct DielectricHalf {
    Vec3 h;
    float cos_oh, cos_ih, fresnel, denom2;
} DielectricHalf;

static bool dielectric_half(Vec3 wo, Vec3 wi, float eta, DielectricHalf *d)
{
    if (wi.z == 0.0f)
        return false;
    Vec3 m = wi.z > 0.0f ? v3_add(wo, wi) : v3_add(wo, v3_scale(wi, eta));
    float l = v3_length(m);
    if (!(l > 0.0f))
        return false;
    m = v3_scale(m, (m.z < 0.0f ? -1.0f : 1.0f) / l);
    if (!(v3_dot(m, wo) > 0.0f) || v3_dot(m, wi) * wi.z <= 0.0f)
        return false;
    d->h = m;
    d->cos_oh = v3_dot(wo, m);
    d->cos_ih = v3_dot(wi, m);
    d->fresnel = sg_fresnel_dielectric(d->cos_oh, eta);
    float denom = d->cos_ih + d->cos_oh / eta;
    d->denom2 = denom * denom;
    return true;
}

float sg_ggx_dielectric_f(Vec3 wo, Vec3 wi, float eta, float ax, float ay)
{
    DielectricHalf d;
    if (!dielectric_half(wo, wi, eta, &d))
        return 0.0f;
    float dg = sg_ggx_d(d.h, ax, ay) * sg_ggx_g(wo, wi, ax, ay);
    if (wi.z > 0.0f)
        return dg * d.fresnel / (4.0f * wo.z * wi.z);
    return dg * (1.0f - d.fresnel) * fabsf(d.cos_ih * d.cos_oh / (wi.z * wo.z * d.denom2)) / (eta * eta);
}

float sg_ggx_dielectric_pdf(Vec3 wo, Vec3 wi, float eta, float ax, float ay)
{
    DielectricHalf d;
    if (!dielectric_half(wo, wi, eta, &d))
        return 0.0f;
    float visible = sg_ggx_g1(wo, ax, ay) * sg_ggx_d(d.h, ax, ay) * d.cos_oh / wo.z; /* density of h */
    if (wi.z > 0.0f)
        return visible / (4.0f * d.cos_oh) * d.fresnel;
    return visible * fabsf(d.cos_ih) / d.denom2 * (1.0f - d.fresnel);
}

bool sg_ggx_dielectric_sample(Vec3 wo, float eta, float ax, float ay, float uc, float u1, float u2, Vec3 *wi,
                              float *weight, float *pdf)
{
    Vec3 h = sg_ggx_sample_visible(wo, ax, ay, u1, u2);
    float cos_oh = v3_dot(wo, h);
    float f = sg_fresnel_dielectric(cos_oh, eta);
    Vec3 w;
    float scale = 1.0f;
    if (uc < f) {
        w = v3_sub(v3_scale(h, 2.0f * cos_oh), wo);
        if (!(w.z > 0.0f))
            return false;
    } else {
        float sin2_t = (1.0f - cos_oh * cos_oh) / (eta * eta);
        if (!(sin2_t < 1.0f))
            return false; /* total internal reflection: f = 1, not reached */
        float cos_t = sqrtf(1.0f - sin2_t);
        w = v3_add(v3_scale(wo, -1.0f / eta), v3_scale(h, cos_oh / eta - cos_t));
        if (!(w.z < 0.0f))
            return false;
        scale = 1.0f / (eta * eta);
    }
    w = v3_normalize(w);
    float p = sg_ggx_dielectric_pdf(wo, w, eta, ax, ay);
    if (!(p > 0.0f))
        return false; /* at the edge of the support, in float */
    *wi = w;
    *pdf = p;
    *weight = scale * sg_ggx_g(wo, w, ax, ay) / sg_ggx_g1(wo, ax, ay);
    return true;
}
