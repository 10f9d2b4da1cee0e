#include "merge.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "render/renderer.h"

/* What every input must agree on (a merge of different renders is no
 * render), and what is copied where all agree. */
static const char *const checked[] = {"sampling", "seed", "sg:shard_count", "sg:scene_hash", "sg:cache_hash",
                                      "sg:recipe"};
#define CHECKED (int)(sizeof checked / sizeof checked[0])
static const char *const copied[] = {"sg:max_depth", "sg:lobe_exponent", "sg:alpha", "sg:roulette", "sg:clamping",
                                     "sg:scene", "sg:cache", "sg:exposure"};
#define COPIED (int)(sizeof copied / sizeof copied[0])
#define VALUE_MAX 512

typedef struct Input {
    const char *path;
    int width, height;
    float *rgb;
    long spp;
    double seconds, guide_share;
    uint64_t nonfinite;
    bool has_guide_share;
    int first;            /* its lowest shard index: the merge's order */
    char *shards;         /* per shard index: held */
    char checked[CHECKED][VALUE_MAX];
    char copied[COPIED][VALUE_MAX];
    bool has_copied[COPIED];
} Input;

struct SgMerged {
    int width, height, shard_count, held;
    float *rgb;
    long spp;
    double seconds;
    char missing[1024];
    /* the output's attributes and their text */
    SgImageAttribute attrs[CHECKED + COPIED + 6];
    int attr_count;
    char values[CHECKED + COPIED + 6][VALUE_MAX];
    char *shard_list;
    double exposure;
};

static bool read_attribute(const char *path, const char *name, char *buf, bool required, SgError *err)
{
    SgError e = {0};
    if (sg_image_read_attribute(path, name, buf, VALUE_MAX, &e))
        return true;
    buf[0] = 0;
    if (required)
        sg_fail(err, "%s: not a render shard (no %s attribute)", path, name);
    return !required;
}

static void input_free(Input *in)
{
    free(in->rgb);
    free(in->shards);
}

static bool input_read(Input *in, const char *path, SgError *err)
{
    memset(in, 0, sizeof *in);
    in->path = path;
    char buf[VALUE_MAX];
    /* the shard attributes first: a file not ours is said so, not read whole */
    if (!read_attribute(path, "sg:shards", buf, true, err))
        return false;
    char shards[VALUE_MAX];
    snprintf(shards, sizeof shards, "%s", buf);
    for (int i = 0; i < CHECKED; i++)
        if (!read_attribute(path, checked[i], in->checked[i], true, err))
            return false;
    long count;
    if (!sg_parse_long(in->checked[2], 1, SG_SHARDS_MAX, &count))
        return sg_fail(err, "%s: sg:shard_count '%s' is not a shard count", path, in->checked[2]);
    in->shards = calloc((size_t)count, 1);
    if (!in->shards)
        return sg_fail(err, "%s: out of memory", path);
    in->first = -1;
    for (char *tok = strtok(shards, ","); tok; tok = strtok(NULL, ",")) {
        long k;
        if (!sg_parse_long(tok, 0, count - 1, &k))
            return sg_fail(err, "%s: sg:shards holds '%s', not a shard of %ld", path, tok, count);
        if (in->shards[k])
            return sg_fail(err, "%s: sg:shards names shard %ld twice", path, k);
        in->shards[k] = 1;
        if (in->first < 0 || k < in->first)
            in->first = (int)k;
    }
    if (in->first < 0)
        return sg_fail(err, "%s: sg:shards is empty", path);
    if (!read_attribute(path, "spp", buf, true, err))
        return false;
    if (!sg_parse_long(buf, 1, 1L << 40, &in->spp))
        return sg_fail(err, "%s: spp '%s' is not a positive count", path, buf);
    if (read_attribute(path, "seconds", buf, false, err) && buf[0])
        in->seconds = atof(buf);
    long nonfinite;
    if (read_attribute(path, "sg:nonfinite_samples", buf, false, err) && buf[0] &&
        sg_parse_long(buf, 0, LONG_MAX, &nonfinite))
        in->nonfinite = (uint64_t)nonfinite;
    if (read_attribute(path, "sg:guide_share", buf, false, err) && buf[0]) {
        in->guide_share = atof(buf);
        in->has_guide_share = true;
    }
    for (int i = 0; i < COPIED; i++)
        in->has_copied[i] = read_attribute(path, copied[i], in->copied[i], false, err) && in->copied[i][0];
    return sg_image_read(path, &in->width, &in->height, &in->rgb, err);
}

static int by_first_shard(const void *a, const void *b)
{
    const Input *x = a, *y = b;
    return (x->first > y->first) - (x->first < y->first);
}

static void add_attribute(SgMerged *m, const char *name, const char *value)
{
    int i = m->attr_count++;
    snprintf(m->values[i], VALUE_MAX, "%s", value);
    m->attrs[i] = (SgImageAttribute){name, m->values[i]};
}

/* "0,1,3" of the shards held: ascending, the form render writes. */
static char *shard_list(const char *held, int count)
{
    size_t cap = (size_t)count * 7 + 1;
    char *s = malloc(cap), *p = s;
    if (!s)
        return NULL;
    *p = 0;
    for (int k = 0; k < count; k++)
        if (held[k])
            p += snprintf(p, cap - (size_t)(p - s), "%s%d", p == s ? "" : ",", k);
    return s;
}

SgMerged *sg_merge_files(const char *const *paths, int count, bool partial, SgError *err)
{
    if (count < 1)
        return sg_fail(err, "no shard given"), NULL;
    Input *in = calloc((size_t)count, sizeof *in);
    SgMerged *m = calloc(1, sizeof *m);
    char *held = NULL;
    double *sum = NULL;
    if (!in || !m) {
        sg_fail(err, "out of memory");
        goto fail;
    }
    for (int i = 0; i < count; i++)
        if (!input_read(&in[i], paths[i], err))
            goto fail;
    for (int i = 1; i < count; i++) {
        if (in[i].width != in[0].width || in[i].height != in[0].height) {
            sg_fail(err, "%s is %dx%d, %s is %dx%d: not shards of one render", in[0].path, in[0].width,
                    in[0].height, in[i].path, in[i].width, in[i].height);
            goto fail;
        }
        for (int a = 0; a < CHECKED; a++)
            if (strcmp(in[i].checked[a], in[0].checked[a])) {
                sg_fail(err, "%s has %s '%s', %s has '%s': not shards of one render", in[0].path, checked[a],
                        in[0].checked[a], in[i].path, in[i].checked[a]);
                goto fail;
            }
    }
    int shards = atoi(in[0].checked[2]);
    held = calloc((size_t)shards, sizeof *held);
    int *owner = calloc((size_t)shards, sizeof *owner);
    if (!held || !owner) {
        free(owner);
        sg_fail(err, "out of memory");
        goto fail;
    }
    for (int i = 0; i < count; i++)
        for (int k = 0; k < shards; k++)
            if (in[i].shards[k]) {
                if (held[k]) {
                    sg_fail(err, "%s and %s both hold shard %d of %d", in[owner[k]].path, in[i].path, k, shards);
                    free(owner);
                    goto fail;
                }
                held[k] = 1;
                owner[k] = i;
            }
    free(owner);
    char *p = m->missing;
    for (int k = 0; k < shards; k++)
        if (!held[k]) {
            if ((size_t)(p - m->missing) < sizeof m->missing - 16)
                p += snprintf(p, sizeof m->missing - (size_t)(p - m->missing), "%s%d", p == m->missing ? "" : ",", k);
            else if (p[-1] != '.')
                p += snprintf(p, sizeof m->missing - (size_t)(p - m->missing), "...");
        } else {
            m->held++;
        }
    if (m->missing[0] && !partial) {
        sg_fail(err, "shards %s of %d are missing (%d given): --partial merges what is there", m->missing, shards,
                m->held);
        goto fail;
    }

    /* the spp-weighted mean, in double, summed in shard order (the same
     * result whatever order the files were given in) */
    qsort(in, (size_t)count, sizeof *in, by_first_shard);
    size_t values = (size_t)in[0].width * in[0].height * 3;
    sum = calloc(values, sizeof *sum);
    m->rgb = malloc(values * sizeof *m->rgb);
    if (!sum || !m->rgb) {
        sg_fail(err, "out of memory for a %dx%d image", in[0].width, in[0].height);
        goto fail;
    }
    double share = 0;
    bool all_share = true;
    uint64_t nonfinite = 0;
    for (int i = 0; i < count; i++) {
        double w = (double)in[i].spp;
        for (size_t v = 0; v < values; v++)
            sum[v] += w * in[i].rgb[v];
        m->spp += in[i].spp;
        m->seconds += in[i].seconds;
        nonfinite += in[i].nonfinite;
        share += w * in[i].guide_share;
        all_share = all_share && in[i].has_guide_share;
    }
    for (size_t v = 0; v < values; v++)
        m->rgb[v] = (float)(sum[v] / (double)m->spp);
    m->width = in[0].width;
    m->height = in[0].height;
    m->shard_count = shards;

    char buf[64];
    snprintf(buf, sizeof buf, "%ld", m->spp);
    add_attribute(m, "spp", buf);
    snprintf(buf, sizeof buf, "%.3f", m->seconds);
    add_attribute(m, "seconds", buf);
    for (int a = 0; a < CHECKED; a++)
        add_attribute(m, checked[a], in[0].checked[a]);
    m->shard_list = shard_list(held, shards);
    if (!m->shard_list) {
        sg_fail(err, "out of memory");
        goto fail;
    }
    m->attrs[m->attr_count++] = (SgImageAttribute){"sg:shards", m->shard_list};
    snprintf(buf, sizeof buf, "%llu", (unsigned long long)nonfinite);
    add_attribute(m, "sg:nonfinite_samples", buf);
    if (all_share) {
        snprintf(buf, sizeof buf, "%.4f", share / (double)m->spp);
        add_attribute(m, "sg:guide_share", buf);
    }
    for (int a = 0; a < COPIED; a++) {
        bool same = in[0].has_copied[a];
        for (int i = 1; i < count && same; i++)
            same = in[i].has_copied[a] && !strcmp(in[i].copied[a], in[0].copied[a]);
        if (same) {
            add_attribute(m, copied[a], in[0].copied[a]);
            if (!strcmp(copied[a], "sg:exposure"))
                m->exposure = atof(in[0].copied[a]);
        }
    }
    for (int i = 0; i < count; i++)
        input_free(&in[i]);
    free(in);
    free(held);
    free(sum);
    return m;

fail:
    if (in)
        for (int i = 0; i < count; i++)
            input_free(&in[i]);
    free(in);
    free(held);
    free(sum);
    sg_merged_free(m);
    return NULL;
}

void sg_merged_free(SgMerged *m)
{
    if (!m)
        return;
    free(m->rgb);
    free(m->shard_list);
    free(m);
}

int sg_merged_width(const SgMerged *m) { return m->width; }
int sg_merged_height(const SgMerged *m) { return m->height; }
const float *sg_merged_rgb(const SgMerged *m) { return m->rgb; }
long sg_merged_spp(const SgMerged *m) { return m->spp; }
double sg_merged_seconds(const SgMerged *m) { return m->seconds; }
int sg_merged_shards_held(const SgMerged *m) { return m->held; }
int sg_merged_shard_count(const SgMerged *m) { return m->shard_count; }
const char *sg_merged_missing(const SgMerged *m) { return m->missing; }
double sg_merged_exposure(const SgMerged *m) { return m->exposure; }

bool sg_merged_write(const SgMerged *m, const char *exr, const char *png, double exposure, SgError *err)
{
    /* the EXR last, as render does: it is what make and the farm wait for */
    if (png && !sg_image_write_png(png, m->width, m->height, m->rgb, exposure, err))
        return false;
    return sg_image_write_exr(exr, m->width, m->height, m->rgb, m->attrs, m->attr_count, err);
}
