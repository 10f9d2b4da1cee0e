/* The guided mode's mixture, learned per region of the scene.
 *
 * The one-sample mixture draws a bounce from the BSDF with probability
 * alpha and from a cosine-power lobe toward the skeleton's importance point
 * otherwise. Which mixture is best depends on the place: where light
 * arrives along the skeleton's direction the lobe wins (narrow far from the
 * light, wide near it), where the guide points at a wall the BSDF does:
 * the paper's future work ("blend the two sampling approaches", strength
 * chosen by region), learned while rendering.
 *
 * Regions are cells of a uniform grid over the scene's bounds, split by the
 * dominant axis of the shading normal (6 bins), so that the two sides of a
 * thin wall learn apart. Coarse regions (4x4x4 cells) answer for fine ones
 * with too few samples, the whole scene for coarse ones.
 *
 * For each candidate (alpha, exponent) the learner estimates from the
 * bounces traced so far the variance it would give: a bounce drawn from the
 * current density p, with one-sample estimate v (its contribution over p),
 * adds
 *     w v^2 p / (alpha_k p_bsdf + (1 - alpha_k) p_lobe_k)
 * to candidate k's sum, an unbiased estimate of that candidate's second
 * moment whichever density drew the sample; minus w times the squared mean
 * of v (the same for all) it is the region's share of the image's
 * variance, w being the bounce's weight in its pixel (its squared
 * throughput). A region takes the candidate that makes the whole image's
 * variance times render time least, the other regions' choices given,
 * counting a guided bounce as GUIDED_COST BSDF ones: so a region whose
 * bounces weigh little in the image cannot pay for the cache query however
 * much it would lower its own variance.
 *
 * The skeleton's lobe can point the wrong way: the light may reach a
 * region from a lit wall rather than along the skeleton. So each region
 * also learns an axis of its own, the mean direction of what its bounces
 * brought back (sum of v d: an unbiased estimate of the first moment of
 * f cos L whatever density drew d), fitted on the coarse regions and on
 * the fine ones with enough records, and candidates that draw the lobe
 * around that axis compete with the skeleton's on the same second-moment
 * estimates: the guide starts from the skeleton and learns where its lobe
 * is wrong. Where the bounces' rays end on a surface the region also learns
 * a point, the mean of their ends weighted by v (where its light comes
 * from, as the skeleton's importance point says where the light lies), and
 * a lobe toward it from each vertex (parallax: the direction changes across
 * the region) competes too. Light from several lit patches has several
 * peaks that one lobe cannot follow: the region also keeps a histogram of
 * where its light came from (SG_MIXTURE_BINS below), and candidates that
 * draw from it compete as well. A learned axis, point or histogram is
 * fixed during a pass (each pass stays unbiased); its candidates' moments
 * are taken only from records made while it was in use.
 *
 * Every vertex of a learning path also reports what its bounce brought
 * back (all that came after the bounce, per unit throughput of the
 * bounce); each region's root mean square of that drives the guided
 * mode's learned Russian roulette (render/roulette.h).
 *
 * Unbiased: a pass uses only the choices made after the previous passes,
 * which are fixed before it starts, so each pass is an unbiased estimate.
 * Deterministic for any thread count: records are kept per image tile and
 * summed in tile order after the pass. */
#ifndef SG_MIXTURE_LEARNING_H
#define SG_MIXTURE_LEARNING_H

#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "error.h"
#include "vecmath.h"

#ifdef __cplusplus
extern "C" {
#endif

#define SG_NO_REGION UINT32_MAX
#define SG_MIXTURE_SKELETON_CANDIDATES 7
#define SG_MIXTURE_CANDIDATES 22

/* A choice of mixture: BSDF probability, lobe exponent, and whether the
 * lobe's axis is the region's learned one (learned_axis: its learned
 * direction, or with learned_point the direction to its learned point)
 * rather than the skeleton's, or (learned_histogram, with learned_axis)
 * the guide is the region's learned histogram of directions instead of a
 * lobe. */
typedef struct SgMixtureCandidate {
    float alpha, exponent;
    bool learned_axis, learned_point, learned_histogram;
} SgMixtureCandidate;

/* A region's learned histogram of directions: where its bounces' light
 * came from (the sum of v over the records whose direction fell in each
 * bin, an unbiased estimate of the integral of f cos L over the bin,
 * whatever density drew them), as a density piecewise constant over the
 * bins of the octahedral square map of the sphere. Light that reaches a
 * region from several lit patches has several peaks, which one lobe cannot
 * follow. */
#define SG_MIXTURE_HIST_RES 16
#define SG_MIXTURE_BINS (SG_MIXTURE_HIST_RES * SG_MIXTURE_HIST_RES)

/* Candidate 0 is the BSDF alone; 1..6 pair alpha 0.8 or 0.6 with a wide,
 * middle or narrow lobe toward the skeleton's importance point (exponents
 * 4, 16, 64: the paper's adaptive strength, "small near direct lighting,
 * strong far away"); 7..12 pair alpha 0.7 or 0.4 with the same lobes
 * around the region's learned direction, 13..18 toward its learned point;
 * 19..21 pair alpha 0.7, 0.45 or 0.2 with the region's learned histogram. */
extern const SgMixtureCandidate sg_mixture_candidates[SG_MIXTURE_CANDIDATES];
/* Records after which a region stops learning (settles): its choice stays,
 * and where it is the BSDF alone its bounces no longer ask the cache. High:
 * a region's axis, point and histogram keep being refitted as its records
 * grow fourfold (on Sponza, learning until 4096 records and then no more
 * left guided's relMSE 2x above what 128 training passes reach when every
 * region keeps learning). */
#define SG_MIXTURE_SETTLED_SAMPLES 262144u
/* Where a region (and its coarse region) has too few samples yet: a mild
 * mixture, so that the first passes already try the lobe and learn its
 * worth from its own samples (better on the corridor and the window test
 * than starting from the BSDF alone; the Cornell box pays ~2% for it). */
#define SG_MIXTURE_INITIAL 2

/* A sky seen through portals (windows) is sampled by next-event
 * estimation through them with some probability, the share, and from its
 * own distribution otherwise (render/lights.h). Which share is best depends
 * on the place: deep in a room lit through its window every light sample
 * that misses the window is wasted, out in the open the portals are, and
 * beside a window whose view holds the sun the sky's own sampling finds
 * the sun where a point uniform on the window does not. Each region learns
 * its share from its vertices' sky samples: one drawn with density q0 and
 * bringing F (before its density) adds F^2 / (q_k q0) to candidate k's sum,
 * an unbiased estimate of the second moment that share's estimator would
 * have, q_k = share_k p_portals + (1 - share_k) p_sky; the least wins.
 * Candidate SG_PORTAL_SHARE_DEFAULT is PORTAL_SHARE, used where nothing is
 * known yet. */
#define SG_PORTAL_SHARES 5
#define SG_PORTAL_SHARE_DEFAULT 2
extern const float sg_portal_shares[SG_PORTAL_SHARES];

/* One diffuse or glossy vertex of a learning path as the learner sees it:
 * what left it, and, where the bounce was guided, how it was drawn. */
typedef struct SgMixtureRecord {
    uint32_t region;
    /* what the vertex's bounce brought back (luminance, per unit
     * throughput of the bounce): all that came after the bounce; < 0
     * unknown. Its regional second moment drives the learned roulette. */
    float radiance;
    bool lobe;       /* the bounce was drawn by the mixture: the fields below are set */
    bool no_skeleton; /* the skeleton gave no axis here: its candidates draw from the BSDF */
    float pdf_bsdf;  /* BSDF sampler's density of the direction taken */
    float cos_axis;  /* its cosine with the skeleton lobe's axis, and with the axis */
    float cos_mirror; /* mirrored across the surface (the folded lobe's two halves) */
    Vec3 direction;  /* the direction taken (zero: unknown, the learned axis skips the record) */
    Vec3 normal;     /* the shading normal it was taken about */
    Vec3 position;   /* the vertex */
    float distance;  /* how far the bounce's ray went (INFINITY or 0: unknown) */
    float pdf;       /* density of the mixture that drew it */
    float estimate;  /* v: the bounce's one-sample estimate (luminance) */
    float weight;    /* w: its weight in the pixel, the squared throughput before it */
    /* its light sample of a sky with portals, if it took one (contribution:
     * F, the throughput in it; the share it was drawn with) */
    bool sky;
    float sky_contribution, sky_pdf_portals, sky_pdf_sky, sky_share;
} SgMixtureRecord;

typedef struct SgMixtureLearner SgMixtureLearner;

/* A grid of `cells_longest` cells along the longest side of [lo, hi]
 * (local coordinates), `tiles` record buffers (one per image tile).
 * Candidate `initial` is used where a region has too few samples. */
SgMixtureLearner *sg_mixture_learner_create(Vec3 lo, Vec3 hi, int cells_longest, uint32_t tiles,
                                            int initial, SgError *err);
void sg_mixture_learner_free(SgMixtureLearner *l);

/* The region of point p with shading normal n (outside the grid: the nearest cell's). */
uint32_t sg_mixture_region(const SgMixtureLearner *l, Vec3 p, Vec3 n);
/* The mixture to use in a region (SG_NO_REGION: the initial one). */
SgMixtureCandidate sg_mixture_choice(const SgMixtureLearner *l, uint32_t region);
/* What a bounce reads from the learner, inline (it runs at every bounce):
 * the region of p with normal n, its alpha and whether it still learns. */
typedef struct SgMixtureView {
    Vec3 lo;
    float inv_size;
    float cell_max[3];             /* cells - 1/2: truncates to the last cell */
    /* region of cell (x, y, z) in normal bin b: base[b] + x stride[b][0] +
     * y stride[b][1] + z stride[b][2]. Each pair of opposite bins has its
     * own table whose fastest axes lie in the walls it holds (y then z for
     * the x bins, x then z for y, x then y for z), the two bins side by
     * side: the regions of a wall's row share cache lines, as the renderer
     * reads one at every bounce. */
    uint32_t base[6];
    uint32_t stride[6][3];
    const uint8_t *state;          /* per region: SG_MIXTURE_STATE_* bits */
    SgMixtureCandidate of_state[32];
    /* per region: its learned axis (3 floats, local coordinates; zero: none
     * yet) and point (4 floats: x, y, z, and 1 where it has one), read
     * where its state has SG_MIXTURE_STATE_AXIS */
    const float *axis;
    const float *point;
    /* per region: the histogram it uses (its own or its coarse region's),
     * as an index into `histogram` (SG_MIXTURE_BINS floats each: the
     * cumulative distribution over the bins, the last 1), or
     * SG_NO_REGION: none */
    const uint32_t *histogram_of;
    const float *histogram;
    uint32_t generation;           /* publications so far: the records' stamp */
    /* per region: root mean square of what a bounce brings back per unit
     * throughput (its coarse region's where it has too few samples), < 0:
     * see global_radiance (sg_mixture_radiance) */
    const float *radiance;
    float global_radiance; /* the whole scene's, < 0 unknown */
    /* per region: its portal share, as an index into sg_portal_shares */
    const uint8_t *portal_share;
} SgMixtureView;

const SgMixtureView *sg_mixture_view(const SgMixtureLearner *l);

/* A region's state byte: the candidate in use (31: the initial one), whether
 * the region has settled (stopped learning), whether its candidate uses
 * the skeleton's lobe (bounces there ask the guide) or a learned axis. */
#define SG_MIXTURE_STATE_CANDIDATE 31u
#define SG_MIXTURE_STATE_SETTLED 32u
#define SG_MIXTURE_STATE_LOBE 64u
#define SG_MIXTURE_STATE_AXIS 128u

/* The bin of a unit normal: its dominant axis and sign (0..5; the opposite
 * normal's bin is bin ^ 1). A renderer keeps it per triangle. */
static inline uint32_t sg_mixture_normal_bin(Vec3 n)
{
    float ax = n.x < 0.0f ? -n.x : n.x, ay = n.y < 0.0f ? -n.y : n.y, az = n.z < 0.0f ? -n.z : n.z;
    return ax >= ay && ax >= az ? (n.x < 0.0f) : ay >= az ? 2u + (n.y < 0.0f) : 4u + (n.z < 0.0f);
}
/* The region of cell (x, y, z) (inside the grid) in normal bin `bin`. */
static inline uint32_t sg_mixture_region_of_cell(const SgMixtureView *v, uint32_t x, uint32_t y, uint32_t z,
                                                 uint32_t bin)
{
    const uint32_t *s = v->stride[bin];
    return v->base[bin] + x * s[0] + y * s[1] + z * s[2];
}
/* The region of p whose normal falls in `bin` (a point outside the grid
 * counts in the nearest cell); v->state[region] tells the rest. */
static inline uint32_t sg_mixture_region_at(const SgMixtureView *v, Vec3 p, uint32_t bin)
{
    /* clamped into the grid (branch-free, NaN to 0): it covers the scene's
     * triangles, so only rounding puts a hit point outside */
    float x = sg_minf(sg_maxf((p.x - v->lo.x) * v->inv_size, 0.0f), v->cell_max[0]),
          y = sg_minf(sg_maxf((p.y - v->lo.y) * v->inv_size, 0.0f), v->cell_max[1]),
          z = sg_minf(sg_maxf((p.z - v->lo.z) * v->inv_size, 0.0f), v->cell_max[2]);
    return sg_mixture_region_of_cell(v, (uint32_t)x, (uint32_t)y, (uint32_t)z, bin);
}
/* The same, with the region's mixture and whether it still learns. */
static inline uint32_t sg_mixture_lookup(const SgMixtureView *v, Vec3 p, uint32_t bin, SgMixtureCandidate *choice,
                                         bool *learning)
{
    uint32_t region = sg_mixture_region_at(v, p, bin);
    uint8_t st = v->state[region];
    *choice = v->of_state[st & SG_MIXTURE_STATE_CANDIDATE];
    *learning = !(st & SG_MIXTURE_STATE_SETTLED);
    return region;
}
/* What a bounce from a region brings back (SG_NO_REGION: the scene), as
 * the learned roulette reads it: the root mean square per unit throughput,
 * the coarse region's or the scene's where the region has too few samples;
 * < 0 unknown. */
static inline float sg_mixture_radiance(const SgMixtureView *v, uint32_t region)
{
    float m = region != SG_NO_REGION ? v->radiance[region] : -1.0f;
    return m >= 0.0f ? m : v->global_radiance;
}
/* The share of a sky's light samples a region draws through its portals. */
static inline float sg_mixture_portal_share(const SgMixtureView *v, uint32_t region)
{
    return sg_portal_shares[region != SG_NO_REGION ? v->portal_share[region] : SG_PORTAL_SHARE_DEFAULT];
}
/* Does the region still learn? One with enough samples is settled: its
 * choice stays, and paths no longer pay for the cache query there when it
 * is the BSDF alone. */
bool sg_mixture_learning(const SgMixtureLearner *l, uint32_t region);
/* Adds a record to a tile's buffer; only the thread rendering that tile
 * calls it. A record that does not fit in memory is dropped (learning is
 * only an aid; the estimate stays unbiased). */
void sg_mixture_record(SgMixtureLearner *l, uint32_t tile, const SgMixtureRecord *rec);
/* After a pass: sums every tile's records in tile order, re-chooses the
 * alpha of each region that got samples, empties the buffers, and the view
 * shows the new choices. */
void sg_mixture_update(SgMixtureLearner *l);
/* The same in two halves, so that learning from one pass overlaps the
 * next (the view then lags one pass; still unbiased, since it is fixed
 * during each pass, and deterministic):
 *   sg_mixture_end_pass, between passes: the view shows what
 *     sg_mixture_learn has learned so far; the pass's records are put
 *     aside to be learned (learned at once if the last ones were not);
 *   sg_mixture_learn, on one thread while the next pass renders (it
 *     reads only the records put aside and writes only the learner's
 *     own tables, not the view nor the buffers being filled). */
void sg_mixture_end_pass(SgMixtureLearner *l);
void sg_mixture_learn(SgMixtureLearner *l);

/* The view as bytes (a field file's part), and back: all that a learner
 * that learns no more gives the renderer. Restore fails on bytes of
 * another size of grid. */
size_t sg_mixture_view_size(const SgMixtureLearner *l);
void sg_mixture_view_save(const SgMixtureLearner *l, void *out);
bool sg_mixture_view_restore(SgMixtureLearner *l, const void *in, size_t size);

/* A region's sample count, for tests and reports. */
uint64_t sg_mixture_region_samples(const SgMixtureLearner *l, uint32_t region);
/* Of the sky samples seen so far that brought light, the share of those
 * whose region now uses each portal share (fractions[SG_PORTAL_SHARES]);
 * false: none seen. (Where none brought light the share changes nothing,
 * and the region keeps the default.) */
bool sg_mixture_portal_share_use(const SgMixtureLearner *l, double fractions[SG_PORTAL_SHARES]);
/* Share of the bounces seen so far that fall in regions whose choice now
 * uses the lobe (alpha < 1), and of those whose lobe is the learned axis. */
double sg_mixture_guided_fraction(const SgMixtureLearner *l);
double sg_mixture_learned_axis_fraction(const SgMixtureLearner *l);
/* A fine region's learned axis and point as the view shows them (false: none yet). */
bool sg_mixture_region_axis(const SgMixtureLearner *l, uint32_t region, Vec3 *axis);
bool sg_mixture_region_point(const SgMixtureLearner *l, uint32_t region, Vec3 *point);
/* The axis of a learned-point lobe at p: toward the point, or the learned
 * direction where the point is too near p to tell one (or absent). */
static inline Vec3 sg_mixture_point_axis(const float point[4], const float axis[3], Vec3 p)
{
    if (point[3] > 0.0f) {
        Vec3 d = v3(point[0] - p.x, point[1] - p.y, point[2] - p.z);
        float len2 = v3_dot(d, d);
        if (len2 > 1e-12f)
            return v3_scale(d, 1.0f / sqrtf(len2));
    }
    return v3(axis[0], axis[1], axis[2]);
}

/* The bin of a unit direction in the octahedral square map. */
uint32_t sg_mixture_histogram_bin(Vec3 w);
/* A histogram's density at w (solid angle), and a direction drawn from it
 * with u1, u2 in [0, 1): a bin by its probability, then a point uniform in
 * the bin's square. */
float sg_mixture_histogram_pdf(const float *cdf, Vec3 w);
Vec3 sg_mixture_histogram_sample(const float *cdf, float u1, float u2);

#ifdef __cplusplus
}
#endif
#endif
