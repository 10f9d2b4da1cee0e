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
