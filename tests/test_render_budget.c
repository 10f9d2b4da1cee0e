/* Learning within the render: a learned mode renders from its first pass,
 * the image keeps every pass weighted by its estimated variance
 * (render/film.h), and guided stops learning when a further stretch would
 * not pay within the render's budget (render/renderer.h). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "support_render.h"

/* Guided on the two rooms, its lobe toward the window. */
static SgtFixedPoint window_point = {{2.0, 1.0, 1.0}};

/* Under the sanitizers (SG_SANITIZED, ~5x slower) the statistical tests
 * take half the seeds and passes. */
static int scaled(int n) { return getenv("SG_SANITIZED") ? n / 2 : n; }

static SgRenderOptions window_options(SgScene *s, uint64_t seed)
{
    SgRenderOptions o = sgt_options(s, SG_SAMPLING_GUIDED);
    o.importance.importance_point = sgt_fixed_point_guide;
    o.importance.ctx = &window_point;
    o.seed = seed;
    return o;
}

static float *image_of(SgRenderer *r, const SgRenderOptions *o)
{
    float *img = malloc(sizeof *img * 3 * (size_t)o->width * o->height);
    cr_assert_not_null(img);
    sg_renderer_image(r, img);
    return img;
}

/* relMSE of channel 0 against a reference, the worst 0.1 % of pixels kept
 * (the image is small: 1200 pixels). */
static double rel_mse(const float *img, const float *ref, size_t pixels)
{
    double e = 0.0;
    for (size_t i = 0; i < pixels; i++) {
        double d = img[3 * i] - ref[3 * i];
        e += d * d / ((double)ref[3 * i] * ref[3 * i] + 0.01);
    }
    return e / (double)pixels;
}

static double image_mean(const float *img, size_t pixels)
{
    double m = 0.0;
    for (size_t i = 0; i < pixels; i++)
        m += img[3 * i];
    return m / (double)pixels;
}

/* A reference of the rooms: a field trained 64 passes, then 1024 passes. */
static float *window_reference(SgScene *s)
{
    SgRenderOptions o = window_options(s, 1000);
    o.training_passes = 64;
    SgError err = {0};
    SgRenderer *r = sg_renderer_create(s, &o, &err);
    cr_assert_not_null(r, "%s", err.message);
    cr_assert(sg_renderer_train(r, &err), "%s", err.message);
    sg_renderer_freeze(r);
    for (int p = 0; p < scaled(1024); p++)
        sg_renderer_pass(r);
    float *ref = image_of(r, &o);
    sg_renderer_free(r);
    return ref;
}

/* The same passes in all, T learning and M frozen: learned within the
 * render, the T passes count in the image; trained apart, only the M do.
 * Counted in, the image's error is lower (over several seeds). */
Test(render_budget, the_passes_learned_from_count_in_the_image, .timeout = 120)
{
    SgScene *s = sgt_window_rooms();
    float *ref = window_reference(s);
    const int learning = 16, frozen = 16, seeds = scaled(6);
    double apart = 0.0, within = 0.0;
    for (int k = 0; k < seeds; k++) {
        SgError err = {0};
        SgRenderOptions o = window_options(s, 10 + (uint64_t)k);
        o.training_passes = learning;
        size_t pixels = (size_t)o.width * o.height;

        SgRenderer *a = sg_renderer_create(s, &o, &err);
        cr_assert_not_null(a, "%s", err.message);
        cr_assert(sg_renderer_train(a, &err));
        sg_renderer_freeze(a);
        for (int p = 0; p < frozen; p++)
            sg_renderer_pass(a);
        float *img_a = image_of(a, &o);
        apart += rel_mse(img_a, ref, pixels) / seeds;

        SgRenderer *b = sg_renderer_create(s, &o, &err);
        cr_assert_not_null(b, "%s", err.message);
        for (int p = 0; p < learning + frozen; p++)
            sg_renderer_pass(b);
        cr_assert_eq(sg_renderer_learned_passes(b), learning, "it learned %d passes", sg_renderer_learned_passes(b));
        cr_assert_eq(sg_renderer_spp(b), learning + frozen);
        float *img_b = image_of(b, &o);
        within += rel_mse(img_b, ref, pixels) / seeds;
        free(img_a);
        free(img_b);
        sg_renderer_free(a);
        sg_renderer_free(b);
    }
    cr_log_info("relMSE, %d learning + %d frozen passes: trained apart %.4g, learned within %.4g (%.2fx)", learning,
                frozen, apart, within, apart / within);
    cr_assert_lt(within, 0.8 * apart, "within %.4g, apart %.4g", within, apart);
    free(ref);
    sgt_scene_free(s);
}

/* Unbiased: the weighted image's mean over the rooms, over seeds, is the
 * reference's within its standard error. */
Test(render_budget, the_weighted_image_is_unbiased, .timeout = 120)
{
    SgScene *s = sgt_window_rooms();
    float *ref = window_reference(s);
    const int seeds = scaled(12);
    double sum = 0.0, sum2 = 0.0, ref_mean = 0.0;
    size_t pixels = 0;
    for (int k = 0; k < seeds; k++) {
        SgError err = {0};
        SgRenderOptions o = window_options(s, 50 + (uint64_t)k);
        pixels = (size_t)o.width * o.height;
        SgRenderer *r = sg_renderer_create(s, &o, &err);
        cr_assert_not_null(r, "%s", err.message);
        sg_renderer_set_budget(r, 48, 0.0);
        for (int p = 0; p < 48; p++)
            sg_renderer_pass(r);
        float *img = image_of(r, &o);
        double m = image_mean(img, pixels);
        sum += m;
        sum2 += m * m;
        free(img);
        sg_renderer_free(r);
    }
    ref_mean = image_mean(ref, pixels);
    double mean = sum / seeds, se = sqrt(fmax(sum2 / seeds - mean * mean, 0.0) / (seeds - 1));
    cr_log_info("image mean: weighted %.5f +- %.5f, reference %.5f", mean, se, ref_mean);
    cr_assert_lt(fabs(mean - ref_mean), 4.0 * se + 0.002 * ref_mean, "weighted %.5f +- %.5f, reference %.5f", mean, se,
                 ref_mean);
    free(ref);
    sgt_scene_free(s);
}

/* The furnace (every path brings exactly its albedo's share: the image is
 * 1): learning within the render, the weights add up to one. */
Test(render_budget, a_learning_render_of_the_furnace_is_one)
{
    SgScene *s = sgt_furnace_scene();
    SgRenderOptions o = sgt_options(s, SG_SAMPLING_GUIDED);
    SgtFixedPoint corner = {{0.9, 1.4, 1.9}};
    o.importance.importance_point = sgt_fixed_point_guide;
    o.importance.ctx = &corner;
    o.roulette = SG_ROULETTE_ALBEDO;
    o.training_passes = 8;
    SgError err = {0};
    SgRenderer *r = sg_renderer_create(s, &o, &err);
    cr_assert_not_null(r, "%s", err.message);
    SgtSampleMean m = sgt_passes_mean(r, 24, (size_t)o.width * o.height);
    cr_assert_eq(sg_renderer_learned_passes(r), 8);
    float *img = image_of(r, &o);
    double mean = image_mean(img, (size_t)o.width * o.height);
    cr_log_info("furnace: image %.5f, samples %.5f +- %.5f", mean, m.mean, m.std_error);
    cr_assert_float_eq(mean, 1.0, fmax(4.0 * m.std_error, 1e-4));
    free(img);
    sg_renderer_free(r);
    sgt_scene_free(s);
}

/* Guided judges its learning: with room in the budget it learns for a
 * while and stops at a checkpoint before the end; with little room, it
 * leaves at least as many passes after its learning as it took. */
Test(render_budget, guided_stops_learning_when_it_stops_paying, .timeout = 120)
{
    SgScene *s = sgt_window_rooms();
    int budgets[2] = {512, 24};
    for (int b = 0; b < 2; b++) {
        SgRenderOptions o = window_options(s, 3);
        SgError err = {0};
        SgRenderer *r = sg_renderer_create(s, &o, &err);
        cr_assert_not_null(r, "%s", err.message);
        sg_renderer_set_budget(r, budgets[b], 0.0);
        int stopped = 0;
        for (int p = 0; p < budgets[b]; p++) {
            sg_renderer_pass(r);
            if (!stopped && !sg_renderer_learning(r))
                stopped = sg_renderer_spp(r);
        }
        int learned = sg_renderer_learned_passes(r);
        cr_log_info("budget %d passes: learned from %d", budgets[b], learned);
        cr_assert_eq(learned, stopped);
        cr_assert_geq(learned, 8, "it judges from the 8th pass on");
        cr_assert_eq(learned & (learned - 1), 0, "at a checkpoint: %d", learned);
        /* its last stretch (learned / 2 passes) left at least as many after it */
        cr_assert_geq(budgets[b] - learned, learned / 2, "learned %d of %d passes", learned, budgets[b]);
        sg_renderer_free(r);
    }
    sgt_scene_free(s);
}

/* Deterministic: the learning within the render, its checkpoints'
 * judgement (costs in rays, not seconds) and the weights are the same on
 * one thread and on two, so is the image, bit for bit. */
Test(render_budget, the_same_seed_learns_and_weighs_alike_on_any_thread_count, .timeout = 120)
{
    SgScene *s = sgt_window_rooms();
    float *img[2];
    int learned[2];
    for (int k = 0; k < 2; k++) {
        SgRenderOptions o = window_options(s, 21);
        o.threads = k + 1;
        SgError err = {0};
        SgRenderer *r = sg_renderer_create(s, &o, &err);
        cr_assert_not_null(r, "%s", err.message);
        sg_renderer_set_budget(r, 96, 0.0);
        for (int p = 0; p < 96; p++)
            sg_renderer_pass(r);
        learned[k] = sg_renderer_learned_passes(r);
        img[k] = image_of(r, &o);
        sg_renderer_free(r);
    }
    cr_assert_eq(learned[0], learned[1], "learned %d passes on one thread, %d on two", learned[0], learned[1]);
    cr_assert_gt(learned[0], 0);
    cr_assert_eq(memcmp(img[0], img[1], sizeof(float) * 3 * 40 * 30), 0, "the images differ");
    free(img[0]);
    free(img[1]);
    sgt_scene_free(s);
}
