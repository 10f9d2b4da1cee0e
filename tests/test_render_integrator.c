/* End-to-end tests of the path tracer on analytic scenes built in memory:
 * furnace (exact answer 1), a plane under a uniform emitter (closed form),
 * determinism across thread counts, scale invariance, and agreement of the
 * guided and bsdf estimators. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../render/bsdf.h"
#include "scene_builder.h"
#include "../render/guides/openpgl_field.h"
#include "../render/renderer.h"
#include "image_io.h"
#include "support_files.h"
#include "support_render.h"

typedef struct Stats {
    double mean[3];
    double std_error; /* of the luminance-free channel-0 mean over every sample */
    double min_pixel, max_pixel;
    uint64_t nonfinite;
    double branches; /* split off per camera path */
    double lobe_share; /* of the diffuse and glossy bounces, drawn by the guide */
} Stats;

/* Renders `spp` passes; the mean over every sample of the image (or of
 * the pixel window [x0,x1)x[y0,y1)) with its standard error from the
 * spread of the samples (they are independent). */
static Stats render_stats(SgRenderer *r, const SgRenderOptions *o, int spp, int x0, int y0, int x1, int y1)
{
    double sum[3] = {0}, sum2 = 0;
    long n = 0;
    for (int p = 0; p < spp; p++) {
        sg_renderer_pass(r);
        const float *last = sg_renderer_last_pass(r);
        for (int y = y0; y < y1; y++)
            for (int x = x0; x < x1; x++) {
                const float *c = last + 3 * ((size_t)y * o->width + x);
                for (int i = 0; i < 3; i++)
                    sum[i] += c[i];
                sum2 += (double)c[0] * c[0];
                n++;
            }
    }
    Stats st = {0};
    for (int i = 0; i < 3; i++)
        st.mean[i] = sum[i] / n;
    st.std_error = sqrt(fmax(0.0, sum2 / n - st.mean[0] * st.mean[0]) / (n - 1));
    float *img = malloc(sizeof(float) * 3 * o->width * o->height);
    sg_renderer_image(r, img);
    st.min_pixel = INFINITY;
    st.max_pixel = -INFINITY;
    for (int y = y0; y < y1; y++)
        for (int x = x0; x < x1; x++) {
            double v = img[3 * ((size_t)y * o->width + x)];
            st.min_pixel = fmin(st.min_pixel, v);
            st.max_pixel = fmax(st.max_pixel, v);
        }
    st.nonfinite = sgt_stats(r).nonfinite;
    st.branches = sgt_stats(r).branches_per_path;
    st.lobe_share = sgt_stats(r).lobe_share;
    free(img);
    return st;
}

/* render_stats of a renderer made and freed for the purpose. */
static Stats render_scene_stats(const SgScene *s, const SgRenderOptions *o, int spp, int x0, int y0, int x1,
                                int y1)
{
    SgError err = {0};
    SgRenderer *r = sg_renderer_create(s, o, &err);
    cr_assert_not_null(r, "%s", err.message);
    Stats st = render_stats(r, o, spp, x0, y0, x1, y1);
    sg_renderer_free(r);
    return st;
}

/* Closed box, inward normals, albedo 0.5, emission 0.5: L = 0.5 + 0.5 L = 1. */
static SgScene *furnace_scene(void) { return sgt_furnace_scene(); }

/* How a furnace is rendered, and what share of its bounces the guide's
 * lobe must draw (lobe_min <= share <= lobe_max). */
typedef struct FurnaceCase {
    SgSampling mode;
    double scale;        /* the scene scaled and moved far from the origin (1: as made) */
    float alpha;         /* guided: the mixture's BSDF share, or SG_ALPHA_LEARNED */
    float lobe_exponent;
    SgImportanceFn guide; /* NULL: a fixed point inside the box */
    double lobe_min, lobe_max;
    int spp;             /* 0: 64 */
} FurnaceCase;

/* The guide's axis is the wall's inward normal: the importance point is
 * one unit along the normal of the face of the furnace box nearest p. With
 * the axis on the normal the lobe covers the whole hemisphere, so even
 * the paper's lobe-only rule has the exact answer. */
static bool normal_axis_guide(void *ctx, const double p[3], uint32_t light, double q[3])
{
    (void)ctx;
    (void)light;
    const double lo[3] = {-1, -1, -1}, hi[3] = {1, 1.5, 2};
    int axis = 0;
    double best = INFINITY, sign = 1;
    for (int a = 0; a < 3; a++) {
        if (p[a] - lo[a] < best)
            best = p[a] - lo[a], axis = a, sign = 1;
        if (hi[a] - p[a] < best)
            best = hi[a] - p[a], axis = a, sign = -1;
    }
    memcpy(q, p, 3 * sizeof *q);
    q[axis] += sign;
    return true;
}

/* The furnace's walls glow but are no lights, and its one light is a quad
 * outside that faces away: next-event estimation never reaches it, so no
 * vertex is directly lit and the paper's rule draws the lobe everywhere.
 * The answer stays 1 (the walls' emission is found by the bounces). */
static void hide_the_lights(SgScene *s)
{
    const float black[3] = {0, 0, 0}, glow[3] = {1, 1, 1};
    uint32_t lm = sgt_add_material(s, SG_MATERIAL_DIFFUSE, black, glow);
    const double away[4][3] = {{-1, 3, -1}, {-1, 3, 1}, {1, 3, 1}, {1, 3, -1}}; /* above the box, facing up */
    sgt_add_quad(s, away, lm);
    sgt_finish(s);
    uint32_t hidden = s->light_count - 1;
    for (uint32_t t = 0; t < s->triangle_count; t++)
        s->triangle_light[t] = s->triangle_light[t] == hidden ? 0 : SG_NO_LIGHT;
    s->lights[0] = s->lights[hidden];
    s->light_count = 1;
}

static void skip_without_openpgl(void)
{
    if (!sg_pgl_available())
        cr_skip_test("this build has no Open PGL (make openpgl builds it)");
}

static void furnace_run(const FurnaceCase *fc)
{
    if (fc->mode == SG_SAMPLING_OPENPGL)
        skip_without_openpgl();
    SgScene *s = furnace_scene();
    const double scale = fc->scale;
    const double offset[3] = {3e3 * scale, -1e3 * scale, 7e2 * scale};
    if (scale != 1.0)
        sgt_scale_offset(s, scale, offset);
    sgt_finish(s);
    if (fc->guide == normal_axis_guide)
        hide_the_lights(s);
    SgRenderOptions o;
    sg_render_options_default(&o, s);
    o.max_depth = 64; /* truncation error 0.5^64 */
    o.sampling = fc->mode;
    o.alpha = fc->alpha;
    o.seed = 5;
    SgtFixedPoint fp = {{0.9 * scale + offset[0] * (scale != 1.0), -0.8 * scale + offset[1] * (scale != 1.0),
                      1.7 * scale + offset[2] * (scale != 1.0)}};
    o.importance.importance_point = fc->guide ? fc->guide : sgt_fixed_point_guide;
    o.importance.ctx = &fp;
    o.lobe_exponent = fc->lobe_exponent;
    const int spp = fc->spp ? fc->spp : 64;
    SgError err = {0};
    SgRenderer *r = sg_renderer_create(s, &o, &err);
    cr_assert_not_null(r, "%s", err.message);
    Stats st = render_stats(r, &o, spp, 0, 0, o.width, o.height);
    double lobe = sgt_stats(r).lobe_share;
    sg_renderer_free(r);
    const char *name = sg_sampling_name(fc->mode);
    cr_log_info("furnace %s alpha %g scale %g: mean %.5f %.5f %.5f +- %.5f, pixels in [%.3f, %.3f], "
                "lobe drew %.4f of bounces, %.2f branches split off a path",
                name, fc->alpha, scale, st.mean[0], st.mean[1], st.mean[2], st.std_error, st.min_pixel,
                st.max_pixel, lobe, st.branches);
    cr_assert_eq(st.nonfinite, 0);
    cr_assert(lobe >= fc->lobe_min && lobe <= fc->lobe_max, "furnace %s: the lobe drew %.4f of the bounces, "
              "expected [%.2f, %.2f]", name, lobe, fc->lobe_min, fc->lobe_max);
    /* guided's learned roulette splits paths here, so the exact answer
     * checks the branches' weights too */
    if (fc->mode == SG_SAMPLING_GUIDED && fc->alpha == SG_ALPHA_LEARNED)
        cr_assert_gt(st.branches, 0.2, "furnace guided: %.3f branches split off a path", st.branches);
    /* the mean over 768 samples a pass: within 4 standard errors of exactly 1 */
    cr_assert(fabs(st.mean[0] - 1.0) < 4.0 * st.std_error + 1e-6,
              "furnace %s: mean %.5f, expected 1 +- %.5f", name, st.mean[0], 4.0 * st.std_error);
    cr_assert(st.std_error < 0.02, "furnace %s: standard error %.4f is suspiciously large", name, st.std_error);
    /* and no pixel far off: sigma_pixel = se * sqrt(768).
     * Only for BSDF sampling, whose weights are bounded by the albedo: a
     * guided weight may reach 1/alpha times that at every bounce, and the
     * paper's lobe-only weights are unbounded (its fireflies), so the tails
     * are too heavy for a Gaussian bound on single pixels. */
    if (fc->mode == SG_SAMPLING_BSDF) {
        double pixel_sigma = st.std_error * sqrt((double)o.width * o.height);
        cr_assert(st.min_pixel > 1.0 - 6 * pixel_sigma && st.max_pixel < 1.0 + 6 * pixel_sigma,
                  "furnace %s: a pixel at %.3f / %.3f", name, st.min_pixel, st.max_pixel);
    }
    sgt_scene_free(s);
}

static void furnace_case(SgSampling mode, double scale)
{
    FurnaceCase fc = {mode, scale, SG_ALPHA_LEARNED, 8, NULL, 0.0, 1.0, 64};
    if (mode == SG_SAMPLING_BSDF)
        fc.lobe_max = 0.0;
    furnace_run(&fc);
}

Test(render_integrator, furnace_bsdf) { furnace_case(SG_SAMPLING_BSDF, 1.0); }
/* the learner settles on the BSDF here (every wall is lit): this checks
 * the learned roulette's and the splitting's weights, not the mixture */
Test(render_integrator, furnace_guided) { furnace_case(SG_SAMPLING_GUIDED, 1.0); }
Test(render_integrator, furnace_tiny_scale_far_from_origin) { furnace_case(SG_SAMPLING_BSDF, 1e-4); }
Test(render_integrator, furnace_huge_scale_far_from_origin) { furnace_case(SG_SAMPLING_GUIDED, 1e5); }

/* The mixture itself: with a fixed alpha every vertex has the lobe (the
 * importance point is inside the convex box, so every axis is above its
 * wall), which draws 1 - alpha of the bounces; the mixture's pdf weights
 * both the bounce and, through MIS, the next-event estimate. */
Test(render_integrator, furnace_guided_alpha_half)
{
    FurnaceCase fc = {SG_SAMPLING_GUIDED, 1.0, 0.5f, 8, NULL, 0.49, 0.51, 512};
    furnace_run(&fc);
}

Test(render_integrator, furnace_guided_alpha_quarter_narrow_lobe)
{
    FurnaceCase fc = {SG_SAMPLING_GUIDED, 1.0, 0.25f, 16, NULL, 0.74, 0.76, 1024};
    furnace_run(&fc);
}

/* The peer: Open PGL's field learns during the passes and draws up to
 * half of the diffuse bounces (Cycles' guiding probability) once trained. */
Test(render_integrator, furnace_openpgl)
{
    FurnaceCase fc = {SG_SAMPLING_OPENPGL, 1.0, SG_ALPHA_LEARNED, 8, NULL, 0.3, 0.5, 128};
    furnace_run(&fc);
}

/* The paper's rule with the lobe at every vertex (none is directly lit):
 * the lobe's weights alone, f cos / ((p + 1) / (2 pi) cos^p), must sum to
 * the exact answer (p = 2 keeps their variance finite). */
Test(render_integrator, furnace_skeleton_lobe_at_every_vertex)
{
    FurnaceCase fc = {SG_SAMPLING_SKELETON, 1.0, SG_ALPHA_LEARNED, 2, normal_axis_guide, 0.995, 1.0, 256};
    furnace_run(&fc);
}

/* Point-to-parallel-rectangle form factor, the point below one corner of
 * an a x b rectangle at distance c. */
static double corner_form_factor(double a, double b, double c)
{
    double A = a / c, B = b / c;
    double sa = sqrt(1 + A * A), sb = sqrt(1 + B * B);
    return (A / sa * atan(B / sa) + B / sb * atan(A / sb)) / (2 * M_PI);
}

/* A black square (2a wide) emitting le downward at height h. */
static void add_square_light(SgScene *s, double a, double h, float le)
{
    const float black[3] = {0, 0, 0}, em[3] = {le, le, le};
    uint32_t light_m = sgt_add_material(s, SG_MATERIAL_DIFFUSE, black, em);
    const double light[4][3] = {{-a, h, -a}, {a, h, -a}, {a, h, a}, {-a, h, a}}; /* faces down */
    sgt_add_quad(s, light, light_m);
}

/* A 100-wide horizontal quad at height y, facing up. */
static void add_wide_quad(SgScene *s, double y, uint32_t material)
{
    const double q[4][3] = {{-50, y, -50}, {-50, y, 50}, {50, y, 50}, {50, y, -50}};
    sgt_add_quad(s, q, material);
}

/* s finished and seen from (0, camera_y, 0) straight at the origin (a 9 mm
 * patch at 0.5), 256 passes under `mode` (the guides led to a point of a
 * light at height 1); s freed. */
static Stats render_origin_view(SgScene *s, SgSampling mode, uint64_t seed, double camera_y)
{
    const double pos[3] = {0, camera_y, 0}, at[3] = {0, 0, 0}, up[3] = {0, 0, 1};
    sgt_set_camera(s, pos, at, up, 1.0, 16, 16);
    sgt_finish(s);
    SgRenderOptions o;
    sg_render_options_default(&o, s);
    o.sampling = mode;
    o.seed = seed;
    SgtFixedPoint fp = {{0.3, 1.0, -0.2}};
    o.importance.importance_point = sgt_fixed_point_guide;
    o.importance.ctx = &fp;
    Stats st = render_scene_stats(s, &o, 256, 0, 0, o.width, o.height);
    sgt_scene_free(s);
    return st;
}

/* The mean within 4 standard errors and `rel` of the expected value. */
static void expect_mean(const char *what, SgSampling mode, Stats st, double expected, double rel)
{
    cr_log_info("%s %s: %.5f +- %.5f, expected %.5f", what, sg_sampling_name(mode), st.mean[0], st.std_error,
                expected);
    cr_assert_eq(st.nonfinite, 0);
    cr_assert(fabs(st.mean[0] - expected) <= 4.0 * st.std_error + rel * expected,
              "%s %s: %.5f, expected %.5f +- %.5f", what, sg_sampling_name(mode), st.mean[0], expected,
              4 * st.std_error);
}

/* A diffuse floor (albedo rho) under a black emitting square of radiance
 * Le at height h: at the floor's centre L = rho Le 4 F(a, a, h). */
static void plane_case(SgSampling mode, SgMaterialType floor_type)
{
    const double a = 2.0, h = 1.0;
    const float rho = 0.6f, le = 2.0f;
    SgScene *s = sgt_scene_new();
    const float alb[3] = {rho, rho, rho};
    add_wide_quad(s, 0, sgt_add_material(s, floor_type, alb, NULL));
    add_square_light(s, a, h, le);
    double expected = rho * le * 4.0 * corner_form_factor(a, a, h);
    expect_mean("plane", mode, render_origin_view(s, mode, 11, 0.5), expected, 1e-3);
}

Test(render_integrator, plane_under_square_light_bsdf) { plane_case(SG_SAMPLING_BSDF, SG_MATERIAL_DIFFUSE); }
Test(render_integrator, plane_under_square_light_guided) { plane_case(SG_SAMPLING_GUIDED, SG_MATERIAL_DIFFUSE); }

/* A lamp shade: a diffuse transmitter (R, T) across the whole floor plane,
 * under the emitting square of plane_case, seen from below: what passes
 * is T / pi times the irradiance above, L = T Le 4 F(a, a, h); what it
 * reflects goes up to the black light and is lost. */
static void lamp_shade_case(SgSampling mode)
{
    const double a = 2.0, h = 1.0;
    const float r = 0.3f, t = 0.5f, le = 2.0f;
    SgScene *s = sgt_scene_new();
    const float refl[3] = {r, r, r};
    uint32_t shade_m = sgt_add_material(s, SG_MATERIAL_DIFFUSE_TRANSMISSION, refl, NULL);
    for (int c = 0; c < 3; c++)
        sgt_material(s, shade_m)->transmittance[c] = t;
    add_wide_quad(s, 0, shade_m);
    add_square_light(s, a, h, le);
    double expected = t * le * 4.0 * corner_form_factor(a, a, h);
    expect_mean("lamp shade", mode, render_origin_view(s, mode, 12, -0.5), expected, 1e-3);
}

Test(render_integrator, lamp_shade_transmits_bsdf) { lamp_shade_case(SG_SAMPLING_BSDF); }
Test(render_integrator, lamp_shade_transmits_guided) { lamp_shade_case(SG_SAMPLING_GUIDED); }
Test(render_integrator, lamp_shade_transmits_openpgl) /* a guide that learns what crosses the shade */
{
    skip_without_openpgl();
    lamp_shade_case(SG_SAMPLING_OPENPGL);
}

/* ---- cut-outs ------------------------------------------------------------ */

/* plane_case's floor and light with a black screen between them (y = 0.75)
 * made a cut-out: alpha a constant, or (alpha < 0) a fine checkerboard of
 * alpha 1 and 0; `passed`: the share of the light expected through it. */
static void cut_screen_case(SgSampling mode, float alpha, double passed)
{
    SgScene *s = sgt_scene_new();
    const float alb[3] = {0.6f, 0.6f, 0.6f}, black[3] = {0, 0, 0};
    uint32_t floor_m = sgt_add_material(s, SG_MATERIAL_DIFFUSE, alb, NULL);
    uint32_t screen_m = sgt_add_material(s, SG_MATERIAL_DIFFUSE, black, NULL);
    SgMaterial *screen = sgt_material(s, screen_m);
    screen->cutout = true;
    screen->alpha = alpha < 0.0f ? 1.0f : alpha;
    if (alpha < 0.0f) { /* squares of 0.05 over the 100-wide screen */
        screen->alpha_texture = 1;
        s->textures = calloc(1, sizeof *s->textures);
        s->texture_count = 1;
        s->textures[0] = (SgTexture){.kind = SG_TEXTURE_CHECKERBOARD, .uscale = 2000, .vscale = 2000, .scale = 1,
                                     .input = {{0, {1, 1, 1}}, {0, {0, 0, 0}}}, .mean = {0.5f, 0.5f, 0.5f}};
    }
    add_wide_quad(s, 0, floor_m);
    add_square_light(s, 2.0, 1.0, 2.0f);
    add_wide_quad(s, 0.75, screen_m);
    s->uvs = malloc(2 * s->vertex_count * sizeof *s->uvs);
    for (uint32_t v = 0; v < s->vertex_count; v++) { /* u, v in [0, 1] across each quad */
        s->uvs[2 * v] = (float)((s->positions[3 * v] + 50) / 100);
        s->uvs[2 * v + 1] = (float)((s->positions[3 * v + 2] + 50) / 100);
    }
    char what[64];
    snprintf(what, sizeof what, "screen alpha %g", alpha);
    double expected = passed * 0.6 * 2.0 * 4.0 * corner_form_factor(2, 2, 1);
    expect_mean(what, mode, render_origin_view(s, mode, 13, 0.5), expected, 1e-2);
}

/* alpha 0: no shadow at all; 0.5: half the rays pass; a checkerboard
 * texture of open and closed squares: half the light. */
Test(render_integrator, cutout_alpha_0_casts_no_shadow) { cut_screen_case(SG_SAMPLING_BSDF, 0.0f, 1.0); }
Test(render_integrator, cutout_alpha_0_guided) { cut_screen_case(SG_SAMPLING_GUIDED, 0.0f, 1.0); }
Test(render_integrator, cutout_constant_alpha_half) { cut_screen_case(SG_SAMPLING_BSDF, 0.5f, 0.5); }
Test(render_integrator, cutout_half_cut_texture_passes_half) { cut_screen_case(SG_SAMPLING_BSDF, -1.0f, 0.5); }
Test(render_integrator, cutout_opaque_alpha_1_is_a_shadow) { cut_screen_case(SG_SAMPLING_BSDF, 1.0f, 0.0); }

/* ---- shading normals ------------------------------------------------------ */

/* A constant tangent-space normal map tilted by theta toward the mesh's u
 * direction (rgb = (n + 1) / 2), as texture 1 of s. */
static void add_tilted_normal_map(SgScene *s, double theta)
{
    s->textures = calloc(1, sizeof *s->textures);
    s->texture_count = 1;
    float c[3] = {(float)(0.5 + 0.5 * sin(theta)), 0.5f, (float)(0.5 + 0.5 * cos(theta))};
    s->textures[0] = (SgTexture){.kind = SG_TEXTURE_SCALE, .uscale = 1, .vscale = 1, .scale = 1,
                                 .input = {{0, {c[0], c[1], c[2]}}, {0, {1, 1, 1}}},
                                 .mean = {c[0], c[1], c[2]}};
}

/* u = x, v = z: a floor's tangent is +x. */
static void uv_from_xz(SgScene *s)
{
    s->uvs = malloc(2 * s->vertex_count * sizeof *s->uvs);
    for (uint32_t v = 0; v < s->vertex_count; v++) {
        s->uvs[2 * v] = (float)s->positions[3 * v];
        s->uvs[2 * v + 1] = (float)s->positions[3 * v + 2];
    }
}

/* How the floor of tilted_floor is made. */
typedef enum FloorTilt { FLOOR_TILTED_PLUS_X, FLOOR_TILTED_MINUS_X, FLOOR_NORMAL_MAP, FLOOR_BUMP_MAP } FloorTilt;

/* A displacement rising toward +x, k world units per unit of u, as an
 * image (bilinear: exactly linear between texel centres); its path. */
static const char *ramp_image(double k)
{
    enum { W = 64 };
    static char path[4200];
    float rgb[3 * W * 2];
    for (int y = 0; y < 2; y++)
        for (int x = 0; x < W; x++)
            for (int c = 0; c < 3; c++)
                rgb[3 * (y * W + x) + c] = (float)(k * (x + 0.5) / W);
    snprintf(path, sizeof path, "%s/ramp.exr", sg_test_tmpdir());
    SgError err = {0};
    cr_assert(sg_image_write_exr(path, W, 2, rgb, NULL, 0, &err), "%s", err.message);
    return path;
}

/* The floor's centre under a square light off to +x: a quad truly tilted
 * by 30 degrees toward +x or -x, or flat with a normal map tilted toward
 * +x, or with a bump map rising toward +x (its normal leans toward -x). */
static Stats tilted_floor(FloorTilt how)
{
    const double a = 0.8, cx = 0.5, h = 1.0, theta = 30.0 * M_PI / 180.0;
    SgScene *s = sgt_scene_new();
    const float alb[3] = {0.6f, 0.6f, 0.6f}, black[3] = {0, 0, 0}, em[3] = {2, 2, 2};
    uint32_t floor_m = sgt_add_material(s, SG_MATERIAL_DIFFUSE, alb, NULL);
    uint32_t light_m = sgt_add_material(s, SG_MATERIAL_DIFFUSE, black, em);
    if (how == FLOOR_NORMAL_MAP || how == FLOOR_BUMP_MAP) {
        if (how == FLOOR_NORMAL_MAP) {
            sgt_material(s, floor_m)->normal_texture = 1;
            add_tilted_normal_map(s, theta);
        } else { /* u = (x + 50) / 100: dp/du is 100 x, so slope tan(theta) is k = 100 tan(theta) */
            sgt_material(s, floor_m)->bump_texture = 1;
            sgt_material(s, floor_m)->bump_scale = 1;
            s->textures = calloc(1, sizeof *s->textures);
            s->texture_count = 1;
            s->textures[0] = (SgTexture){.kind = SG_TEXTURE_IMAGE, .uscale = 1, .vscale = 1, .scale = 1,
                                         .path = strdup(ramp_image(100 * tan(theta))), .wrap = SG_WRAP_CLAMP};
        }
        const double floor[4][3] = {{-50, 0, -50}, {-50, 0, 50}, {50, 0, 50}, {50, 0, -50}};
        sgt_add_quad(s, floor, floor_m);
    } else { /* normal (sign sin, cos, 0): the plane sign x sin + y cos = 0 */
        double sign = how == FLOOR_TILTED_PLUS_X ? 1 : -1, ux = 0.5 * cos(theta), uy = -0.5 * sign * sin(theta);
        const double floor[4][3] = {{-ux, -uy, -0.5}, {-ux, -uy, 0.5}, {ux, uy, 0.5}, {ux, uy, -0.5}};
        sgt_add_quad(s, floor, floor_m);
    }
    const double light[4][3] = {{cx - a, h, -a}, {cx + a, h, -a}, {cx + a, h, a}, {cx - a, h, a}};
    sgt_add_quad(s, light, light_m);
    const double pos[3] = {0, 0.5, 0}, at[3] = {0, 0, 0}, up[3] = {0, 0, 1};
    sgt_set_camera(s, pos, at, up, 1.0, 16, 16);
    s->uvs = malloc(2 * s->vertex_count * sizeof *s->uvs);
    for (uint32_t v = 0; v < s->vertex_count; v++) {
        s->uvs[2 * v] = (float)((s->positions[3 * v] + 50) / 100);
        s->uvs[2 * v + 1] = (float)((s->positions[3 * v + 2] + 50) / 100);
    }
    sgt_finish(s);
    SgRenderOptions o;
    sg_render_options_default(&o, s);
    o.seed = 14 + (uint64_t)how;
    Stats st = render_scene_stats(s, &o, 256, 0, 0, o.width, o.height);
    sgt_scene_free(s);
    return st;
}

static void expect_same_floor(const char *what, Stats got, Stats want)
{
    double tol = 4.0 * hypot(got.std_error, want.std_error) + 1e-3 * want.mean[0];
    cr_log_info("%s %.5f +- %.5f, tilted quad %.5f +- %.5f", what, got.mean[0], got.std_error, want.mean[0],
                want.std_error);
    cr_assert_eq(got.nonfinite, 0);
    cr_assert(fabs(got.mean[0] - want.mean[0]) < tol, "%s %.5f, tilted %.5f +- %.5f", what, got.mean[0],
              want.mean[0], tol);
}

Test(render_integrator, normal_and_bump_maps_reflect_like_a_tilted_quad)
{
    Stats plus = tilted_floor(FLOOR_TILTED_PLUS_X), minus = tilted_floor(FLOOR_TILTED_MINUS_X);
    /* the light is off to +x: the two tilts differ, so the side is tested */
    cr_assert_gt(plus.mean[0] - minus.mean[0], 10.0 * hypot(plus.std_error, minus.std_error));
    expect_same_floor("normal-mapped", tilted_floor(FLOOR_NORMAL_MAP), plus);
    expect_same_floor("bump-mapped", tilted_floor(FLOOR_BUMP_MAP), minus);
}

/* A small patch whose normal map leans 80 degrees toward a light below its
 * plane: the shading normal sees the light, the surface does not. Nothing
 * may reach the camera above (no light through the surface: light samples
 * and bounces below the geometric surface count for nothing, and the
 * surface itself stands in the way of what would). */
Test(render_integrator, normal_map_lets_no_light_through_the_surface)
{
    SgScene *s = sgt_scene_new();
    const float alb[3] = {0.8f, 0.8f, 0.8f}, black[3] = {0, 0, 0}, em[3] = {5, 5, 5};
    uint32_t patch_m = sgt_add_material(s, SG_MATERIAL_DIFFUSE, alb, NULL);
    uint32_t light_m = sgt_add_material(s, SG_MATERIAL_DIFFUSE, black, em);
    sgt_material(s, patch_m)->normal_texture = 1;
    add_tilted_normal_map(s, 80.0 * M_PI / 180.0);
    const double patch[4][3] = {{-0.1, 0, -0.1}, {-0.1, 0, 0.1}, {0.1, 0, 0.1}, {0.1, 0, -0.1}}; /* faces up */
    const double light[4][3] = {{0.5, -0.3, -0.5}, {0.5, -0.3, 0.5}, {1.5, -0.3, 0.5}, {1.5, -0.3, -0.5}};
    sgt_add_quad(s, patch, patch_m);
    sgt_add_quad(s, light, light_m); /* faces up, toward the patch's underside */
    const double pos[3] = {0, 0.5, 0}, at[3] = {0, 0, 0}, up[3] = {0, 0, 1};
    sgt_set_camera(s, pos, at, up, 1.0, 16, 16);
    uv_from_xz(s);
    sgt_finish(s);
    SgRenderOptions o;
    sg_render_options_default(&o, s);
    o.seed = 16;
    Stats st = render_scene_stats(s, &o, 64, 0, 0, o.width, o.height);
    cr_log_info("patch over a light below it: %.6f (max %.6f)", st.mean[0], st.max_pixel);
    cr_assert_eq(st.max_pixel, 0.0, "light came through the surface: max pixel %g", st.max_pixel);
    sgt_scene_free(s);
}

/* ---- materials: exact answers ------------------------------------------ */

/* Turns the triangles of s whose three vertices have coordinate `axis`
 * equal to `value` to material m (a face of a box made by sgt_add_box_inside). */
static void set_face_material(SgScene *s, int axis, double value, uint32_t m)
{
    for (uint32_t t = 0; t < s->triangle_count; t++) {
        bool on = true;
        for (int k = 0; k < 3; k++)
            on = on && s->positions[3 * s->indices[3 * t + k] + axis] == value;
        if (on)
            s->triangle_material[t] = m;
    }
}

/* The directional albedo of the normalized Phong lobe, seen at theta_o
 * from the normal: the integral over the upper hemisphere of
 * (p + 2) / (2 pi) max(0, wi.r)^p cos(theta_i), r the mirror direction,
 * by the midpoint rule (it is exactly 1 at normal incidence). */
static double phong_albedo(double p, double theta_o)
{
    const int nt = 2000, np = 2000;
    const double r[3] = {-sin(theta_o), 0.0, cos(theta_o)};
    double sum = 0.0;
    for (int i = 0; i < nt; i++) {
        double t = (i + 0.5) * (M_PI / 2) / nt;
        for (int j = 0; j < np; j++) {
            double ph = (j + 0.5) * 2 * M_PI / np;
            double c = sin(t) * cos(ph) * r[0] + sin(t) * sin(ph) * r[1] + cos(t) * r[2];
            if (c > 0.0)
                sum += pow(c, p) * cos(t) * sin(t);
        }
    }
    return sum * (M_PI / 2 / nt) * (2 * M_PI / np) * (p + 2) / (2 * M_PI);
}

/* A floor of material `floor` in a box whose other walls glow (radiance 1,
 * black), its centre seen from theta_deg off its normal (guided: with a
 * fixed alpha 0.5 and the lobe toward a point under the ceiling): the
 * render's statistics over spp passes, and the share of bounces the lobe
 * drew. What the floor reflects is its directional albedo. */
static Stats floor_in_glowing_box_lit(SgSampling mode, const SgMaterial *floor, double theta_deg, uint64_t seed,
                                      int spp, double *lobe_share, bool glow_below);

static Stats floor_in_glowing_box(SgSampling mode, const SgMaterial *floor, double theta_deg, uint64_t seed, int spp,
                                  double *lobe_share)
{
    return floor_in_glowing_box_lit(mode, floor, theta_deg, seed, spp, lobe_share, false);
}

/* glow_below: a wide plane under the floor glows upward too (radiance 1),
 * for what a dielectric floor lets through. */
static Stats floor_in_glowing_box_lit(SgSampling mode, const SgMaterial *floor, double theta_deg, uint64_t seed,
                                      int spp, double *lobe_share, bool glow_below)
{
    SgScene *s = sgt_scene_new();
    const float black[3] = {0, 0, 0}, glow[3] = {1, 1, 1};
    uint32_t wall = sgt_add_material(s, SG_MATERIAL_DIFFUSE, black, glow);
    uint32_t floor_m = sgt_add_material(s, floor->type, floor->diffuse, NULL);
    *sgt_material(s, floor_m) = *floor;
    const double lo[3] = {-1, 0, -1}, hi[3] = {1, 2, 1};
    sgt_add_box_inside(s, lo, hi, wall);
    set_face_material(s, 1, 0.0, floor_m);
    if (glow_below) {
        const double below[4][3] = {{-100, -1, -100}, {-100, -1, 100}, {100, -1, 100}, {100, -1, -100}};
        sgt_add_quad(s, below, wall);
    }
    double th = theta_deg * M_PI / 180.0;
    const double pos[3] = {0.5 * sin(th), 0.5 * cos(th), 0}, at[3] = {0, 0, 0};
    const double up_z[3] = {0, 0, 1}, up_y[3] = {0, 1, 0};
    sgt_set_camera(s, pos, at, theta_deg == 0 ? up_z : up_y, 1.0, 16, 16);
    sgt_finish(s);
    SgRenderOptions o;
    sg_render_options_default(&o, s);
    o.sampling = mode;
    o.alpha = 0.5f;
    o.seed = seed;
    SgtFixedPoint fp = {{0.4, 1.2, -0.3}};
    o.importance.importance_point = sgt_fixed_point_guide;
    o.importance.ctx = &fp;
    SgError err = {0};
    SgRenderer *r = sg_renderer_create(s, &o, &err);
    cr_assert_not_null(r, "%s", err.message);
    Stats st = render_stats(r, &o, spp, 0, 0, o.width, o.height);
    *lobe_share = sgt_stats(r).lobe_share;
    sg_renderer_free(r);
    sgt_scene_free(s);
    return st;
}

/* A glossy floor in the glowing box reflects Le (kd + ks A(theta_o)), A
 * the Phong lobe's directional albedo. At normal incidence A = 1: energy
 * exactly conserved. Away from it part of the lobe is below the floor and
 * lost: A < 1, as computed. */
static void glossy_case(SgSampling mode, double theta_deg)
{
    const float kd = 0.3f, ks = 0.6f, p = 20.0f, le = 1.0f;
    SgMaterial floor;
    sg_material_default(&floor, "floor");
    floor.type = SG_MATERIAL_GLOSSY;
    for (int i = 0; i < 3; i++) {
        floor.diffuse[i] = kd;
        floor.specular[i] = ks;
    }
    floor.exponent = p;
    double th = theta_deg * M_PI / 180.0, lobe;
    Stats st = floor_in_glowing_box(mode, &floor, theta_deg, 21, 1024, &lobe);
    double albedo = phong_albedo(p, th);
    double expected = le * (kd + ks * albedo);
    cr_log_info("glossy floor %s at %g degrees: %.5f +- %.5f, expected %.5f (Phong albedo %.5f), lobe drew %.3f",
                sg_sampling_name(mode), theta_deg, st.mean[0], st.std_error, expected, albedo, lobe);
    if (theta_deg == 0)
        cr_assert(fabs(albedo - 1.0) < 1e-4, "the quadrature gives %.6f at normal incidence", albedo);
    else
        cr_assert_lt(albedo, 0.95, "a lobe this far from the normal loses energy: %.4f", albedo);
    if (mode == SG_SAMPLING_GUIDED)
        cr_assert(lobe > 0.48 && lobe < 0.52, "the lobe drew %.3f of the bounces", lobe);
    cr_assert_eq(st.nonfinite, 0);
    /* 1e-3: the pixels see the floor within half a degree of theta_o */
    cr_assert(fabs(st.mean[0] - expected) < 4.0 * st.std_error + 1e-3 * expected,
              "glossy floor %s at %g degrees: %.5f, expected %.5f +- %.5f", sg_sampling_name(mode), theta_deg,
              st.mean[0], expected, 4 * st.std_error);
}

/* The directional albedo of the BSDF of material m seen at theta_o (from
 * +z, wo in the xz plane), channel 0, by the midpoint rule over the upper
 * hemisphere of bsdf_eval: independent of every sampler. */
static double bsdf_albedo_quadrature(const SgMaterial *sm, double theta_o)
{
    Material m;
    material_init(&m, sm);
    Bsdf b;
    bsdf_init(&b, &m, v3(0, 0, 1), v3((float)sin(theta_o), 0.0f, (float)cos(theta_o)), m.kd);
    const int nt = 1500, np = 1500;
    double sum = 0.0;
    for (int i = 0; i < nt; i++) {
        double t = (i + 0.5) * (M_PI / 2) / nt;
        for (int j = 0; j < np; j++) {
            double ph = (j + 0.5) * 2 * M_PI / np;
            Vec3 wi = v3((float)(sin(t) * cos(ph)), (float)(sin(t) * sin(ph)), (float)cos(t));
            sum += bsdf_eval(&b, wi).x * cos(t) * sin(t);
        }
    }
    return sum * (M_PI / 2 / nt) * (2 * M_PI / np);
}

/* A rough conductor or a coated diffuse floor in a glowing box: the floor
 * reflects Le times the BSDF's directional albedo, whichever sampler draws
 * the bounces (the guided mixture with the skeleton lobe: unbiased with
 * the microfacet BSDFs' pdfs in its MIS). */
static void microfacet_floor_case(SgSampling mode, SgMaterialType type, double theta_deg)
{
    SgMaterial floor;
    sg_material_default(&floor, "floor");
    floor.type = type;
    floor.roughness[0] = floor.roughness[1] = 0.3f;
    const float eta[3] = {0.2f, 0.92f, 1.1f}, k[3] = {3.91f, 2.45f, 2.14f}; /* copper */
    memcpy(floor.eta, eta, sizeof eta);
    memcpy(floor.k, k, sizeof k);
    double lobe;
    Stats st = floor_in_glowing_box(mode, &floor, theta_deg, 23, 1024, &lobe);
    double expected = bsdf_albedo_quadrature(&floor, theta_deg * M_PI / 180.0);
    cr_log_info("%s floor %s at %g degrees: %.5f +- %.5f, expected %.5f, lobe drew %.4f",
                type == SG_MATERIAL_CONDUCTOR ? "conductor" : "coated", sg_sampling_name(mode), theta_deg, st.mean[0],
                st.std_error, expected, lobe);
    cr_assert_eq(st.nonfinite, 0);
    /* alpha 0.5 and the point above the floor: every floor vertex has the
     * lobe, which draws half the bounces (measured 0.5011); a guided mode
     * fallen back to BSDF sampling draws none */
    if (mode == SG_SAMPLING_GUIDED)
        cr_assert(lobe > 0.48 && lobe < 0.52, "the lobe drew %.4f of the bounces", lobe);
    cr_assert(fabs(st.mean[0] - expected) < 4.0 * st.std_error + 2e-3 * expected,
              "%s: %.5f, expected %.5f +- %.5f", sg_sampling_name(mode), st.mean[0], expected, 4 * st.std_error);
}

/* A rough glass floor (index 1.5, GGX alpha 0.3) between the glowing box
 * and a glowing plane below: it returns Le times the integral over the
 * whole sphere of f |cos| (render/microfacet.h; what it transmits carries
 * 1 / eta^2: the light below is seen from inside the glass), by
 * quadrature. */
static void rough_dielectric_floor_case(SgSampling mode, double theta_deg)
{
    SgMaterial floor;
    sg_material_default(&floor, "floor");
    floor.type = SG_MATERIAL_DIELECTRIC;
    floor.ior = 1.5f;
    floor.roughness[0] = floor.roughness[1] = 0.3f;
    double lobe;
    Stats st = floor_in_glowing_box_lit(mode, &floor, theta_deg, 29, 1024, &lobe, true);
    double th = theta_deg * M_PI / 180.0;
    Vec3 wo = v3((float)sin(th), 0.0f, (float)cos(th));
    const int nt = 1500, np = 1500;
    double expected = 0.0, reflected = 0.0;
    for (int i = 0; i < nt; i++) {
        double t = (i + 0.5) * M_PI / nt;
        for (int j = 0; j < np; j++) {
            double ph = (j + 0.5) * 2 * M_PI / np;
            Vec3 wi = v3((float)(sin(t) * cos(ph)), (float)(sin(t) * sin(ph)), (float)cos(t));
            double x = sg_ggx_dielectric_f(wo, wi, 1.5f, 0.3f, 0.3f) * fabs(cos(t)) * sin(t);
            expected += x;
            reflected += t < M_PI / 2 ? x : 0.0;
        }
    }
    expected *= (M_PI / nt) * (2 * M_PI / np);
    reflected *= (M_PI / nt) * (2 * M_PI / np);
    cr_log_info("rough glass floor %s at %g degrees: %.5f +- %.5f, expected %.5f (of it reflected %.5f), lobe drew %.4f",
                sg_sampling_name(mode), theta_deg, st.mean[0], st.std_error, expected, reflected, lobe);
    cr_assert_eq(st.nonfinite, 0);
    /* the plane below counts: without it only the reflected part would come back */
    cr_assert_gt(expected - reflected, 0.2);
    /* Rough glass is sampled by its BSDF alone in every mode (no guide, no
     * light sampling: renderer.c's rough_dielectric_bounce), and the walls
     * are black, so no vertex here has a lobe: the guided and openpgl
     * cases check that their modes take that path, unbiased. A guide that
     * drew at glass would draw here. (The dressed rooms, rough glass in the
     * door, check the guides beside it.) */
    cr_assert_eq(lobe, 0.0, "%s: the guide drew %.4f of the bounces at rough glass", sg_sampling_name(mode), lobe);
    cr_assert(fabs(st.mean[0] - expected) < 4.0 * st.std_error + 2e-3 * expected, "%s: %.5f, expected %.5f +- %.5f",
              sg_sampling_name(mode), st.mean[0], expected, 4 * st.std_error);
}

Test(render_integrator, rough_dielectric_floor_bsdf) { rough_dielectric_floor_case(SG_SAMPLING_BSDF, 40.0); }
Test(render_integrator, rough_dielectric_floor_guided) { rough_dielectric_floor_case(SG_SAMPLING_GUIDED, 70.0); }
Test(render_integrator, rough_dielectric_floor_openpgl) /* its bounces recorded for training, with their pdfs */
{
    skip_without_openpgl();
    rough_dielectric_floor_case(SG_SAMPLING_OPENPGL, 40.0);
}

Test(render_integrator, rough_conductor_floor_bsdf) { microfacet_floor_case(SG_SAMPLING_BSDF, SG_MATERIAL_CONDUCTOR, 40.0); }
Test(render_integrator, rough_conductor_floor_guided)
{
    microfacet_floor_case(SG_SAMPLING_GUIDED, SG_MATERIAL_CONDUCTOR, 40.0);
}
Test(render_integrator, coated_diffuse_floor_bsdf) { microfacet_floor_case(SG_SAMPLING_BSDF, SG_MATERIAL_COATED_DIFFUSE, 0.0); }
Test(render_integrator, coated_diffuse_floor_guided)
{
    microfacet_floor_case(SG_SAMPLING_GUIDED, SG_MATERIAL_COATED_DIFFUSE, 60.0);
}

Test(render_integrator, glossy_floor_normal_incidence_bsdf) { glossy_case(SG_SAMPLING_BSDF, 0.0); }
Test(render_integrator, glossy_floor_normal_incidence_guided) { glossy_case(SG_SAMPLING_GUIDED, 0.0); }
Test(render_integrator, glossy_floor_60_degrees_bsdf) { glossy_case(SG_SAMPLING_BSDF, 60.0); }
Test(render_integrator, glossy_floor_60_degrees_guided) { glossy_case(SG_SAMPLING_GUIDED, 60.0); }

/* Flips the winding of the triangles from `first` on: a box made inside
 * out becomes a solid (normals outward). */
static void flip_from(SgScene *s, uint32_t first)
{
    for (uint32_t t = first; t < s->triangle_count; t++) {
        uint32_t tmp = s->indices[3 * t + 1];
        s->indices[3 * t + 1] = s->indices[3 * t + 2];
        s->indices[3 * t + 2] = tmp;
    }
}

static uint32_t add_mirror(SgScene *s, float ks, const float emission[3])
{
    const float black[3] = {0, 0, 0};
    uint32_t m = sgt_add_material(s, SG_MATERIAL_MIRROR, black, emission);
    for (int i = 0; i < 3; i++)
        sgt_material(s, m)->specular[i] = ks;
    return m;
}

/* A furnace of diffuse and mirror walls (each reflecting 0.5, each
 * emitting 0.5) around a glass cube: mirrors and glass lose nothing, the
 * radiance squeezed entering the glass is given back leaving it, so every
 * pixel is exactly 1 again. */
static void mirror_glass_furnace(SgSampling mode)
{
    SgScene *s = sgt_scene_new();
    const float half[3] = {0.5f, 0.5f, 0.5f};
    uint32_t diffuse = sgt_add_material(s, SG_MATERIAL_DIFFUSE, half, half);
    uint32_t mirror = add_mirror(s, 0.5f, half);
    uint32_t glass = sgt_add_material(s, SG_MATERIAL_DIELECTRIC, NULL, NULL);
    sgt_material(s, glass)->ior = 1.5f;
    const double lo[3] = {-1, -1, -1}, hi[3] = {1, 1.5, 2};
    sgt_add_box_inside(s, lo, hi, diffuse);
    set_face_material(s, 0, -1.0, mirror);
    set_face_material(s, 1, 1.5, mirror);
    set_face_material(s, 2, 2.0, mirror);
    uint32_t cube = s->triangle_count;
    const double glo[3] = {-0.6, -0.9, 0.6}, ghi[3] = {0.4, 0.1, 1.6};
    sgt_add_box_inside(s, glo, ghi, glass);
    flip_from(s, cube);
    const double pos[3] = {0.2, 0.1, -0.6}, at[3] = {-0.1, -0.4, 1.1}, up[3] = {0, 1, 0};
    sgt_set_camera(s, pos, at, up, 90, 32, 24);
    sgt_finish(s);
    SgRenderOptions o;
    sg_render_options_default(&o, s);
    o.max_depth = 64;
    o.sampling = mode;
    o.alpha = 0.5f;
    o.seed = 9;
    SgtFixedPoint fp = {{0.6, 1.0, -0.5}};
    o.importance.importance_point = sgt_fixed_point_guide;
    o.importance.ctx = &fp;
    Stats st = render_scene_stats(s, &o, 128, 0, 0, o.width, o.height);
    cr_log_info("mirror and glass furnace %s: mean %.5f +- %.5f", sg_sampling_name(mode), st.mean[0], st.std_error);
    cr_assert_eq(st.nonfinite, 0);
    cr_assert(fabs(st.mean[0] - 1.0) < 4.0 * st.std_error + 1e-6, "mirror and glass furnace %s: %.5f +- %.5f",
              sg_sampling_name(mode), st.mean[0], 4.0 * st.std_error);
    sgt_scene_free(s);
}

Test(render_integrator, mirror_and_glass_furnace_bsdf) { mirror_glass_furnace(SG_SAMPLING_BSDF); }
Test(render_integrator, mirror_and_glass_furnace_guided) { mirror_glass_furnace(SG_SAMPLING_GUIDED); }

/* Unpolarized Fresnel reflectance of a ray from a medium of index 1 into
 * one of index n at incidence theta. */
static double fresnel(double n, double theta)
{
    double ci = cos(theta), st = sin(theta) / n, ct = sqrt(1.0 - st * st);
    double rs = (ci - n * ct) / (ci + n * ct), rp = (n * ci - ct) / (n * ci + ct);
    return 0.5 * (rs * rs + rp * rp);
}

/* An emitter (radiance Le, black) inside a glass slab of index n, seen
 * from the air at 30 degrees: what leaves the slab is what enters it,
 * 1 - R(30), and radiance in the glass is n^2 that in the air:
 * L = Le (1 - R) / n^2. A reflected camera ray goes to the black sky. */
Test(render_integrator, emitter_in_a_glass_slab)
{
    const double n = 1.5, le = 2.0, theta = 30.0 * M_PI / 180.0;
    SgScene *s = sgt_scene_new();
    const float black[3] = {0, 0, 0}, glow[3] = {(float)le, (float)le, (float)le};
    uint32_t glass = sgt_add_material(s, SG_MATERIAL_DIELECTRIC, NULL, NULL);
    sgt_material(s, glass)->ior = (float)n;
    uint32_t emitter = sgt_add_material(s, SG_MATERIAL_DIFFUSE, black, glow);
    const double lo[3] = {-5, -1, -5}, hi[3] = {5, 0, 5};
    sgt_add_box_inside(s, lo, hi, glass);
    flip_from(s, 0);
    const double e[4][3] = {{-4, -0.5, -4}, {-4, -0.5, 4}, {4, -0.5, 4}, {4, -0.5, -4}}; /* faces up */
    sgt_add_quad(s, e, emitter);
    const double pos[3] = {sin(theta), cos(theta), 0}, at[3] = {0, 0, 0}, up[3] = {0, 1, 0};
    sgt_set_camera(s, pos, at, up, 0.5, 16, 16);
    sgt_finish(s);
    SgRenderOptions o;
    sg_render_options_default(&o, s);
    o.seed = 4;
    Stats st = render_scene_stats(s, &o, 256, 0, 0, o.width, o.height);
    double expected = le * (1.0 - fresnel(n, theta)) / (n * n);
    cr_log_info("emitter in glass: %.5f +- %.5f, expected %.5f (R = %.5f)", st.mean[0], st.std_error, expected,
                fresnel(n, theta));
    cr_assert_eq(st.nonfinite, 0);
    cr_assert(fabs(st.mean[0] - expected) < 4.0 * st.std_error + 1e-3 * expected,
              "emitter in glass: %.5f, expected %.5f +- %.5f", st.mean[0], expected, 4 * st.std_error);
    sgt_scene_free(s);
}

/* A glass slab of thickness d whose inside absorbs sigma_a per channel,
 * over an emitter (radiance Le) facing up, seen straight down: each pass
 * through the slab keeps exp(-sigma_a d), each face lets 1 - R through and
 * returns R, so L = Le (1 - R)^2 T / (1 - R^2 T^2), T = exp(-sigma_a d)
 * (radiance's compression entering the glass undone leaving it). */
Test(render_integrator, absorbing_glass_slab_tints_by_beer_lambert)
{
    const double n = 1.5, le = 2.0, d = 1.0, sigma[3] = {0.1, 0.5, 1.0};
    SgScene *s = sgt_scene_new();
    const float black[3] = {0, 0, 0}, glow[3] = {(float)le, (float)le, (float)le};
    uint32_t glass = sgt_add_material(s, SG_MATERIAL_DIELECTRIC, NULL, NULL);
    sgt_material(s, glass)->ior = (float)n;
    for (int c = 0; c < 3; c++)
        sgt_material(s, glass)->sigma_a[c] = (float)sigma[c];
    uint32_t emitter = sgt_add_material(s, SG_MATERIAL_DIFFUSE, black, glow);
    const double lo[3] = {-5, -d, -5}, hi[3] = {5, 0, 5};
    sgt_add_box_inside(s, lo, hi, glass);
    flip_from(s, 0);
    const double e[4][3] = {{-50, -2, -50}, {-50, -2, 50}, {50, -2, 50}, {50, -2, -50}}; /* faces up */
    sgt_add_quad(s, e, emitter);
    const double pos[3] = {0, 1, 0}, at[3] = {0, 0, 0}, up[3] = {0, 0, 1};
    sgt_set_camera(s, pos, at, up, 0.5, 16, 16);
    sgt_finish(s);
    SgRenderOptions o;
    sg_render_options_default(&o, s);
    o.seed = 5;
    o.max_depth = 64;
    Stats st = render_scene_stats(s, &o, 256, 0, 0, o.width, o.height);
    double r = fresnel(n, 0.0);
    cr_assert_eq(st.nonfinite, 0);
    for (int c = 0; c < 3; c++) {
        double t = exp(-sigma[c] * d), expected = le * (1 - r) * (1 - r) * t / (1 - r * r * t * t);
        double tol = 4.0 * st.std_error * fmax(1.0, expected / fmax(st.mean[0], 1e-9)) + 2e-3 * expected;
        cr_log_info("absorbing slab, channel %d: %.5f, expected %.5f +- %.5f", c, st.mean[c], expected, tol);
        cr_assert(fabs(st.mean[c] - expected) < tol, "channel %d: %.5f, expected %.5f +- %.5f", c, st.mean[c],
                  expected, tol);
    }
    sgt_scene_free(s);
}

/* A two-room scene: the light is in room A, the camera looks at a wall of
 * room B that only indirect light reaches, through a door. */
static SgScene *two_rooms_with(bool dressed);
static SgScene *two_rooms(void) { return two_rooms_with(false); }

/* dressed: room B's floor a rough conductor (copper, alpha 0.3), the
 * partition's side the camera sees a coated diffuse whose albedo is a
 * checkerboard along its uv, and a rough glass pane (alpha 0.2) across
 * the door. */
static SgScene *two_rooms_with(bool dressed)
{
    SgScene *s = sgt_scene_new();
    const float white[3] = {0.7f, 0.7f, 0.7f}, red[3] = {0.7f, 0.2f, 0.2f}, em[3] = {20, 20, 20};
    const float black[3] = {0, 0, 0};
    uint32_t w = sgt_add_material(s, SG_MATERIAL_DIFFUSE, white, NULL);
    uint32_t rm = sgt_add_material(s, SG_MATERIAL_DIFFUSE, red, NULL);
    uint32_t lm = sgt_add_material(s, SG_MATERIAL_DIFFUSE, black, em);
    const double lo[3] = {0, 0, 0}, hi[3] = {4, 2, 2};
    sgt_add_box_inside(s, lo, hi, w);
    /* partition at x = 2 with a door from z = 1.4 to 2 (both sides) */
    const double p1[4][3] = {{2, 0, 0}, {2, 2, 0}, {2, 2, 1.4}, {2, 0, 1.4}};
    const double p2[4][3] = {{2, 0, 0}, {2, 0, 1.4}, {2, 2, 1.4}, {2, 2, 0}};
    uint32_t partition_b = rm;
    if (dressed) {
        uint32_t copper = sgt_add_material(s, SG_MATERIAL_CONDUCTOR, black, NULL);
        SgMaterial *c = sgt_material(s, copper);
        const float eta[3] = {0.2f, 0.92f, 1.1f}, k[3] = {3.91f, 2.45f, 2.14f};
        memcpy(c->eta, eta, sizeof eta);
        memcpy(c->k, k, sizeof k);
        c->roughness[0] = c->roughness[1] = 0.3f;
        for (uint32_t t = 0; t < s->triangle_count; t++) /* room B's floor: y = 0, x > 2 */
            if (s->positions[3 * s->indices[3 * t] + 1] == 0.0 && s->positions[3 * s->indices[3 * t + 1] + 1] == 0.0 &&
                s->positions[3 * s->indices[3 * t + 2] + 1] == 0.0)
                s->triangle_material[t] = copper; /* the whole floor: both rooms */
        partition_b = sgt_add_material(s, SG_MATERIAL_COATED_DIFFUSE, red, NULL);
        sgt_material(s, partition_b)->roughness[0] = sgt_material(s, partition_b)->roughness[1] = 0.1f;
        sgt_material(s, partition_b)->diffuse_texture = 1;
        s->textures = calloc(1, sizeof *s->textures);
        s->texture_count = 1;
        s->textures[0] = (SgTexture){.kind = SG_TEXTURE_CHECKERBOARD, .uscale = 4, .vscale = 4, .scale = 1,
                                     .input = {{0, {0.8f, 0.8f, 0.8f}}, {0, {0.1f, 0.3f, 0.6f}}},
                                     .mean = {0.45f, 0.55f, 0.7f}};
    }
    sgt_add_quad(s, p1, partition_b);
    sgt_add_quad(s, p2, w);
    if (dressed) { /* a rough glass pane across the door */
        uint32_t glass = sgt_add_material(s, SG_MATERIAL_DIELECTRIC, black, NULL);
        sgt_material(s, glass)->roughness[0] = sgt_material(s, glass)->roughness[1] = 0.2f;
        const double pane[4][3] = {{2, 0, 1.4}, {2, 2, 1.4}, {2, 2, 2}, {2, 0, 2}};
        sgt_add_quad(s, pane, glass);
    }
    /* small light on room A's ceiling, facing down */
    const double l[4][3] = {{0.8, 1.99, 0.8}, {1.2, 1.99, 0.8}, {1.2, 1.99, 1.2}, {0.8, 1.99, 1.2}};
    sgt_add_quad(s, l, lm);
    const double pos[3] = {3.8, 1.0, 1.0}, at[3] = {2, 1, 0.7}, up[3] = {0, 1, 0};
    sgt_set_camera(s, pos, at, up, 70, 40, 30);
    if (dressed) { /* uv: (z, y), where the partition's checkerboard varies */
        s->uvs = malloc(2 * s->vertex_count * sizeof *s->uvs);
        for (uint32_t v = 0; v < s->vertex_count; v++) {
            s->uvs[2 * v] = (float)s->positions[3 * v + 2];
            s->uvs[2 * v + 1] = (float)s->positions[3 * v + 1];
        }
    }
    sgt_finish(s);
    return s;
}

/* The two rooms (dressed or not) rendered spp passes by bsdf and by `mode`
 * (the guided ones with a fixed point in the door): the means agree within
 * three standard errors. */
static void rooms_agree(bool dressed, SgSampling mode, int spp)
{
    SgScene *s = two_rooms_with(dressed);
    SgRenderOptions o;
    sg_render_options_default(&o, s);
    SgtFixedPoint door = {{2.0, 1.0, 1.7}};
    o.importance.importance_point = sgt_fixed_point_guide;
    o.importance.ctx = &door;
    o.max_depth = 8;
    o.seed = 1;
    o.lobe_exponent = 10;
    Stats b = render_scene_stats(s, &o, spp, 0, 0, o.width, o.height);
    o.sampling = mode;
    o.seed = 2;
    Stats g = render_scene_stats(s, &o, spp, 0, 0, o.width, o.height);
    double se = sqrt(b.std_error * b.std_error + g.std_error * g.std_error);
    const char *name = dressed ? "dressed rooms" : "two rooms";
    cr_log_info("%s: bsdf %.5f +- %.5f, %s %.5f +- %.5f, its guide drew %.4f of the bounces", name, b.mean[0],
                b.std_error, sg_sampling_name(mode), g.mean[0], g.std_error, g.lobe_share);
    cr_assert(b.mean[0] > 0.0);
    /* the guide must take part, or this compares bsdf with itself: guided's
     * learned mixture drew 0.0285 (two rooms, 48 spp) and 0.0413 (dressed,
     * 512 spp) of the bounces, openpgl's field 0.3955 (dressed); the bounds
     * are about a third and a half of those, a guide fallen back to BSDF
     * sampling draws none */
    double least = mode == SG_SAMPLING_OPENPGL ? 0.2 : 0.01;
    cr_assert_gt(g.lobe_share, least, "%s: %s's guide drew %.4f of the bounces, expected more than %.2f", name,
                 sg_sampling_name(mode), g.lobe_share, least);
    cr_assert(fabs(b.mean[0] - g.mean[0]) < 3.0 * se, "%s: bsdf %.5f vs %s %.5f, 3 se = %.5f", name, b.mean[0],
              sg_sampling_name(mode), g.mean[0], 3 * se);
    cr_assert_eq(b.nonfinite + g.nonfinite, 0);
    sgt_scene_free(s);
}

Test(render_integrator, guided_agrees_with_bsdf_in_dark_room) { rooms_agree(false, SG_SAMPLING_GUIDED, 48); }

/* The same with a rough conductor floor, a textured coated diffuse and
 * rough glass in the door: the guides stay unbiased with the microfacet
 * BSDFs' pdfs in their MIS and textured albedos in their roulettes. */
/* Under the sanitizers half the samples: the same paths are checked, the
 * 3 se bound widens with them. */
static int dressed_spp(void) { return getenv("SG_SANITIZED") ? 256 : 512; }
Test(render_integrator, guided_agrees_with_bsdf_in_dressed_rooms) { rooms_agree(true, SG_SAMPLING_GUIDED, dressed_spp()); }
Test(render_integrator, openpgl_agrees_with_bsdf_in_dressed_rooms)
{
    skip_without_openpgl();
    rooms_agree(true, SG_SAMPLING_OPENPGL, dressed_spp());
}

Test(render_integrator, openpgl_agrees_with_bsdf_in_dark_room)
{
    skip_without_openpgl();
    SgScene *s = two_rooms();
    SgRenderOptions o;
    sg_render_options_default(&o, s);
    o.max_depth = 8;
    o.seed = 1;
    Stats b = render_scene_stats(s, &o, 64, 0, 0, o.width, o.height);
    o.sampling = SG_SAMPLING_OPENPGL;
    o.seed = 2;
    SgError err = {0};
    SgRenderer *r = sg_renderer_create(s, &o, &err);
    cr_assert_not_null(r, "%s", err.message);
    Stats p = render_stats(r, &o, 64, 0, 0, o.width, o.height);
    double share = sgt_stats(r).lobe_share;
    int passes = sgt_stats(r).training_passes;
    sg_renderer_free(r);
    double se = sqrt(b.std_error * b.std_error + p.std_error * p.std_error);
    cr_log_info("two rooms: bsdf %.5f +- %.5f, openpgl %.5f +- %.5f, guide drew %.3f, %d training passes", b.mean[0],
                b.std_error, p.mean[0], p.std_error, share, passes);
    cr_assert_eq(passes, 64, "every pass's paths train the field: %d", passes);
    cr_assert(share > 0.2, "the field guides: it drew %.3f of the bounces", share);
    cr_assert(fabs(b.mean[0] - p.mean[0]) < 3.0 * se, "bsdf %.5f vs openpgl %.5f, 3 se = %.5f", b.mean[0],
              p.mean[0], 3 * se);
    cr_assert_eq(b.nonfinite + p.nonfinite, 0);
    sgt_scene_free(s);
}

/* Renders `passes` passes of s with 1, 2 and 5 threads, asserts the three
 * images are the same bytes, and returns the first (the caller frees it).
 * check(r) asserts, for each, that the mode did what the test is about. */
static float *same_image_for_any_thread_count(const SgScene *s, SgRenderOptions o, int passes,
                                              void (*check)(const SgRenderer *r, int threads))
{
    size_t n = (size_t)o.width * o.height * 3;
    float *img[3];
    const int threads[3] = {1, 2, 5};
    for (int k = 0; k < 3; k++) {
        o.threads = threads[k];
        SgError err = {0};
        SgRenderer *r = sg_renderer_create(s, &o, &err);
        cr_assert_not_null(r, "%s", err.message);
        for (int p = 0; p < passes; p++)
            sg_renderer_pass(r);
        check(r, threads[k]);
        img[k] = malloc(n * sizeof(float));
        sg_renderer_image(r, img[k]);
        sg_renderer_free(r);
    }
    cr_assert(memcmp(img[0], img[1], n * sizeof(float)) == 0, "1 and 2 threads differ");
    cr_assert(memcmp(img[0], img[2], n * sizeof(float)) == 0, "1 and 5 threads differ");
    free(img[1]);
    free(img[2]);
    return img[0];
}

static void check_openpgl_guides(const SgRenderer *r, int threads)
{
    cr_assert_gt(sgt_stats(r).lobe_share, 0.1, "%d threads: the field guides in this test", threads);
}

/* The same image for any thread count: openpgl's field is trained
 * deterministically (its samples sorted) from every pass's paths. */
Test(render_integrator, openpgl_same_image_for_any_thread_count)
{
    skip_without_openpgl();
    SgScene *s = two_rooms();
    SgRenderOptions o;
    sg_render_options_default(&o, s);
    o.sampling = SG_SAMPLING_OPENPGL;
    o.seed = 42;
    free(same_image_for_any_thread_count(s, o, 8, check_openpgl_guides));
    sgt_scene_free(s);
}

/* The learner chose the lobe somewhere and the lobe drew bounces: the
 * learned choices are part of what must not depend on threads. */
static void check_learned_lobe(const SgRenderer *r, int threads)
{
    double regions = sgt_stats(r).guided_fraction, lobe = sgt_stats(r).lobe_share;
    cr_log_info("%d threads: lobe in %.3f of the learner's bounces, drew %.3f of all", threads, regions, lobe);
    cr_assert(regions > 0.005 && lobe > 0.005, "the mixture uses the lobe in this test: %.3f of the "
              "learner's bounces, drew %.3f", regions, lobe);
}

Test(render_integrator, same_seed_same_image_for_any_thread_count)
{
    SgScene *s = two_rooms();
    SgRenderOptions o;
    sg_render_options_default(&o, s);
    SgtFixedPoint door = {{2.0, 1.0, 1.7}};
    o.importance.importance_point = sgt_fixed_point_guide;
    o.importance.ctx = &door;
    o.sampling = SG_SAMPLING_GUIDED;
    o.seed = 42;
    /* 12 passes: the learned mixture changes after every one of them
     * (all paths learn in the first two, then every 2nd, 4th, 8th) */
    float *img = same_image_for_any_thread_count(s, o, 12, check_learned_lobe);
    /* and another seed does change it (the test can fail) */
    size_t n = (size_t)o.width * o.height * 3;
    o.seed = 43;
    SgError err = {0};
    SgRenderer *r = sg_renderer_create(s, &o, &err);
    for (int p = 0; p < 4; p++)
        sg_renderer_pass(r);
    float *other = malloc(n * sizeof(float));
    sg_renderer_image(r, other);
    sg_renderer_free(r);
    cr_assert(memcmp(img, other, n * sizeof(float)) != 0);
    free(img);
    free(other);
    sgt_scene_free(s);
}

Test(render_integrator, refuses_bad_options)
{
    SgScene *s = two_rooms();
    SgRenderOptions o;
    sg_render_options_default(&o, s);
    SgError err = {0};
    o.sampling = SG_SAMPLING_GUIDED; /* no guide */
    cr_assert_null(sg_renderer_create(s, &o, &err));
    cr_assert(strstr(err.message, "cache") != NULL, "%s", err.message);
    SgtFixedPoint fp = {{0, 0, 0}};
    o.importance.importance_point = sgt_fixed_point_guide;
    o.importance.ctx = &fp;
    o.alpha = 0.0f; /* a pure lobe would be biased */
    err = (SgError){0};
    cr_assert_null(sg_renderer_create(s, &o, &err));
    cr_assert(strstr(err.message, "alpha") != NULL, "%s", err.message);
    sgt_scene_free(s);
}

Test(render_integrator, camera_inside_a_solid_is_detected)
{
    /* a box with outward normals (a solid), camera inside */
    SgScene *s = sgt_scene_new();
    const float w[3] = {0.5f, 0.5f, 0.5f}, em[3] = {1, 1, 1};
    uint32_t m = sgt_add_material(s, SG_MATERIAL_DIFFUSE, w, NULL);
    uint32_t lm = sgt_add_material(s, SG_MATERIAL_DIFFUSE, w, em);
    const double lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
    sgt_add_box_inside(s, lo, hi, m);
    for (uint32_t t = 0; t < s->triangle_count; t++) { /* flip: outward normals */
        uint32_t tmp = s->indices[3 * t + 1];
        s->indices[3 * t + 1] = s->indices[3 * t + 2];
        s->indices[3 * t + 2] = tmp;
    }
    const double l[4][3] = {{-1, 3, -1}, {1, 3, -1}, {1, 3, 1}, {-1, 3, 1}};
    sgt_add_quad(s, l, lm);
    const double pos[3] = {0, 0, 0}, at[3] = {0, 0, 1};
    sgt_finish_looking(s, pos, at, 60, 16, 16);
    SgRenderOptions o;
    sg_render_options_default(&o, s);
    SgError err = {0};
    SgRenderer *r = sg_renderer_create(s, &o, &err);
    sg_renderer_pass(r);
    cr_assert_gt(sgt_stats(r).backface_fraction, 0.99);
    sg_renderer_free(r);
    sgt_scene_free(s);
    /* and the furnace (camera inside, facing front faces) is not flagged */
    s = furnace_scene();
    sg_render_options_default(&o, s);
    r = sg_renderer_create(s, &o, &err);
    sg_renderer_pass(r);
    cr_assert_lt(sgt_stats(r).backface_fraction, 0.01);
    sg_renderer_free(r);
    sgt_scene_free(s);
}
