/* No firefly from learning. A guide that learns on the clock decides from
 * thin statistics in its first passes: a region's mixture fitted to bounces
 * that never met the sun's patch, a learned roulette whose second moments
 * are underestimated alike. The renderer bounds what one sample can weigh
 * against BSDF sampling with the albedo roulette (render/integrator.c,
 * WEIGHT_RATIO_MAX), so guided's first passes are no worse than bsdf's.
 *
 * The scene (tests/data/sun-window): a sky and a low sun through the window
 * of the far room, seen from the next room through a door, its importance
 * cache built by the programs. The skeleton's lobe points at the window;
 * the light comes mostly from the sun's patch on the floor. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>

#include "../render/guides/importance_file.h"
#include "scene_load.h"
#include "support_files.h"
#include "support_render.h"

#define SCENE "tests/data/sun-window/sun-window.json"

static SgRenderOptions options(const SgScene *s, SgSampling mode, const SgImportanceSource *guide, uint64_t seed)
{
    SgRenderOptions o = sgt_options(s, mode);
    if (guide)
        o.importance = *guide;
    o.seed = seed;
    return o;
}

/* The image after `passes` passes of a render whose budget they are. */
static float *render(const SgScene *s, const SgRenderOptions *o, int passes)
{
    SgError err = {0};
    SgRenderer *r = sg_renderer_create(s, o, &err);
    cr_assert_not_null(r, "%s", err.message);
    sg_renderer_set_budget(r, passes, 0.0);
    for (int p = 0; p < passes; p++)
        sg_renderer_pass(r);
    float *img = malloc(sizeof *img * 3 * (size_t)o->width * o->height);
    cr_assert_not_null(img);
    sg_renderer_image(r, img);
    sg_renderer_free(r);
    return img;
}

static double mse(const float *img, const float *ref, size_t values)
{
    double e = 0.0;
    for (size_t i = 0; i < values; i++)
        e += ((double)img[i] - ref[i]) * ((double)img[i] - ref[i]);
    return e / (double)values;
}

/* Over 16 seeds of 8 passes each, guided learning from its first pass has
 * a lower MSE than bsdf. Unbounded, one sample in a few thousand weighed
 * 20-100x what bsdf would give its path and the mean MSE was 2.2x bsdf's;
 * bounded, it is 0.6x. */
Test(render_fireflies, a_sun_through_a_window_makes_no_firefly_while_guided_learns, .timeout = 240)
{
    SgError err = {0};
    const char *path = sg_test_source_path(SCENE);
    SgScene *s = sg_scene_load(path, &err);
    cr_assert_not_null(s, "%s", err.message);
    const char *cache = sg_test_precompute(path, sg_test_tmpdir());
    SgRenderOptions ro = options(s, SG_SAMPLING_BSDF, NULL, 1000);
    SgImportanceFile file = {0};
    SgImportanceSource guide = ro.importance;
    cr_assert(sg_importance_file_open(&file, cache, s, path, &guide, &err), "%s", err.message);
    size_t values = 3 * (size_t)ro.width * ro.height;
    float *ref = render(s, &ro, getenv("SG_SANITIZED") ? 256 : 1024);
    const int seeds = 16, passes = 8;
    double guided = 0.0, bsdf = 0.0, worst = 0.0;
    for (int k = 0; k < seeds; k++) {
        SgRenderOptions og = options(s, SG_SAMPLING_GUIDED, &guide, 1 + (uint64_t)k);
        SgRenderOptions ob = options(s, SG_SAMPLING_BSDF, NULL, 1 + (uint64_t)k);
        float *g = render(s, &og, passes), *b = render(s, &ob, passes);
        double eg = mse(g, ref, values), eb = mse(b, ref, values);
        guided += eg / seeds;
        bsdf += eb / seeds;
        worst = fmax(worst, eg / eb);
        free(g);
        free(b);
    }
    cr_log_info("MSE over %d seeds of %d passes: guided %.4g, bsdf %.4g (%.2fx; worst seed %.2fx)", seeds, passes,
                guided, bsdf, guided / bsdf, worst);
    cr_assert_lt(guided, 0.9 * bsdf, "guided %.4g, bsdf %.4g", guided, bsdf);
    cr_assert_lt(worst, 2.0, "a seed's guided MSE is %.2fx its bsdf's", worst);
    free(ref);
    sg_importance_file_close(&file);
    sg_scene_free(s);
}
