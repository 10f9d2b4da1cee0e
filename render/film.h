/* The film: every pixel's sum of samples over the passes, and the last
 * pass's samples alone. A sample that is NaN or infinite never reaches it.
 *
 * While a guide learns, its passes get better as they go: the film keeps
 * them in groups (the passes between two of the guide's checkpoints), and
 * the image weights each group by the inverse of its estimated variance,
 * so that the early, noisy passes count without spoiling the later ones
 * (practical path guiding's rule for combining its iterations). A group's
 * variance per pass is the mean, over the pixels, of its passes' squared
 * distance to the image of all passes, in luminance (the worst 0.1 % of
 * pixels left out: one firefly does not decide a weight). Each
 * pass is an unbiased estimate and a weight is one number for the whole
 * image, so a pixel's own samples move its weights by 1/pixels at most:
 * the combination is unbiased up to that (tests/test_render_film.c
 * measures it in a furnace).
 *
 * With one group (a render that learns nothing, or one from a frozen
 * field) the image is the plain mean of the passes, as it always was. */
#ifndef SG_RENDER_FILM_H
#define SG_RENDER_FILM_H

#include <stdbool.h>
#include <stddef.h>

#include "color.h"
#include "vecmath.h"

/* A closed group of passes: each pixel's sum of samples and sum of squared
 * luminance over them (floats: they decide weights and hold a few hundred
 * passes at most). */
typedef struct FilmGroup {
    float *sum;    /* width * height * 3 */
    float *square; /* width * height */
    int passes;
    double cost; /* what its passes cost (the renderer counts rays) */
} FilmGroup;

#define FILM_GROUPS_MAX 24

typedef struct Film {
    int width, height;
    double *sum;    /* the open group's sums, width * height * 3 */
    double *square; /* the open group's sums of squared luminance, width * height */
    float *last;    /* the last pass's samples, width * height * 3 */
    int passes;     /* in the open group */
    double cost;    /* the open group's passes' cost */
    FilmGroup groups[FILM_GROUPS_MAX];
    int group_count;
} Film;

/* False when out of memory. */
bool film_init(Film *f, int width, int height);
void film_free(Film *f);

/* Adds pixel `pix`'s sample of this pass; a non-finite one counts as 0
 * (and returns false). */
static inline bool film_add(Film *f, size_t pix, Vec3 *L)
{
    bool finite = isfinite(L->x) && isfinite(L->y) && isfinite(L->z);
    if (!finite)
        *L = v3(0, 0, 0);
    f->last[3 * pix] = L->x;
    f->last[3 * pix + 1] = L->y;
    f->last[3 * pix + 2] = L->z;
    f->sum[3 * pix] += L->x;
    f->sum[3 * pix + 1] += L->y;
    f->sum[3 * pix + 2] += L->z;
    double y = sg_luminance(L->x, L->y, L->z);
    f->square[pix] += y * y;
    return finite;
}

/* A pass is complete; `cost`: what it cost (the renderer counts its rays). */
static inline void film_end_pass(Film *f, double cost)
{
    f->passes++;
    f->cost += cost;
}

/* Closes the open group: its passes keep their place in the image, weighted
 * as a group of their own. False when out of memory or FILM_GROUPS_MAX are
 * closed already (the open group then goes on: still unbiased). */
bool film_close_group(Film *f);

/* Every pixel back to no sample, every group gone. */
void film_clear(Film *f);

/* Each group's estimated variance per pass (luminance, the worst 0.1 % of
 * pixels left out; 0: unknown, under 3 passes in all): groups[0..group_count-1]
 * then the open group (if it has passes) in variance[], and their cost per
 * pass in cost[] (NULL: not wanted). Returns how many were written (at most
 * FILM_GROUPS_MAX + 1). */
int film_group_variances(const Film *f, double *variance, double *cost);

/* The image: the groups' means weighted by their passes over their
 * variance (one group: its mean), linear RGB, width * height * 3 floats. */
void film_image(const Film *f, float *rgb);

/* All passes, in every group. */
int film_passes(const Film *f);

#endif
