#include "material.h"

#include <math.h>
#include <string.h>

#include "microfacet.h"

void material_init(Material *m, const SgMaterial *src)
{
    memset(m, 0, sizeof *m);
    m->type = src->type;
    m->kd = v3(fmaxf(0, src->diffuse[0]), fmaxf(0, src->diffuse[1]), fmaxf(0, src->diffuse[2]));
    m->ks = v3(fmaxf(0, src->specular[0]), fmaxf(0, src->specular[1]), fmaxf(0, src->specular[2]));
    m->emission = v3(fmaxf(0, src->emission[0]), fmaxf(0, src->emission[1]),
                     fmaxf(0, src->emission[2]));
    m->emissive = v3_max_component(m->emission) > 0.0f;
    m->exponent = src->exponent > 0 ? fminf(src->exponent, 1e5f) : 1.0f;
    m->ior = src->ior > 1.0f ? src->ior : 1.5f;
    if (m->type == SG_MATERIAL_DIFFUSE)
        m->ks = v3(0, 0, 0);
    if (m->type == SG_MATERIAL_DIFFUSE || m->type == SG_MATERIAL_GLOSSY) {
        /* energy conservation: kd + ks <= 1 per channel */
        float worst = v3_max_component(v3_add(m->kd, m->ks));
        if (worst > 1.0f) {
            m->kd = v3_scale(m->kd, 1.0f / worst);
            m->ks = v3_scale(m->ks, 1.0f / worst);
        }
        float ld = luminance(m->kd), ls = luminance(m->ks);
        m->black = ld + ls <= 0.0f;
        m->diffuse_weight = m->black ? 1.0f : ld / (ld + ls);
        if (ls <= 0.0f)
            m->type = SG_MATERIAL_DIFFUSE;
        m->roughness = m->diffuse_weight > 0.0f ? 1.0f : sqrtf(2.0f / (m->exponent + 2.0f));
    } else if (m->type == SG_MATERIAL_CONDUCTOR) {
        m->eta = v3(fmaxf(src->eta[0], 1e-3f), fmaxf(src->eta[1], 1e-3f), fmaxf(src->eta[2], 1e-3f));
        m->k = v3(fmaxf(src->k[0], 0), fmaxf(src->k[1], 0), fmaxf(src->k[2], 0));
        m->ax = fmaxf(src->roughness[0], 0);
        m->ay = fmaxf(src->roughness[1], 0);
        m->delta = fmaxf(m->ax, m->ay) < SG_GGX_SMOOTH_ALPHA;
        m->ax = fmaxf(m->ax, SG_GGX_SMOOTH_ALPHA);
        m->ay = fmaxf(m->ay, SG_GGX_SMOOTH_ALPHA);
        m->ks = sg_fresnel_conductor3(1.0f, m->eta, m->k);
        m->kd = v3(0, 0, 0);
        m->roughness = sqrtf(m->ax * m->ay);
    } else if (m->type == SG_MATERIAL_COATED_DIFFUSE) {
        m->kd = v3(fminf(m->kd.x, 1), fminf(m->kd.y, 1), fminf(m->kd.z, 1));
        /* alpha 0 would be a smooth coat: the narrowest GGX lobe stands in */
        m->ax = fmaxf(src->roughness[0], SG_GGX_SMOOTH_ALPHA);
        m->ay = fmaxf(src->roughness[1], SG_GGX_SMOOTH_ALPHA);
        m->fdr = sg_fresnel_diffuse_internal(m->ior);
        float f0 = sg_fresnel_dielectric(1.0f, m->ior);
        m->ks = v3(f0, f0, f0);
        m->roughness = 1.0f; /* its diffuse_weight is the vertex's (render/bsdf.c) */
    } else if (m->type == SG_MATERIAL_DIELECTRIC) {
        /* smooth below pbrt's threshold: the exact refraction (a delta) */
        m->ax = fmaxf(src->roughness[0], 0);
        m->ay = fmaxf(src->roughness[1], 0);
        m->delta = fmaxf(m->ax, m->ay) < SG_GGX_SMOOTH_ALPHA;
        m->ax = fmaxf(m->ax, SG_GGX_SMOOTH_ALPHA);
        m->ay = fmaxf(m->ay, SG_GGX_SMOOTH_ALPHA);
        m->roughness = sqrtf(m->ax * m->ay);
    } else if (m->type == SG_MATERIAL_DIFFUSE_TRANSMISSION) {
        m->kt = v3(fmaxf(0, src->transmittance[0]), fmaxf(0, src->transmittance[1]), fmaxf(0, src->transmittance[2]));
        m->ks = v3(0, 0, 0);
        float worst = v3_max_component(v3_add(m->kd, m->kt)); /* R + T <= 1 per channel */
        if (worst > 1.0f) {
            m->kd = v3_scale(m->kd, 1.0f / worst);
            m->kt = v3_scale(m->kt, 1.0f / worst);
        }
        m->black = luminance(m->kd) + luminance(m->kt) <= 0.0f;
        m->diffuse_weight = 1.0f; /* each side is a Lambertian alone (bsdf.h) */
        m->roughness = 1.0f;
    } else if (m->type == SG_MATERIAL_MIRROR) {
        if (v3_max_component(m->ks) <= 0.0f)
            m->ks = v3(1, 1, 1); /* a mirror given without Ks reflects fully */
        m->ks = v3(fminf(m->ks.x, 1), fminf(m->ks.y, 1), fminf(m->ks.z, 1));
    }
    m->delta = m->delta || m->type == SG_MATERIAL_MIRROR;
    m->microfacet = !m->delta && (m->type == SG_MATERIAL_CONDUCTOR || m->type == SG_MATERIAL_COATED_DIFFUSE);
    m->texture = src->diffuse_texture;
    m->cutout = src->cutout && (src->alpha_texture || src->alpha < 1.0f);
    m->alpha = fminf(fmaxf(src->alpha, 0.0f), 1.0f);
    m->alpha_texture = src->cutout ? src->alpha_texture : 0;
    m->normal_texture = src->normal_texture;
    m->bump_texture = src->normal_texture ? 0 : src->bump_texture;
    m->bump_scale = src->bump_scale;
    if (m->type == SG_MATERIAL_DIELECTRIC) {
        m->sigma_a = v3(fmaxf(0, src->sigma_a[0]), fmaxf(0, src->sigma_a[1]), fmaxf(0, src->sigma_a[2]));
        m->absorbs = v3_max_component(m->sigma_a) > 0.0f;
    }
}
