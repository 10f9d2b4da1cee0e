/* The microfacet BSDFs (render/bsdf.h, render/microfacet.h) beyond their
 * samplers (chi-square: test_render_sampling.c): Fresnel values against
 * their closed forms, white furnaces (energy never above 1; how much GGX
 * conductors and rough dielectrics lose at high roughness), and the coated diffuse against a
 * random walk through the layer it stands for (pbrt-v4's coateddiffuse
 * walks the same layer stochastically). */
#include <criterion/criterion.h>
#include <math.h>
#include <string.h>

#include "../render/bsdf.h"
#include "rng.h"
#include "scene_builder.h"

static Bsdf make_bsdf(SgMaterialType type, float alpha, Vec3 albedo, float eta, float k, float cos_o)
{
    SgMaterial sm;
    sg_material_default(&sm, "test");
    sm.type = type;
    sm.roughness[0] = sm.roughness[1] = alpha;
    for (int c = 0; c < 3; c++) {
        sm.eta[c] = eta;
        sm.k[c] = k;
    }
    sm.diffuse[0] = albedo.x;
    sm.diffuse[1] = albedo.y;
    sm.diffuse[2] = albedo.z;
    Material m;
    material_init(&m, &sm);
    Bsdf b;
    Vec3 wo = v3(sqrtf(1.0f - cos_o * cos_o), 0.0f, cos_o);
    bsdf_init(&b, &m, v3(0, 0, 1), wo, m.kd);
    return b;
}

/* The directional albedo int f cos dwi by the BSDF's own sampling, with
 * its standard error. */
static double albedo(const Bsdf *b, uint64_t seed, double *error)
{
    SgRng rng;
    sg_rng_seed(&rng, seed, 3);
    const int n = 400000;
    double sum = 0.0, sum2 = 0.0;
    for (int i = 0; i < n; i++) {
        float u0 = sg_rng_float(&rng), u1 = sg_rng_float(&rng), u2 = sg_rng_float(&rng);
        Vec3 wi = bsdf_sample(b, u0, u1, u2);
        float pdf = bsdf_pdf(b, wi);
        double x = 0.0;
        if (wi.z > 0.0f && pdf > 0.0f)
            x = bsdf_eval(b, wi).y * wi.z / pdf;
        cr_assert(isfinite(x) && x >= 0.0, "sample %d: f cos / pdf = %g", i, x);
        sum += x;
        sum2 += x * x;
    }
    double mean = sum / n;
    *error = sqrt(fmax(sum2 / n - mean * mean, 0.0) / n);
    return mean;
}

Test(render_bsdf, fresnel_matches_closed_forms)
{
    /* normal incidence: ((n - 1)^2 + k^2) / ((n + 1)^2 + k^2) */
    float n = 0.2f, k = 3.9f;
    float expected = ((n - 1) * (n - 1) + k * k) / ((n + 1) * (n + 1) + k * k);
    cr_assert_float_eq(sg_fresnel_conductor(1.0f, n, k), expected, 1e-5f);
    /* k = 0 is a dielectric */
    for (float c = 0.05f; c <= 1.0f; c += 0.1f)
        cr_assert_float_eq(sg_fresnel_conductor(c, 1.5f, 0.0f), sg_fresnel_dielectric(c, 1.5f), 1e-5f);
    cr_assert_float_eq(sg_fresnel_dielectric(1.0f, 1.5f), 0.04f, 1e-6f);
    cr_assert_float_eq(sg_fresnel_dielectric(0.0f, 1.5f), 1.0f, 1e-6f); /* grazing */
    cr_assert_float_eq(sg_fresnel_dielectric(-0.5f, 1.5f), 1.0f, 1e-6f); /* total internal reflection */
    /* pbrt's reflectance-to-k gives that reflectance back at normal incidence */
    cr_assert_float_eq(sg_fresnel_conductor(1.0f, 1.0f, sg_conductor_k_of_reflectance(0.7f)), 0.7f, 1e-4f);
    /* the coat's diffuse reflectance from inside, index 1.5: 1 - (1 - 0.0918) / 1.5^2 (Egan-Hilgeman's
     * fit of the outside value) */
    cr_assert_float_eq(sg_fresnel_diffuse_internal(1.5f), 1.0f - (1.0f - 0.0918f) / 2.25f, 2e-3f);
}

/* A conductor that reflects everything (pbrt's reflectance 1: eta 1, k
 * large): what it returns is what the single-scattering GGX keeps. */
Test(render_bsdf, white_furnace_conductor_loses_energy_with_roughness)
{
    const float alphas[] = {0.05f, 0.1f, 0.3f, 0.6f, 1.0f};
    const float cosines[] = {1.0f, 0.5f, 0.1f};
    for (int c = 0; c < 3; c++) {
        double previous = 2.0;
        for (int a = 0; a < 5; a++) {
            Bsdf b = make_bsdf(SG_MATERIAL_CONDUCTOR, alphas[a], v3(1, 1, 1), 1.0f, 1e4f, cosines[c]);
            double err, e = albedo(&b, 100 + a, &err);
            cr_log_info("conductor alpha %.2f, cos_o %.1f: albedo %.4f +- %.4f", alphas[a], cosines[c], e, err);
            cr_assert(e <= 1.0 + 4.0 * err + 1e-4, "alpha %g cos %g: albedo %g above 1", alphas[a], cosines[c], e);
            if (cosines[c] >= 0.5f) /* at grazing angles masking makes it non-monotone */
                cr_assert(e <= previous + 4.0 * err, "cos %g: albedo grows with roughness", cosines[c]);
            if (alphas[a] <= 0.05f && cosines[c] >= 0.5f)
                cr_assert(e > 0.99, "alpha %g cos %g: albedo %g, a smooth lobe keeps nearly all", alphas[a],
                          cosines[c], e);
            previous = e;
        }
    }
    /* what single scattering keeps, by an independent quadrature of
     * D G / (4 cos_o cos_i) cos_i over the hemisphere (400 x 800 midpoint
     * grid): alpha 1 from above keeps under a third (its microfacet normals
     * are cosine-distributed: half of them reflect below the surface) */
    const struct {
        float alpha, cos_o;
        double expected;
    } known[] = {{0.1f, 0.5f, 0.96921}, {0.3f, 1.0f, 0.87736}, {0.6f, 0.5f, 0.64267}, {1.0f, 1.0f, 0.30685}};
    for (int i = 0; i < 4; i++) {
        Bsdf b = make_bsdf(SG_MATERIAL_CONDUCTOR, known[i].alpha, v3(1, 1, 1), 1.0f, 1e4f, known[i].cos_o);
        double err, e = albedo(&b, 7 + i, &err);
        cr_assert(fabs(e - known[i].expected) < 4.0 * err + 2e-3, "alpha %g cos %g: albedo %g, quadrature %g",
                  known[i].alpha, known[i].cos_o, e, known[i].expected);
    }
}

Test(render_bsdf, white_furnace_coated_diffuse_keeps_energy)
{
    const float alphas[] = {0.01f, 0.1f, 0.3f};
    const float cosines[] = {1.0f, 0.5f, 0.15f};
    for (int a = 0; a < 3; a++)
        for (int c = 0; c < 3; c++) {
            Bsdf b = make_bsdf(SG_MATERIAL_COATED_DIFFUSE, alphas[a], v3(1, 1, 1), 1.5f, 0.0f, cosines[c]);
            double err, e = albedo(&b, 200 + 3 * a + c, &err);
            cr_log_info("coated white alpha %.2f, cos_o %.2f: albedo %.4f +- %.4f", alphas[a], cosines[c], e, err);
            cr_assert(e <= 1.0 + 4.0 * err + 1e-4, "alpha %g cos %g: albedo %g above 1", alphas[a], cosines[c], e);
            /* a white base gives back all the coat lets in (1 - F): only
             * the coat's GGX loses, most at grazing angles */
            float through = 1.0f - sg_fresnel_dielectric(cosines[c], 1.5f);
            cr_assert(e > through, "alpha %g cos %g: albedo %g below what the coat lets in", alphas[a], cosines[c], e);
            if (cosines[c] >= 0.5f && alphas[a] <= 0.1f)
                cr_assert(e > 0.99, "alpha %g cos %g: albedo %g", alphas[a], cosines[c], e);
        }
}

/* The layer the coated diffuse stands for, walked photon by photon as
 * pbrt-v4's coateddiffuse does (a smooth coat of index eta over a
 * Lambertian base of albedo r, no medium between): the fraction of light
 * from cos_o that leaves again, and of it the part that crossed the coat. */
static void layer_walk(float cos_o, float r, float eta, uint64_t seed, double *total, double *through)
{
    SgRng rng;
    sg_rng_seed(&rng, seed, 5);
    const int n = 400000;
    long out = 0, crossed = 0;
    for (int i = 0; i < n; i++) {
        if (sg_rng_float(&rng) < sg_fresnel_dielectric(cos_o, eta)) {
            out++; /* the coat reflects it */
            continue;
        }
        for (int bounce = 0; bounce < 1000; bounce++) {
            if (!(sg_rng_float(&rng) < r))
                break; /* the base absorbs it */
            float mu = sqrtf(sg_rng_float(&rng)); /* Lambertian: cosine-distributed */
            if (!(sg_rng_float(&rng) < sg_fresnel_dielectric(-mu, eta))) {
                out++;
                crossed++;
                break;
            }
        }
    }
    *total = (double)out / n;
    *through = (double)crossed / n;
}

Test(render_bsdf, coated_diffuse_matches_the_layer_it_models)
{
    const float reflectances[] = {0.2f, 0.58f, 0.9f};
    const float cosines[] = {0.9f, 0.4f};
    for (int i = 0; i < 3; i++)
        for (int c = 0; c < 2; c++) {
            float r = reflectances[i];
            double walk, walk_through;
            layer_walk(cosines[c], r, 1.5f, 300 + 2 * i + c, &walk, &walk_through);
            /* the narrowest coat: the smooth layer the walk models */
            Bsdf b = make_bsdf(SG_MATERIAL_COATED_DIFFUSE, 0.0f, v3(r, r, r), 1.5f, 0.0f, cosines[c]);
            double err, e = albedo(&b, 400 + 2 * i + c, &err);
            cr_log_info("coated r %.2f cos_o %.1f: albedo %.4f +- %.4f, layer walk %.4f (through the coat %.4f)",
                        r, cosines[c], e, err, walk, walk_through);
            double walk_err = sqrt(walk * (1.0 - walk) / 400000.0);
            cr_assert(fabs(e - walk) < 4.0 * (err + walk_err) + 2e-3, "r %g cos %g: albedo %g, layer %g", r,
                      cosines[c], e, walk);
            cr_assert_float_eq(bsdf_albedo(&b).y, walk, 4.0 * walk_err + 2e-3, "the roulette's albedo %g, layer %g",
                               bsdf_albedo(&b).y, walk);
        }
}

/* A rough dielectric (render/microfacet.h) keeps at most the energy it
 * receives: the flux it reflects and transmits (radiance weights with the
 * transmitted 1 / eta^2 undone) is at most 1, near 1 when smooth, and the
 * reflected share of a nearly smooth interface is the smooth Fresnel. The
 * sampler's mean is checked against an independent quadrature of f |cos|
 * over the sphere. */
static void dielectric_flux(Vec3 wo, float eta, float alpha, uint64_t seed, double *reflected, double *transmitted,
                            double *error)
{
    SgRng rng;
    sg_rng_seed(&rng, seed, 5);
    const int n = 400000;
    double r = 0.0, t = 0.0, sum2 = 0.0;
    for (int i = 0; i < n; i++) {
        Vec3 wi;
        float weight, pdf;
        float u0 = sg_rng_float(&rng), u1 = sg_rng_float(&rng), u2 = sg_rng_float(&rng);
        if (!sg_ggx_dielectric_sample(wo, eta, alpha, alpha, u0, u1, u2, &wi, &weight, &pdf))
            continue;
        cr_assert(isfinite(weight) && weight >= 0.0f && pdf > 0.0f, "sample %d: weight %g pdf %g", i, weight, pdf);
        double x = wi.z > 0.0f ? weight : weight * eta * eta;
        *(wi.z > 0.0f ? &r : &t) += x;
        sum2 += x * x;
    }
    *reflected = r / n;
    *transmitted = t / n;
    double mean = (r + t) / n;
    *error = sqrt(fmax(sum2 / n - mean * mean, 0.0) / n);
}

static double dielectric_flux_quadrature(Vec3 wo, float eta, float alpha)
{
    const int nt = 800, np = 400;
    double sum = 0.0;
    for (int i = 0; i < nt; i++) {
        double theta = M_PI * (i + 0.5) / nt;
        for (int j = 0; j < np; j++) {
            double phi = 2.0 * M_PI * (j + 0.5) / np;
            Vec3 wi = v3((float)(sin(theta) * cos(phi)), (float)(sin(theta) * sin(phi)), (float)cos(theta));
            double f = sg_ggx_dielectric_f(wo, wi, eta, alpha, alpha);
            if (wi.z < 0.0f)
                f *= eta * eta;
            sum += f * fabs(wi.z) * sin(theta);
        }
    }
    return sum * (M_PI / nt) * (2.0 * M_PI / np);
}

Test(render_bsdf, white_furnace_rough_dielectric_keeps_at_most_its_energy)
{
    const float alphas[] = {0.01f, 0.1f, 0.3f, 0.6f};
    const float etas[] = {1.5f, 1.0f / 1.5f};
    const float cosines[] = {1.0f, 0.5f, 0.15f};
    for (int e = 0; e < 2; e++)
        for (int c = 0; c < 3; c++)
            for (int a = 0; a < 4; a++) {
                Vec3 wo = v3(sqrtf(1.0f - cosines[c] * cosines[c]), 0.0f, cosines[c]);
                double r, t, err;
                dielectric_flux(wo, etas[e], alphas[a], 300 + 12 * e + 4 * c + a, &r, &t, &err);
                double total = r + t;
                cr_log_info("dielectric eta %.3f alpha %.2f cos_o %.2f: reflects %.4f, transmits %.4f, total %.4f +- "
                            "%.4f",
                            etas[e], alphas[a], cosines[c], r, t, total, err);
                cr_assert(total <= 1.0 + 4.0 * err + 1e-4, "eta %g alpha %g cos %g: flux %g above 1", etas[e],
                          alphas[a], cosines[c], total);
                if (alphas[a] <= 0.01f) { /* nearly smooth: Fresnel's split, all energy kept */
                    double f = sg_fresnel_dielectric(cosines[c], etas[e]);
                    cr_assert(fabs(r - f) < 4.0 * err + 5e-3, "eta %g cos %g: reflects %g, Fresnel %g", etas[e],
                              cosines[c], r, f);
                    cr_assert(total > 0.99, "eta %g cos %g: smooth flux %g", etas[e], cosines[c], total);
                }
                if (a == 2 && c < 2) {
                    double q = dielectric_flux_quadrature(wo, etas[e], alphas[a]);
                    cr_assert(fabs(total - q) < 4.0 * err + 3e-3, "eta %g alpha %g cos %g: sampled %g, quadrature %g",
                              etas[e], alphas[a], cosines[c], total, q);
                }
            }
}

/* ---- diffuse transmission ------------------------------------------------ */

/* Its albedo over the whole sphere, by its own sampler: R + T per channel,
 * whatever wo; the reflected and transmitted halves each on their side. */
Test(render_bsdf, white_furnace_diffuse_transmission_returns_r_plus_t)
{
    const Vec3 r = v3(0.3f, 0.5f, 0.1f), t = v3(0.6f, 0.2f, 0.0f);
    DiffuseTransmission d = bsdf_diffuse_transmission(v3_normalize(v3(0.2f, -0.4f, 1.0f)), r, t);
    SgRng rng;
    sg_rng_seed(&rng, 46, 1);
    const int n = 200000;
    double up[3] = {0}, down[3] = {0};
    for (int i = 0; i < n; i++) {
        Vec3 wi = bsdf_diffuse_sample(&d, sg_rng_float(&rng), sg_rng_float(&rng), sg_rng_float(&rng));
        float pdf = bsdf_diffuse_pdf(&d, wi), c = v3_dot(wi, d.n);
        cr_assert(pdf > 0.0f, "sample %d has pdf 0", i);
        Vec3 x = v3_scale(bsdf_diffuse_eval(&d, wi), fabsf(c) / pdf);
        double *side = c > 0.0f ? up : down;
        side[0] += x.x;
        side[1] += x.y;
        side[2] += x.z;
    }
    /* f |cos| / pdf is constant on each side (the sampler is exact): tight */
    const float rr[3] = {r.x, r.y, r.z}, tt[3] = {t.x, t.y, t.z};
    for (int c = 0; c < 3; c++) {
        cr_assert_float_eq(up[c] / n, rr[c], 0.01, "channel %d reflected %g, expected %g", c, up[c] / n, rr[c]);
        cr_assert_float_eq(down[c] / n, tt[c], 0.01, "channel %d transmitted %g, expected %g", c, down[c] / n,
                           tt[c]);
    }
    /* the integrator's one side per vertex: in expectation the same */
    double sum[3] = {0};
    for (int i = 0; i < n; i++) {
        Vec3 a;
        bsdf_diffuse_side(&d, sg_rng_float(&rng), &a);
        sum[0] += a.x;
        sum[1] += a.y;
        sum[2] += a.z;
    }
    for (int c = 0; c < 3; c++)
        cr_assert_float_eq(sum[c] / n, rr[c] + tt[c], 0.01, "side choice, channel %d: %g", c, sum[c] / n);
    /* a pure transmitter never reflects */
    DiffuseTransmission only_t = bsdf_diffuse_transmission(v3(0, 0, 1), v3(0, 0, 0), v3(0.5f, 0.5f, 0.5f));
    Vec3 a;
    cr_assert(bsdf_diffuse_side(&only_t, 0.0f, &a));
    cr_assert_float_eq(a.x, 0.5f, 1e-6f);
}

/* The material keeps R + T <= 1 and is black only when both are. */
Test(render_bsdf, diffuse_transmission_material_conserves_energy)
{
    SgMaterial sm;
    sg_material_default(&sm, "shade");
    sm.type = SG_MATERIAL_DIFFUSE_TRANSMISSION;
    const float r[3] = {0.8f, 0.2f, 0.0f}, t[3] = {0.8f, 0.3f, 0.0f};
    memcpy(sm.diffuse, r, sizeof r);
    memcpy(sm.transmittance, t, sizeof t);
    Material m;
    material_init(&m, &sm);
    cr_assert_float_eq(m.kd.x + m.kt.x, 1.0f, 1e-5f);
    cr_assert(!m.black && !m.delta && !m.microfacet);
    sm.diffuse[0] = sm.diffuse[1] = 0.0f;
    sm.transmittance[0] = sm.transmittance[1] = 0.0f;
    material_init(&m, &sm);
    cr_assert(m.black);
}
