/* The film: every pixel's sum of samples over the passes, and the last
 * pass's samples alone. A sample that is NaN or infinite never reaches it. */
#ifndef SG_RENDER_FILM_H
#define SG_RENDER_FILM_H

#include <stdbool.h>
#include <stddef.h>

#include "vecmath.h"

typedef struct Film {
    int width, height;
    double *sum; /* width * height * 3 */
    float *last; /* width * height * 3 */
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
    return finite;
}

/* Every pixel back to no sample. */
void film_clear(Film *f);

/* The mean of `spp` passes, linear RGB, width * height * 3 floats. */
void film_image(const Film *f, int spp, float *rgb);

#endif
