/* The renderer's materials: diffuse, glossy (diffuse plus a normalized
 * Phong lobe), mirror and dielectric, made from the scene's SgMaterial with
 * energy conservation enforced, and the BSDF value of the non-delta ones. */
#ifndef SG_RENDER_MATERIAL_H
#define SG_RENDER_MATERIAL_H

#include <stdbool.h>

#include "color.h"
#include "sampling.h"
#include "scene.h"
#include "vecmath.h"

typedef struct Material {
    SgMaterialType type;
    Vec3 kd, ks, emission;
    float exponent, ior;
    float diffuse_weight; /* probability of sampling the diffuse part */
    float roughness;      /* for Open PGL: 1 diffuse, sqrt(2 / (p + 2)) a Phong lobe alone */
    bool emissive;
    bool black;           /* no scattering at all */
} Material;

void material_init(Material *m, const SgMaterial *src);

/* Luminance of a linear RGB value (common/color.h). */
static inline float luminance(Vec3 c) { return sg_luminancef(c.x, c.y, c.z); }

/* BSDF value (times nothing) of a diffuse/glossy material, wi above the surface. */
static inline Vec3 material_eval(const Material *m, const SgGlossyLobe *lobe, Vec3 wi)
{
    Vec3 f = v3_scale(m->kd, SG_INV_PI);
    if (m->type == SG_MATERIAL_GLOSSY) {
        float c = v3_dot(wi, lobe->r);
        if (c > 0.0f) {
            float s = (m->exponent + 2.0f) * (0.5f * SG_INV_PI) * sg_pow_exponent(sg_minf(c, 1.0f), m->exponent);
            f = v3_add(f, v3_scale(m->ks, s));
        }
    }
    return f;
}

#endif
