#include "seen_light.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

SeenLight *seen_light_create(int width, int height, int rays_max)
{
    SeenLight *sl = calloc(1, sizeof *sl);
    if (!sl)
        return NULL;
    size_t pixels = (size_t)width * height;
    sl->width = width;
    sl->height = height;
    sl->rays_max = rays_max < 0 ? 0 : rays_max > SEEN_RAYS_MAX ? SEEN_RAYS_MAX : rays_max;
    sl->views = calloc(pixels, sizeof *sl->views);
    sl->samples = calloc(pixels, sizeof *sl->samples);
    sl->view_sum = calloc(pixels, sizeof *sl->view_sum);
    sl->view_sq = calloc(pixels, sizeof *sl->view_sq);
    sl->sample_sum = calloc(pixels, sizeof *sl->sample_sum);
    sl->sample_sq = calloc(pixels, sizeof *sl->sample_sq);
    sl->survey_first = calloc(pixels, sizeof *sl->survey_first);
    if (!sl->views || !sl->samples || !sl->view_sum || !sl->view_sq || !sl->sample_sum || !sl->sample_sq ||
        !sl->survey_first) {
        seen_light_free(sl);
        return NULL;
    }
    return sl;
}

void seen_light_free(SeenLight *sl)
{
    if (!sl)
        return;
    free(sl->views);
    free(sl->samples);
    free(sl->view_sum);
    free(sl->view_sq);
    free(sl->sample_sum);
    free(sl->sample_sq);
    free(sl->survey_first);
    free(sl);
}

void seen_light_clear(SeenLight *sl)
{
    size_t pixels = (size_t)sl->width * sl->height;
    memset(sl->views, 0, pixels * sizeof *sl->views);
    memset(sl->samples, 0, pixels * sizeof *sl->samples);
    memset(sl->view_sum, 0, pixels * sizeof *sl->view_sum);
    memset(sl->view_sq, 0, pixels * sizeof *sl->view_sq);
    memset(sl->sample_sum, 0, pixels * sizeof *sl->sample_sum);
    memset(sl->sample_sq, 0, pixels * sizeof *sl->sample_sq);
    sl->image_variance = 0.0;
}

int seen_light_rays_for(double vs, double v, double cost_rays, int rays_max)
{
    if (!(vs > 0.0) || rays_max <= 0)
        return 0;
    if (!(v > 0.0)) /* the image's noise not known yet */
        return rays_max;
    double k = sqrt(vs * (cost_rays > 1.0 ? cost_rays : 1.0) / v) - 1.0;
    if (!(k >= 0.5)) /* NaN too */
        return 0;
    return k >= rays_max ? rays_max : (int)(k + 0.5);
}

/* Sample variance of n values from their sum and sum of squares; 0 where
 * what is left is rounding (a view that never varies). */
static double variance(double n, double sum, double sq)
{
    double mean = sum / n, v = (sq - sum * mean) / (n - 1.0);
    return v > 1e-9 * (mean * mean) ? v : 0.0;
}

int seen_light_rays(const SeenLight *sl, size_t pix, double cost_rays)
{
    if (sl->rays_max <= 0 || sl->views[pix] < 2)
        return 0;
    double vs = variance(sl->views[pix], sl->view_sum[pix], sl->view_sq[pix]);
    return seen_light_rays_for(vs, sl->image_variance, cost_rays, sl->rays_max);
}

void seen_light_estimate(SeenLight *sl, int passes)
{
    if (passes < SEEN_FROM_PASS || sl->rays_max <= 0)
        return;
    size_t pixels = (size_t)sl->width * sl->height, counted = 0;
    double sum = 0.0;
    for (size_t p = 0; p < pixels; p++)
        if (sl->samples[p] >= 2) {
            sum += variance(sl->samples[p], sl->sample_sum[p], sl->sample_sq[p]);
            counted++;
        }
    sl->image_variance = counted ? sum / (double)counted : 0.0;
}
