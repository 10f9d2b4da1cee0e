#include "bsdf.h"

#include <math.h>

/* The coated diffuse is the classic two-layer model (Weidlich & Wilkie
 * 2007; Tungsten's and Mitsuba's rough plastic): a GGX dielectric coat
 * reflects F(wo.h) of the light as a microfacet lobe; what it lets in
 * (1 - F(wi.n)) reaches the base, which reflects R of it diffusely; of the
 * light going back up, the coat lets out 1 - F of each direction and
 * returns fdr of the whole to the base, again and again:
 *   f = D G F(wo.h) / (4 cos_o cos_i)
 *     + (1 - F(cos_i)) (1 - F(cos_o)) R / (pi ior^2 (1 - R fdr)).
 * Its albedo is at most F + (1 - F) = 1. pbrt-v4's coateddiffuse follows
 * the same light through a stochastic layer walk; this closed form leaves
 * out the rough coat's own spread of what crosses it (the crossings use
 * the smooth interface's Fresnel), measured against pbrt where it can be
 * (README.md, "pbrt-v4 scenes"). */

/* What the base gives back, per unit of what the coat lets through to it
 * and out again: R, and R fdr R, ... */
static inline float coated_base(float r, float fdr) { return r / (1.0f - r * fdr); }

void bsdf_init_microfacet(Bsdf *b, const Material *m, Vec3 n, Vec3 wo, Vec3 albedo)
{
    b->kind = m->type == SG_MATERIAL_CONDUCTOR ? BSDF_CONDUCTOR : BSDF_COATED;
    b->lobe.n = n;
    b->lobe.r = n;
    b->lobe.exponent = 0.0f;
    b->wo = sg_to_local(wo, b->lobe.n); /* the frame is made again where needed: small BSDFs copy fast */
    b->wo.z = sg_maxf(b->wo.z, 1e-6f); /* wo faces n; keep it above at grazing angles */
    b->ax = m->ax;
    b->ay = m->ay;
    if (b->kind == BSDF_CONDUCTOR) {
        b->lobe.diffuse_weight = 0.0f;
        bsdf_conductor_index(m, albedo, &b->ks, &b->k);
        b->albedo = m->texture ? albedo : m->ks;
        return;
    }
    b->kd = albedo;
    b->ior = m->ior;
    b->fdr = m->fdr;
    /* the coat with the share of its Fresnel at wo; the base with what it gives back */
    float f = sg_fresnel_dielectric(b->wo.z, b->ior);
    float base = (1.0f - f) * (1.0f - b->fdr) * coated_base(luminance(albedo), b->fdr);
    b->lobe.diffuse_weight = base / (f + base);
    /* the smooth layer's albedo from wo (its rough coat loses a little more) */
    b->albedo = v3(f + (1.0f - f) * (1.0f - b->fdr) * coated_base(albedo.x, b->fdr),
                   f + (1.0f - f) * (1.0f - b->fdr) * coated_base(albedo.y, b->fdr),
                   f + (1.0f - f) * (1.0f - b->fdr) * coated_base(albedo.z, b->fdr));
}

/* The microfacet lobe's D G / (4 cos_o cos_i) and wo.h, for wi above. */
static float microfacet_lobe(const Bsdf *b, Vec3 wi, float *cos_oh)
{
    Vec3 h = v3_normalize(v3_add(b->wo, wi));
    *cos_oh = v3_dot(b->wo, h);
    if (!(*cos_oh > 0.0f))
        return 0.0f;
    return sg_ggx_d(h, b->ax, b->ay) * sg_ggx_g(b->wo, wi, b->ax, b->ay) / (4.0f * b->wo.z * wi.z);
}

Vec3 bsdf_eval_microfacet(const Bsdf *b, Vec3 wi)
{
    Vec3 l = sg_to_local(wi, b->lobe.n);
    if (!(l.z > 0.0f))
        return v3(0, 0, 0);
    float cos_oh;
    float lobe = microfacet_lobe(b, l, &cos_oh);
    if (b->kind == BSDF_CONDUCTOR)
        return v3_scale(sg_fresnel_conductor3(cos_oh, b->ks, b->k), lobe);
    float spec = lobe * sg_fresnel_dielectric(cos_oh, b->ior);
    float cross = (1.0f - sg_fresnel_dielectric(l.z, b->ior)) * (1.0f - sg_fresnel_dielectric(b->wo.z, b->ior)) /
                  (SG_PI * b->ior * b->ior);
    return v3(spec + cross * coated_base(b->kd.x, b->fdr), spec + cross * coated_base(b->kd.y, b->fdr),
              spec + cross * coated_base(b->kd.z, b->fdr));
}

float bsdf_pdf_microfacet(const Bsdf *b, Vec3 wi)
{
    Vec3 l = sg_to_local(wi, b->lobe.n);
    float pdf = sg_ggx_pdf_reflect(b->wo, l, b->ax, b->ay);
    if (b->kind == BSDF_CONDUCTOR)
        return pdf;
    float pd = b->lobe.diffuse_weight;
    return (1.0f - pd) * pdf + pd * sg_maxf(l.z, 0.0f) * SG_INV_PI;
}

Vec3 bsdf_sample_microfacet(const Bsdf *b, float u0, float u1, float u2)
{
    if (b->kind == BSDF_COATED && u0 < b->lobe.diffuse_weight)
        return sg_sample_cosine_hemisphere(b->lobe.n, u1, u2);
    Vec3 h = sg_ggx_sample_visible(b->wo, b->ax, b->ay, u1, u2);
    Vec3 wi = v3_sub(v3_scale(h, 2.0f * v3_dot(b->wo, h)), b->wo);
    return v3_normalize(sg_to_world(wi, b->lobe.n));
}

Vec3 bsdf_diffuse_eval(const DiffuseTransmission *d, Vec3 wi)
{
    float c = v3_dot(wi, d->n);
    return c > 0.0f ? v3_scale(d->r, SG_INV_PI) : c < 0.0f ? v3_scale(d->t, SG_INV_PI) : v3(0, 0, 0);
}

float bsdf_diffuse_pdf(const DiffuseTransmission *d, Vec3 wi)
{
    float c = v3_dot(wi, d->n);
    return (c > 0.0f ? d->pr * c : (1.0f - d->pr) * -c) * SG_INV_PI;
}

Vec3 bsdf_diffuse_sample(const DiffuseTransmission *d, float u0, float u1, float u2)
{
    return sg_sample_cosine_hemisphere(u0 < d->pr ? d->n : v3_scale(d->n, -1.0f), u1, u2);
}

bool bsdf_diffuse_side(const DiffuseTransmission *d, float u, Vec3 *albedo)
{
    if (u < d->pr) {
        *albedo = v3_scale(d->r, 1.0f / d->pr);
        return false;
    }
    *albedo = v3_scale(d->t, 1.0f / (1.0f - d->pr));
    return true;
}

void bsdf_sample_delta(const Material *m, Vec3 albedo, Vec3 wo, Vec3 n, bool entering, float u, SpecularBounce *b)
{
    b->pdf = 1.0f;
    b->delta = true;
    b->transmitted = false;
    b->eta = 1.0f;
    if (!bsdf_delta_chooses(m)) { /* a mirror, or a conductor with its Fresnel at this angle */
        Vec3 tint = m->ks;
        if (m->type == SG_MATERIAL_CONDUCTOR) {
            Vec3 eta, k;
            bsdf_conductor_index(m, albedo, &eta, &k);
            tint = sg_fresnel_conductor3(v3_dot(wo, n), eta, k);
        }
        b->wi = v3_normalize(sg_reflect(wo, n));
        b->weight = b->rr_weight = tint;
        return;
    }
    float eta = entering ? 1.0f / m->ior : m->ior; /* eta_i / eta_t */
    float cos_i = v3_dot(wo, n);
    float fresnel = sg_fresnel_dielectric(cos_i, entering ? m->ior : 1.0f / m->ior);
    b->rr_weight = v3(1, 1, 1);
    if (u < fresnel) { /* reflected (always, past the critical angle) */
        b->wi = v3_normalize(sg_reflect(wo, n));
        b->weight = v3(1, 1, 1);
        return;
    }
    float cos_t = sqrtf(1.0f - eta * eta * fmaxf(0.0f, 1.0f - cos_i * cos_i));
    b->wi = v3_normalize(v3_add(v3_scale(wo, -eta), v3_scale(n, eta * cos_i - cos_t)));
    b->weight = v3(eta * eta, eta * eta, eta * eta); /* radiance is compressed entering glass */
    b->transmitted = true;
    b->eta = 1.0f / eta;
}

bool bsdf_sample_rough_glass(const Material *m, Vec3 wo, Vec3 n, bool entering, float uc, float u1, float u2,
                             SpecularBounce *b)
{
    float eta = entering ? m->ior : 1.0f / m->ior; /* beyond the surface over wo's side */
    Vec3 wo_l = sg_to_local(wo, n);
    wo_l.z = sg_maxf(wo_l.z, 1e-6f); /* wo faces n; keep it above at grazing angles */
    Vec3 wi_l;
    float weight, pdf;
    if (!sg_ggx_dielectric_sample(wo_l, eta, m->ax, m->ay, uc, u1, u2, &wi_l, &weight, &pdf))
        return false;
    b->wi = v3_normalize(sg_to_world(wi_l, n));
    b->transmitted = wi_l.z < 0.0f;
    b->weight = v3(weight, weight, weight);
    float rr = b->transmitted ? weight * eta * eta : weight;
    b->rr_weight = v3(rr, rr, rr);
    b->pdf = pdf;
    b->eta = b->transmitted ? eta : 1.0f;
    b->delta = false;
    return true;
}
