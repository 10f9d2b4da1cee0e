/* The learner's histograms of directions: octahedral bins over the sphere,
 * a piecewise-constant density over them (render/sampling.h). */
#include "mixture_learning.h"

#include "../sampling.h"

#include <math.h>

/* ---- the histogram's density ------------------------------------------------ */

/* The octahedral map of the sphere onto the square [-1, 1]^2: w / |w|_1 on
 * the octahedron, its lower half folded out to the corners. No
 * trigonometry either way (a bounce draws and evaluates it several times;
 * the equal-area map's atan, sin and cos cost the Cornell box 40% of its
 * rays per second). Its solid angle per unit of the square is 1 / |p|^3
 * for p on the octahedron (|p|_1 = 1), i.e. |w|_1^3 for unit w: between 1
 * and 3^1.5 across the square, so a bin's solid angle is not all equal and
 * the density within a bin follows that factor. */
/* The fold between the octahedron's lower half and the square's corners:
 * its own inverse. */
static inline void octahedral_fold(float *x, float *y)
{
    float fx = copysignf(1.0f - fabsf(*y), *x), fy = copysignf(1.0f - fabsf(*x), *y);
    *x = fx, *y = fy;
}

static inline void octahedral_square(Vec3 w, float *px, float *py, float *l1)
{
    float s = fabsf(w.x) + fabsf(w.y) + fabsf(w.z);
    *px = w.x / s, *py = w.y / s, *l1 = s;
    if (w.z < 0.0f)
        octahedral_fold(px, py);
}

static inline uint32_t octahedral_bin(float px, float py)
{
    int x = (int)((px + 1.0f) * (0.5f * SG_MIXTURE_HIST_RES)), y = (int)((py + 1.0f) * (0.5f * SG_MIXTURE_HIST_RES));
    x = x < 0 ? 0 : x >= SG_MIXTURE_HIST_RES ? SG_MIXTURE_HIST_RES - 1 : x;
    y = y < 0 ? 0 : y >= SG_MIXTURE_HIST_RES ? SG_MIXTURE_HIST_RES - 1 : y;
    return (uint32_t)(y * SG_MIXTURE_HIST_RES + x);
}

uint32_t sg_mixture_histogram_bin(Vec3 w)
{
    float px, py, l1;
    octahedral_square(w, &px, &py, &l1);
    return octahedral_bin(px, py);
}

float sg_mixture_histogram_pdf(const float *cdf, Vec3 w)
{
    float px, py, l1;
    octahedral_square(w, &px, &py, &l1);
    uint32_t b = octahedral_bin(px, py);
    float p = sg_piecewise_massf(cdf, b);
    /* the bin's probability over its area of the square (4 / bins), times
     * the square's area per solid angle, |p|^3 = 1 / |w|_1^3 */
    float inv = 1.0f / l1;
    return fmaxf(p, 0.0f) * (SG_MIXTURE_BINS * 0.25f) * inv * inv * inv;
}

Vec3 sg_mixture_histogram_sample(const float *cdf, float u1, float u2)
{
    /* the bin, then a point uniform in its cell: the probability u1 had
     * left over places it across the cell */
    float s;
    uint32_t bin = sg_piecewise_samplef(cdf, SG_MIXTURE_BINS, u1, &s);
    s = fminf(fmaxf(s, 0.0f), 0x1.fffffep-1f);
    const float cell = 2.0f / SG_MIXTURE_HIST_RES;
    float x = -1.0f + ((float)(bin % SG_MIXTURE_HIST_RES) + s) * cell;
    float y = -1.0f + ((float)(bin / SG_MIXTURE_HIST_RES) + u2) * cell;
    float z = 1.0f - fabsf(x) - fabsf(y);
    if (z < 0.0f)
        octahedral_fold(&x, &y);
    return v3_normalize(v3(x, y, z));
}
