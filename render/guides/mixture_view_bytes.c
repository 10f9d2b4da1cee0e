/* The mixture learner's view as bytes: what a field file keeps of a
 * trained learner (render --field-out) and gives back to a frozen one. */
#include "mixture_learner_state.h"

#include <string.h>

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
