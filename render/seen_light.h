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
 * pixel, then SEEN_SURVEY - 1 more where that first view differs within
 * the pixel's 3x3 neighbourhood (render/renderer.c, survey_views), so that
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
 * Until V is known (SEEN_FROM_PASS passes), a silhouette takes the most;
 * never more than SEEN_RAYS_MAX. Deterministic: V is made between passes
 * from every pixel's sums in a fixed order, and a pixel's choice depends on
 * V and its own views alone, whatever the threads. */
#ifndef SG_RENDER_SEEN_LIGHT_H
#define SG_RENDER_SEEN_LIGHT_H

#include <stddef.h>
#include <stdint.h>

#define SEEN_FROM_PASS 4
#define SEEN_RAYS_MAX 16
#define SEEN_SURVEY 16

typedef struct SeenLight {
    int width, height;
    int rays_max;                   /* the most extra rays a sample takes (0: none) */
    double image_variance;          /* V above; 0: not known yet */
    uint32_t *views;                /* per pixel: camera rays that looked (survey, samples' own, extra) */
    uint32_t *samples;              /* per pixel: samples */
    double *view_sum, *view_sq;     /* per pixel: the views' luminance, and its squares */
    double *sample_sum, *sample_sq; /* per pixel: the samples' luminance (views averaged), and its squares */
    float *survey_first;            /* per pixel: the survey's first view (render/renderer.c) */
} SeenLight;

/* NULL when out of memory; rays_max in [0, SEEN_RAYS_MAX]. */
SeenLight *seen_light_create(int width, int height, int rays_max);
void seen_light_free(SeenLight *sl);

/* Forgets every view and sample (a render from a frozen field starts as
 * one loaded from its file does). */
void seen_light_clear(SeenLight *sl);

/* The extra rays for one view's variance vs, the image's variance of a
 * sample v and a sample's cost in rays (the rule above), at most rays_max;
 * v <= 0 (not known): rays_max wherever vs > 0. */
int seen_light_rays_for(double vs, double v, double cost_rays, int rays_max);

/* Pixel pix's extra rays for its next sample. */
int seen_light_rays(const SeenLight *sl, size_t pix, double cost_rays);

/* Remakes V from every pixel's samples so far, `passes` of them (not
 * before SEEN_FROM_PASS). */
void seen_light_estimate(SeenLight *sl, int passes);

/* One view (a camera ray's seen light, luminance) of pixel pix. */
static inline void seen_light_add_view(SeenLight *sl, size_t pix, double l)
{
    sl->views[pix]++;
    sl->view_sum[pix] += l;
    sl->view_sq[pix] += l * l;
}

/* One sample of pixel pix as the film gets it (luminance). */
static inline void seen_light_add_sample(SeenLight *sl, size_t pix, double l)
{
    sl->samples[pix]++;
    sl->sample_sum[pix] += l;
    sl->sample_sq[pix] += l * l;
}

#endif
