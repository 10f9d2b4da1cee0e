#include "mixture_learning.h"

#include "../lights.h" /* PORTAL_SHARE */
#include "../sampling.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* BSDF alone first: with equal estimates the cheaper, safer choice wins. */
const SgMixtureCandidate sg_mixture_candidates[SG_MIXTURE_CANDIDATES] = {
    {1.0f, 16.0f, false, false, false}, {0.8f, 4.0f, false, false, false}, {0.8f, 16.0f, false, false, false},
    {0.8f, 64.0f, false, false, false}, {0.6f, 4.0f, false, false, false}, {0.6f, 16.0f, false, false, false},
    {0.6f, 64.0f, false, false, false}, {0.7f, 4.0f, true, false, false},  {0.7f, 16.0f, true, false, false},
    {0.7f, 64.0f, true, false, false},  {0.4f, 4.0f, true, false, false},  {0.4f, 16.0f, true, false, false},
    {0.4f, 64.0f, true, false, false},  {0.7f, 4.0f, true, true, false},   {0.7f, 16.0f, true, true, false},
    {0.7f, 64.0f, true, true, false},   {0.4f, 4.0f, true, true, false},   {0.4f, 16.0f, true, true, false},
    {0.4f, 64.0f, true, true, false},   {0.7f, 16.0f, true, false, true}, {0.45f, 16.0f, true, false, true},
    {0.2f, 16.0f, true, false, true}};
/* The portal shares: none (out in the open), even, PORTAL_SHARE (the
 * default, render/lights.h), and nearly all (deep in a room lit through
 * its windows; not all, so that sky a window found too small still gets
 * light samples). */
const float sg_portal_shares[SG_PORTAL_SHARES] = {0.0f, 0.5f, PORTAL_SHARE, 0.95f, 0.99f};
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

SgMixtureLearner *sg_mixture_learner_create(Vec3 lo, Vec3 hi, int cells_longest, uint32_t tiles,
                                            int initial, SgError *err)
{
    float ext[3] = {hi.x - lo.x, hi.y - lo.y, hi.z - lo.z};
    float longest = fmaxf(ext[0], fmaxf(ext[1], ext[2]));
    if (!(longest > 0.0f) || !isfinite(longest) || cells_longest < 1 || cells_longest > 1024 || initial < 0 ||
        initial >= SG_MIXTURE_CANDIDATES)
        return sg_fail(err, "mixture learner: bad bounds or cell count"), NULL;
    SgMixtureLearner *l = calloc(1, sizeof *l);
    if (!l)
        return sg_fail(err, "mixture learner: out of memory"), NULL;
    float size = longest / (float)cells_longest;
    size_t cells = 1, coarse = 1;
    for (int i = 0; i < 3; i++) {
        l->cells[i] = (int)ceilf(ext[i] / size) + 1;
        l->coarse_cells[i] = (l->cells[i] + COARSE - 1) / COARSE;
        cells *= (size_t)l->cells[i];
        coarse *= (size_t)l->coarse_cells[i];
    }
    l->region_count = (uint32_t)(cells * 6);
    l->coarse_count = (uint32_t)(coarse * 6);
    l->initial = initial;
    for (int k = 0; k < SG_MIXTURE_CANDIDATES; k++)
        for (int e = 0; e < EXPONENTS; e++)
            if (sg_mixture_candidates[k].exponent == exponents[e])
                l->exponent_of[k] = e;
    l->tiles = tiles;
    l->choice = malloc(l->region_count);
    l->state = malloc(l->region_count);
    l->coarse_choice = malloc(l->coarse_count);
    l->touched = malloc(sizeof *l->touched * ((size_t)l->region_count + l->coarse_count));
    l->is_touched = calloc(l->region_count, 1);
    l->coarse_touched = calloc(l->coarse_count, 1);
    l->stats = calloc(l->region_count, sizeof *l->stats);
    l->coarse = calloc(l->coarse_count, sizeof *l->coarse);
    l->coarse_of = malloc(sizeof *l->coarse_of * l->region_count);
    size_t buffers = 2 * (size_t)(tiles ? tiles : 1);
    l->buffers = aligned_alloc(_Alignof(RecordBuffer), buffers * sizeof *l->buffers);
    if (l->buffers)
        memset(l->buffers, 0, buffers * sizeof *l->buffers);
    l->radiance = malloc(sizeof *l->radiance * l->region_count);
    l->view_state = malloc(l->region_count);
    l->view_radiance = malloc(sizeof *l->view_radiance * l->region_count);
    l->changed = malloc(sizeof *l->changed * l->region_count);
    l->flags = calloc(l->region_count, 1);
    l->seen = malloc(sizeof *l->seen * l->region_count);
    l->axis = calloc((size_t)l->region_count * 3, sizeof *l->axis);
    l->view_axis = calloc((size_t)l->region_count * 3, sizeof *l->view_axis);
    l->coarse_axis = calloc((size_t)l->coarse_count * 3, sizeof *l->coarse_axis);
    l->own_axis = calloc(l->region_count, 1);
    l->point = calloc((size_t)l->region_count * 4, sizeof *l->point);
    l->view_point = calloc((size_t)l->region_count * 4, sizeof *l->view_point);
    l->coarse_point = calloc((size_t)l->coarse_count * 4, sizeof *l->coarse_point);
    size_t entries = (size_t)l->region_count + l->coarse_count;
    l->histogram_sum = calloc(entries * SG_MIXTURE_BINS, sizeof *l->histogram_sum);
    l->histogram = calloc(entries * SG_MIXTURE_BINS, sizeof *l->histogram);
    l->view_histogram = calloc(entries * SG_MIXTURE_BINS, sizeof *l->view_histogram);
    l->histogram_of = malloc(sizeof *l->histogram_of * l->region_count);
    l->view_histogram_of = malloc(sizeof *l->view_histogram_of * l->region_count);
    l->own_histogram = calloc(l->region_count, 1);
    l->histogram_dirty = calloc(entries, 1);
    l->histogram_changed = malloc(sizeof *l->histogram_changed * entries);
    l->share_choice = malloc(l->region_count);
    l->coarse_share_choice = malloc(l->coarse_count);
    l->portal_share = malloc(l->region_count);
    l->view_portal_share = malloc(l->region_count);
    if (!l->share_choice || !l->coarse_share_choice || !l->portal_share || !l->view_portal_share ||
        !l->histogram_sum || !l->histogram || !l->view_histogram || !l->histogram_of || !l->view_histogram_of ||
        !l->own_histogram || !l->histogram_dirty || !l->histogram_changed || !l->point || !l->view_point || !l->coarse_point || !l->axis || !l->view_axis || !l->coarse_axis ||
        !l->own_axis || !l->radiance || !l->choice || !l->state || !l->coarse_choice || !l->touched || !l->is_touched ||
        !l->coarse_touched || !l->stats || !l->coarse || !l->coarse_of || !l->buffers || !l->view_state ||
        !l->view_radiance || !l->changed || !l->flags || !l->seen) {
        sg_mixture_learner_free(l);
        return sg_fail(err, "mixture learner: out of memory for %u regions", (unsigned)(cells * 6)), NULL;
    }
    for (uint32_t b = 0; b < 6; b++) {
        uint32_t nx = (uint32_t)l->cells[0], ny = (uint32_t)l->cells[1], nz = (uint32_t)l->cells[2];
        uint32_t *st = l->view.stride[b];
        l->view.base[b] = (b >> 1) * 2u * (uint32_t)cells + (b & 1u);
        switch (b >> 1) {
        case 0: st[1] = 2, st[2] = 2 * ny, st[0] = 2 * ny * nz; break; /* y, z, x */
        case 1: st[0] = 2, st[2] = 2 * nx, st[1] = 2 * nx * nz; break; /* x, z, y */
        default: st[0] = 2, st[1] = 2 * nx, st[2] = 2 * nx * ny; break; /* x, y, z */
        }
    }
    for (int z = 0; z < l->cells[2]; z++)
        for (int y = 0; y < l->cells[1]; y++)
            for (int x = 0; x < l->cells[0]; x++) {
                size_t c = ((size_t)(z / COARSE) * l->coarse_cells[1] + y / COARSE) * l->coarse_cells[0] +
                           x / COARSE;
                for (int bin = 0; bin < 6; bin++)
                    l->coarse_of[sg_mixture_region_of_cell(&l->view, (uint32_t)x, (uint32_t)y, (uint32_t)z,
                                                           (uint32_t)bin)] = (uint32_t)(c * 6 + bin);
            }
    memset(l->choice, -1, l->region_count);
    memset(l->state, STATE_INITIAL | (sg_mixture_candidates[initial].alpha < 1.0f ? SG_MIXTURE_STATE_LOBE : 0),
           l->region_count);
    for (uint32_t i = 0; i < l->region_count; i++)
        l->radiance[i] = -1.0f;
    memcpy(l->view_state, l->state, l->region_count);
    memcpy(l->view_radiance, l->radiance, sizeof *l->radiance * l->region_count);
    l->view.radiance = l->view_radiance;
    l->global_radiance = l->view.global_radiance = -1.0f;
    l->view.lo = lo;
    l->view.inv_size = 1.0f / size;
    for (int i = 0; i < 3; i++)
        l->view.cell_max[i] = (float)l->cells[i] - 0.5f;
    l->view.state = l->view_state;
    for (int k = 0; k < 32; k++)
        l->view.of_state[k] = sg_mixture_candidates[k < SG_MIXTURE_CANDIDATES ? k : initial];
    l->view.axis = l->view_axis;
    l->view.point = l->view_point;
    for (uint32_t i = 0; i < l->region_count; i++)
        l->histogram_of[i] = l->view_histogram_of[i] = SG_NO_REGION;
    l->view.histogram_of = l->view_histogram_of;
    l->view.histogram = l->view_histogram;
    memset(l->coarse_choice, -1, l->coarse_count);
    l->global_choice = -1;
    memset(l->share_choice, -1, l->region_count);
    memset(l->coarse_share_choice, -1, l->coarse_count);
    l->global_share_choice = -1;
    memset(l->portal_share, SG_PORTAL_SHARE_DEFAULT, l->region_count);
    memset(l->view_portal_share, SG_PORTAL_SHARE_DEFAULT, l->region_count);
    l->view.portal_share = l->view_portal_share;
    return l;
}

void sg_mixture_learner_free(SgMixtureLearner *l)
{
    if (!l)
        return;
    if (l->buffers)
        for (uint32_t t = 0; t < 2 * l->tiles; t++)
            free(l->buffers[t].data);
    free(l->buffers);
    free(l->choice);
    free(l->state);
    free(l->coarse_choice);
    free(l->touched);
    free(l->is_touched);
    free(l->coarse_touched);
    free(l->stats);
    free(l->coarse);
    free(l->coarse_of);
    free(l->radiance);
    free(l->view_state);
    free(l->view_radiance);
    free(l->changed);
    free(l->flags);
    free(l->seen);
    free(l->axis);
    free(l->view_axis);
    free(l->coarse_axis);
    free(l->own_axis);
    free(l->point);
    free(l->view_point);
    free(l->coarse_point);
    free(l->histogram_sum);
    free(l->histogram);
    free(l->view_histogram);
    free(l->histogram_of);
    free(l->view_histogram_of);
    free(l->own_histogram);
    free(l->histogram_dirty);
    free(l->histogram_changed);
    free(l->share_choice);
    free(l->coarse_share_choice);
    free(l->portal_share);
    free(l->view_portal_share);
    free(l);
}

uint32_t sg_mixture_region(const SgMixtureLearner *l, Vec3 p, Vec3 n)
{
    SgMixtureCandidate choice;
    bool learning;
    return sg_mixture_lookup(&l->view, p, sg_mixture_normal_bin(n), &choice, &learning);
}

SgMixtureCandidate sg_mixture_choice(const SgMixtureLearner *l, uint32_t region)
{
    return l->view.of_state[region < l->region_count ? l->state[region] & SG_MIXTURE_STATE_CANDIDATE : STATE_INITIAL];
}

bool sg_mixture_learning(const SgMixtureLearner *l, uint32_t region)
{
    return region < l->region_count && !(l->state[region] & STATE_SETTLED);
}

const SgMixtureView *sg_mixture_view(const SgMixtureLearner *l) { return &l->view; }

/* The region's view entry is stale until the next sg_mixture_end_pass. */
static void mark_changed(SgMixtureLearner *l, uint32_t region)
{
    if (!(l->flags[region] & REGION_CHANGED)) {
        l->flags[region] |= REGION_CHANGED;
        l->changed[l->changed_count++] = region;
    }
}

static void refresh_state(SgMixtureLearner *l, uint32_t region)
{
    int k = l->choice[region];
    if (k < 0)
        k = l->coarse_choice[l->coarse_of[region]];
    if (k < 0)
        k = l->global_choice;
    int candidate = k < 0 ? (int)STATE_INITIAL : k;
    /* a region without a choice of its own has too few samples to settle:
     * its statistics are not read */
    bool settled = l->choice[region] >= 0 && l->stats[region].samples >= SETTLED_SAMPLES;
    SgMixtureCandidate c = l->view.of_state[candidate];
    unsigned lobe = c.alpha >= 1.0f ? 0u : c.learned_axis ? SG_MIXTURE_STATE_AXIS : SG_MIXTURE_STATE_LOBE;
    uint8_t st = (uint8_t)(candidate | (settled ? STATE_SETTLED : 0) | lobe);
    if (st != l->state[region]) {
        l->state[region] = st;
        mark_changed(l, region);
    }
    if (!l->global.sky_samples)
        return; /* no sky with portals: every region keeps the default */
    int s = l->share_choice[region];
    if (s < 0)
        s = l->coarse_share_choice[l->coarse_of[region]];
    if (s < 0)
        s = l->global_share_choice;
    uint8_t share = (uint8_t)(s < 0 ? SG_PORTAL_SHARE_DEFAULT : s);
    if (share != l->portal_share[region]) {
        l->portal_share[region] = share;
        mark_changed(l, region);
    }
}

/* The folded lobe's density at each exponent, given a direction's
 * cosines with the axis and its mirror image: cos^4, ^16, ^64 by squaring. */
static void folded_lobe_densities(float cos_axis, float cos_mirror, float lobe[EXPONENTS])
{
    float c1 = fminf(fmaxf(cos_axis, 0.0f), 1.0f), c2 = fminf(fmaxf(cos_mirror, 0.0f), 1.0f);
    for (int e = 0; e < EXPONENTS; e++) {
        for (int s = 0; s < 2; s++) { /* 4 = 2^2, then 2 more squarings per step */
            c1 *= c1;
            c2 *= c2;
        }
        lobe[e] = (exponents[e] + 1.0f) * (0.5f / 3.14159265f) * (c1 + c2);
    }
}

/* v^2 p / p_k for candidate k, whose guide (lobe or histogram) has density
 * pdf_guide at the direction. p_k = 0: that candidate could never have
 * drawn this direction, which carries light: it would be biased. */
static float candidate_term(int k, float weight, float pdf_bsdf, float pdf_guide)
{
    float a = sg_mixture_candidates[k].alpha;
    float p = a * pdf_bsdf + (1.0f - a) * pdf_guide;
    return p > 0.0f ? weight / p : INFINITY;
}

void sg_mixture_record(SgMixtureLearner *l, uint32_t tile, const SgMixtureRecord *rec)
{
    if (tile >= l->tiles || rec->region >= l->region_count)
        return;
    RecordBuffer *b = &l->buffers[l->filling * l->tiles + tile];
    if (b->count == b->capacity) {
        size_t cap = b->capacity ? 2 * b->capacity : 1024;
        StoredRecord *d = realloc(b->data, cap * sizeof *d);
        if (!d)
            return;
        b->data = d;
        b->capacity = cap;
    }
    StoredRecord *st = &b->data[b->count++];
    st->region = rec->region;
    st->weight = rec->weight;
    st->radiance = rec->radiance >= 0.0f && isfinite(rec->radiance) ? rec->radiance : -1.0f;
    st->lobe = rec->lobe;
    st->estimate = 0.0f;
    memset(st->axis_terms, 0, sizeof st->axis_terms);
    st->bin = -1;
    st->generation = l->view.generation;
    memset(st->fit, 0, sizeof st->fit);
    memset(st->point_fit, 0, sizeof st->point_fit);
    st->sky = rec->sky;
    if (rec->sky) {
        float f = rec->sky_contribution, q0 = rec->sky_share * rec->sky_pdf_portals +
                                              (1.0f - rec->sky_share) * rec->sky_pdf_sky;
        for (int k = 0; k < SG_PORTAL_SHARES; k++) {
            float qk = sg_portal_shares[k] * rec->sky_pdf_portals + (1.0f - sg_portal_shares[k]) * rec->sky_pdf_sky;
            /* a share that could never have drawn a direction that brought light: infinite */
            st->sky_term[k] = !(f > 0.0f) || !isfinite(f) || !(q0 > 0.0f) ? 0.0f
                              : qk > 0.0f                                  ? f / qk * (f / q0)
                                                                           : INFINITY;
        }
    }
    if (!rec->lobe)
        return;
    const float *axis = &l->view_axis[3 * (size_t)rec->region];
    const float *point = &l->view_point[4 * (size_t)rec->region];
    bool has_axis = axis[0] != 0.0f || axis[1] != 0.0f || axis[2] != 0.0f;
    bool has_point = has_axis && point[3] > 0.0f;
    uint32_t histogram = l->view.histogram_of[rec->region];
    bool has_direction = rec->direction.x != 0.0f || rec->direction.y != 0.0f || rec->direction.z != 0.0f;
    float v = rec->estimate;
    if (!(v > 0.0f) || !isfinite(v)) {
        /* a sample that brought nothing back */
        st->axis_terms[0] = has_axis;
        st->axis_terms[1] = has_point;
        st->axis_terms[HISTOGRAM_FAMILY] = histogram != SG_NO_REGION;
        return;
    }
    st->estimate = v;
    float weight = v * v * rec->pdf;
    float lobe[EXPONENTS];
    if (rec->no_skeleton) { /* every skeleton candidate draws from the BSDF here */
        float term = rec->pdf_bsdf > 0.0f ? weight / rec->pdf_bsdf : INFINITY;
        for (int k = 0; k < SKELETON_CANDIDATES; k++)
            st->term[k] = term;
    } else {
        folded_lobe_densities(rec->cos_axis, rec->cos_mirror, lobe);
        for (int k = 0; k < SKELETON_CANDIDATES; k++)
            st->term[k] = candidate_term(k, weight, rec->pdf_bsdf, lobe[l->exponent_of[k]]);
    }
    if (!has_direction)
        return;
    Vec3 d = rec->direction, x = rec->position;
    st->fit[0] = v * d.x, st->fit[1] = v * d.y, st->fit[2] = v * d.z;
    st->bin = (int16_t)sg_mixture_histogram_bin(d);
    if (histogram != SG_NO_REGION) {
        float p_histogram =
            sg_mixture_histogram_pdf(&l->view.histogram[(size_t)histogram * SG_MIXTURE_BINS], d);
        for (int k = 0; k < HISTOGRAM_CANDIDATES; k++) {
            int c = SKELETON_CANDIDATES + HISTOGRAM_FAMILY * AXIS_CANDIDATES + k;
            st->term[c] = candidate_term(c, weight, rec->pdf_bsdf, p_histogram);
        }
        st->axis_terms[HISTOGRAM_FAMILY] = true;
    }
    float t = rec->distance;
    if (t > 0.0f && isfinite(t)) {
        st->point_fit[0] = v * (x.x + t * d.x), st->point_fit[1] = v * (x.y + t * d.y);
        st->point_fit[2] = v * (x.z + t * d.z), st->point_fit[3] = v;
    }
    if (!has_axis)
        return;
    for (int f = 0; f < HISTOGRAM_FAMILY; f++) {
        if (f == 1 && !has_point)
            break;
        Vec3 a = f == 0 ? v3(axis[0], axis[1], axis[2]) : sg_mixture_point_axis(point, axis, x);
        float c1, c2;
        sg_folded_cosines(a, rec->normal, d, &c1, &c2);
        folded_lobe_densities(c1, c2, lobe);
        for (int k = 0; k < AXIS_CANDIDATES; k++) {
            int c = SKELETON_CANDIDATES + f * AXIS_CANDIDATES + k;
            st->term[c] = candidate_term(c, weight, rec->pdf_bsdf, lobe[l->exponent_of[c]]);
        }
        st->axis_terms[f] = true;
    }
}

static bool fallback_settled(const RegionStats *st)
{
    return st->samples >= FALLBACK_SETTLED && st->radiance_samples >= FALLBACK_SETTLED;
}

static void add_record(RegionStats *st, const StoredRecord *rec)
{
    if (rec->sky) {
        st->sky_samples++;
        st->sky_lit += rec->sky_term[SG_PORTAL_SHARE_DEFAULT] > 0.0f;
        for (int k = 0; k < SG_PORTAL_SHARES; k++)
            st->sky_moment[k] += rec->sky_term[k];
    }
    if (rec->radiance >= 0.0f) {
        st->radiance_sum2 += (double)rec->radiance * rec->radiance;
        st->radiance_samples++;
    }
    if (!rec->lobe)
        return;
    st->samples++;
    double w = rec->weight;
    if (!(w > 0.0) || !isfinite(w))
        return;
    st->weight += w; /* a bounce that brought nothing back still counts */
    /* records drawn while the learned axis, point and histogram were in use */
    for (int f = 0; f < FAMILIES; f++)
        if (rec->generation >= st->axis_from[f] && rec->axis_terms[f]) {
            st->axis_samples[f]++;
            st->axis_weight[f] += w;
        }
    if (rec->estimate == 0.0f)
        return;
    st->weighted += w * rec->estimate;
    for (int k = 0; k < SKELETON_CANDIDATES; k++)
        st->moment[k] += w * rec->term[k];
    for (int i = 0; i < 3; i++)
        st->fit[i] += rec->fit[i];
    for (int i = 0; i < 4; i++)
        st->point_fit[i] += rec->point_fit[i];
    for (int f = 0; f < FAMILIES; f++) {
        if (rec->generation < st->axis_from[f] || !rec->axis_terms[f])
            continue;
        st->axis_weighted[f] += w * rec->estimate;
        for (int k = 0; k < (f == HISTOGRAM_FAMILY ? HISTOGRAM_CANDIDATES : AXIS_CANDIDATES); k++)
            st->axis_moment[f][k] += w * rec->term[SKELETON_CANDIDATES + f * AXIS_CANDIDATES + k];
    }
}

/* The region's share of the image variance under candidate k: its bounces'
 * weighted variance, summed (so a region many paths cross counts more). */
static double region_variance(const RegionStats *st, int k)
{
    double mean2 = st->weight > 0.0 ? st->weighted * st->weighted / st->weight : 0.0;
    if (k < SKELETON_CANDIDATES)
        return fmax(0.0, st->moment[k] - mean2);
    /* the learned candidates: measured on the records drawn while the
     * axis and point were in use, scaled to all of the region's */
    int f = (k - SKELETON_CANDIDATES) / AXIS_CANDIDATES, i = (k - SKELETON_CANDIDATES) % AXIS_CANDIDATES;
    if (st->axis_samples[f] < AXIS_MIN_SAMPLES || !(st->axis_weight[f] > 0.0))
        return INFINITY;
    return fmax(0.0, st->axis_moment[f][i] * (st->weight / st->axis_weight[f]) - mean2);
}

static double region_cost(const RegionStats *st, int k)
{
    return (double)st->samples *
           (k == 0 ? 1.0 : sg_mixture_candidates[k].learned_axis ? LEARNED_AXIS_COST : GUIDED_COST);
}

/* The candidate that makes the image's variance times render time least,
 * the other regions' choices given: (V_rest + V_k) (T_rest + T_k), where
 * V_rest, T_rest are the level's totals without this region. Or -1 with
 * too few samples. A region whose bounces weigh little in the image cannot
 * pay for the guide's cost however much it would lower its own variance. */
static int best_candidate(const RegionStats *st, const Totals *t, int candidates)
{
    if (st->samples < MIN_SAMPLES)
        return -1;
    double v_rest = fmax(0.0, t->variance - st->variance), t_rest = fmax(0.0, t->cost - st->cost);
    int best = 0;
    double best_score = INFINITY;
    for (int k = 0; k < candidates; k++) {
        double score = (v_rest + region_variance(st, k)) * (t_rest + region_cost(st, k));
        if (score < best_score) {
            best = k;
            best_score = score;
        }
    }
    return best;
}

/* Re-chooses a region and keeps its level's totals current. */
static int choose(RegionStats *st, Totals *t, int candidates)
{
    int k = best_candidate(st, t, candidates);
    int counted = k < 0 ? 0 : k;
    t->variance -= st->variance;
    t->cost -= st->cost;
    st->variance = region_variance(st, counted);
    st->cost = region_cost(st, counted);
    t->variance += st->variance;
    t->cost += st->cost;
    return k;
}

/* The portal share whose sky samples' second moment is least (the
 * default where they tie), or -1 with too few sky samples. */
static int best_share(const RegionStats *st)
{
    if (st->sky_samples < SHARE_MIN_SAMPLES)
        return -1;
    int best = SG_PORTAL_SHARE_DEFAULT;
    for (int k = 0; k < SG_PORTAL_SHARES; k++)
        if (st->sky_moment[k] < st->sky_moment[best])
            best = k;
    return best;
}

static float rms_radiance(const RegionStats *st)
{
    return st->radiance_samples >= RADIANCE_MIN_SAMPLES
               ? (float)sqrt(st->radiance_sum2 / (double)st->radiance_samples)
               : -1.0f;
}

/* A fine region's own root mean square outgoing radiance, pulled toward
 * its coarse region's (the scene's while that has too few) as if that had
 * given MIN_SAMPLES of its reports: (S + N0 M2_coarse) / (n + N0). What
 * leaves a vertex in the dark is heavy-tailed (most reports 0, a rare one
 * that found the light carries the rest), so a region's own mean square
 * from a few hundred reports is most often far below its truth; the learned
 * roulette then cut its paths at ROULETTE_MIN_SURVIVAL and the rare
 * survivor that found the light came back 20 times too heavy: the
 * fireflies of guided on a corridor lit round two corners (issue 29). The
 * coarse region has seen many more of the paths through that part of the
 * scene; past a few thousand reports the region's own estimate rules. */
static float shrunk_rms_radiance(const SgMixtureLearner *l, uint32_t region)
{
    const RegionStats *st = &l->stats[region], *prior = &l->coarse[l->coarse_of[region]];
    if (st->radiance_samples < RADIANCE_MIN_SAMPLES)
        return -1.0f;
    if (prior->radiance_samples < RADIANCE_MIN_SAMPLES)
        prior = &l->global;
    if (prior->radiance_samples < RADIANCE_MIN_SAMPLES)
        return rms_radiance(st);
    double n0 = MIN_SAMPLES, prior_m2 = prior->radiance_sum2 / (double)prior->radiance_samples;
    return (float)sqrt((st->radiance_sum2 + n0 * prior_m2) / ((double)st->radiance_samples + n0));
}

/* A region's root mean square outgoing radiance (shrunk_rms_radiance), or
 * its coarse region's; -1 leaves it to the whole scene's
 * (view.global_radiance), which changes every pass and would otherwise be
 * copied to every sparse region. */
static void refresh_radiance(SgMixtureLearner *l, uint32_t region)
{
    float m = l->flags[region] & REGION_SEEN ? shrunk_rms_radiance(l, region) : -1.0f;
    if (m >= 0.0f)
        l->flags[region] |= REGION_OWN_RADIANCE;
    else
        m = rms_radiance(&l->coarse[l->coarse_of[region]]);
    if (m != l->radiance[region]) {
        l->radiance[region] = m;
        mark_changed(l, region);
    }
}

/* Brings the view up to date with what has been learned. */
static void publish(SgMixtureLearner *l)
{
    if (l->changed_count > l->region_count / 8) {
        memcpy(l->view_state, l->state, l->region_count);
        memcpy(l->view_radiance, l->radiance, sizeof *l->radiance * l->region_count);
        memcpy(l->view_axis, l->axis, 3 * sizeof *l->axis * l->region_count);
        memcpy(l->view_point, l->point, 4 * sizeof *l->point * l->region_count);
        memcpy(l->view_histogram_of, l->histogram_of, sizeof *l->histogram_of * l->region_count);
        memcpy(l->view_portal_share, l->portal_share, l->region_count);
    } else
        for (uint32_t i = 0; i < l->changed_count; i++) {
            uint32_t r = l->changed[i];
            l->view_state[r] = l->state[r];
            l->view_radiance[r] = l->radiance[r];
            memcpy(&l->view_axis[3 * (size_t)r], &l->axis[3 * (size_t)r], 3 * sizeof *l->axis);
            memcpy(&l->view_point[4 * (size_t)r], &l->point[4 * (size_t)r], 4 * sizeof *l->point);
            l->view_histogram_of[r] = l->histogram_of[r];
            l->view_portal_share[r] = l->portal_share[r];
        }
    for (uint32_t i = 0; i < l->histogram_changed_count; i++) {
        size_t e = l->histogram_changed[i];
        memcpy(&l->view_histogram[e * SG_MIXTURE_BINS], &l->histogram[e * SG_MIXTURE_BINS],
               SG_MIXTURE_BINS * sizeof *l->histogram);
        l->histogram_dirty[e] = 0;
    }
    l->histogram_changed_count = 0;
    l->view.generation = ++l->generation;
    for (uint32_t i = 0; i < l->changed_count; i++)
        l->flags[l->changed[i]] &= (uint8_t)~REGION_CHANGED;
    l->changed_count = 0;
    l->view.global_radiance = l->global_radiance;
}

void sg_mixture_end_pass(SgMixtureLearner *l)
{
    sg_mixture_learn(l); /* records not learned yet (no-op when they were) */
    publish(l);
    l->filling ^= 1u;
}

void sg_mixture_update(SgMixtureLearner *l)
{
    sg_mixture_end_pass(l);
    sg_mixture_learn(l);
    publish(l);
}

/* A family's axis, point or histogram changed: its candidates' sums
 * restart from the records of the next publication on. */
static void forget_family(RegionStats *st, int f, uint32_t generation)
{
    st->axis_from[f] = generation + 1; /* the records of the passes that use the new axis */
    st->axis_samples[f] = 0;
    st->axis_weight[f] = st->axis_weighted[f] = 0.0;
    memset(st->axis_moment[f], 0, sizeof st->axis_moment[f]);
}

static void forget_learned_moments(RegionStats *st, uint32_t generation)
{
    for (int f = 0; f < FAMILIES; f++)
        forget_family(st, f, generation);
}

/* Fits histogram entry e from its sums (false: nothing to fit): the
 * sums' share of each bin, with HISTOGRAM_FLOOR spread evenly, as a
 * cumulative distribution; listed for the next publication. */
static bool fit_histogram(SgMixtureLearner *l, size_t e)
{
    const float *sum = &l->histogram_sum[e * SG_MIXTURE_BINS];
    double total = 0.0;
    for (int b = 0; b < SG_MIXTURE_BINS; b++)
        total += sum[b];
    if (!(total > 0.0) || !isfinite(total))
        return false;
    float *cdf = &l->histogram[e * SG_MIXTURE_BINS];
    double scale = (1.0 - HISTOGRAM_FLOOR) / total, floor = HISTOGRAM_FLOOR / SG_MIXTURE_BINS, c = 0.0;
    for (int b = 0; b < SG_MIXTURE_BINS; b++) {
        c += sum[b] * scale + floor;
        cdf[b] = (float)c;
    }
    cdf[SG_MIXTURE_BINS - 1] = 1.0f;
    if (!l->histogram_dirty[e]) {
        l->histogram_dirty[e] = 1;
        l->histogram_changed[l->histogram_changed_count++] = (uint32_t)e;
    }
    return true;
}

/* Refits a region's axis and point on its schedule (AXIS_FIT_FIRST
 * records, then each AXIS_FIT_GROWTH times more): the direction of the sum
 * of v d, the mean of v (x + t d). True when they changed. */
static bool fit_axis(RegionStats *st, float axis[3], float point[4], uint32_t generation)
{
    uint64_t due = st->fitted_at ? st->fitted_at * AXIS_FIT_GROWTH : AXIS_FIT_FIRST;
    if (st->samples < due)
        return false;
    st->fitted_at = st->samples;
    double len = sqrt(st->fit[0] * st->fit[0] + st->fit[1] * st->fit[1] + st->fit[2] * st->fit[2]);
    if (!(len > 0.0) || !isfinite(len))
        return false;
    for (int i = 0; i < 3; i++)
        axis[i] = (float)(st->fit[i] / len);
    double pw = st->point_fit[3];
    bool has_point = pw > 0.0 && isfinite(pw);
    for (int i = 0; i < 3; i++)
        point[i] = has_point ? (float)(st->point_fit[i] / pw) : 0.0f;
    point[3] = has_point ? 1.0f : 0.0f;
    forget_learned_moments(st, generation);
    return true;
}

/* A fine region's axis in use changes (its own fit, or its coarse
 * region's where it has none): its learned candidates start again. */
static void set_axis(SgMixtureLearner *l, uint32_t region, const float axis[3], const float point[4])
{
    float *a = &l->axis[3 * (size_t)region], *p = &l->point[4 * (size_t)region];
    if (!memcmp(a, axis, 3 * sizeof *a) && !memcmp(p, point, 4 * sizeof *p))
        return;
    memcpy(a, axis, 3 * sizeof *a);
    memcpy(p, point, 4 * sizeof *p);
    forget_learned_moments(&l->stats[region], l->generation);
    mark_changed(l, region);
}

/* A fine region's own fit; a region that has settled keeps the axis it has. */
static void fit_fine_axis(SgMixtureLearner *l, uint32_t region)
{
    RegionStats *st = &l->stats[region];
    if (st->samples >= SETTLED_SAMPLES)
        return;
    if (!fit_axis(st, &l->axis[3 * (size_t)region], &l->point[4 * (size_t)region], l->generation))
        return;
    l->own_axis[region] = 1;
    if (st->samples >= HISTOGRAM_OWN_SAMPLES && fit_histogram(l, region)) {
        l->own_histogram[region] = 1;
        l->histogram_of[region] = region;
    }
    mark_changed(l, region);
}

void sg_mixture_learn(SgMixtureLearner *l)
{
    uint32_t fine = 0, coarse = 0;
    uint32_t *coarse_list = l->touched + l->region_count;
    const uint32_t learning = l->filling ^ 1u;
    size_t records = 0;
    for (uint32_t t = 0; t < l->tiles; t++)
        records += l->buffers[learning * l->tiles + t].count;
    if (!records)
        return;
    for (uint32_t t = 0; t < l->tiles; t++) {
        RecordBuffer *b = &l->buffers[learning * l->tiles + t];
        for (size_t i = 0; i < b->count; i++) {
            const StoredRecord *rec = &b->data[i];
            uint32_t c = l->coarse_of[rec->region];
            add_record(&l->stats[rec->region], rec);
            bool sums = rec->bin >= 0 && rec->estimate > 0.0f;
            if (sums)
                l->histogram_sum[(size_t)rec->region * SG_MIXTURE_BINS + (size_t)rec->bin] += rec->estimate;
            if (!(l->flags[rec->region] & REGION_SEEN)) {
                l->flags[rec->region] |= REGION_SEEN;
                l->seen[l->seen_count++] = rec->region;
            }
            if (!l->is_touched[rec->region]) {
                l->is_touched[rec->region] = 1;
                l->touched[fine++] = rec->region;
            }
            if (!fallback_settled(&l->global))
                add_record(&l->global, rec);
            if (fallback_settled(&l->coarse[c]))
                continue;
            add_record(&l->coarse[c], rec);
            if (sums)
                l->histogram_sum[((size_t)l->region_count + c) * SG_MIXTURE_BINS + (size_t)rec->bin] += rec->estimate;
            if (!l->coarse_touched[c]) {
                l->coarse_touched[c] = 1;
                coarse_list[coarse++] = c;
            }
        }
        b->count = 0;
    }
    /* the whole scene has no axis of its own */
    int8_t g = (int8_t)choose(&l->global, &l->global_totals, SKELETON_CANDIDATES);
    int8_t gs = (int8_t)best_share(&l->global);
    if (g != l->global_choice || gs != l->global_share_choice) {
        bool mixture = g != l->global_choice, share = gs != l->global_share_choice;
        l->global_choice = g; /* rare: every region that follows it looks again */
        l->global_share_choice = gs;
        for (uint32_t i = 0; i < l->region_count; i++)
            if ((mixture && l->choice[i] < 0 && l->coarse_choice[l->coarse_of[i]] < 0) ||
                (share && l->share_choice[i] < 0 && l->coarse_share_choice[l->coarse_of[i]] < 0))
                refresh_state(l, i);
    }
    for (uint32_t i = 0; i < fine; i++) {
        l->is_touched[l->touched[i]] = 0;
        fit_fine_axis(l, l->touched[i]);
        l->choice[l->touched[i]] = (int8_t)choose(&l->stats[l->touched[i]], &l->fine_totals, SG_MIXTURE_CANDIDATES);
        l->share_choice[l->touched[i]] = (int8_t)best_share(&l->stats[l->touched[i]]);
        refresh_state(l, l->touched[i]);
        refresh_radiance(l, l->touched[i]);
    }
    for (uint32_t i = 0; i < coarse; i++) {
        uint32_t c = coarse_list[i];
        l->coarse_touched[c] = 0;
        bool refitted =
            fit_axis(&l->coarse[c], &l->coarse_axis[3 * (size_t)c], &l->coarse_point[4 * (size_t)c], l->generation);
        bool new_histogram = refitted && fit_histogram(l, (size_t)l->region_count + c);
        int8_t k = (int8_t)choose(&l->coarse[c], &l->coarse_totals, SG_MIXTURE_CANDIDATES);
        bool rechosen = k != l->coarse_choice[c];
        int8_t share = (int8_t)best_share(&l->coarse[c]);
        bool share_rechosen = share != l->coarse_share_choice[c];
        l->coarse_share_choice[c] = share;
        /* its radiance goes to its sparse fine regions each time its
         * samples double: the estimate settles, the copies cost */
        RegionStats *cs = &l->coarse[c];
        bool answers_radiance = cs->radiance_samples >= RADIANCE_MIN_SAMPLES &&
                                cs->radiance_samples >= 2 * cs->radiance_published;
        if (answers_radiance)
            cs->radiance_published = cs->radiance_samples;
        if (!rechosen && !share_rechosen && !answers_radiance && !refitted)
            continue;
        l->coarse_choice[c] = k;
        /* the fine regions it answers for: its cells, same normal bin */
        uint32_t cell = c / 6, bin = c % 6;
        int cx = (int)(cell % (uint32_t)l->coarse_cells[0]);
        int cy = (int)(cell / (uint32_t)l->coarse_cells[0] % (uint32_t)l->coarse_cells[1]);
        int cz = (int)(cell / ((uint32_t)l->coarse_cells[0] * (uint32_t)l->coarse_cells[1]));
        for (int z = cz * COARSE; z < (cz + 1) * COARSE && z < l->cells[2]; z++)
            for (int y = cy * COARSE; y < (cy + 1) * COARSE && y < l->cells[1]; y++)
                for (int x = cx * COARSE; x < (cx + 1) * COARSE && x < l->cells[0]; x++) {
                    uint32_t f = sg_mixture_region_of_cell(&l->view, (uint32_t)x, (uint32_t)y, (uint32_t)z, bin);
                    if (refitted && !l->own_axis[f])
                        set_axis(l, f, &l->coarse_axis[3 * (size_t)c], &l->coarse_point[4 * (size_t)c]);
                    if (new_histogram && !l->own_histogram[f]) { /* its histogram is the coarse one, refitted */
                        l->histogram_of[f] = l->region_count + c;
                        forget_family(&l->stats[f], HISTOGRAM_FAMILY, l->generation);
                        mark_changed(l, f);
                    }
                    if ((rechosen && l->choice[f] < 0) || (share_rechosen && l->share_choice[f] < 0))
                        refresh_state(l, f);
                    if (answers_radiance && !(l->flags[f] & REGION_OWN_RADIANCE))
                        refresh_radiance(l, f);
                }
    }
    l->global_radiance = rms_radiance(&l->global);
}

uint64_t sg_mixture_region_samples(const SgMixtureLearner *l, uint32_t region)
{
    return region < l->region_count ? l->stats[region].samples : 0;
}

bool sg_mixture_portal_share_use(const SgMixtureLearner *l, double fractions[SG_PORTAL_SHARES])
{
    double all = 0.0;
    for (int k = 0; k < SG_PORTAL_SHARES; k++)
        fractions[k] = 0.0;
    for (uint32_t s = 0; s < l->seen_count; s++) {
        uint32_t i = l->seen[s];
        double n = (double)l->stats[i].sky_lit;
        fractions[l->portal_share[i]] += n;
        all += n;
    }
    for (int k = 0; k < SG_PORTAL_SHARES && all > 0.0; k++)
        fractions[k] /= all;
    return all > 0.0;
}


/* Share of the bounces seen, weighted by each region's, whose region's
 * choice has state bits `bits`. */
static double fraction_with(const SgMixtureLearner *l, unsigned bits)
{
    double all = 0.0, some = 0.0;
    for (uint32_t s = 0; s < l->seen_count; s++) {
        uint32_t i = l->seen[s];
        double n = (double)l->stats[i].samples;
        all += n;
        if (n > 0.0 && (l->state[i] & bits))
            some += n;
    }
    return all > 0.0 ? some / all : 0.0;
}

double sg_mixture_guided_fraction(const SgMixtureLearner *l)
{
    return fraction_with(l, SG_MIXTURE_STATE_LOBE | SG_MIXTURE_STATE_AXIS);
}

double sg_mixture_learned_axis_fraction(const SgMixtureLearner *l)
{
    return fraction_with(l, SG_MIXTURE_STATE_AXIS);
}

bool sg_mixture_region_axis(const SgMixtureLearner *l, uint32_t region, Vec3 *axis)
{
    if (region >= l->region_count)
        return false;
    const float *a = &l->view_axis[3 * (size_t)region];
    *axis = v3(a[0], a[1], a[2]);
    return a[0] != 0.0f || a[1] != 0.0f || a[2] != 0.0f;
}

bool sg_mixture_region_point(const SgMixtureLearner *l, uint32_t region, Vec3 *point)
{
    if (region >= l->region_count)
        return false;
    const float *p = &l->view_point[4 * (size_t)region];
    *point = v3(p[0], p[1], p[2]);
    return p[3] > 0.0f;
}

/* region count, the scene's radiance, then per region its state byte,
 * radiance, axis and point, then per region its portal share; then the
 * histograms in use: their count, each entry's index and distribution, and
 * per region the entry it uses */
static size_t fixed_view_size(const SgMixtureLearner *l)
{
    return sizeof(uint32_t) + sizeof(float) + (size_t)l->region_count * (2 + 8 * sizeof(float));
}

#define HISTOGRAM_BYTES (sizeof(uint32_t) + SG_MIXTURE_BINS * sizeof(float))

/* The histogram entries some region's view uses, marked in `used` (one
 * byte an entry); their count. */
static uint32_t used_histograms(const SgMixtureLearner *l, uint8_t *used)
{
    uint32_t n = 0;
    for (uint32_t r = 0; r < l->region_count; r++) {
        uint32_t e = l->view_histogram_of[r];
        if (e != SG_NO_REGION && !used[e]) {
            used[e] = 1;
            n++;
        }
    }
    return n;
}

size_t sg_mixture_view_size(const SgMixtureLearner *l)
{
    uint8_t *used = calloc((size_t)l->region_count + l->coarse_count, 1);
    if (!used)
        return 0;
    uint32_t n = used_histograms(l, used);
    free(used);
    return fixed_view_size(l) + sizeof(uint32_t) + n * HISTOGRAM_BYTES + sizeof(uint32_t) * l->region_count;
}

void sg_mixture_view_save(const SgMixtureLearner *l, void *out)
{
    unsigned char *o = out;
    memcpy(o, &l->region_count, sizeof(uint32_t));
    memcpy(o + 4, &l->view.global_radiance, sizeof(float));
    memcpy(o + 8, l->view_state, l->region_count);
    memcpy(o + 8 + l->region_count, l->view_radiance, sizeof(float) * l->region_count);
    memcpy(o + 8 + l->region_count * (size_t)5, l->view_axis, 3 * sizeof(float) * l->region_count);
    memcpy(o + 8 + l->region_count * (size_t)17, l->view_point, 4 * sizeof(float) * l->region_count);
    memcpy(o + 8 + l->region_count * (size_t)33, l->view_portal_share, l->region_count);
    o += fixed_view_size(l);
    uint32_t entries = l->region_count + l->coarse_count;
    uint8_t *used = calloc(entries, 1);
    uint32_t n = used ? used_histograms(l, used) : 0;
    memcpy(o, &n, sizeof n);
    o += sizeof n;
    for (uint32_t e = 0; used && e < entries; e++)
        if (used[e]) {
            memcpy(o, &e, sizeof e);
            memcpy(o + sizeof e, &l->view_histogram[(size_t)e * SG_MIXTURE_BINS], SG_MIXTURE_BINS * sizeof(float));
            o += HISTOGRAM_BYTES;
        }
    memcpy(o, l->view_histogram_of, sizeof(uint32_t) * l->region_count);
    free(used);
}

bool sg_mixture_view_restore(SgMixtureLearner *l, const void *in, size_t size)
{
    const unsigned char *i = in;
    uint32_t regions, n;
    size_t fixed = fixed_view_size(l), entries = (size_t)l->region_count + l->coarse_count;
    if (size < fixed + sizeof n)
        return false;
    memcpy(&regions, i, sizeof regions);
    memcpy(&n, i + fixed, sizeof n);
    if (regions != l->region_count || n > entries ||
        size != fixed + sizeof n + n * HISTOGRAM_BYTES + sizeof(uint32_t) * l->region_count)
        return false;
    const unsigned char *h = i + fixed + sizeof n, *of = h + n * HISTOGRAM_BYTES;
    for (uint32_t k = 0; k < n; k++, h += HISTOGRAM_BYTES) {
        uint32_t e;
        memcpy(&e, h, sizeof e);
        float last; /* a cumulative distribution ends at 1 */
        memcpy(&last, h + sizeof e + (SG_MIXTURE_BINS - 1) * sizeof(float), sizeof last);
        if (e >= entries || last != 1.0f)
            return false;
        memcpy(&l->view_histogram[(size_t)e * SG_MIXTURE_BINS], h + sizeof e, SG_MIXTURE_BINS * sizeof(float));
    }
    const unsigned char *share = i + 8 + l->region_count * (size_t)33;
    for (uint32_t r = 0; r < l->region_count; r++)
        if (share[r] >= SG_PORTAL_SHARES)
            return false;
    for (uint32_t r = 0; r < l->region_count; r++) {
        uint32_t e;
        memcpy(&e, of + sizeof e * r, sizeof e);
        if (e != SG_NO_REGION && e >= entries)
            return false;
        l->view_histogram_of[r] = e;
    }
    memcpy(&l->view.global_radiance, i + 4, sizeof(float));
    memcpy(l->view_state, i + 8, l->region_count);
    memcpy(l->view_radiance, i + 8 + l->region_count, sizeof(float) * l->region_count);
    memcpy(l->view_axis, i + 8 + l->region_count * (size_t)5, 3 * sizeof(float) * l->region_count);
    memcpy(l->view_point, i + 8 + l->region_count * (size_t)17, 4 * sizeof(float) * l->region_count);
    memcpy(l->view_portal_share, share, l->region_count);
    return true;
}

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
    float p = cdf[b] - (b ? cdf[b - 1] : 0.0f);
    /* the bin's probability over its area of the square (4 / bins), times
     * the square's area per solid angle, |p|^3 = 1 / |w|_1^3 */
    float inv = 1.0f / l1;
    return fmaxf(p, 0.0f) * (SG_MIXTURE_BINS * 0.25f) * inv * inv * inv;
}

Vec3 sg_mixture_histogram_sample(const float *cdf, float u1, float u2)
{
    /* the first bin whose cumulative probability exceeds u1 */
    uint32_t lo = 0, hi = SG_MIXTURE_BINS - 1;
    while (lo < hi) {
        uint32_t mid = (lo + hi) / 2;
        if (cdf[mid] > u1)
            hi = mid;
        else
            lo = mid + 1;
    }
    float below = lo ? cdf[lo - 1] : 0.0f, p = cdf[lo] - below;
    float s = p > 0.0f ? (u1 - below) / p : 0.5f;
    s = fminf(fmaxf(s, 0.0f), 0x1.fffffep-1f);
    const float cell = 2.0f / SG_MIXTURE_HIST_RES;
    float x = -1.0f + ((float)(lo % SG_MIXTURE_HIST_RES) + s) * cell;
    float y = -1.0f + ((float)(lo / SG_MIXTURE_HIST_RES) + u2) * cell;
    float z = 1.0f - fabsf(x) - fabsf(y);
    if (z < 0.0f)
        octahedral_fold(&x, &y);
    return v3_normalize(v3(x, y, z));
}
