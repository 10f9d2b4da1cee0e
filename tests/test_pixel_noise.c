/* The learned roulette's measure of each pixel's noise (render/pixel_noise.h):
 * the deviation weighs relMSE and the linear MSE, so bright pixels keep
 * their paths. */
#include <criterion/criterion.h>
#include <math.h>

#include "render/pixel_noise.h"
#include "threads.h"

#define W 40
#define H 20

/* Left half dim, right half bright; each pixel's 4 samples are
 * I (1 - s), I (1 + s), I (1 - s), I (1 + s): mean I, relative spread s. */
static PixelNoise *two_halves(double dim, double bright, double s_dim, double s_bright, int threads)
{
    PixelNoise *pn = pixel_noise_create(W, H);
    cr_assert_not_null(pn);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            double i = x < W / 2 ? dim : bright, s = x < W / 2 ? s_dim : s_bright;
            for (int k = 0; k < 4; k++)
                pixel_noise_add(pn, (size_t)y * W + x, i * (k % 2 ? 1.0 + s : 1.0 - s));
        }
    SgThreadPool *pool = sg_thread_pool_create(threads);
    cr_assert_not_null(pool);
    pixel_noise_estimate(pn, 4, pool);
    sg_thread_pool_free(pool);
    return pn;
}

Test(pixel_noise, bright_pixels_weigh_as_the_linear_mse_has_them)
{
    const double dim = 0.01, bright = 1.0;
    PixelNoise *pn = two_halves(dim, bright, 0.5, 0.5, 2);
    /* pixels 5 columns from the border and the edges: their 5x5 box sees one half */
    double d_dim = pixel_noise_deviation(pn, (size_t)10 * W + 5);
    double d_bright = pixel_noise_deviation(pn, (size_t)10 * W + W - 6);
    cr_assert(d_dim > 0.0 && d_bright > d_dim, "%g %g", d_dim, d_bright);
    /* deviation^2 is V / w, w = 1 / (I^2 + eps) + 1 / M^2: the ratio of two
     * pixels' deviations is their weights' inverse ratio */
    double m = (dim + bright) / 2, eps = (0.25 * m) * (0.25 * m);
    double w_dim = 1.0 / (dim * dim + eps) + 1.0 / (m * m), w_bright = 1.0 / (bright * bright + eps) + 1.0 / (m * m);
    double expected = sqrt(w_dim / w_bright), got = d_bright / d_dim;
    cr_assert(fabs(got / expected - 1.0) < 1e-4, "bright / dim deviation %g, expected %g", got, expected);
    /* on relMSE alone the bright pixel's deviation would be twice this
     * (its paths cut that much more often) */
    double relmse_alone = sqrt((bright * bright + eps) / (dim * dim + eps));
    cr_assert(relmse_alone > 2.0 * got, "%g against %g", relmse_alone, got);
    pixel_noise_free(pn);
}

Test(pixel_noise, the_same_for_any_thread_count)
{
    PixelNoise *a = two_halves(0.02, 3.0, 0.3, 0.7, 1), *b = two_halves(0.02, 3.0, 0.3, 0.7, 3);
    for (size_t p = 0; p < (size_t)W * H; p++)
        cr_assert_eq(pixel_noise_deviation(a, p), pixel_noise_deviation(b, p), "pixel %zu", p);
    pixel_noise_free(a);
    pixel_noise_free(b);
}
