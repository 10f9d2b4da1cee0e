/* PCG32 (O'Neill 2014): small state, good statistics, and a stream per
 * pixel so that renders do not depend on the thread schedule. */
#ifndef SG_RNG_H
#define SG_RNG_H

#include <stdint.h>

typedef struct SgRng {
    uint64_t state;
    uint64_t inc;
} SgRng;

static inline uint32_t sg_rng_next(SgRng *r)
{
    uint64_t old = r->state;
    r->state = old * 6364136223846793005ULL + r->inc;
    uint32_t xorshifted = (uint32_t)(((old >> 18u) ^ old) >> 27u);
    uint32_t rot = (uint32_t)(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((-rot) & 31));
}

static inline void sg_rng_seed(SgRng *r, uint64_t seed, uint64_t stream)
{
    r->state = 0;
    r->inc = (stream << 1u) | 1u;
    sg_rng_next(r);
    r->state += seed;
    sg_rng_next(r);
}

/* Uniform float in [0, 1): 24 random bits, never returns 1. */
static inline float sg_rng_float(SgRng *r)
{
    return (float)(sg_rng_next(r) >> 8) * (1.0f / 16777216.0f);
}

#endif
