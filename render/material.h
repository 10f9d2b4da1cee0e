/* The renderer's materials, made from the scene's SgMaterial with energy
 * conservation enforced: diffuse, glossy (diffuse plus a normalized Phong
 * lobe), mirror, dielectric (GGX, or the exact refraction when smooth),
 * conductor (GGX, or a mirror with its Fresnel when smooth), coated
 * diffuse and diffuse transmission. render/bsdf.h turns one into
 * the BSDF at a vertex. */
#ifndef SG_RENDER_MATERIAL_H
#define SG_RENDER_MATERIAL_H

#include <stdbool.h>
#include <stdint.h>

#include "color.h"
#include "sampling.h"
#include "scene.h"
#include "vecmath.h"

typedef struct Material {
    SgMaterialType type;
    Vec3 kd, ks, emission; /* conductor: ks its reflectance at normal incidence */
    Vec3 kt;               /* diffuse transmission: what it lets through (kd: what it reflects) */
    float exponent, ior;
    float diffuse_weight; /* diffuse, glossy: probability of sampling the diffuse part
                           * (the microfacet kinds': their vertex's, render/bsdf.c) */
    float roughness;      /* for Open PGL: 1 diffuse, sqrt(2 / (p + 2)) a Phong lobe alone, GGX alpha */
    bool emissive;
    bool black;           /* no scattering at all */
    bool delta;           /* a specular bounce: mirror, smooth glass, smooth conductor */
    bool microfacet;      /* a rough conductor or a coated diffuse: render/bsdf.c's BSDFs */
    Vec3 eta, k;          /* conductor: complex index of refraction */
    float ax, ay;         /* conductor, coated diffuse, dielectric: GGX alpha */
    float fdr;            /* coated diffuse: the coat's diffuse reflectance from inside */
    uint32_t texture;     /* 1 + index of the texture that varies kd (SgMaterial.diffuse_texture); 0: none */
    bool cutout;          /* rays may pass through (SgMaterial.cutout): alpha, or alpha_texture's value */
    bool absorbs;         /* dielectric: sigma_a > 0, what it encloses absorbs */
    Vec3 sigma_a;
    uint32_t normal_texture, bump_texture; /* shading normals (SgMaterial's) */
    float bump_scale;
    float alpha;
    uint32_t alpha_texture;
} Material;

void material_init(Material *m, const SgMaterial *src);

/* Luminance of a linear RGB value (common/color.h). */
static inline float luminance(Vec3 c) { return sg_luminancef(c.x, c.y, c.z); }

#endif
