#include "roulette.h"

#include <math.h>

bool roulette_albedo(const PathGuide *g, Vec3 *beta, Vec3 *rr_beta, SgRng *rng, GuideSegment *seg)
{
    return roulette_survive(g, roulette_albedo_survival(*rr_beta), beta, rr_beta, rng, seg);
}

bool roulette_survive(const PathGuide *g, float q, Vec3 *beta, Vec3 *rr_beta, SgRng *rng, GuideSegment *seg)
{
    if (seg) /* a learned field learns what survivors carry */
        g->ops->record_survival(seg, q);
    if (!(sg_rng_float(rng) < q))
        return false;
    *beta = v3_scale(*beta, 1.0f / q);
    *rr_beta = v3_scale(*rr_beta, 1.0f / q);
    return true;
}

RouletteVerdict roulette_learned(float worth, int depth, int branches, bool may_split, float min_survival,
                                 SgRng *rng)
{
    float q = ROULETTE_GAIN * worth, split = SPLIT_GAIN * worth;
    if (depth >= ROULETTE_DEPTH && q < 1.0f) {
        q = sg_maxf(q, sg_maxf(ROULETTE_MIN_SURVIVAL, min_survival));
        if (q >= 1.0f)
            return (RouletteVerdict){1, 1.0f};
        if (!(sg_rng_float(rng) < q))
            return (RouletteVerdict){0, 0.0f};
        return (RouletteVerdict){1, 1.0f / q};
    }
    if (split > 1.0f && may_split) {
        split = sg_minf(split, sg_minf((float)SPLIT_MAX, (float)(1 + SPLIT_BRANCHES_MAX - branches)));
        int n = (int)split + (sg_rng_float(rng) < split - floorf(split));
        return (RouletteVerdict){n, 1.0f / split};
    }
    return (RouletteVerdict){1, 1.0f};
}

void roulette_prepare_pass(PixelNoise *noise, int spp, SgThreadPool *pool)
{
    if (noise && spp > 1 && (spp < 8 || !(spp & (spp - 1)) || spp % 16 == 0))
        pixel_noise_estimate(noise, spp, pool);
}
