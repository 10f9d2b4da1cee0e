#include "mixture_learning.h"
#include "mixture_learner_state.h"

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

/* Every array the learner holds, sized for its regions; false when one
 * could not be had (sg_mixture_learner_free frees what was). */
static bool learner_alloc(SgMixtureLearner *l)
{
    l->choice = malloc(l->region_count);
    l->state = malloc(l->region_count);
    l->coarse_choice = malloc(l->coarse_count);
    l->touched = malloc(sizeof *l->touched * ((size_t)l->region_count + l->coarse_count));
    l->is_touched = calloc(l->region_count, 1);
    l->coarse_touched = calloc(l->coarse_count, 1);
    l->stats = calloc(l->region_count, sizeof *l->stats);
    l->coarse = calloc(l->coarse_count, sizeof *l->coarse);
    l->coarse_of = malloc(sizeof *l->coarse_of * l->region_count);
    size_t buffers = 2 * (size_t)(l->tiles ? l->tiles : 1);
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
    bool missing = !l->choice || !l->state || !l->coarse_choice || !l->touched || !l->is_touched ||
                   !l->coarse_touched || !l->stats || !l->coarse || !l->coarse_of || !l->buffers || !l->radiance ||
                   !l->view_state || !l->view_radiance || !l->changed || !l->flags || !l->seen || !l->axis ||
                   !l->view_axis || !l->coarse_axis || !l->own_axis || !l->point || !l->view_point ||
                   !l->coarse_point || !l->histogram_sum || !l->histogram || !l->view_histogram ||
                   !l->histogram_of || !l->view_histogram_of || !l->own_histogram || !l->histogram_dirty ||
                   !l->histogram_changed || !l->share_choice || !l->coarse_share_choice || !l->portal_share ||
                   !l->view_portal_share;
    return !missing;
}

/* The view's region index (the strides of each of the 6 normal bins'
 * cell grids) and each fine region's coarse region. */
static void learner_index(SgMixtureLearner *l, size_t cells)
{
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
}

/* Where learning starts: no choice, the initial candidate in use, no
 * radiance, axis, histogram or share of a region's own; the view a copy. */
static void learner_start(SgMixtureLearner *l, Vec3 lo, float size, int initial)
{
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
}

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
    if (!learner_alloc(l)) {
        sg_mixture_learner_free(l);
        return sg_fail(err, "mixture learner: out of memory for %u regions", (unsigned)(cells * 6)), NULL;
    }
    learner_index(l, cells);
    learner_start(l, lo, size, initial);
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

/* A sky sample's terms: each portal share's second-moment estimate. */
static void record_sky_terms(StoredRecord *st, const SgMixtureRecord *rec)
{
    float f = rec->sky_contribution,
          q0 = rec->sky_share * rec->sky_pdf_portals + (1.0f - rec->sky_share) * rec->sky_pdf_sky;
    for (int k = 0; k < SG_PORTAL_SHARES; k++) {
        float qk = sg_portal_shares[k] * rec->sky_pdf_portals + (1.0f - sg_portal_shares[k]) * rec->sky_pdf_sky;
        /* a share that could never have drawn a direction that brought light: infinite */
        st->sky_term[k] = !(f > 0.0f) || !isfinite(f) || !(q0 > 0.0f) ? 0.0f
                          : qk > 0.0f                                  ? f / qk * (f / q0)
                                                                       : INFINITY;
    }
}

/* A guided bounce's direction, for what is learned from it: the axis and
 * point fits' shares, its histogram bin, and the learned candidates' terms
 * (weight: v^2 p). */
static void record_learned_terms(const SgMixtureLearner *l, StoredRecord *st, const SgMixtureRecord *rec,
                                 float weight)
{
    const float *axis = &l->view_axis[3 * (size_t)rec->region];
    const float *point = &l->view_point[4 * (size_t)rec->region];
    bool has_axis = axis[0] != 0.0f || axis[1] != 0.0f || axis[2] != 0.0f;
    bool has_point = has_axis && point[3] > 0.0f;
    uint32_t histogram = l->view.histogram_of[rec->region];
    float v = rec->estimate;
    float lobe[EXPONENTS];
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
    if (rec->sky)
        record_sky_terms(st, rec);
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
    if (has_direction)
        record_learned_terms(l, st, rec, weight);
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
 * fireflies of guided on a corridor lit round two corners (data/dark-corridor). The
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

/* The pass before's records into their regions' sums (fine, coarse and
 * the whole scene's); the regions they touched listed in l->touched, the
 * fine ones' count in *fine and the coarse ones' in *coarse (after them). */
static void gather_records(SgMixtureLearner *l, uint32_t *fine, uint32_t *coarse)
{
    uint32_t *coarse_list = l->touched + l->region_count;
    const uint32_t learning = l->filling ^ 1u;
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
                l->touched[(*fine)++] = rec->region;
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
                coarse_list[(*coarse)++] = c;
            }
        }
        b->count = 0;
    }
}

/* The whole scene's choices (it has no axis of its own). */
static void learn_global(SgMixtureLearner *l)
{
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
}

/* What changed in coarse region c, for the fine regions it answers for. */
typedef struct CoarseNews {
    bool refitted, new_histogram, rechosen, share_rechosen, answers_radiance;
} CoarseNews;

/* Coarse region c's news to the fine regions it answers for: its cells,
 * the same normal bin. */
static void hand_down(SgMixtureLearner *l, uint32_t c, const CoarseNews *news)
{
    uint32_t cell = c / 6, bin = c % 6;
    int cx = (int)(cell % (uint32_t)l->coarse_cells[0]);
    int cy = (int)(cell / (uint32_t)l->coarse_cells[0] % (uint32_t)l->coarse_cells[1]);
    int cz = (int)(cell / ((uint32_t)l->coarse_cells[0] * (uint32_t)l->coarse_cells[1]));
    for (int z = cz * COARSE; z < (cz + 1) * COARSE && z < l->cells[2]; z++)
        for (int y = cy * COARSE; y < (cy + 1) * COARSE && y < l->cells[1]; y++)
            for (int x = cx * COARSE; x < (cx + 1) * COARSE && x < l->cells[0]; x++) {
                uint32_t f = sg_mixture_region_of_cell(&l->view, (uint32_t)x, (uint32_t)y, (uint32_t)z, bin);
                if (news->refitted && !l->own_axis[f])
                    set_axis(l, f, &l->coarse_axis[3 * (size_t)c], &l->coarse_point[4 * (size_t)c]);
                if (news->new_histogram && !l->own_histogram[f]) { /* its histogram is the coarse one, refitted */
                    l->histogram_of[f] = l->region_count + c;
                    forget_family(&l->stats[f], HISTOGRAM_FAMILY, l->generation);
                    mark_changed(l, f);
                }
                if ((news->rechosen && l->choice[f] < 0) || (news->share_rechosen && l->share_choice[f] < 0))
                    refresh_state(l, f);
                if (news->answers_radiance && !(l->flags[f] & REGION_OWN_RADIANCE))
                    refresh_radiance(l, f);
            }
}

static void learn_coarse(SgMixtureLearner *l, uint32_t c)
{
    l->coarse_touched[c] = 0;
    CoarseNews news;
    news.refitted =
        fit_axis(&l->coarse[c], &l->coarse_axis[3 * (size_t)c], &l->coarse_point[4 * (size_t)c], l->generation);
    news.new_histogram = news.refitted && fit_histogram(l, (size_t)l->region_count + c);
    int8_t k = (int8_t)choose(&l->coarse[c], &l->coarse_totals, SG_MIXTURE_CANDIDATES);
    news.rechosen = k != l->coarse_choice[c];
    int8_t share = (int8_t)best_share(&l->coarse[c]);
    news.share_rechosen = share != l->coarse_share_choice[c];
    l->coarse_share_choice[c] = share;
    /* its radiance goes to its sparse fine regions each time its
     * samples double: the estimate settles, the copies cost */
    RegionStats *cs = &l->coarse[c];
    news.answers_radiance = cs->radiance_samples >= RADIANCE_MIN_SAMPLES &&
                            cs->radiance_samples >= 2 * cs->radiance_published;
    if (news.answers_radiance)
        cs->radiance_published = cs->radiance_samples;
    if (!news.rechosen && !news.share_rechosen && !news.answers_radiance && !news.refitted)
        return;
    l->coarse_choice[c] = k;
    hand_down(l, c, &news);
}

void sg_mixture_learn(SgMixtureLearner *l)
{
    const uint32_t learning = l->filling ^ 1u;
    size_t records = 0;
    for (uint32_t t = 0; t < l->tiles; t++)
        records += l->buffers[learning * l->tiles + t].count;
    if (!records)
        return;
    uint32_t fine = 0, coarse = 0;
    gather_records(l, &fine, &coarse);
    learn_global(l);
    for (uint32_t i = 0; i < fine; i++) {
        l->is_touched[l->touched[i]] = 0;
        fit_fine_axis(l, l->touched[i]);
        l->choice[l->touched[i]] = (int8_t)choose(&l->stats[l->touched[i]], &l->fine_totals, SG_MIXTURE_CANDIDATES);
        l->share_choice[l->touched[i]] = (int8_t)best_share(&l->stats[l->touched[i]]);
        refresh_state(l, l->touched[i]);
        refresh_radiance(l, l->touched[i]);
    }
    const uint32_t *coarse_list = l->touched + l->region_count;
    for (uint32_t i = 0; i < coarse; i++)
        learn_coarse(l, coarse_list[i]);
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
