/* End-to-end tests of the path tracer on analytic scenes built in memory:
 * furnace (exact answer 1), a plane under a uniform emitter (closed form),
 * determinism across thread counts, scale invariance, and agreement of the
 * guided and bsdf estimators. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "../render/renderer.h"
#include "support_render.h"

typedef struct Stats {
    double mean[3];
    double std_error; /* of the luminance-free channel-0 mean over every sample */
    double min_pixel, max_pixel;
    uint64_t nonfinite;
    double branches; /* split off per camera path */
} Stats;

/* Renders `spp` passes; the mean over every sample of the image (or of
 * the pixel window [x0,x1)x[y0,y1)) with its standard error from the
 * spread of the samples (they are independent). */
static Stats render_stats(SgScene *s, SgRenderOptions *o, int spp, int x0, int y0, int x1, int y1)
{
    SgError err = {0};
    SgRenderer *r = sg_renderer_create(s, o, &err);
    cr_assert_not_null(r, "%s", err.message);
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
    st.nonfinite = sg_renderer_nonfinite(r);
    st.branches = sg_renderer_branches_per_path(r);
    free(img);
    sg_renderer_free(r);
    return st;
}

/* Closed box, inward normals, albedo 0.5, emission 0.5: L = 0.5 + 0.5 L = 1. */
static SgScene *furnace_scene(void)
{
    SgScene *s = sgt_scene_new();
    const float half[3] = {0.5f, 0.5f, 0.5f};
    uint32_t m = sgt_add_material(s, SG_MATERIAL_DIFFUSE, half, half);
    const double lo[3] = {-1, -1, -1}, hi[3] = {1, 1.5, 2};
    sgt_add_box_inside(s, lo, hi, m);
    const double pos[3] = {0.2, 0.1, 0.3}, at[3] = {1, 0.5, 2}, up[3] = {0, 1, 0};
    sgt_set_camera(s, pos, at, up, 90, 32, 24);
    sgt_finish(s);
    return s;
}

static void furnace_case(SgSampling mode, double scale)
{
    SgScene *s = furnace_scene();
    const double offset[3] = {3e3 * scale, -1e3 * scale, 7e2 * scale};
    if (scale != 1.0)
        sgt_scale_offset(s, scale, offset);
    sgt_finish(s);
    SgRenderOptions o;
    sg_render_options_default(&o, s);
    o.max_depth = 64; /* truncation error 0.5^64 */
    o.sampling = mode;
    o.seed = 5;
    SgtFixedPoint fp = {{0.9 * scale + offset[0] * (scale != 1.0), -0.8 * scale + offset[1] * (scale != 1.0),
                      1.7 * scale + offset[2] * (scale != 1.0)}};
    o.guide.importance_point = sgt_fixed_point_guide;
    o.guide.ctx = &fp;
    o.lobe_exponent = 8;
    const int spp = 64;
    Stats st = render_stats(s, &o, spp, 0, 0, o.width, o.height);
    cr_log_info("furnace %s scale %g: mean %.5f %.5f %.5f +- %.5f, pixels in [%.3f, %.3f], %.2f branches "
                "split off a path",
                sg_sampling_name(mode), scale, st.mean[0], st.mean[1], st.mean[2], st.std_error,
                st.min_pixel, st.max_pixel, st.branches);
    cr_assert_eq(st.nonfinite, 0);
    /* guided's learned roulette splits paths here, so the exact answer
     * checks the branches' weights too */
    if (mode == SG_SAMPLING_GUIDED)
        cr_assert_gt(st.branches, 0.2, "furnace guided: %.3f branches split off a path", st.branches);
    /* the mean over 49152 samples: within 4 standard errors of exactly 1 */
    cr_assert(fabs(st.mean[0] - 1.0) < 4.0 * st.std_error + 1e-6,
              "furnace %s: mean %.5f, expected 1 +- %.5f", sg_sampling_name(mode), st.mean[0],
              4.0 * st.std_error);
    cr_assert(st.std_error < 0.02, "furnace %s: standard error %.4f is suspiciously large",
              sg_sampling_name(mode), st.std_error);
    /* and no pixel far off: each has 64 samples, sigma_pixel = se * sqrt(768).
     * Only for BSDF sampling, whose weights are bounded by the albedo: a
     * guided weight may reach 1/alpha times that at every bounce, and the
     * paper's lobe-only weights are unbounded (its fireflies), so the tails
     * are too heavy for a Gaussian bound on single pixels. */
    if (mode != SG_SAMPLING_BSDF) {
        sgt_scene_free(s);
        return;
    }
    double pixel_sigma = st.std_error * sqrt((double)o.width * o.height);
    cr_assert(st.min_pixel > 1.0 - 6 * pixel_sigma && st.max_pixel < 1.0 + 6 * pixel_sigma,
              "furnace %s: a pixel at %.3f / %.3f", sg_sampling_name(mode), st.min_pixel,
              st.max_pixel);
    sgt_scene_free(s);
}

Test(render_integrator, furnace_bsdf) { furnace_case(SG_SAMPLING_BSDF, 1.0); }
Test(render_integrator, furnace_guided) { furnace_case(SG_SAMPLING_GUIDED, 1.0); }
Test(render_integrator, furnace_skeleton) { furnace_case(SG_SAMPLING_SKELETON, 1.0); }
Test(render_integrator, furnace_tiny_scale_far_from_origin) { furnace_case(SG_SAMPLING_BSDF, 1e-4); }
Test(render_integrator, furnace_huge_scale_far_from_origin) { furnace_case(SG_SAMPLING_GUIDED, 1e5); }

/* Point-to-parallel-rectangle form factor, the point below one corner of
 * an a x b rectangle at distance c. */
static double corner_form_factor(double a, double b, double c)
{
    double A = a / c, B = b / c;
    double sa = sqrt(1 + A * A), sb = sqrt(1 + B * B);
    return (A / sa * atan(B / sa) + B / sb * atan(A / sb)) / (2 * M_PI);
}

/* A diffuse floor (albedo rho) under a black emitting square of radiance
 * Le at height h: at the floor's centre L = rho Le 4 F(a, a, h). */
static void plane_case(SgSampling mode, SgMaterialType floor_type)
{
    const double a = 2.0, h = 1.0;
    const float rho = 0.6f, le = 2.0f;
    SgScene *s = sgt_scene_new();
    const float alb[3] = {rho, rho, rho}, black[3] = {0, 0, 0}, em[3] = {le, le, le};
    uint32_t floor_m = sgt_add_material(s, floor_type, alb, NULL);
    uint32_t light_m = sgt_add_material(s, SG_MATERIAL_DIFFUSE, black, em);
    const double floor[4][3] = {{-50, 0, -50}, {-50, 0, 50}, {50, 0, 50}, {50, 0, -50}};
    const double light[4][3] = {{-a, h, -a}, {a, h, -a}, {a, h, a}, {-a, h, a}}; /* faces down */
    sgt_add_quad(s, floor, floor_m);
    sgt_add_quad(s, light, light_m);
    const double pos[3] = {0, 0.5, 0}, at[3] = {0, 0, 0}, up[3] = {0, 0, 1};
    sgt_set_camera(s, pos, at, up, 1.0, 16, 16); /* looks at a 9 mm patch */
    sgt_finish(s);
    SgRenderOptions o;
    sg_render_options_default(&o, s);
    o.sampling = mode;
    o.seed = 11;
    SgtFixedPoint fp = {{0.3, h, -0.2}};
    o.guide.importance_point = sgt_fixed_point_guide;
    o.guide.ctx = &fp;
    Stats st = render_stats(s, &o, 256, 0, 0, o.width, o.height);
    double expected = rho * le * 4.0 * corner_form_factor(a, a, h);
    cr_log_info("plane %s: %.5f +- %.5f, expected %.5f", sg_sampling_name(mode), st.mean[0],
                st.std_error, expected);
    cr_assert(fabs(st.mean[0] - expected) < 4.0 * st.std_error + 1e-3 * expected,
              "plane %s: %.5f, expected %.5f +- %.5f", sg_sampling_name(mode), st.mean[0], expected,
              4 * st.std_error);
    sgt_scene_free(s);
}

Test(render_integrator, plane_under_square_light_bsdf) { plane_case(SG_SAMPLING_BSDF, SG_MATERIAL_DIFFUSE); }
Test(render_integrator, plane_under_square_light_guided) { plane_case(SG_SAMPLING_GUIDED, SG_MATERIAL_DIFFUSE); }

/* A two-room scene: the light is in room A, the camera looks at a wall of
 * room B that only indirect light reaches, through a door. */
static SgScene *two_rooms(void)
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
    sgt_add_quad(s, p1, rm);
    sgt_add_quad(s, p2, w);
    /* small light on room A's ceiling, facing down */
    const double l[4][3] = {{0.8, 1.99, 0.8}, {1.2, 1.99, 0.8}, {1.2, 1.99, 1.2}, {0.8, 1.99, 1.2}};
    sgt_add_quad(s, l, lm);
    const double pos[3] = {3.8, 1.0, 1.0}, at[3] = {2, 1, 0.7}, up[3] = {0, 1, 0};
    sgt_set_camera(s, pos, at, up, 70, 40, 30);
    sgt_finish(s);
    return s;
}

Test(render_integrator, guided_agrees_with_bsdf_in_dark_room)
{
    SgScene *s = two_rooms();
    SgRenderOptions o;
    sg_render_options_default(&o, s);
    SgtFixedPoint door = {{2.0, 1.0, 1.7}};
    o.guide.importance_point = sgt_fixed_point_guide;
    o.guide.ctx = &door;
    o.max_depth = 8;
    o.seed = 1;
    o.lobe_exponent = 10;
    Stats b = render_stats(s, &o, 48, 0, 0, o.width, o.height);
    o.sampling = SG_SAMPLING_GUIDED;
    o.seed = 2;
    Stats g = render_stats(s, &o, 48, 0, 0, o.width, o.height);
    double se = sqrt(b.std_error * b.std_error + g.std_error * g.std_error);
    cr_log_info("two rooms: bsdf %.5f +- %.5f, guided %.5f +- %.5f", b.mean[0], b.std_error,
                g.mean[0], g.std_error);
    cr_assert(b.mean[0] > 0.0);
    cr_assert(fabs(b.mean[0] - g.mean[0]) < 3.0 * se, "bsdf %.5f vs guided %.5f, 3 se = %.5f",
              b.mean[0], g.mean[0], 3 * se);
    cr_assert_eq(b.nonfinite + g.nonfinite, 0);
    sgt_scene_free(s);
}

Test(render_integrator, same_seed_same_image_for_any_thread_count)
{
    SgScene *s = two_rooms();
    SgRenderOptions o;
    sg_render_options_default(&o, s);
    SgtFixedPoint door = {{2.0, 1.0, 1.7}};
    o.guide.importance_point = sgt_fixed_point_guide;
    o.guide.ctx = &door;
    o.sampling = SG_SAMPLING_GUIDED;
    o.seed = 42;
    size_t n = (size_t)o.width * o.height * 3;
    float *img[3];
    const int threads[3] = {1, 2, 5};
    for (int k = 0; k < 3; k++) {
        o.threads = threads[k];
        SgError err = {0};
        SgRenderer *r = sg_renderer_create(s, &o, &err);
        cr_assert_not_null(r, "%s", err.message);
        /* 12 passes: the learned mixture changes after every one of them
         * (all paths learn in the first two, then every 2nd, 4th, 8th) */
        for (int p = 0; p < 12; p++)
            sg_renderer_pass(r);
        cr_assert_geq(sg_renderer_guided_fraction(r), 0.0, "the mixture is learned in this test");
        img[k] = malloc(n * sizeof(float));
        sg_renderer_image(r, img[k]);
        sg_renderer_free(r);
    }
    cr_assert(memcmp(img[0], img[1], n * sizeof(float)) == 0, "1 and 2 threads differ");
    cr_assert(memcmp(img[0], img[2], n * sizeof(float)) == 0, "1 and 5 threads differ");
    /* and another seed does change it (the test can fail) */
    o.seed = 43;
    SgError err = {0};
    SgRenderer *r = sg_renderer_create(s, &o, &err);
    for (int p = 0; p < 4; p++)
        sg_renderer_pass(r);
    float *other = malloc(n * sizeof(float));
    sg_renderer_image(r, other);
    sg_renderer_free(r);
    cr_assert(memcmp(img[0], other, n * sizeof(float)) != 0);
    for (int k = 0; k < 3; k++)
        free(img[k]);
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
    o.guide.importance_point = sgt_fixed_point_guide;
    o.guide.ctx = &fp;
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
    const double pos[3] = {0, 0, 0}, at[3] = {0, 0, 1}, up[3] = {0, 1, 0};
    sgt_set_camera(s, pos, at, up, 60, 16, 16);
    sgt_finish(s);
    SgRenderOptions o;
    sg_render_options_default(&o, s);
    SgError err = {0};
    SgRenderer *r = sg_renderer_create(s, &o, &err);
    sg_renderer_pass(r);
    cr_assert_gt(sg_renderer_backface_fraction(r), 0.99);
    sg_renderer_free(r);
    sgt_scene_free(s);
    /* and the furnace (camera inside, facing front faces) is not flagged */
    s = furnace_scene();
    sg_render_options_default(&o, s);
    r = sg_renderer_create(s, &o, &err);
    sg_renderer_pass(r);
    cr_assert_lt(sg_renderer_backface_fraction(r), 0.01);
    sg_renderer_free(r);
    sgt_scene_free(s);
}
