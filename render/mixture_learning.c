#include "mixture_learning.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* BSDF alone first: with equal estimates the cheaper, safer choice wins. */
const float sg_mixture_candidates[SG_MIXTURE_CANDIDATES] = {1.0f, 0.9f, 0.8f, 0.7f, 0.6f};

/* Samples a region needs before its own estimate is trusted, and after
 * which it stops learning. */
#define MIN_SAMPLES 256u
#define SETTLED_SAMPLES 4096
#define STATE_INITIAL 7
#define STATE_SETTLED 8

/* A record as kept: its terms computed by the thread that made it, so that
 * the sequential sum after the pass is only additions. */
typedef struct StoredRecord {
    uint32_t region;
    float estimate;
    float term[SG_MIXTURE_CANDIDATES]; /* v^2 p / p_k */
} StoredRecord;

typedef struct RecordBuffer {
    StoredRecord *data;
    size_t count, capacity;
} RecordBuffer;

typedef struct RegionStats {
    double moment[SG_MIXTURE_CANDIDATES]; /* sums of v^2 p / p_k */
    double sum;                           /* sum of v */
    uint64_t samples;
} RegionStats;

/* Cost of a guided bounce relative to a BSDF one (cache query, densities
 * of the lobe), measured on the corridor and the Cornell box. */
#define GUIDED_COST 1.25
/* A coarse region is this many fine cells on a side: it answers for the
 * fine regions that have too few samples of their own. */
#define COARSE 4

struct SgMixtureLearner {
    int cells[3];          /* fine grid */
    int coarse_cells[3];
    Vec3 lo;
    float inv_size;
    uint32_t region_count, coarse_count;
    float initial_alpha;
    /* per fine region, all the renderer reads at a bounce (one byte, so
     * that the table stays in cache): the candidate in use (STATE_INITIAL:
     * none yet) and STATE_SETTLED once the region stops learning */
    uint8_t *state;
    int8_t *choice;        /* per fine region: candidate index, -1 too few samples */
    int8_t *coarse_choice; /* per coarse region */
    RegionStats *stats;    /* per fine region */
    RegionStats *coarse;   /* per coarse region */
    uint32_t *touched;     /* fine regions, then coarse ones, with new records */
    uint8_t *is_touched, *coarse_touched;
    uint32_t *coarse_of;   /* fine region -> coarse region */
    uint32_t tiles;
    RecordBuffer *buffers; /* per tile */
    SgMixtureView view;
};

SgMixtureLearner *sg_mixture_learner_create(Vec3 lo, Vec3 hi, int cells_longest, uint32_t tiles,
                                            float initial_alpha, SgError *err)
{
    float ext[3] = {hi.x - lo.x, hi.y - lo.y, hi.z - lo.z};
    float longest = fmaxf(ext[0], fmaxf(ext[1], ext[2]));
    if (!(longest > 0.0f) || !isfinite(longest) || cells_longest < 1 || cells_longest > 1024)
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
    l->lo = lo;
    l->inv_size = 1.0f / size;
    l->region_count = (uint32_t)(cells * 6);
    l->coarse_count = (uint32_t)(coarse * 6);
    l->initial_alpha = initial_alpha;
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
    l->buffers = calloc(tiles ? tiles : 1, sizeof *l->buffers);
    if (!l->choice || !l->state || !l->coarse_choice || !l->touched || !l->is_touched || !l->coarse_touched || !l->stats ||
        !l->coarse || !l->coarse_of || !l->buffers) {
        sg_mixture_learner_free(l);
        return sg_fail(err, "mixture learner: out of memory for %u regions", (unsigned)(cells * 6)), NULL;
    }
    for (int z = 0; z < l->cells[2]; z++)
        for (int y = 0; y < l->cells[1]; y++)
            for (int x = 0; x < l->cells[0]; x++) {
                size_t fine = ((size_t)z * l->cells[1] + y) * l->cells[0] + x;
                size_t c = ((size_t)(z / COARSE) * l->coarse_cells[1] + y / COARSE) * l->coarse_cells[0] +
                           x / COARSE;
                for (int bin = 0; bin < 6; bin++)
                    l->coarse_of[fine * 6 + bin] = (uint32_t)(c * 6 + bin);
            }
    memset(l->choice, -1, l->region_count);
    memset(l->state, STATE_INITIAL, l->region_count);
    l->view.lo = lo;
    l->view.inv_size = l->inv_size;
    for (int i = 0; i < 3; i++)
        l->view.cells[i] = (float)l->cells[i];
    l->view.stride_y = l->cells[0];
    l->view.stride_z = l->cells[0] * l->cells[1];
    l->view.state = l->state;
    for (int k = 0; k < 8; k++)
        l->view.alpha_of_state[k] = k < SG_MIXTURE_CANDIDATES ? sg_mixture_candidates[k] : initial_alpha;
    memset(l->coarse_choice, -1, l->coarse_count);
    return l;
}

void sg_mixture_learner_free(SgMixtureLearner *l)
{
    if (!l)
        return;
    if (l->buffers)
        for (uint32_t t = 0; t < l->tiles; t++)
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
    free(l);
}

uint32_t sg_mixture_region(const SgMixtureLearner *l, Vec3 p, Vec3 n)
{
    float v[3] = {(p.x - l->lo.x) * l->inv_size, (p.y - l->lo.y) * l->inv_size, (p.z - l->lo.z) * l->inv_size};
    int c[3];
    for (int i = 0; i < 3; i++) {
        if (!(v[i] >= 0.0f && v[i] < (float)l->cells[i]))
            return SG_NO_REGION;
        c[i] = (int)v[i];
    }
    float a[3] = {fabsf(n.x), fabsf(n.y), fabsf(n.z)};
    int axis = a[0] >= a[1] && a[0] >= a[2] ? 0 : (a[1] >= a[2] ? 1 : 2);
    float s = axis == 0 ? n.x : (axis == 1 ? n.y : n.z);
    uint32_t bin = (uint32_t)(2 * axis + (s < 0.0f));
    size_t cell = ((size_t)c[2] * l->cells[1] + c[1]) * l->cells[0] + c[0];
    return (uint32_t)(cell * 6 + bin);
}

static float state_alpha(const SgMixtureLearner *l, uint8_t state)
{
    state &= 7;
    return state == STATE_INITIAL ? l->initial_alpha : sg_mixture_candidates[state];
}

float sg_mixture_alpha(const SgMixtureLearner *l, uint32_t region)
{
    return region < l->region_count ? state_alpha(l, l->state[region]) : l->initial_alpha;
}

bool sg_mixture_learning(const SgMixtureLearner *l, uint32_t region)
{
    return region < l->region_count && !(l->state[region] & STATE_SETTLED);
}

const SgMixtureView *sg_mixture_view(const SgMixtureLearner *l) { return &l->view; }

static void refresh_state(SgMixtureLearner *l, uint32_t region)
{
    int k = l->choice[region];
    if (k < 0)
        k = l->coarse_choice[l->coarse_of[region]];
    l->state[region] = (uint8_t)((k < 0 ? STATE_INITIAL : k) |
                                 (l->stats[region].samples >= SETTLED_SAMPLES ? STATE_SETTLED : 0));
}

void sg_mixture_record(SgMixtureLearner *l, uint32_t tile, const SgMixtureRecord *rec)
{
    if (tile >= l->tiles || rec->region >= l->region_count)
        return;
    RecordBuffer *b = &l->buffers[tile];
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
    float v = rec->estimate;
    if (!(v > 0.0f) || !isfinite(v)) {
        st->estimate = 0.0f;
        return;
    }
    st->estimate = v;
    float weight = v * v * rec->pdf;
    for (int k = 0; k < SG_MIXTURE_CANDIDATES; k++) {
        float a = sg_mixture_candidates[k];
        float p = a * rec->pdf_bsdf + (1.0f - a) * rec->pdf_lobe;
        /* p = 0: that candidate could never have drawn this direction,
         * which carries light: it would be biased */
        st->term[k] = p > 0.0f ? weight / p : INFINITY;
    }
}

static void add_record(RegionStats *st, const StoredRecord *rec)
{
    st->samples++;
    if (rec->estimate == 0.0f)
        return;
    st->sum += rec->estimate;
    for (int k = 0; k < SG_MIXTURE_CANDIDATES; k++)
        st->moment[k] += rec->term[k];
}

/* The candidate with the least variance times cost, or -1 if too few samples. */
static int best_candidate(const RegionStats *st)
{
    if (st->samples < MIN_SAMPLES)
        return -1;
    double n = (double)st->samples, mean = st->sum / n;
    int best = 0;
    double best_cost = fmax(0.0, st->moment[0] / n - mean * mean);
    for (int k = 1; k < SG_MIXTURE_CANDIDATES; k++) {
        double cost = fmax(0.0, st->moment[k] / n - mean * mean) * GUIDED_COST;
        if (cost < best_cost) {
            best = k;
            best_cost = cost;
        }
    }
    return best;
}

void sg_mixture_update(SgMixtureLearner *l)
{
    uint32_t fine = 0, coarse = 0;
    uint32_t *coarse_list = l->touched + l->region_count;
    for (uint32_t t = 0; t < l->tiles; t++) {
        RecordBuffer *b = &l->buffers[t];
        for (size_t i = 0; i < b->count; i++) {
            const StoredRecord *rec = &b->data[i];
            uint32_t c = l->coarse_of[rec->region];
            add_record(&l->stats[rec->region], rec);
            add_record(&l->coarse[c], rec);
            if (!l->is_touched[rec->region]) {
                l->is_touched[rec->region] = 1;
                l->touched[fine++] = rec->region;
            }
            if (!l->coarse_touched[c]) {
                l->coarse_touched[c] = 1;
                coarse_list[coarse++] = c;
            }
        }
        b->count = 0;
    }
    for (uint32_t i = 0; i < fine; i++) {
        l->is_touched[l->touched[i]] = 0;
        l->choice[l->touched[i]] = (int8_t)best_candidate(&l->stats[l->touched[i]]);
        refresh_state(l, l->touched[i]);
    }
    for (uint32_t i = 0; i < coarse; i++) {
        uint32_t c = coarse_list[i];
        l->coarse_touched[c] = 0;
        int8_t k = (int8_t)best_candidate(&l->coarse[c]);
        if (k == l->coarse_choice[c])
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
                    size_t f = ((size_t)z * l->cells[1] + y) * l->cells[0] + x;
                    if (l->choice[f * 6 + bin] < 0)
                        refresh_state(l, (uint32_t)(f * 6 + bin));
                }
    }
}

uint64_t sg_mixture_region_samples(const SgMixtureLearner *l, uint32_t region)
{
    return region < l->region_count ? l->stats[region].samples : 0;
}

uint32_t sg_mixture_region_count(const SgMixtureLearner *l) { return l->region_count; }

double sg_mixture_guided_fraction(const SgMixtureLearner *l)
{
    /* weighted by the bounces each region has seen */
    double all = 0.0, guided = 0.0;
    for (uint32_t i = 0; i < l->region_count; i++) {
        double n = (double)l->stats[i].samples;
        all += n;
        if (n > 0.0 && sg_mixture_alpha(l, i) < 1.0f)
            guided += n;
    }
    return all > 0.0 ? guided / all : 0.0;
}
