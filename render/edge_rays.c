#include "edge_rays.h"

#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

EdgeRays *edge_rays_create(int width, int height, int rays_max)
{
    EdgeRays *sl = calloc(1, sizeof *sl);
    if (!sl)
        return NULL;
    size_t pixels = (size_t)width * height;
    sl->width = width;
    sl->height = height;
    sl->rays_max = rays_max < 0 ? 0 : rays_max > EDGE_RAYS_MAX ? EDGE_RAYS_MAX : rays_max;
    sl->views = calloc(pixels, sizeof *sl->views);
    sl->samples = calloc(pixels, sizeof *sl->samples);
    sl->view_sum = calloc(pixels, sizeof *sl->view_sum);
    sl->view_sq = calloc(pixels, sizeof *sl->view_sq);
    sl->sample_sum = calloc(pixels, sizeof *sl->sample_sum);
    sl->sample_sq = calloc(pixels, sizeof *sl->sample_sq);
    sl->survey_first = calloc(pixels, sizeof *sl->survey_first);
    if (!sl->views || !sl->samples || !sl->view_sum || !sl->view_sq || !sl->sample_sum || !sl->sample_sq ||
        !sl->survey_first) {
        edge_rays_free(sl);
        return NULL;
    }
    return sl;
}

void edge_rays_free(EdgeRays *sl)
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

void edge_rays_clear(EdgeRays *sl)
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

int edge_rays_count_for(double vs, double v, double cost_rays, int rays_max)
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

int edge_rays_count(const EdgeRays *sl, size_t pix, double cost_rays)
{
    if (sl->rays_max <= 0 || sl->views[pix] < 2)
        return 0;
    double vs = variance(sl->views[pix], sl->view_sum[pix], sl->view_sq[pix]);
    return edge_rays_count_for(vs, sl->image_variance, cost_rays, sl->rays_max);
}

void edge_rays_estimate(EdgeRays *sl, int passes)
{
    if (passes < EDGE_RAYS_FROM_PASS || sl->rays_max <= 0)
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

/* ---- the survey ------------------------------------------------------------
 * In two steps, one job per image row each: one ray a pixel, then the
 * other EDGE_RAYS_SURVEY - 1 only where that first view differs within the
 * pixel's 3x3 neighbourhood. A silhouette crossing a pixel also crosses
 * between its neighbours' first views; where nothing differs (no light in
 * view, the inside of a lamp or of a flat sky) the other rays would find
 * nothing, and the survey's time is on the render's clock. A sliver that
 * every neighbour's first ray misses is left to the pixel's own samples,
 * as it was before the survey existed. */
typedef struct SurveyCtx {
    EdgeRays *er;
    const Integrator *it;
    const Camera *cam;
    PixelSampler sampler;
    float *first; /* per pixel: the first view's luminance (er->survey_first) */
    _Atomic uint64_t rays;
} SurveyCtx;

static float survey_view(SurveyCtx *sc, int x, int y, int j, int thread, PathStats *st)
{
    size_t pix = (size_t)y * sc->er->width + x;
    float jx, jy;
    pixel_sampler_survey(&sc->sampler, pix, j, &jx, &jy);
    float v = luminance(integrator_seen(sc->it, sc->cam->pos, camera_ray(sc->cam, x, y, jx, jy), thread, st));
    edge_rays_add_view(sc->er, pix, v);
    return v;
}

static void survey_first_row(void *vctx, uint64_t row, int thread)
{
    SurveyCtx *sc = vctx;
    PathStats st = {0};
    int y = (int)row, w = sc->er->width;
    for (int x = 0; x < w; x++)
        sc->first[(size_t)y * w + x] = survey_view(sc, x, y, 0, thread, &st);
    atomic_fetch_add(&sc->rays, st.rays);
}

/* Whether pixel (x, y)'s first view differs from a neighbour's (exactly:
 * a lamp of one radiance against the dark is two values; a NaN differs). */
static bool survey_differs(const SurveyCtx *sc, int x, int y)
{
    int w = sc->er->width, h = sc->er->height;
    float v = sc->first[(size_t)y * w + x];
    for (int dy = -1; dy <= 1; dy++)
        for (int dx = -1; dx <= 1; dx++) {
            int nx = x + dx, ny = y + dy;
            if (nx >= 0 && nx < w && ny >= 0 && ny < h && !(sc->first[(size_t)ny * w + nx] == v))
                return true;
        }
    return false;
}

static void survey_rest_row(void *vctx, uint64_t row, int thread)
{
    SurveyCtx *sc = vctx;
    PathStats st = {0};
    int y = (int)row;
    for (int x = 0; x < sc->er->width; x++)
        if (survey_differs(sc, x, y))
            for (int j = 1; j < EDGE_RAYS_SURVEY; j++)
                survey_view(sc, x, y, j, thread, &st);
    atomic_fetch_add(&sc->rays, st.rays);
}

uint64_t edge_rays_survey(EdgeRays *er, const Integrator *it, const Camera *cam, uint64_t seed, SgThreadPool *pool)
{
    SurveyCtx sc = {.er = er, .it = it, .cam = cam, .first = er->survey_first};
    pixel_sampler_init(&sc.sampler, seed, 0);
    sg_thread_pool_run(pool, (uint64_t)er->height, survey_first_row, &sc);
    sg_thread_pool_run(pool, (uint64_t)er->height, survey_rest_row, &sc);
    return atomic_load(&sc.rays);
}

/* ---- a sample's extra rays ------------------------------------------------ */

Vec3 edge_rays_sample(EdgeRays *er, const Integrator *it, const Camera *cam, const PixelSampler *ps,
                      double sample_rays, int x, int y, Vec3 L, Vec3 seen, int thread, PathStats *st)
{
    size_t pix = (size_t)y * er->width + x;
    int k = edge_rays_count(er, pix, sample_rays);
    Vec3 views = seen;
    edge_rays_add_view(er, pix, luminance(seen));
    for (int j = 0; j < k; j++) {
        float jx, jy;
        pixel_sampler_view(ps, pix, j, EDGE_RAYS_MAX, &jx, &jy);
        Vec3 v = integrator_seen(it, cam->pos, camera_ray(cam, x, y, jx, jy), thread, st);
        edge_rays_add_view(er, pix, luminance(v));
        views = v3_add(views, v);
    }
    if (k)
        L = v3_add(v3_sub(L, seen), v3_scale(views, 1.0f / (float)(k + 1)));
    edge_rays_add_sample(er, pix, luminance(L));
    return L;
}
