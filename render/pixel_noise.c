#include "pixel_noise.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>

#define DEVIATION_RADIUS 2
#define DEVIATION_FLOOR 0.25
/* The linear MSE's weight beside relMSE's in what the roulette steers by
 * (pixel_noise.h): 1 gave, against 0 (relMSE alone), at equal time (10 s,
 * 4 seeds, guided from stored fields) relMSE -23% on the dark corridor,
 * -16% on the corridor, -8% on Sponza and the sunlit house, +1% on the
 * bathroom and Cornell box, +3% on the staircase (noise), and linear MSE
 * -20% to -60% everywhere; 0.25 gained less, 4 lost relMSE on the bathroom
 * (+10%) and the Cornell box (+4%). */
#define LINEAR_WEIGHT 1.0

/* One step of pixel_noise_estimate over the image's rows (run in parallel;
 * per-row sums are added in row order after, so the result does not depend
 * on the thread count). */
typedef struct DeviationStep {
    PixelNoise *noise;
    double n;      /* samples per pixel so far */
    int step;      /* 0: horizontal box, 1: vertical box, 2: relative variance, 3: deviation */
    double eps, relative;
    double linear; /* LINEAR_WEIGHT / image_mean^2, the linear MSE's weight */
    double *row_sum;
} DeviationStep;

/* A pixel's weight in the error the roulette minimizes (pixel_noise.h):
 * relMSE's, 1 / (I^2 + eps), and the linear MSE's beside it. */
static inline double pixel_weight(const DeviationStep *d, float mean)
{
    return 1.0 / ((double)mean * mean + d->eps) + d->linear;
}

static void deviation_row(void *vctx, uint64_t row, int thread)
{
    (void)thread;
    DeviationStep *d = vctx;
    PixelNoise *pn = d->noise;
    const int w = pn->width, h = pn->height, y = (int)row;
    const double n = d->n;
    const size_t pixels = (size_t)w * h;
    float *mean = pn->deviation + (size_t)y * w, *rows = pn->deviation + pixels;
    const double *bounced = pn->sum + (size_t)y * w;
    double acc = 0.0;
    switch (d->step) {
    case 0: /* running sum along the row */
        for (int x = 0; x < DEVIATION_RADIUS && x < w; x++)
            acc += bounced[x];
        for (int x = 0; x < w; x++) {
            if (x + DEVIATION_RADIUS < w)
                acc += bounced[x + DEVIATION_RADIUS];
            if (x - DEVIATION_RADIUS - 1 >= 0)
                acc -= bounced[x - DEVIATION_RADIUS - 1];
            int lo = x - DEVIATION_RADIUS < 0 ? 0 : x - DEVIATION_RADIUS;
            int hi = x + DEVIATION_RADIUS >= w ? w - 1 : x + DEVIATION_RADIUS;
            rows[(size_t)y * w + x] = (float)(acc / (n * (hi - lo + 1)));
        }
        break;
    case 1: {
        int lo = y - DEVIATION_RADIUS < 0 ? 0 : y - DEVIATION_RADIUS;
        int hi = y + DEVIATION_RADIUS >= h ? h - 1 : y + DEVIATION_RADIUS;
        for (int x = 0; x < w; x++) {
            float m = 0.0f;
            for (int j = lo; j <= hi; j++)
                m += rows[(size_t)j * w + x];
            m /= (float)(hi - lo + 1);
            mean[x] = m > 0.0f && isfinite(m) ? m : 0.0f;
            acc += mean[x];
        }
        break;
    }
    case 2:
        for (int x = 0; x < w; x++) {
            double m = bounced[x] / n;
            double var = (pn->sum_sq[(size_t)y * w + x] - n * m * m) / (n - 1.0);
            acc += (var > 0.0 ? var : 0.0) * pixel_weight(d, mean[x]);
        }
        break;
    default:
        for (int x = 0; x < w; x++)
            mean[x] = (float)sqrt(d->relative / pixel_weight(d, mean[x]));
    }
    d->row_sum[y] = acc;
}

static double deviation_step(DeviationStep *d, int step, SgThreadPool *pool)
{
    d->step = step;
    int h = d->noise->height;
    sg_thread_pool_run(pool, (uint64_t)h, deviation_row, d);
    double total = 0.0;
    for (int y = 0; y < h; y++)
        total += d->row_sum[y];
    return total;
}

void pixel_noise_estimate(PixelNoise *pn, int spp, SgThreadPool *pool)
{
    const double pixels = (double)pn->width * pn->height;
    DeviationStep d = {.noise = pn, .n = spp, .row_sum = pn->rows};
    deviation_step(&d, 0, pool);
    double image_mean = deviation_step(&d, 1, pool) / pixels;
    d.eps = DEVIATION_FLOOR * image_mean * DEVIATION_FLOOR * image_mean;
    d.linear = image_mean > 0.0 ? LINEAR_WEIGHT / (image_mean * image_mean) : 0.0;
    double relative = deviation_step(&d, 2, pool);
    d.relative = d.eps > 0.0 && isfinite(relative) ? relative / pixels : 0.0;
    deviation_step(&d, 3, pool);
}

PixelNoise *pixel_noise_create(int width, int height)
{
    PixelNoise *pn = calloc(1, sizeof *pn);
    if (!pn)
        return NULL;
    size_t pixels = (size_t)width * height;
    pn->width = width;
    pn->height = height;
    pn->deviation = calloc(2 * pixels, sizeof *pn->deviation);
    pn->sum = calloc(pixels, sizeof *pn->sum);
    pn->sum_sq = calloc(pixels, sizeof *pn->sum_sq);
    pn->rows = calloc((size_t)height, sizeof *pn->rows);
    if (!pn->deviation || !pn->sum || !pn->sum_sq || !pn->rows) {
        pixel_noise_free(pn);
        return NULL;
    }
    return pn;
}

void pixel_noise_free(PixelNoise *pn)
{
    if (!pn)
        return;
    free(pn->deviation);
    free(pn->sum);
    free(pn->sum_sq);
    free(pn->rows);
    free(pn);
}
