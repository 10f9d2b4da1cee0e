/* Extra camera rays where the light seen directly varies within a pixel
 * (render/edge_rays.h): how many a sample takes, from the pixel's views
 * and the image's noise; which pixels the survey finds; and what they do
 * to a light's edge in a render. */
#include <criterion/criterion.h>
#include <math.h>

#include "render/edge_rays.h"
#include "render/renderer.h"
#include "support_render.h"

/* k + 1 = sqrt(Vs R / V), rounded, within [0, EDGE_RAYS_MAX]. */
Test(edge_rays, rays_balance_a_views_noise_against_the_images)
{
    cr_assert_eq(edge_rays_count_for(0.0, 1.0, 10.0, 16), 0, "a view that never varies takes none");
    cr_assert_eq(edge_rays_count_for(1.0, 0.0, 10.0, 16), 16, "the image's noise unknown: as many as allowed");
    cr_assert_eq(edge_rays_count_for(1.0, 0.0, 10.0, 5), 5);
    cr_assert_eq(edge_rays_count_for(1.0, 0.0, 10.0, 0), 0, "--edge-rays 0");
    cr_assert_eq(edge_rays_count_for(1.0, 1.0, 4.0, 16), 1, "sqrt(4) = 2 views: one more ray");
    cr_assert_eq(edge_rays_count_for(1.0, 1.0, 9.0, 16), 2, "sqrt(9) = 3 views");
    cr_assert_eq(edge_rays_count_for(4.0, 1.0, 4.0, 16), 3, "sqrt(16) = 4 views");
    cr_assert_eq(edge_rays_count_for(25.0, 1.0, 4.0, 16), 9, "sqrt(100) = 10 views");
    cr_assert_eq(edge_rays_count_for(1.0, 4.0, 1.0, 16), 0, "a view quieter than the image: no ray pays");
    cr_assert_eq(edge_rays_count_for(1000.0, 1.0, 10.0, 16), 16, "at most the most");
    cr_assert_eq(edge_rays_count_for(NAN, 1.0, 10.0, 16), 0);
    /* a sample costs at least its camera ray */
    cr_assert_eq(edge_rays_count_for(16.0, 1.0, 0.0, 16), 3, "sqrt(16 x 1) = 4 views");
}

/* n views of pixel pix, 0 and `hi` in turn (mean hi/2). */
static void views(EdgeRays *sl, size_t pix, int n, double hi)
{
    for (int i = 0; i < n; i++)
        edge_rays_add_view(sl, pix, i % 2 ? hi : 0.0);
}

/* n samples of every pixel, mean 1, spread s: 1 - s, 1 + s in turn. */
static void samples_everywhere(EdgeRays *sl, int n, double s)
{
    for (int i = 0; i < n; i++)
        for (size_t p = 0; p < (size_t)sl->width * sl->height; p++)
            edge_rays_add_sample(sl, p, i % 2 ? 1.0 + s : 1.0 - s);
}

Test(edge_rays, a_silhouette_takes_rays_by_its_noise_against_the_images)
{
    EdgeRays *sl = edge_rays_create(4, 1, EDGE_RAYS_MAX);
    cr_assert_not_null(sl);
    views(sl, 0, 1, 1.0);
    cr_assert_eq(edge_rays_count(sl, 0, 10.0), 0, "one view: nothing known to vary");
    edge_rays_add_view(sl, 0, 1.0);
    cr_assert_eq(edge_rays_count(sl, 0, 10.0), EDGE_RAYS_MAX, "a silhouette, the image's noise unknown: the most");
    views(sl, 1, 400, 2.0); /* Vs = 1 (n/(n-1) aside) */
    views(sl, 2, 400, 0.2); /* Vs = 0.01 */
    for (int i = 0; i < 64; i++)
        edge_rays_add_view(sl, 3, 17.25); /* wholly on a light */
    cr_assert_eq(edge_rays_count(sl, 3, 10.0), 0, "a constant view (rounding aside) takes none");
    /* samples of variance s^2 n/(n-1): s = 0.5 over 400 samples, V ~ 1/4 */
    samples_everywhere(sl, 2, 0.5);
    edge_rays_estimate(sl, EDGE_RAYS_FROM_PASS - 1);
    cr_assert_eq(sl->image_variance, 0.0, "V is not made before EDGE_RAYS_FROM_PASS passes");
    samples_everywhere(sl, 398, 0.5);
    edge_rays_estimate(sl, 400);
    cr_assert_float_eq(sl->image_variance, 0.25 * 400.0 / 399.0, 1e-9, "V = %g", sl->image_variance);
    /* k + 1 = sqrt(Vs R / V): sqrt(1 x 4 / 0.25) = 4, sqrt(0.01 x 4 / 0.25) = 0.4 */
    cr_assert_eq(edge_rays_count(sl, 1, 4.0), 3);
    cr_assert_eq(edge_rays_count(sl, 2, 4.0), 0, "a silhouette too faint for the image's noise");
    cr_assert_eq(edge_rays_count(sl, 2, 400.0), 3, "unless its samples cost 100x more: sqrt(0.01 x 400 / 0.25) = 4");
    edge_rays_free(sl);

    sl = edge_rays_create(1, 1, 0);
    views(sl, 0, 64, 1.0);
    cr_assert_eq(edge_rays_count(sl, 0, 10.0), 0, "--edge-rays 0 takes none");
    edge_rays_free(sl);
}

/* A light's edge through the middle of pixel column 3 of an 8x8 image,
 * over `passes` passes with up to `edge_rays` extra camera
 * rays a sample: column 3's values (8 of them) to `col`, extra rays a
 * sample to *per_sample; every other pixel must be exact. */
static void render_edge_column_behind(int edge_rays, uint64_t seed, int passes, bool behind_cutout, double col[8],
                                      double *per_sample)
{
    SgScene *s = sgt_scene_new();
    const float black[3] = {0, 0, 0}, glow[3] = {1, 1, 1};
    uint32_t lm = sgt_add_material(s, SG_MATERIAL_DIFFUSE, black, glow);
    const int w = 8;
    const double fov = 40.0, t = tan(fov * M_PI / 360.0);
    const double edge = (2.0 * 3.5 / w - 1.0) * t;
    const double q[4][3] = {{edge, -10, -1}, {10, -10, -1}, {10, 10, -1}, {edge, 10, -1}};
    sgt_add_quad(s, q, lm);
    if (behind_cutout) { /* a black screen of alpha 0 across the whole view, facing the camera */
        uint32_t screen = sgt_add_material(s, SG_MATERIAL_DIFFUSE, black, NULL);
        sgt_material(s, screen)->cutout = true;
        sgt_material(s, screen)->alpha = 0.0f;
        const double c[4][3] = {{-10, -10, -0.5}, {10, -10, -0.5}, {10, 10, -0.5}, {-10, 10, -0.5}};
        sgt_add_quad(s, c, screen);
    }
    const double pos[3] = {0, 0, 0}, at[3] = {0, 0, -1};
    sgt_finish_looking(s, pos, at, fov, w, w);
    SgRenderOptions o;
    sg_render_options_default(&o, s);
    o.max_depth = 1;
    o.seed = seed;
    o.edge_rays = edge_rays;
    SgError err = {0};
    SgRenderer *r = sg_renderer_create(s, &o, &err);
    cr_assert_not_null(r, "%s", err.message);
    for (int p = 0; p < passes; p++)
        sg_renderer_pass(r);
    float img[3 * 8 * 8];
    sg_renderer_image(r, img);
    *per_sample = sgt_stats(r).edge_rays_per_sample;
    sg_renderer_free(r);
    for (int y = 0; y < w; y++)
        for (int x = 0; x < w; x++) {
            double v = img[3 * (y * w + x)];
            if (x == 3)
                col[y] = v;
            else
                cr_assert_float_eq(v, x < 3 ? 0.0 : 1.0, 1e-6, "pixel (%d, %d) is %g", x, y, v);
        }
    sgt_scene_free(s);
}

static void render_edge_column(int edge_rays, uint64_t seed, int passes, double col[8], double *per_sample)
{
    render_edge_column_behind(edge_rays, seed, passes, false, col, per_sample);
}

/* The same edge seen through a cut-out that lets every ray pass: the edge
 * rays see past it as the camera's rays do, so the column is the same. */
Test(edge_rays, the_edge_rays_see_through_cut_outs)
{
    double open[8], cut[8], per_open, per_cut;
    render_edge_column(16, 5, 32, open, &per_open);
    render_edge_column_behind(16, 5, 32, true, cut, &per_cut);
    cr_assert_gt(per_cut, 0.0, "the survey found the edge behind the cut-out");
    for (int y = 0; y < 8; y++)
        cr_assert_float_eq(cut[y], open[y], 1e-6, "row %d: %g through the cut-out, %g without", y, cut[y], open[y]);
}

/* A light's edge through the middle of a column of pixels: each of them
 * sees the light over exactly half its area, so its value is 0.5 Le. With
 * independent jitter its error after n passes would be 0.5 Le / sqrt(n)
 * (0.031 at 256); the passes' stratified jitter must do far better on
 * every one of them (render_tile's pixel_jitter), the edge rays off (the
 * passes' own rays alone; render/edge_rays.h: the test below). */
Test(edge_rays, a_lights_edge_converges_faster_than_independent_jitter)
{
    const int passes = 256;
    double col[8], per_sample, worst = 0.0;
    render_edge_column(0, 3, passes, col, &per_sample);
    for (int y = 0; y < 8; y++)
        worst = fmax(worst, fabs(col[y] - 0.5));
    double independent = 0.5 / sqrt((double)passes);
    cr_log_info("light's edge: worst pixel off by %.4f after %d passes (independent jitter: %.4f typical)", worst,
                passes, independent);
    cr_assert_lt(worst, independent / 3, "the edge's pixels are off by up to %.4f", worst);
}

/* The edge's pixels see a light over half their area and nothing else
 * varies in the image: the survey finds them, and each of their samples
 * takes extra camera rays (the most until the image's noise is known, then
 * as many as that noise makes worth it), the other pixels none
 * (render/edge_rays.h). Their
 * error falls well below what the sample's own stratified ray leaves, and
 * over 16 seeds their mean is 0.5 within its standard error (a view
 * weighted wrong, k views for k + 1, say, would be off by 3%). */
Test(edge_rays, a_lights_edge_takes_extra_camera_rays)
{
    const int passes = 32, seeds = 16;
    double sq[2] = {0, 0}, sum = 0.0, sum2 = 0.0;
    for (int with = 0; with < 2; with++)
        for (int k = 0; k < seeds; k++) {
            double col[8], per_sample;
            render_edge_column(with ? 16 : 0, (uint64_t)k + 1, passes, col, &per_sample);
            /* the survey's first ray a pixel and the rest in columns 2 to 4 (the
             * first views differ there: dark, either, lit), then up to 16 a
             * sample in column 3 alone */
            double survey = (64.0 + (EDGE_RAYS_SURVEY - 1) * 24.0) / 64.0;
            double most = with ? survey / passes + 16.0 * 8.0 / 64.0 : 0.0;
            cr_assert(per_sample <= most + 1e-9 && per_sample >= 0.5 * most, "extra rays a sample %g (most %g)",
                      per_sample, most);
            for (int y = 0; y < 8; y++) {
                sq[with] += (col[y] - 0.5) * (col[y] - 0.5);
                if (with) {
                    sum += col[y];
                    sum2 += col[y] * col[y];
                }
            }
        }
    double n = 8.0 * seeds, rms_own = sqrt(sq[0] / n), rms_extra = sqrt(sq[1] / n);
    double mean = sum / n, se = sqrt((sum2 / n - mean * mean) / (n - 1.0));
    cr_log_info("light's edge after %d passes: rms error %.5f with its own rays, %.5f with extra rays; mean %.5f +- "
                "%.5f", passes, rms_own, rms_extra, mean, se);
    cr_assert_lt(rms_extra, rms_own / 3, "extra rays: rms %.5f against %.5f", rms_extra, rms_own);
    cr_assert(fabs(mean - 0.5) < 4.0 * se + 1e-6, "the edge's mean is %.5f +- %.5f, not 0.5", mean, se);
}

/* The survey takes its other rays only where the first views differ
 * within a pixel's 3x3 neighbourhood: with the light's edge through
 * column 3, columns 3 and some of 2 and 4 (whose neighbours in column 3
 * saw either side), 8 to 24 pixels of 64; the edge's 8 pixels then take
 * 16 rays a sample each in the first pass (the image's noise not known
 * yet). A light that fills the view differs nowhere: one ray a pixel and
 * nothing more. */
Test(edge_rays, the_survey_looks_again_only_where_first_views_differ)
{
    double col[8], per_sample;
    render_edge_column(16, 5, 1, col, &per_sample);
    double extra = 16.0 * 8.0, least = (64.0 + (EDGE_RAYS_SURVEY - 1) * 8.0 + extra) / 64.0,
           most = (64.0 + (EDGE_RAYS_SURVEY - 1) * 24.0 + extra) / 64.0;
    cr_log_info("the edge: %.4f extra rays a sample in the first pass (%.4f to %.4f; every pixel surveyed: %.4f)",
                per_sample, least, most, (64.0 * EDGE_RAYS_SURVEY + extra) / 64.0);
    cr_assert(per_sample >= least - 1e-12 && per_sample <= most + 1e-12, "%.4f extra rays a sample", per_sample);

    SgScene *s = sgt_scene_new();
    const float black[3] = {0, 0, 0}, glow[3] = {1, 1, 1};
    uint32_t lm = sgt_add_material(s, SG_MATERIAL_DIFFUSE, black, glow);
    const double q[4][3] = {{-10, -10, -1}, {10, -10, -1}, {10, 10, -1}, {-10, 10, -1}};
    sgt_add_quad(s, q, lm);
    const double pos[3] = {0, 0, 0}, at[3] = {0, 0, -1};
    sgt_finish_looking(s, pos, at, 40.0, 8, 8);
    SgRenderOptions o;
    sg_render_options_default(&o, s);
    o.max_depth = 1;
    o.edge_rays = 16;
    SgError err = {0};
    SgRenderer *r = sg_renderer_create(s, &o, &err);
    cr_assert_not_null(r, "%s", err.message);
    sg_renderer_pass(r);
    cr_assert_float_eq(sgt_stats(r).edge_rays_per_sample, 1.0, 1e-12, "a light filling the view: %g rays a sample",
                       sgt_stats(r).edge_rays_per_sample);
    sg_renderer_free(r);
    sgt_scene_free(s);
}
