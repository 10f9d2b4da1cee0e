/* The BSDFs. At a diffuse, glossy or rough reflecting vertex (the Bsdf
 * below, where lights are sampled and guides draw), made from its material
 * and (where textured) the albedo at the hit, in the frame of the shading
 * normal on wo's side. Reflection only: every kind is zero below the
 * surface, though its sampler may draw there (a valid direction with f = 0,
 * so that each pdf is a density over the whole sphere, as sampling.h's).
 * Diffuse transmission is a Lambertian on the side the vertex chooses
 * (DiffuseTransmission, below).
 * Mirrors, smooth conductors and glass, smooth or rough, are sampled alone
 * (SpecularBounce, at the end).
 *   PHONG      diffuse + normalized Phong lobe (sampling.h's SgGlossyLobe):
 *              the diffuse and glossy materials, bit for bit as before
 *   CONDUCTOR  GGX microfacets with a conductor's complex Fresnel
 *   COATED     a diffuse base under a GGX dielectric coat (below)
 * The samplers draw from the density bsdf_pdf returns: tests hold them to
 * it by chi-square (tests/test_render_bsdf.c), and a white furnace to
 * energy conservation. */
#ifndef SG_RENDER_BSDF_H
#define SG_RENDER_BSDF_H

#include <stdbool.h>

#include "material.h"
#include "microfacet.h"
#include "sampling.h"
#include "vecmath.h"

typedef enum BsdfKind { BSDF_PHONG, BSDF_CONDUCTOR, BSDF_COATED } BsdfKind;

typedef struct Bsdf {
    /* PHONG: its lobes; every kind: lobe.n, the shading normal, and
     * lobe.diffuse_weight, the probability that the sampler draws from a
     * diffuse part (Open PGL guides that share) */
    SgGlossyLobe lobe;
    BsdfKind kind;
    Vec3 kd;          /* PHONG: diffuse albedo; COATED: the base's albedo */
    Vec3 ks;          /* PHONG: the Phong lobe's albedo; CONDUCTOR: eta */
    Vec3 k;           /* CONDUCTOR: the absorption part of the index */
    Vec3 albedo;      /* microfacet kinds: about what the surface reflects (bsdf_albedo) */
    /* microfacet kinds */
    Vec3 wo;          /* in the frame (t, b, lobe.n) of v3_basis(lobe.n) */
    float ax, ay;     /* GGX alpha along t and b */
    float ior;        /* COATED: the coat's index */
    float fdr;        /* COATED: diffuse reflectance of the coat from inside */
} Bsdf;

/* The BSDF of material m at a vertex: shading normal n on wo's side, wo
 * the direction back along the incoming ray, albedo the material's
 * `diffuse` there (its texture's value, or m->kd). */
static inline void bsdf_init(Bsdf *b, const Material *m, Vec3 n, Vec3 wo, Vec3 albedo);

/* f(wo, wi) for wi above the surface (wi.n > 0). */
static inline Vec3 bsdf_eval(const Bsdf *b, Vec3 wi);
/* Density of bsdf_sample's directions. */
static inline float bsdf_pdf(const Bsdf *b, Vec3 wi);
/* A direction from u0 (which lobe), u1, u2. */
static inline Vec3 bsdf_sample(const Bsdf *b, float u0, float u1, float u2);

/* A conductor's complex index at a point: the material's eta and k, or
 * where a texture gives its reflectance, pbrt's eta 1 and the k that
 * reflects the texture's value (albedo) at normal incidence. */
static inline void bsdf_conductor_index(const Material *m, Vec3 albedo, Vec3 *eta, Vec3 *k)
{
    if (!m->texture) {
        *eta = m->eta;
        *k = m->k;
        return;
    }
    *eta = v3(1, 1, 1);
    *k = v3(sg_conductor_k_of_reflectance(albedo.x), sg_conductor_k_of_reflectance(albedo.y),
            sg_conductor_k_of_reflectance(albedo.z));
}

/* The microfacet kinds' halves of the above (render/bsdf.c); the Phong kind
 * is the common one and stays inline. */
void bsdf_init_microfacet(Bsdf *b, const Material *m, Vec3 n, Vec3 wo, Vec3 albedo);
Vec3 bsdf_eval_microfacet(const Bsdf *b, Vec3 wi);
float bsdf_pdf_microfacet(const Bsdf *b, Vec3 wi);
Vec3 bsdf_sample_microfacet(const Bsdf *b, float u0, float u1, float u2);

static inline void bsdf_init(Bsdf *b, const Material *m, Vec3 n, Vec3 wo, Vec3 albedo)
{
    if (m->microfacet) {
        bsdf_init_microfacet(b, m, n, wo, albedo);
        return;
    }
    b->kind = BSDF_PHONG;
    b->kd = albedo;
    b->ks = m->ks;
    float weight = m->diffuse_weight;
    if (m->texture) { /* the texture moves the balance of the two parts */
        float ld = luminance(albedo), ls = luminance(m->ks);
        weight = ld + ls > 0.0f ? ld / (ld + ls) : 1.0f;
    }
    b->lobe = sg_glossy_lobe(n, wo, m->type == SG_MATERIAL_GLOSSY ? m->exponent : 0.0f, weight);
}

/* About what the surface reflects: the albedo roulette's factor (the
 * Phong kind's is kd + ks, made where needed: every vertex sets up its
 * BSDF, few reach the roulette). */
static inline Vec3 bsdf_albedo(const Bsdf *b) { return b->kind == BSDF_PHONG ? v3_add(b->kd, b->ks) : b->albedo; }

static inline Vec3 bsdf_eval(const Bsdf *b, Vec3 wi)
{
    if (b->kind != BSDF_PHONG)
        return bsdf_eval_microfacet(b, wi);
    Vec3 f = v3_scale(b->kd, SG_INV_PI);
    if (b->lobe.diffuse_weight < 1.0f) {
        float c = v3_dot(wi, b->lobe.r);
        if (c > 0.0f) {
            float p = b->lobe.exponent;
            float s = (p + 2.0f) * (0.5f * SG_INV_PI) * sg_pow_exponent(sg_minf(c, 1.0f), p);
            f = v3_add(f, v3_scale(b->ks, s));
        }
    }
    return f;
}

static inline float bsdf_pdf(const Bsdf *b, Vec3 wi)
{
    return b->kind == BSDF_PHONG ? sg_pdf_glossy(&b->lobe, wi) : bsdf_pdf_microfacet(b, wi);
}

static inline Vec3 bsdf_sample(const Bsdf *b, float u0, float u1, float u2)
{
    return b->kind == BSDF_PHONG ? sg_sample_glossy(&b->lobe, u0, u1, u2) : bsdf_sample_microfacet(b, u0, u1, u2);
}

/* Diffuse transmission (pbrt-v4's diffusetransmission): Lambertian
 * reflection r on wo's side of the surface, Lambertian transmission t on
 * the other, f = r / pi above n and t / pi below. Its sampler draws the
 * side by the luminance shares (pr), then a cosine direction there. The
 * integrator makes the same choice once per vertex (bsdf_diffuse_side)
 * and then treats the chosen side as a Lambertian of albedo r / pr or
 * t / (1 - pr): light samples, guides and the roulette see one
 * hemisphere as everywhere else, and the expectation is the full BSDF. */
typedef struct DiffuseTransmission {
    Vec3 n;   /* on wo's side */
    Vec3 r, t;
    float pr; /* probability of drawing the reflecting side */
} DiffuseTransmission;

static inline DiffuseTransmission bsdf_diffuse_transmission(Vec3 n, Vec3 r, Vec3 t)
{
    float lr = luminance(r), lt = luminance(t);
    return (DiffuseTransmission){n, r, t, lr + lt > 0.0f ? lr / (lr + lt) : 1.0f};
}

Vec3 bsdf_diffuse_eval(const DiffuseTransmission *d, Vec3 wi);
float bsdf_diffuse_pdf(const DiffuseTransmission *d, Vec3 wi);
Vec3 bsdf_diffuse_sample(const DiffuseTransmission *d, float u0, float u1, float u2);
/* The side a vertex scatters on, from u: true where it transmits; *albedo
 * is the Lambertian's there, divided by the side's probability. */
bool bsdf_diffuse_side(const DiffuseTransmission *d, float u, Vec3 *albedo);

/* One-sample mixture (defensive importance sampling), the guided bounce:
 * the BSDF's sampler with probability alpha, a cosine-power lobe folded
 * onto the hemisphere of lobe.n (sampling.h's SgFoldedLobe) otherwise.
 * The pdf, alpha p_bsdf + (1 - alpha) p_lobe, takes wn = w.n and also
 * gives p_bsdf and w's cosines with the lobe's axis and its mirror image. */
static inline Vec3 bsdf_mixture_sample(const Bsdf *b, const SgFoldedLobe *lobe, float alpha, float u0, float u1,
                                       float u2)
{
    if (u0 < alpha)
        return bsdf_sample(b, u0 / alpha, u1, u2);
    return sg_sample_folded_lobe(lobe->axis, b->lobe.n, lobe->exponent, u1, u2);
}

static inline float bsdf_mixture_pdf(const Bsdf *b, const SgFoldedLobe *lobe, float alpha, Vec3 w, float wn,
                                     float *pdf_bsdf, float *c1, float *c2)
{
    *pdf_bsdf = bsdf_pdf(b, w);
    return alpha * *pdf_bsdf + (1.0f - alpha) * sg_pdf_folded_lobe_at(lobe, w, wn, c1, c2);
}

/* A bounce drawn from a mirror's, a smooth conductor's or a glass's BSDF
 * alone (no light sample, no guide: a delta bounce, or rough glass, which a
 * shadow ray rarely crosses toward a light). */
typedef struct SpecularBounce {
    Vec3 wi;          /* unit direction */
    Vec3 weight;      /* f cos / pdf (a delta bounce: its Fresnel tint),
                       * radiance's compression through glass included */
    Vec3 rr_weight;   /* the same for the roulette: what is lost, not the compression */
    float pdf;        /* 1 for a delta bounce */
    float eta;        /* the relative index crossed, as Open PGL records it (1 reflected) */
    bool transmitted; /* below the surface: the path leaves on n's other side */
    bool delta;
} SpecularBounce;

/* A delta bounce (m->delta) at normal n facing wo; entering: wo is on the
 * side the winding normal faces. Glass chooses reflection or refraction by
 * its Fresnel with u; `albedo` the texture's value there (conductors). */
void bsdf_sample_delta(const Material *m, Vec3 albedo, Vec3 wo, Vec3 n, bool entering, float u, SpecularBounce *b);
/* Whether bsdf_sample_delta reads u (glass: it draws between two ways). */
static inline bool bsdf_delta_chooses(const Material *m)
{
    return m->type != SG_MATERIAL_MIRROR && m->type != SG_MATERIAL_CONDUCTOR;
}

/* A rough dielectric's bounce (render/microfacet.h), reflected or
 * transmitted through a visible microfacet; false: no direction (the
 * microfacet sent it to the wrong side). */
bool bsdf_sample_rough_glass(const Material *m, Vec3 wo, Vec3 n, bool entering, float uc, float u1, float u2,
                             SpecularBounce *b);

#endif
