/* Which random numbers a pixel's sample takes in each pass, and where in
 * the pixel its camera ray goes: both depend only on (seed, pixel, pass),
 * never on the thread that renders it, so the image is the same for any
 * thread count (and a shard's passes are the whole render's). */
#ifndef SG_RENDER_PIXEL_SAMPLER_H
#define SG_RENDER_PIXEL_SAMPLER_H

#include <stddef.h>
#include <stdint.h>

#include "rng.h"

/* One pass of the whole render (pass numbers count the unsharded render). */
typedef struct PixelSampler {
    uint64_t pass;
    uint64_t pass_key;   /* the pass's random streams (also handed to the guide) */
    uint64_t jitter_key; /* the seed's: the same for every pass */
} PixelSampler;

void pixel_sampler_init(PixelSampler *ps, uint64_t seed, uint64_t pass);

/* Pixel `pix`'s random stream for the pass, and its camera ray's position
 * in the pixel, (jx, jy) in [0, 1)^2. */
void pixel_sampler_start(const PixelSampler *ps, size_t pix, SgRng *rng, float *jx, float *jy);

/* Where in pixel `pix` the pass's j-th extra camera ray goes (j below
 * `per_pass`, render/edge_rays.h): point pass * per_pass + j of an R2
 * sequence rotated by an offset of its own per pixel and seed, so that each
 * point alone is uniform over the pixel and the points of a pass, and of
 * all passes, cover it evenly. */
void pixel_sampler_view(const PixelSampler *ps, size_t pix, int j, int per_pass, float *jx, float *jy);

/* The j-th of the rays that survey pixel `pix` before the first pass
 * (render/edge_rays.h): an R2 pattern rotated per pixel and seed, the same
 * for every pass and shard. */
void pixel_sampler_survey(const PixelSampler *ps, size_t pix, int j, float *jx, float *jy);

#endif
