/* The light the camera sees directly: the emission a camera ray's first hit
 * sends toward it, or the sky past the scene (integrator_trace's `seen`).
 * Where it varies within a pixel (a light's or the sky's silhouette), its
 * in-or-out noise is most of such a pixel's error, and most of the image's
 * linear MSE where a bright light is in view; no way of drawing bounces
 * touches it, only more camera rays do. So a sample there adds k camera
 * rays that look for that light alone (one ray each, nothing shaded) and
 * takes the mean of the k + 1 views for its own: each ray is uniform over
 * the pixel, so the pixel's estimate stays unbiased. Every sampling mode
 * gets them alike.
 *
 * Which pixels: before the first pass, a survey looks (on an R2 pattern
 * of its own, the same for every shard of a render): one camera ray a
 * pixel, then EDGE_RAYS_SURVEY - 1 more where that first view differs within
 * the pixel's 3x3 neighbourhood (edge_rays_survey below), so that
 * a silhouette is known from the first pass on: a pass
 * whose sample saw it through its one ray would weigh in the pixel's mean
 * as much as one that took many (on a straight edge, the passes' own
 * stratified rays are good enough that those first passes would be most of
 * what is left). A pixel whose views never varied takes none.
 *
 * How many: with Vs the variance of one view of pixel p, V the image's mean
 * variance of a sample (the linear MSE's, per sample) and R a sample's cost
 * in rays, the image's variance times its cost is least where
 * k + 1 = sqrt(Vs R / V) (the derivative of sum_p (Vs_p / (k_p + 1) + ...)
 * times sum_p (R + k_p)). So a bright light's silhouette in a quiet image
 * gets many, a sky's texture that hardly varies within a pixel few or none.
 * Until V is known (EDGE_RAYS_FROM_PASS passes), a silhouette takes the most;
 * never more than EDGE_RAYS_MAX. Deterministic: V is made between passes
 * from every pixel's sums in a fixed order, and a pixel's choice depends on
 * V and its own views alone, whatever the threads. */
#ifndef SG_RENDER_EDGE_RAYS_H
#define SG_RENDER_EDGE_RAYS_H

#include <stddef.h>
#include <stdint.h>

#include "camera.h"
#include "integrator.h"
#include "pixel_sampler.h"
#include "threads.h"
#include "vecmath.h"

#define EDGE_RAYS_FROM_PASS 4
#define EDGE_RAYS_MAX 16
#define EDGE_RAYS_SURVEY 16

typedef struct EdgeRays {
    int width, height;
    int rays_max;                   /* the most extra rays a sample takes (0: none) */
    double image_variance;          /* V above; 0: not known yet */
    uint32_t *views;                /* per pixel: camera rays that looked (survey, samples' own, extra) */
    uint32_t *samples;              /* per pixel: samples */
    double *view_sum, *view_sq;     /* per pixel: the views' luminance, and its squares */
    double *sample_sum, *sample_sq; /* per pixel: the samples' luminance (views averaged), and its squares */
    float *survey_first;            /* per pixel: the survey's first view (edge_rays_survey) */
} EdgeRays;

/* NULL when out of memory; rays_max in [0, EDGE_RAYS_MAX]. */
EdgeRays *edge_rays_create(int width, int height, int rays_max);
void edge_rays_free(EdgeRays *sl);

/* Forgets every view and sample (a render from a frozen field starts as
 * one loaded from its file does). */
void edge_rays_clear(EdgeRays *sl);

/* The extra rays for one view's variance vs, the image's variance of a
 * sample v and a sample's cost in rays (the rule above), at most rays_max;
 * v <= 0 (not known): rays_max wherever vs > 0. */
int edge_rays_count_for(double vs, double v, double cost_rays, int rays_max);

/* Pixel pix's extra rays for its next sample. */
int edge_rays_count(const EdgeRays *sl, size_t pix, double cost_rays);

/* Remakes V from every pixel's samples so far, `passes` of them (not
 * before EDGE_RAYS_FROM_PASS). */
void edge_rays_estimate(EdgeRays *sl, int passes);

/* One view (a camera ray's seen light, luminance) of pixel pix. */
static inline void edge_rays_add_view(EdgeRays *sl, size_t pix, double l)
{
    sl->views[pix]++;
    sl->view_sum[pix] += l;
    sl->view_sq[pix] += l * l;
}

/* One sample of pixel pix as the film gets it (luminance). */
static inline void edge_rays_add_sample(EdgeRays *sl, size_t pix, double l)
{
    sl->samples[pix]++;
    sl->sample_sum[pix] += l;
    sl->sample_sq[pix] += l * l;
}

/* The survey before the first pass (above), on the pool, its camera rays
 * on an R2 pattern keyed by `seed` alone: the views it takes go to the
 * pixels' sums. Returns the camera rays it traced. */
uint64_t edge_rays_survey(EdgeRays *er, const Integrator *it, const Camera *cam, uint64_t seed, SgThreadPool *pool);

/* Sample L of pixel (x, y), whose light seen directly was `seen`, with that
 * light made the mean of its own view and of the extra camera rays the
 * pixel takes now (pass sampler ps; sample_rays: a sample's cost in rays);
 * the views and the sample go to the pixel's sums. Returns the sample. */
Vec3 edge_rays_sample(EdgeRays *er, const Integrator *it, const Camera *cam, const PixelSampler *ps,
                      double sample_rays, int x, int y, Vec3 L, Vec3 seen, int thread, PathStats *st);

#endif
