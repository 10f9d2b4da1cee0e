/* How paths are cut short and split: Russian roulette on the albedo
 * (pbrt's rule), and the learned roulette with its splitting half
 * (efficiency-aware, after Rath et al. 2022). Unbiased either way: a path
 * that survives or splits is divided by its survival probability or its
 * split factor. */
#ifndef SG_RENDER_ROULETTE_H
#define SG_RENDER_ROULETTE_H

#include <stdbool.h>

#include "guides/path_guide.h"
#include "pixel_noise.h"
#include "rng.h"
#include "threads.h"
#include "vecmath.h"

/* Learned roulette: from the third vertex on (as albedo roulette), after
 * its next-event estimate, a path's bounce survives with probability
 *     q = min(1, ROULETTE_GAIN |beta| sqrt(M2(region)) / sigma(pixel)),
 * M2 the region's second moment of what a bounce brings back per unit
 * throughput (GuideVertex.rms, from a guide that learns it), sigma the
 * noise the pixel has anyway (render/pixel_noise.h).
 * Cutting adds variance |beta|^2 M2 (1/q - 1) and saves the rest of the
 * path's cost; this q balances the two against the pixel's variance per
 * cost (the ratio of a whole path's cost to its rest folded into
 * ROULETTE_GAIN: 2.8 against 2 and 1.4 measured corridor 5.3x / 4.8x / 4.7x
 * bsdf's efficiency, the Cornell box within noise of 0.97x at all three;
 * 0.7 made fireflies on Sponza). Paths heading into the dark die; paths
 * toward the light live on, where albedo roulette would cut them. Never
 * below ROULETTE_MIN_SURVIVAL, so that a region whose estimate is wrongly
 * low cannot make fireflies. */
#define ROULETTE_DEPTH 2
#define ROULETTE_GAIN 2.8f
#define ROULETTE_MIN_SURVIVAL 0.05f

/* Splitting, the other half of efficiency-aware roulette: where a
 * bounce's worth |beta| sqrt(M2) / sigma(pixel) (as for the learned
 * roulette) times SPLIT_GAIN exceeds 1, the bounce is drawn that many times
 * (randomly rounded), each branch weighted by the inverse of the unrounded
 * factor: the expected weight stays 1. It pays where a bounce's light is
 * most of the pixel's noise and the path to it was costly, at the first
 * vertices. SPLIT_GAIN is well below ROULETTE_GAIN: at 0.9 (equal-time
 * relMSE against bsdf, 1.5 s at 160x120, 4-8 seeds) the Cornell box went
 * from 0.93 to 0.98 and from 0.98 to 1.06 at 6 s, Sponza from 2.9 to 3.5,
 * the bathroom from 2.1 to 2.3, the corridor from 5.2 to 4.9 and the
 * staircase from 1.38 to 1.32; at 1.4 and 2.8 every scene lost (more
 * branches than their light was worth). Not before pass SPLIT_FROM_PASS:
 * on the corridor, splitting on the first passes' estimates (the pixels'
 * noise from a few samples, regions' M2 from their fallbacks) cost a fifth
 * of the efficiency at 0.45 s (3.8x bsdf against 4.6x without splitting,
 * 4.4x splitting from pass 16), where the Cornell box at 1.5 s lost 2%
 * (1.05x from the first pass, 1.03x from pass 16, 0.98x without). A path
 * splits into at most SPLIT_BRANCHES_MAX branches, SPLIT_MAX at one
 * vertex, and waits at most at SPLIT_STACK vertices at once. */
#define SPLIT_GAIN 0.9f
#define SPLIT_FROM_PASS 16
#define SPLIT_MAX 4
#define SPLIT_BRANCHES_MAX 16
#define SPLIT_STACK 12

/* The albedo roulette's survival probability for the rr_beta a path
 * carries (pbrt's rule, at most 0.95). */
static inline float roulette_albedo_survival(Vec3 rr_beta) { return sg_minf(0.95f, v3_max_component(rr_beta)); }

/* Albedo roulette from the rr_beta a path carries (the product of its
 * albedos, what beta would be under BSDF sampling): false cuts the path;
 * a survivor's beta and rr_beta are divided by the survival probability.
 * `seg`: the vertex's record for a guide that learns what survivors carry. */
bool roulette_albedo(const PathGuide *g, Vec3 *beta, Vec3 *rr_beta, SgRng *rng, GuideSegment *seg);
/* The same with the survival probability q a guide gave (PathGuideOps.survival). */
bool roulette_survive(const PathGuide *g, float q, Vec3 *beta, Vec3 *rr_beta, SgRng *rng, GuideSegment *seg);

/* The learned roulette's verdict on a bounce worth `worth` (|beta| rms /
 * the pixel's deviation) at vertex `depth`: how many branches go on (0: the
 * path is cut, 1: it goes on, more: it splits), and the factor beta is
 * multiplied by. `branches` the path's branches so far; `may_split` whether
 * this vertex can wait for more (SPLIT_STACK, SPLIT_FROM_PASS); `min_survival` the
 * least survival the path's weight allows (integrator.c, WEIGHT_RATIO_MAX). */
typedef struct RouletteVerdict {
    int branches;
    float scale;
} RouletteVerdict;

RouletteVerdict roulette_learned(float worth, int depth, int branches, bool may_split, float min_survival,
                                 SgRng *rng);

/* Before each pass of a render with the learned roulette: the pixels'
 * noise remade from the `spp` passes so far, at every pass at first, then
 * at powers of two and every 16th (it settles, and passes wait for it). */
void roulette_prepare_pass(PixelNoise *noise, int spp, SgThreadPool *pool);

#endif
