/* The film's groups of passes: a learning render's passes weighted by
 * their estimated variance (render/film.h). Synthetic passes with known
 * means and variances, no renderer. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>

#include "render/film.h"
#include "rng.h"

#define W 100
#define H 100
#define PIXELS ((size_t)W * H)

/* Pixel p's true value: a gradient, so that relative variance matters. */
static double truth(size_t p) { return 0.2 + 0.8 * (double)(p % W) / W; }

/* One pass: every pixel's true value times (1 + noise), noise uniform with
 * standard deviation `spread` (grey: R = G = B). */
static void add_pass(Film *f, SgRng *rng, double spread, double cost)
{
    for (size_t p = 0; p < PIXELS; p++) {
        double u = sg_rng_float(rng) * 2.0 - 1.0; /* variance 1/3 */
        double v = truth(p) * (1.0 + spread * sqrt(3.0) * u);
        Vec3 L = v3(v, v, v);
        film_add(f, p, &L);
    }
    film_end_pass(f, cost);
}

/* A film of W x H and a stream of random numbers for its passes. */
static void film_start(Film *f, SgRng *rng, uint64_t seed)
{
    cr_assert(film_init(f, W, H));
    sg_rng_seed(rng, seed, 0);
}

static double image_mse(const float *img)
{
    double e = 0.0;
    for (size_t p = 0; p < PIXELS; p++) {
        double d = img[3 * p] - truth(p);
        e += d * d / (truth(p) * truth(p));
    }
    return e / PIXELS;
}

Test(render_film, one_group_is_the_plain_mean)
{
    Film f;
    SgRng rng;
    film_start(&f, &rng, 1);
    for (int i = 0; i < 5; i++)
        add_pass(&f, &rng, 0.5, 1.0);
    double sum0 = f.sum[0];
    float *img = malloc(PIXELS * 3 * sizeof *img);
    film_image(&f, img);
    cr_assert_eq(img[0], (float)(sum0 * (1.0 / 5)), "the mean of the passes, as ever");
    cr_assert_eq(film_passes(&f), 5);
    free(img);
    film_free(&f);
}

/* A group twice as noisy per pass weighs a quarter as much: the
 * combination's error is the optimum's, 1 / (sum of n / variance), and
 * below both the equal-weight mean's and the good group's alone. */
Test(render_film, groups_weigh_by_their_inverse_variance)
{
    Film f;
    SgRng rng;
    film_start(&f, &rng, 2);
    double noisy = 0.4, good = 0.2;
    for (int i = 0; i < 8; i++)
        add_pass(&f, &rng, noisy, 1.0);
    cr_assert(film_close_group(&f));
    for (int i = 0; i < 8; i++)
        add_pass(&f, &rng, good, 1.0);

    double variance[FILM_GROUPS_MAX + 1], cost[FILM_GROUPS_MAX + 1];
    cr_assert_eq(film_group_variances(&f, variance, cost), 2);
    cr_log_info("per-pass variance: %.4g (true %.4g), %.4g (true %.4g)", variance[0], noisy * noisy, variance[1],
                good * good);
    cr_assert_float_eq(variance[1] / variance[0], good * good / (noisy * noisy), 0.02);
    cr_assert_float_eq(cost[0], 1.0, 1e-12);

    float *img = malloc(PIXELS * 3 * sizeof *img);
    film_image(&f, img);
    double combined = image_mse(img);
    double optimum = 1.0 / (8 / (noisy * noisy) + 8 / (good * good));
    double equal = (8 * noisy * noisy + 8 * good * good) / (16.0 * 16.0);
    double good_alone = good * good / 8;
    cr_log_info("relative MSE: combined %.4g, optimum %.4g, equal weights %.4g, good group alone %.4g", combined,
                optimum, equal, good_alone);
    cr_assert_float_eq(combined / optimum, 1.0, 0.05);
    cr_assert_lt(combined, 0.85 * good_alone);
    cr_assert_lt(combined, 0.7 * equal);
    free(img);
    film_free(&f);
}

/* A group that saw nothing (every pass black where the others see light)
 * is far from the image of all passes: it weighs little, where its own
 * spread (none) would have made it weigh the most. (Such a group is biased,
 * which no pass of a renderer is: the image stays a little dark.) */
Test(render_film, a_group_that_saw_nothing_weighs_little)
{
    Film f;
    SgRng rng;
    film_start(&f, &rng, 3);
    for (int i = 0; i < 4; i++) {
        for (size_t p = 0; p < PIXELS; p++) {
            Vec3 L = v3(0, 0, 0);
            film_add(&f, p, &L);
        }
        film_end_pass(&f, 1.0);
    }
    cr_assert(film_close_group(&f));
    for (int i = 0; i < 16; i++)
        add_pass(&f, &rng, 0.3, 1.0);
    float *img = malloc(PIXELS * 3 * sizeof *img);
    film_image(&f, img);
    double mean = 0.0;
    for (size_t p = 0; p < PIXELS; p++)
        mean += img[3 * p] / truth(p);
    mean /= PIXELS;
    cr_log_info("mean over truth with a black group: %.4f (equal weights: %.4f)", mean, 16.0 / 20.0);
    cr_assert_gt(mean, 0.95, "the black group took %.3f of the weight", 1.0 - mean);
    free(img);
    film_free(&f);
}

/* One firefly in the first group (a millionfold sample in one pixel) does
 * not decide the group's weight: the worst 0.1 % of pixels are left out. */
Test(render_film, one_firefly_does_not_decide_a_weight)
{
    double variance[2][FILM_GROUPS_MAX + 1];
    for (int firefly = 0; firefly < 2; firefly++) {
        Film f;
        SgRng rng;
        film_start(&f, &rng, 4);
        for (int i = 0; i < 4; i++)
            add_pass(&f, &rng, 0.4, 1.0);
        if (firefly) {
            Vec3 L = v3(1e6, 1e6, 1e6);
            film_add(&f, 4321, &L);
        }
        cr_assert(film_close_group(&f));
        for (int i = 0; i < 4; i++)
            add_pass(&f, &rng, 0.4, 1.0);
        film_group_variances(&f, variance[firefly], NULL);
        film_free(&f);
    }
    cr_log_info("first group's variance: %.4g, with a firefly %.4g", variance[0][0], variance[1][0]);
    cr_assert_float_eq(variance[1][0] / variance[0][0], 1.0, 0.05);
}

/* Unbiased: over many independent films whose groups differ tenfold in
 * variance, the combined image's mean is the truth within its standard
 * error. The estimates are skewed (exponential samples: the cases where
 * a weight could follow its own samples). */
Test(render_film, the_combination_is_unbiased)
{
    const int films = 40;
    double sum = 0.0, sum2 = 0.0;
    float *img = malloc(PIXELS * 3 * sizeof *img);
    for (int k = 0; k < films; k++) {
        Film f;
        SgRng rng;
        film_start(&f, &rng, 100 + (uint64_t)k);
        for (int group = 0; group < 3; group++) {
            int passes = 1 << group;
            double scale = group == 0 ? 3.0 : 1.0; /* the first group: a heavier tail */
            for (int i = 0; i < passes; i++) {
                for (size_t p = 0; p < PIXELS; p++) {
                    /* mean truth(p): exponential mixed with a point mass */
                    double u = sg_rng_float(&rng);
                    double x = sg_rng_float(&rng) < 1.0 / scale ? -log(1.0 - u) * scale : 0.0;
                    double v = truth(p) * x;
                    Vec3 L = v3(v, v, v);
                    film_add(&f, p, &L);
                }
                film_end_pass(&f, 1.0);
            }
            cr_assert(film_close_group(&f));
        }
        film_image(&f, img);
        double m = 0.0;
        for (size_t p = 0; p < PIXELS; p++)
            m += img[3 * p] / truth(p);
        m /= PIXELS;
        sum += m;
        sum2 += m * m;
        film_free(&f);
    }
    double mean = sum / films, se = sqrt((sum2 / films - mean * mean) / (films - 1));
    cr_log_info("mean over truth: %.5f +- %.5f (%d films)", mean, se, films);
    cr_assert_lt(fabs(mean - 1.0), 4.0 * se + 1e-4);
    free(img);
}
