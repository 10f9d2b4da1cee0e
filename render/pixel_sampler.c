#include "pixel_sampler.h"

#include <math.h>

static uint64_t mix64(uint64_t x)
{
    x ^= x >> 30;
    x *= 0xbf58476d1ce4e5b9ULL;
    x ^= x >> 27;
    x *= 0x94d049bb133111ebULL;
    x ^= x >> 31;
    return x;
}

void pixel_sampler_init(PixelSampler *ps, uint64_t seed, uint64_t pass)
{
    ps->pass = pass;
    ps->pass_key = mix64(seed * 0x9e3779b97f4a7c15ULL + pass + 1);
    ps->jitter_key = mix64(seed ^ 0x6a09e667f3bcc909ULL);
}

/* Where in its pixel pass n's camera ray goes: the n-th point of the R2
 * sequence (Roberts 2018, the plastic number's powers) shifted by an
 * offset drawn per pixel and seed (a Cranley-Patterson rotation). Each pass
 * alone is a uniform jitter, so each pass stays an unbiased estimate; over
 * the passes a pixel's points cover it evenly, so an edge seen directly (a
 * light's silhouette, whose in-or-out noise is otherwise most of the image's
 * squared error) converges faster than with independent jitter. */
static void pixel_jitter(uint64_t key, size_t pix, uint64_t pass, float *jx, float *jy)
{
    uint64_t h = mix64(key ^ ((uint64_t)pix * 0x9e3779b97f4a7c15ULL));
    double x = (double)(h >> 40) * (1.0 / 16777216.0) + (double)pass * 0.75487766624669276;
    double y = (double)(h & 0xffffff) * (1.0 / 16777216.0) + (double)pass * 0.56984029099805327;
    *jx = (float)(x - floor(x));
    *jy = (float)(y - floor(y));
    if (!(*jx < 1.0f)) /* rounding to float */
        *jx = 0.0f;
    if (!(*jy < 1.0f))
        *jy = 0.0f;
}

void pixel_sampler_start(const PixelSampler *ps, size_t pix, SgRng *rng, float *jx, float *jy)
{
    sg_rng_seed(rng, ps->pass_key, pix);
    pixel_jitter(ps->jitter_key, pix, ps->pass, jx, jy);
}

void pixel_sampler_view(const PixelSampler *ps, size_t pix, int j, int per_pass, float *jx, float *jy)
{
    pixel_jitter(ps->jitter_key ^ 0x3c6ef372fe94f82bULL, pix, ps->pass * (uint64_t)per_pass + (uint64_t)j, jx, jy);
}

void pixel_sampler_survey(const PixelSampler *ps, size_t pix, int j, float *jx, float *jy)
{
    pixel_jitter(ps->jitter_key ^ 0xa54ff53a5f1d36f1ULL, pix, (uint64_t)j, jx, jy);
}
