#include "merge.h"

#include <limits.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "output_file.h"
#include "shard_format.h"

/* What every input must have and agree on: a merge of different renders is
 * no render. */
static const char *const checked[] = {SG_ATTR_SAMPLING,   SG_ATTR_SEED,       SG_ATTR_SHARD_COUNT,
                                      SG_ATTR_SCENE_HASH, SG_ATTR_CACHE_HASH, SG_ATTR_RECIPE};
#define CHECKED (int)(sizeof checked / sizeof checked[0])

typedef struct Input {
    const char *path;
    SgImageAttribute *attrs; /* its header, one allocation */
    int attr_count;
    long spp, nonfinite;
    double seconds, guide_share;
    bool has_seconds, has_nonfinite, has_guide_share;
    int first;  /* its lowest shard index: the order of the sum */
    char *held; /* per shard index: 1 where it holds that shard */
} Input;

struct SgMerged {
    int width, height, shard_count, held;
    float *rgb;
    long spp;
    double seconds, exposure;
    char missing[1024];
    SgImageAttribute *attrs; /* each name and value malloc'ed */
    int attr_count;
};

static const char *find(const Input *in, const char *name)
{
    for (int i = 0; i < in->attr_count; i++)
        if (!strcmp(in->attrs[i].name, name))
            return in->attrs[i].value;
    return NULL;
}

static const char *required(const Input *in, const char *name, SgError *err)
{
    const char *v = find(in, name);
    if (!v)
        sg_fail(err, "%s: not a render shard (no %s attribute)", in->path, name);
    return v;
}

static void input_free(Input *in)
{
    free(in->attrs);
    free(in->held);
}

/* sg:shards ("0,1,3") into in->held. */
static bool parse_shards(Input *in, const char *list, int count, SgError *err)
{
    char *copy = strdup(list), *save = NULL;
    in->held = calloc((size_t)count, 1);
    if (!copy || !in->held) {
        free(copy);
        return sg_fail(err, "%s: out of memory", in->path);
    }
    bool ok = true;
    in->first = -1;
    for (char *tok = strtok_r(copy, ",", &save); tok && ok; tok = strtok_r(NULL, ",", &save)) {
        long k;
        if (!sg_parse_long(tok, 0, LONG_MAX, &k))
            ok = sg_fail(err, "%s: " SG_ATTR_SHARDS " holds '%s', not a shard index", in->path, tok);
        else if (k >= count)
            ok = sg_fail(err, "%s: " SG_ATTR_SHARDS " holds shard %ld, not below " SG_ATTR_SHARD_COUNT " %d", in->path, k, count);
        else if (in->held[k])
            ok = sg_fail(err, "%s: " SG_ATTR_SHARDS " names shard %ld twice", in->path, k);
        else {
            in->held[k] = 1;
            if (in->first < 0 || k < in->first)
                in->first = (int)k;
        }
    }
    free(copy);
    if (ok && in->first < 0)
        ok = sg_fail(err, "%s: " SG_ATTR_SHARDS " is empty", in->path);
    return ok;
}

/* An input's header: what makes it a shard, and the numbers merge adds up.
 * The pixels are read later, one input at a time. */
static bool input_read(Input *in, const char *path, SgError *err)
{
    memset(in, 0, sizeof *in);
    in->path = path;
    if (!sg_image_read_attributes(path, &in->attrs, &in->attr_count, err))
        return false;
    /* what says "ours" first, so that another EXR is named as such */
    const char *shards = required(in, SG_ATTR_SHARDS, err);
    if (!shards || !required(in, SG_ATTR_SHARD_COUNT, err) || !required(in, SG_ATTR_RECIPE, err))
        return false;
    for (int a = 0; a < CHECKED; a++)
        if (!required(in, checked[a], err))
            return false;
    const char *spp = required(in, SG_ATTR_SPP, err);
    if (!spp)
        return false;
    long count;
    const char *count_s = find(in, SG_ATTR_SHARD_COUNT);
    if (!sg_parse_long(count_s, 1, SG_SHARDS_MAX, &count))
        return sg_fail(err, "%s: " SG_ATTR_SHARD_COUNT " '%s' is not a shard count (1 to %d)", path, count_s, SG_SHARDS_MAX);
    if (!parse_shards(in, shards, (int)count, err))
        return false;
    /* at most 2^40 a shard: the sums below cannot overflow */
    if (!sg_parse_long(spp, LONG_MIN, LONG_MAX, &in->spp) || in->spp > 1L << 40)
        return sg_fail(err, "%s: spp '%s' is not a sample count", path, spp);
    if (in->spp <= 0)
        return sg_fail(err, "%s: spp %ld: a shard holds at least one sample per pixel", path, in->spp);
    const char *v;
    if ((v = find(in, SG_ATTR_SECONDS))) {
        if (!sg_parse_double(v, 0, 1e300, &in->seconds))
            return sg_fail(err, "%s: seconds '%s' is not a time", path, v);
        in->has_seconds = true;
    }
    if ((v = find(in, SG_ATTR_NONFINITE_SAMPLES))) {
        if (!sg_parse_long(v, 0, LONG_MAX / SG_SHARDS_MAX, &in->nonfinite))
            return sg_fail(err, "%s: " SG_ATTR_NONFINITE_SAMPLES " '%s' is not a count", path, v);
        in->has_nonfinite = true;
    }
    if ((v = find(in, SG_ATTR_GUIDE_SHARE))) {
        if (!sg_parse_double(v, 0, 1, &in->guide_share))
            return sg_fail(err, "%s: " SG_ATTR_GUIDE_SHARE " '%s' is not a share", path, v);
        in->has_guide_share = true;
    }
    return true;
}

static int by_first_shard(const void *a, const void *b)
{
    const Input *x = a, *y = b;
    return (x->first > y->first) - (x->first < y->first);
}

static bool add_attribute(SgMerged *m, const char *name, const char *value, SgError *err)
{
    SgImageAttribute *grown = realloc(m->attrs, (size_t)(m->attr_count + 1) * sizeof *grown);
    if (!grown)
        return sg_fail(err, "out of memory");
    m->attrs = grown;
    char *n = strdup(name), *v = strdup(value);
    if (!n || !v) {
        free(n);
        free(v);
        return sg_fail(err, "out of memory");
    }
    m->attrs[m->attr_count++] = (SgImageAttribute){n, v};
    return true;
}

/* "0,1,3": the shards held, ascending (the form render writes). */
static char *shard_list(const char *held, int count)
{
    size_t cap = (size_t)count * 7 + 1, n = 0;
    char *s = malloc(cap);
    if (!s)
        return NULL;
    s[0] = 0;
    for (int k = 0; k < count; k++)
        if (held[k])
            n += (size_t)snprintf(s + n, cap - n, "%s%d", n ? "," : "", k);
    return s;
}

/* m->missing ("0,2", cut with "..." when long) and m->held; the number missing. */
static int list_missing(SgMerged *m, const char *held, int count)
{
    size_t n = 0, cap = sizeof m->missing;
    int missing = 0;
    for (int k = 0; k < count; k++) {
        if (held[k]) {
            m->held++;
            continue;
        }
        if (missing++ == 0 || n + 16 < cap)
            n += (size_t)snprintf(m->missing + n, cap - n, "%s%d", n ? "," : "", k);
        else if (m->missing[n - 1] != '.')
            n += (size_t)snprintf(m->missing + n, cap - n, ",...");
    }
    return missing;
}

/* Checks that the inputs are shards of one render and that each shard is
 * held once; fills m->missing, m->held, m->shard_count and `held`. */
static bool check_inputs(SgMerged *m, const Input *in, int count, bool partial, char **held, SgError *err)
{
    for (int i = 1; i < count; i++)
        for (int a = 0; a < CHECKED; a++) {
            const char *x = find(&in[0], checked[a]), *y = find(&in[i], checked[a]);
            if (strcmp(x, y))
                return sg_fail(err, "%s has %s '%s', %s has '%s': not shards of one render", in[0].path, checked[a],
                               x, in[i].path, y);
        }
    int shards = m->shard_count = atoi(find(&in[0], SG_ATTR_SHARD_COUNT));
    int *owner = malloc((size_t)shards * sizeof *owner);
    *held = calloc((size_t)shards, 1);
    if (!owner || !*held) {
        free(owner);
        return sg_fail(err, "out of memory");
    }
    for (int i = 0; i < count; i++)
        for (int k = 0; k < shards; k++)
            if (in[i].held[k]) {
                if ((*held)[k]) {
                    sg_fail(err, "%s and %s both hold shard %d of %d", in[owner[k]].path, in[i].path, k, shards);
                    free(owner);
                    return false;
                }
                (*held)[k] = 1;
                owner[k] = i;
            }
    free(owner);
    int missing = list_missing(m, *held, shards);
    if (missing && !partial)
        return sg_fail(err, "shard%s %s of %d %s missing (%d of %d given): --partial merges what is there",
                       missing == 1 ? "" : "s", m->missing, shards, missing == 1 ? "is" : "are", m->held, shards);
    return true;
}

/* The spp-weighted mean, in double, summed in shard order (in is sorted):
 * the same floats whatever order the files were given in. One input's
 * pixels are in memory at a time. */
static bool weighted_mean(SgMerged *m, const Input *in, int count, SgError *err)
{
    double *sum = NULL;
    size_t values = 0;
    bool ok = true;
    for (int i = 0; i < count && ok; i++) {
        int w, h;
        float *rgb;
        if (!sg_image_read(in[i].path, &w, &h, &rgb, err)) {
            ok = false;
            break;
        }
        if (i == 0) {
            m->width = w;
            m->height = h;
            values = (size_t)w * (size_t)h * 3;
            sum = calloc(values, sizeof *sum);
            if (!sum)
                ok = sg_fail(err, "out of memory for a %dx%d image", w, h);
        } else if (w != m->width || h != m->height) {
            ok = sg_fail(err, "%s has size %dx%d, %s has %dx%d: not shards of one render", in[0].path, m->width,
                         m->height, in[i].path, w, h);
        }
        double weight = (double)in[i].spp;
        for (size_t v = 0; ok && v < values; v++)
            sum[v] += weight * (double)rgb[v];
        free(rgb);
        m->spp += in[i].spp;
    }
    if (ok) {
        m->rgb = malloc(values * sizeof *m->rgb);
        if (!m->rgb)
            ok = sg_fail(err, "out of memory for a %dx%d image", m->width, m->height);
        for (size_t v = 0; ok && v < values; v++)
            m->rgb[v] = (float)(sum[v] / (double)m->spp);
    }
    free(sum);
    return ok;
}

/* The merged image's attributes, in render's order for the first four, then
 * the first input's sg: attributes in its order. */
static bool merged_attributes(SgMerged *m, const Input *in, int count, const char *held, SgError *err)
{
    bool all_seconds = true, all_nonfinite = true, all_share = true;
    long nonfinite = 0;
    double share = 0;
    for (int i = 0; i < count; i++) {
        all_seconds = all_seconds && in[i].has_seconds;
        all_nonfinite = all_nonfinite && in[i].has_nonfinite;
        all_share = all_share && in[i].has_guide_share;
        m->seconds += in[i].seconds;
        nonfinite += in[i].nonfinite;
        share += (double)in[i].spp * in[i].guide_share;
    }
    char buf[64];
    snprintf(buf, sizeof buf, "%ld", m->spp);
    if (!add_attribute(m, SG_ATTR_SPP, buf, err))
        return false;
    snprintf(buf, sizeof buf, "%.3f", m->seconds);
    if (all_seconds && !add_attribute(m, SG_ATTR_SECONDS, buf, err))
        return false;
    if (!add_attribute(m, SG_ATTR_SAMPLING, find(&in[0], SG_ATTR_SAMPLING), err) ||
        !add_attribute(m, SG_ATTR_SEED, find(&in[0], SG_ATTR_SEED), err))
        return false;
    for (int a = 0; a < in[0].attr_count; a++) {
        const char *name = in[0].attrs[a].name, *value = in[0].attrs[a].value;
        if (strncmp(name, SG_ATTR_PREFIX, sizeof SG_ATTR_PREFIX - 1))
            continue; /* spp... above; the rest is the file format's */
        bool ok = true;
        if (!strcmp(name, SG_ATTR_SHARDS)) {
            char *list = shard_list(held, m->shard_count);
            ok = list ? add_attribute(m, name, list, err) : sg_fail(err, "out of memory");
            free(list);
        } else if (!strcmp(name, SG_ATTR_NONFINITE_SAMPLES)) {
            snprintf(buf, sizeof buf, "%ld", nonfinite);
            ok = !all_nonfinite || add_attribute(m, name, buf, err);
        } else if (!strcmp(name, SG_ATTR_GUIDE_SHARE)) {
            /* two digits more than render writes: merged images merge again */
            snprintf(buf, sizeof buf, "%.6f", share / (double)m->spp);
            ok = !all_share || add_attribute(m, name, buf, err);
        } else {
            /* copied where all agree (the checked ones do by now) */
            bool same = true;
            for (int i = 1; i < count && same; i++) {
                const char *other = find(&in[i], name);
                same = other && !strcmp(other, value);
            }
            ok = !same || add_attribute(m, name, value, err);
            if (same && !strcmp(name, SG_ATTR_EXPOSURE) && !sg_parse_double(value, -100, 100, &m->exposure))
                m->exposure = 0;
        }
        if (!ok)
            return false;
    }
    return true;
}

SgMerged *sg_merge_files(const char *const *paths, int count, bool partial, SgError *err)
{
    if (count < 1)
        return sg_fail(err, "no shard given"), NULL;
    Input *in = calloc((size_t)count, sizeof *in);
    SgMerged *m = calloc(1, sizeof *m);
    char *held = NULL;
    bool ok = in && m;
    if (!ok)
        sg_fail(err, "out of memory");
    for (int i = 0; ok && i < count; i++)
        ok = input_read(&in[i], paths[i], err);
    ok = ok && check_inputs(m, in, count, partial, &held, err);
    if (ok)
        qsort(in, (size_t)count, sizeof *in, by_first_shard);
    ok = ok && weighted_mean(m, in, count, err) && merged_attributes(m, in, count, held, err);
    if (in)
        for (int i = 0; i < count; i++)
            input_free(&in[i]);
    free(in);
    free(held);
    if (ok)
        return m;
    sg_merged_free(m); /* nothing half-merged leaves */
    return NULL;
}

void sg_merged_free(SgMerged *m)
{
    if (!m)
        return;
    for (int i = 0; i < m->attr_count; i++) {
        free((char *)m->attrs[i].name); /* ours: add_attribute's copies */
        free((char *)m->attrs[i].value);
    }
    free(m->attrs);
    free(m->rgb);
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

const SgImageAttribute *sg_merged_attributes(const SgMerged *m, int *count)
{
    *count = m->attr_count;
    return m->attrs;
}

/* The image writers name the temporary file they were given: say the
 * target instead. */
static bool fail_as(SgError *err, const SgError *e, const char *tmp, const char *path)
{
    size_t n = strlen(tmp);
    if (!strncmp(e->message, tmp, n))
        return sg_fail(err, "%s%s", path, e->message + n);
    return sg_fail(err, "%s: %s", path, e->message);
}

bool sg_merged_write(const SgMerged *m, const char *exr, const char *png, double exposure, SgError *err)
{
    char exr_tmp[4096], png_tmp[4096];
    SgError e = {0};
    sg_temp_path(exr, exr_tmp, sizeof exr_tmp);
    if (png) {
        sg_temp_path(png, png_tmp, sizeof png_tmp);
        if (!sg_image_write_png(png_tmp, m->width, m->height, m->rgb, exposure, &e))
            return fail_as(err, &e, png_tmp, png);
    }
    if (!sg_image_write_exr(exr_tmp, m->width, m->height, m->rgb, m->attrs, m->attr_count, &e)) {
        if (png)
            remove(png_tmp);
        return fail_as(err, &e, exr_tmp, exr);
    }
    if (png && !sg_commit_temp(png_tmp, png, err)) {
        remove(exr_tmp);
        return false;
    }
    return sg_commit_temp(exr_tmp, exr, err);
}
