/* The mixture learner's state, shared by its files: mixture_learning.c
 * (recording and learning), mixture_view_bytes.c (the view as a field
 * file's bytes). Not for the learner's users: mixture_learning.h is. */
#ifndef SG_RENDER_MIXTURE_LEARNER_STATE_H
#define SG_RENDER_MIXTURE_LEARNER_STATE_H

#include "mixture_learning.h"

#define SKELETON_CANDIDATES SG_MIXTURE_SKELETON_CANDIDATES
/* the learned candidates come in families: six around the learned
 * direction (family 0), six toward the learned point (family 1), three
 * drawing from the learned histogram (family 2) */
#define FAMILIES 3
#define AXIS_CANDIDATES 6
#define HISTOGRAM_FAMILY 2
#define HISTOGRAM_CANDIDATES 3
_Static_assert(SKELETON_CANDIDATES + HISTOGRAM_FAMILY * AXIS_CANDIDATES + HISTOGRAM_CANDIDATES ==
                   SG_MIXTURE_CANDIDATES,
               "candidate families");
/* The candidates' lobe exponents, each a power of 4 of the one before, so
 * that a record computes cos^e for all of them by squaring. */
#define EXPONENTS 3
static const float exponents[EXPONENTS] = {4.0f, 16.0f, 64.0f};

/* Samples a region needs before its own estimate is trusted, and after
 * which it stops learning. */
#define MIN_SAMPLES 256u
#define SETTLED_SAMPLES SG_MIXTURE_SETTLED_SAMPLES
/* A region fits its axis when its records reach AXIS_FIT_FIRST, then each
 * time they grow AXIS_FIT_GROWTH times (each refit forgets the moments
 * measured around the old axis), never once it settles; its learned
 * candidates compete once AXIS_MIN_SAMPLES records were drawn while the
 * axis was in use. */
#define AXIS_FIT_FIRST 256u
#define AXIS_FIT_GROWTH 4u
#define AXIS_MIN_SAMPLES 128u
/* A fine region fits a histogram of its own, rather than use its coarse
 * region's, from this many records on (at its axis's refits); every bin
 * keeps HISTOGRAM_FLOOR of the density spread evenly, so that a bin no
 * record has reached yet can still be drawn. */
#define HISTOGRAM_OWN_SAMPLES 1024u
#define HISTOGRAM_FLOOR 0.1f
/* Sky samples a region needs before it chooses its own portal share. */
#define SHARE_MIN_SAMPLES 256u
/* Vertices a region needs before its outgoing radiance is used. */
#define RADIANCE_MIN_SAMPLES 64u
/* A coarse region, or the whole scene, with this many guided bounces and
 * as many vertices stops taking records: it is only a fallback, and adding
 * every record to three levels cost more than the rest of learning (it
 * runs on one thread between passes). */
#define FALLBACK_SETTLED 65536u
#define STATE_INITIAL SG_MIXTURE_STATE_CANDIDATE
#define STATE_SETTLED SG_MIXTURE_STATE_SETTLED
#define REGION_SEEN 1u         /* has records (listed in seen) */
#define REGION_OWN_RADIANCE 2u /* enough of them for its own radiance estimate */
#define REGION_CHANGED 4u      /* listed in changed: its view entry is stale */

/* A record as kept: its terms computed by the thread that made it, so that
 * the sequential sum after the pass is only additions. */
typedef struct StoredRecord {
    uint32_t region;
    float estimate;                    /* v */
    float weight;                      /* w: the bounce's weight in the image */
    float radiance;                    /* outgoing radiance estimate, < 0 none */
    bool lobe;                         /* a guided bounce: estimate and terms set */
    bool axis_terms[FAMILIES];         /* the learned candidates' terms are set */
    int16_t bin;                       /* the direction's histogram bin, -1: none */
    uint32_t generation;               /* the view's when the record was made */
    float fit[3];                      /* v d: the axis fit's share (zero: none) */
    float point_fit[4];                /* v (x + t d) and v: the point fit's share */
    float term[SG_MIXTURE_CANDIDATES]; /* v^2 p / p_k */
    bool sky;                          /* it took a sky sample: sky_term set */
    float sky_term[SG_PORTAL_SHARES];  /* F^2 / (q_k q0) */
} StoredRecord;

/* One cache line each: threads rendering neighbouring tiles append to
 * neighbouring buffers. */
typedef struct RecordBuffer {
    _Alignas(64) StoredRecord *data;
    size_t count, capacity;
} RecordBuffer;

typedef struct RegionStats {
    double moment[SKELETON_CANDIDATES];   /* sums of w v^2 p / p_k */
    double weight, weighted;              /* sums of w and of w v */
    uint64_t samples;
    double radiance_sum2;                 /* sum of squared outgoing radiance estimates */
    uint64_t radiance_samples;
    uint64_t radiance_published;          /* samples when last passed to its fine regions */
    /* what the region adds to its level's totals under its current choice */
    double variance, cost;
    /* the learned axis: sum of v d over its records, the samples at the
     * last fit, and the learned candidates' sums over the records drawn
     * while the current axis was in use (generation axis_from or later) */
    double fit[3], point_fit[4];
    uint64_t fitted_at;
    uint32_t axis_from[FAMILIES];
    uint64_t axis_samples[FAMILIES];
    double axis_weight[FAMILIES], axis_weighted[FAMILIES];
    double axis_moment[FAMILIES][AXIS_CANDIDATES];
    /* its sky samples: count, those that brought light, and each portal
     * share's second-moment sum */
    uint64_t sky_samples, sky_lit;
    double sky_moment[SG_PORTAL_SHARES];
} RegionStats;

/* One level of regions (fine or coarse): sums over its regions of the
 * image variance and the cost of their current choices. */
typedef struct Totals {
    double variance, cost;
} Totals;

/* Cost of a guided bounce relative to a BSDF one (cache query, densities
 * of the lobe), measured on the corridor and the Cornell box; a bounce
 * around the learned axis asks no cache. */
#define GUIDED_COST 1.25
#define LEARNED_AXIS_COST 1.15
/* A coarse region is this many fine cells on a side: it answers for the
 * fine regions that have too few samples of their own. */
#define COARSE 4

struct SgMixtureLearner {
    int cells[3];          /* fine grid */
    int coarse_cells[3];
    uint32_t region_count, coarse_count;
    int initial;
    /* per fine region, all the renderer reads at a bounce (one byte, so
     * that the table stays in cache): the candidate in use (STATE_INITIAL:
     * none yet) and STATE_SETTLED once the region stops learning */
    uint8_t *state;
    int8_t *choice;        /* per fine region: candidate index, -1 too few samples */
    int8_t *coarse_choice; /* per coarse region */
    RegionStats *stats;    /* per fine region */
    RegionStats *coarse;   /* per coarse region */
    Totals fine_totals, coarse_totals, global_totals;
    RegionStats global;    /* the whole scene: answers where a coarse region cannot yet */
    int8_t global_choice;
    uint32_t *touched;     /* fine regions, then coarse ones, with new records */
    uint8_t *is_touched, *coarse_touched;
    uint32_t *coarse_of;   /* fine region -> coarse region */
    uint32_t tiles;
    /* two sets of per-tile buffers: the pass being rendered fills one
     * while sg_mixture_learn reads the other (the pass before) */
    RecordBuffer *buffers;
    uint32_t filling;      /* the set records go to: buffers + filling * tiles */
    int exponent_of[SG_MIXTURE_CANDIDATES]; /* index in exponents[] of each candidate's lobe */
    /* learned axes (3 floats a region, zero: none): the fine regions' in
     * use (their own, else their coarse region's), whether a fine region
     * has its own, the coarse regions', and the copy the renderer reads */
    float *axis, *coarse_axis, *view_axis;
    float *point, *coarse_point, *view_point; /* 4 floats a region: x, y, z, 1 where there is one */
    uint8_t *own_axis;
    uint32_t generation;   /* publications so far */
    /* learned histograms, one entry per fine region then per coarse one
     * (SG_MIXTURE_BINS floats each, untouched pages cost nothing): the sums
     * of v per bin, the distribution fitted from them, and the view's copy;
     * entries fitted since the last publication are listed in
     * histogram_changed; per fine region the entry it uses (histogram_of,
     * and the view's) and whether it is its own */
    float *histogram_sum, *histogram, *view_histogram;
    uint32_t *histogram_of, *view_histogram_of;
    uint8_t *own_histogram, *histogram_dirty;
    uint32_t *histogram_changed;
    uint32_t histogram_changed_count;
    float *radiance;       /* per fine region, as learned */
    float global_radiance;
    /* what the renderer reads (the view) is a copy, brought up to date by
     * sg_mixture_end_pass, so that learning can run while a pass renders */
    uint8_t *view_state;
    float *view_radiance;
    uint32_t *changed;     /* fine regions whose state or radiance changed since (REGION_CHANGED) */
    uint32_t changed_count;
    /* per fine region, REGION_* bits: what the update would otherwise read
     * from the region's statistics (a cache miss each; most of them are
     * cold) */
    uint8_t *flags;
    uint32_t *seen;        /* fine regions with records, in the order they came */
    uint32_t seen_count;
    /* portal shares: each level's own choice (-1: too few sky samples), the
     * one each fine region uses, and the view's copy */
    int8_t *share_choice, *coarse_share_choice;
    int8_t global_share_choice;
    uint8_t *portal_share, *view_portal_share;
    SgMixtureView view;
};

#endif
