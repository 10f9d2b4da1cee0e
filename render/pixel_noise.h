/* The learned roulette's measure of the noise each pixel has anyway. */
#ifndef SG_RENDER_PIXEL_NOISE_H
#define SG_RENDER_PIXEL_NOISE_H

#include <stddef.h>

#include "threads.h"

/* The noise a path may add to each pixel (pixel_noise_deviation):
 * sqrt(V / w), w = 1 / (I^2 + eps) + k / M^2 the pixel's weight in the
 * error the roulette minimizes, I the pixel's bounced light (a 5x5 box
 * mean: one pixel's own is too noisy in the first passes), M the image's
 * mean of it, V the image's mean of w times one sample's variance, eps
 * (DEVIATION_FLOOR M)^2 so that near-black pixels count as relMSE counts
 * them. w weighs relMSE (1 / (I^2 + eps)) and the linear MSE (k / M^2,
 * LINEAR_WEIGHT): on relMSE alone the roulette cut the paths of bright
 * pixels, where the linear MSE lives (guided trailed bsdf in it on the
 * bathroom, 0.74x), and split too many paths of dim ones. A share of the
 * image's error per pixel, as efficiency-aware roulette has it (Rath et
 * al. 2022): one pixel's own variance is too noisy to steer by. Made before
 * the pass from the passes before it, so the pass stays unbiased and its
 * image independent of the thread count. */
typedef struct PixelNoise {
    int width, height;
    double *sum, *sum_sq; /* per pixel: its samples' bounced luminance, and squares */
    float *deviation;     /* per pixel: the estimate (0: unknown); then scratch rows */
    double *rows;         /* per image row, for the estimate's sums */
} PixelNoise;

/* NULL when out of memory. */
PixelNoise *pixel_noise_create(int width, int height);
void pixel_noise_free(PixelNoise *pn);

/* A sample's bounced light (luminance) in pixel `pix`. */
static inline void pixel_noise_add(PixelNoise *pn, size_t pix, double l)
{
    pn->sum[pix] += l;
    pn->sum_sq[pix] += l * l;
}

/* Remakes every pixel's deviation from the `spp` samples added so far
 * (spp >= 2), the rows shared out on the pool. */
void pixel_noise_estimate(PixelNoise *pn, int spp, SgThreadPool *pool);

static inline float pixel_noise_deviation(const PixelNoise *pn, size_t pix) { return pn->deviation[pix]; }

#endif
