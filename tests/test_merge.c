/* bin/merge (merge/merge.h) on synthetic shards written here: the
 * spp-weighted mean bit for bit, order independence, associativity, the
 * merged attributes, the PNG's exposure, --partial, and every refusal with
 * exit status 1, one line naming the files, and no output (an existing file
 * left as it was). Each check also shows that it could fail: the weights,
 * the order and the guide-share weighting make a difference on its data. */
#include <criterion/criterion.h>
#include <dirent.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "image_io.h"
#include "merge/merge.h"
#include "support_files.h"

#define W 16
#define H 9
#define N (W * H * 3)

/* One shard's EXR: what render writes, each field overridable. */
typedef struct ShardSpec {
    const char *shards; /* sg:shards; NULL: "k" */
    int count;          /* sg:shard_count */
    const char *spp;    /* NULL: from the default table */
    const char *sampling, *seed, *scene_hash, *cache_hash, *recipe, *exposure;
    const char *guide_share, *nonfinite, *training_seconds;
    int width;
    const char *omit; /* an attribute left out */
} ShardSpec;

static const long spp4[4] = {3, 5, 2, 6}; /* four shards' spp: unequal, so the weights show */

/* Deterministic pixels (the test's own generator, no global state). */
static float next_value(uint64_t *state, int i)
{
    *state = *state * 6364136223846793005ull + 1442695040888963407ull;
    float u = (float)((*state >> 40) & 0xffffff) / 16777216.0f;
    return u * (i % 5 == 0 ? 100.0f : 1.0f); /* some bright values: a range of exponents */
}

static void random_pixels(float *px, int n, uint64_t seed)
{
    uint64_t s = seed * 0x9e3779b97f4a7c15ull + 1;
    for (int i = 0; i < n; i++)
        px[i] = next_value(&s, i);
}

static char *write_shard(const char *dir, const char *name, int k, ShardSpec s, const float *px)
{
    char spp[32], count[32], shard[32], seconds[32], share[32], nonfinite[32], training[32];
    long spp_value = k < 4 ? spp4[k] : 4;
    snprintf(spp, sizeof spp, "%ld", spp_value);
    snprintf(count, sizeof count, "%d", s.count ? s.count : 4);
    snprintf(shard, sizeof shard, "%d", k);
    snprintf(seconds, sizeof seconds, "%.3f", 0.25 * spp_value);
    snprintf(share, sizeof share, "%.4f", 0.1 * (k + 1));
    snprintf(nonfinite, sizeof nonfinite, "%d", k + 1);
    snprintf(training, sizeof training, "%.3f", 0.01 * (k + 1));
    SgImageAttribute all[] = {
        {"spp", s.spp ? s.spp : spp},
        {"seconds", seconds},
        {"sampling", s.sampling ? s.sampling : "guided"},
        {"seed", s.seed ? s.seed : "7"},
        {"sg:max_depth", "8"},
        {"sg:roulette", "learned"},
        {"sg:nonfinite_samples", s.nonfinite ? s.nonfinite : nonfinite},
        {"sg:guide_share", s.guide_share ? s.guide_share : share},
        {"sg:training_seconds", s.training_seconds ? s.training_seconds : training},
        {"sg:exposure", s.exposure ? s.exposure : "2"},
        {"sg:shards", s.shards ? s.shards : shard},
        {"sg:shard_count", count},
        {"sg:scene_hash", s.scene_hash ? s.scene_hash : "00000000000000aa"},
        {"sg:cache_hash", s.cache_hash ? s.cache_hash : "00000000000000bb"},
        {"sg:recipe", s.recipe ? s.recipe : "00000000000000cc"},
    };
    SgImageAttribute attrs[sizeof all / sizeof all[0]];
    int n = 0;
    for (size_t i = 0; i < sizeof all / sizeof all[0]; i++)
        if (!s.omit || strcmp(all[i].name, s.omit))
            attrs[n++] = all[i];
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    int width = s.width ? s.width : W;
    float *own = NULL;
    if (!px) { /* any pixels of the right size */
        own = malloc((size_t)width * H * 3 * sizeof *own);
        random_pixels(own, width * H * 3, 1000 + (uint64_t)k);
        px = own;
    }
    SgError err = {0};
    cr_assert(sg_image_write_exr(path, width, H, px, attrs, n, &err), "%s", err.message);
    free(own);
    return strdup(path);
}

/* Four shards of one render in dir, spp spp4: paths[k] holds shard k, px[k] its pixels. */
static void four_shards(const char *dir, char *paths[4], float px[4][N])
{
    for (int k = 0; k < 4; k++) {
        char name[32];
        snprintf(name, sizeof name, "s%d.exr", k);
        random_pixels(px[k], N, (uint64_t)k);
        paths[k] = write_shard(dir, name, k, (ShardSpec){0}, px[k]);
    }
}

static void free_paths(char *paths[], int n)
{
    for (int i = 0; i < n; i++)
        free(paths[i]);
}

static void remove_dir(const char *dir)
{
    char cmd[4200];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    cr_assert_eq(system(cmd), 0);
}

/* Most tests' start: four shards (four_shards) in a fresh folder, which it
 * returns... */
static float shard_px[4][N]; /* their pixels (each test runs in a process of its own) */
static const char *four_shards_in_a_folder(char *paths[4])
{
    const char *dir = sg_test_tmpdir();
    four_shards(dir, paths, shard_px);
    return dir;
}

/* ...with out = FOLDER/out.exr. */
static const char *four_shards_and_out(char *paths[4], char out[4096])
{
    const char *dir = four_shards_in_a_folder(paths);
    snprintf(out, 4096, "%s/out.exr", dir);
    return dir;
}

/* ...and their end: the paths freed, the folder removed. */
static void done(const char *dir, char *paths[4])
{
    free_paths(paths, 4);
    remove_dir(dir);
}

/* The formula, as the test knows it: in double, shards in ascending order,
 * rounded to float. */
static float expected_value(float px[4][N], const int *shards, int n, int i)
{
    double sum = 0, spp = 0;
    for (int j = 0; j < n; j++) {
        sum += (double)spp4[shards[j]] * (double)px[shards[j]][i];
        spp += (double)spp4[shards[j]];
    }
    return (float)(sum / spp);
}

/* Runs bin/merge with args; returns its exit status and its stderr in err. */
static int run_merge(const char *args, char *err, size_t size)
{
    char bin[4096], cmd[16384 + 4096 + 2];
    sg_test_program("merge", bin, sizeof bin);
    snprintf(cmd, sizeof cmd, "%s %s", bin, args);
    return sg_test_run(cmd, err, size);
}

/* bin/merge with the arguments given (printf-style), which must succeed;
 * its stderr in err. */
static void merge_ok(char err[2048], const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void merge_ok(char err[2048], const char *fmt, ...)
{
    char args[16384];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(args, sizeof args, fmt, ap);
    va_end(ap);
    cr_assert_eq(run_merge(args, err, 2048), 0, "%s: %s", args, err);
}

static float *read_image(const char *path)
{
    int w = 0, h = 0;
    float *rgb = NULL;
    SgError err = {0};
    cr_assert(sg_image_read(path, &w, &h, &rgb, &err), "%s", err.message);
    cr_assert(w == W && h == H, "%s is %dx%d", path, w, h);
    return rgb;
}

/* An attribute of an image, or NULL without it (a ring of static buffers). */
static const char *attribute(const char *path, const char *name)
{
    static char ring[8][512];
    static int next;
    char *buf = ring[next++ % 8];
    SgError err = {0};
    return sg_image_read_attribute(path, name, buf, 512, &err) ? buf : NULL;
}

Test(merge, the_spp_weighted_mean_bit_for_bit)
{
    char *p[4], err[2048], out[4096];
    const char *dir = four_shards_and_out(p, out);
    merge_ok(err, "%s %s %s %s -o %s --quiet", p[2], p[0], p[3], p[1], out);
    float *got = read_image(out);
    const int all[4] = {0, 1, 2, 3};
    int wrong = 0, unweighted_same = 0;
    for (int i = 0; i < N; i++) {
        float want = expected_value(shard_px, all, 4, i);
        wrong += memcmp(&got[i], &want, sizeof want) != 0;
        float plain = (float)(((double)shard_px[0][i] + shard_px[1][i] + shard_px[2][i] + shard_px[3][i]) / 4.0);
        unweighted_same += plain == want;
    }
    cr_assert_eq(wrong, 0, "%d of %d values are not the spp-weighted mean bit for bit", wrong, N);
    cr_assert_lt(unweighted_same, N / 10, "an unweighted mean would pass too: the test could not see the weights");
    free(got);
    done(dir, p);
}

Test(merge, the_order_the_files_are_given_in_does_not_matter)
{
    /* Pixels where the order of the double sum changes the float: a big
     * value, a small one, and the big one's negative (cancellation). */
    const char *dir = sg_test_tmpdir();
    static float px[4][N];
    char *p[4];
    for (int k = 0; k < 4; k++)
        random_pixels(px[k], N, 50 + (uint64_t)k);
    for (int i = 0; i < N; i += 4) {
        px[0][i] = 0x1p60f;                     /* 3 * 2^60 */
        px[1][i] = 1.0f + (float)(i % 7);       /* lost against 2^60 in double */
        px[2][i] = -1.5f * 0x1p60f;             /* -3 * 2^60 */
        px[3][i] = (float)(i % 3);
    }
    for (int k = 0; k < 4; k++) {
        char name[32];
        snprintf(name, sizeof name, "s%d.exr", k);
        p[k] = write_shard(dir, name, k, (ShardSpec){0}, px[k]);
    }
    const int orders[3][4] = {{0, 1, 2, 3}, {2, 0, 3, 1}, {3, 2, 1, 0}};
    const int all[4] = {0, 1, 2, 3};
    int order_matters = 0;
    for (int o = 0; o < 3; o++) {
        char err[2048], out[4096];
        snprintf(out, sizeof out, "%s/out%d.exr", dir, o);
        const int *q = orders[o];
        merge_ok(err, "%s %s %s %s -o %s --quiet", p[q[0]], p[q[1]], p[q[2]], p[q[3]], out);
        float *got = read_image(out);
        int wrong = 0;
        for (int i = 0; i < N; i++) {
            float want = expected_value(px, all, 4, i);
            wrong += memcmp(&got[i], &want, sizeof want) != 0;
            order_matters += expected_value(px, q, 4, i) != want;
        }
        cr_assert_eq(wrong, 0, "given as %d %d %d %d: %d values differ from the sum in shard order", q[0], q[1],
                     q[2], q[3], wrong);
        free(got);
    }
    cr_assert_gt(order_matters, 0, "summing in the given order would pass too: the test could not see the order");
    /* the library, files given backwards: the same floats */
    const char *backwards[4] = {p[3], p[2], p[1], p[0]};
    SgError e = {0};
    SgMerged *m = sg_merge_files(backwards, 4, false, &e);
    cr_assert_not_null(m, "%s", e.message);
    for (int i = 0; i < N; i++) {
        float want = expected_value(px, all, 4, i);
        cr_assert(memcmp(&sg_merged_rgb(m)[i], &want, sizeof want) == 0, "value %d: %.9g, not %.9g", i,
                  sg_merged_rgb(m)[i], want);
    }
    sg_merged_free(m);
    done(dir, p);
}

Test(merge, merging_merged_images_is_the_same_merge)
{
    char *p[4], args[16384], err[2048], ab[4096], cd[4096], ac[4096], all[4096], regrouped[4096], direct[4096];
    const char *dir = four_shards_in_a_folder(p);
    snprintf(ab, sizeof ab, "%s/ab.exr", dir);
    snprintf(cd, sizeof cd, "%s/cd.exr", dir);
    snprintf(ac, sizeof ac, "%s/ac.exr", dir);
    snprintf(all, sizeof all, "%s/all.exr", dir);
    snprintf(regrouped, sizeof regrouped, "%s/regrouped.exr", dir);
    snprintf(direct, sizeof direct, "%s/direct.exr", dir);
    merge_ok(err, "%s %s -o %s --partial --quiet", p[0], p[1], ab);
    merge_ok(err, "%s %s -o %s --partial --quiet", p[2], p[3], cd);
    snprintf(args, sizeof args, "%s %s -o %s --partial --quiet", p[2], p[0], ac); /* interleaved: 0,2 */
    cr_assert_eq(run_merge(args, err, sizeof err), 0, "%s", err);
    cr_assert_str_eq(attribute(ac, "sg:shards"), "0,2");
    merge_ok(err, "%s %s -o %s --quiet", cd, ab, all);
    merge_ok(err, "%s %s %s -o %s --quiet", p[3], ac, p[1], regrouped);
    merge_ok(err, "%s %s %s %s -o %s --quiet", p[0], p[1], p[2], p[3], direct);
    float *want = read_image(direct);
    const char *merged[2] = {all, regrouped};
    for (int j = 0; j < 2; j++) {
        float *got = read_image(merged[j]);
        double worst = 0;
        for (int i = 0; i < N; i++)
            worst = fmax(worst, fabs((double)got[i] - want[i]) / fmax(1e-30, fabs((double)want[i])));
        cr_log_info("%s against merge(a,b,c,d): worst relative difference %.3g", merged[j], worst);
        cr_assert_lt(worst, 1e-6, "%s: relative difference %.3g", merged[j], worst);
        free(got);
        const char *same[] = {"spp", "seconds", "sg:shards", "sg:shard_count", "sg:nonfinite_samples", "sg:recipe",
                              "sg:max_depth"};
        for (size_t a = 0; a < sizeof same / sizeof same[0]; a++) {
            const char *x = attribute(merged[j], same[a]), *y = attribute(direct, same[a]);
            cr_assert(x && y && !strcmp(x, y), "%s: %s '%s', merged at once '%s'", merged[j], same[a],
                      x ? x : "(none)", y ? y : "(none)");
        }
        /* a mean of rounded means: the same to the digits written */
        const char *x = attribute(merged[j], "sg:guide_share"), *y = attribute(direct, "sg:guide_share");
        cr_assert(x && y && fabs(atof(x) - atof(y)) < 2e-6, "%s: sg:guide_share %s, merged at once %s", merged[j],
                  x ? x : "(none)", y ? y : "(none)");
    }
    cr_assert_str_eq(attribute(all, "spp"), "16");
    cr_assert_str_eq(attribute(all, "sg:shards"), "0,1,2,3");
    free(want);
    done(dir, p);
}

Test(merge, the_merged_attributes)
{
    char *p[4], err[2048], out[4096];
    const char *dir = four_shards_and_out(p, out);
    merge_ok(err, "%s %s %s %s -o %s", p[1], p[3], p[0], p[2], out);
    /* summed: spp, seconds (0.25 s a sample), NaN/inf samples (1+2+3+4) */
    cr_assert_str_eq(attribute(out, "spp"), "16");
    cr_assert_str_eq(attribute(out, "seconds"), "4.000");
    cr_assert_str_eq(attribute(out, "sg:nonfinite_samples"), "10");
    /* the union of the shards, of the same count */
    cr_assert_str_eq(attribute(out, "sg:shards"), "0,1,2,3");
    cr_assert_str_eq(attribute(out, "sg:shard_count"), "4");
    /* the guide's share weighted by spp (0.1 .. 0.4): 0.26875, not the plain 0.25 */
    char share[32];
    snprintf(share, sizeof share, "%.6f", (3 * 0.1 + 5 * 0.2 + 2 * 0.3 + 6 * 0.4) / 16);
    cr_assert_str_eq(attribute(out, "sg:guide_share"), share);
    cr_assert_str_neq(share, "0.250000");
    /* what all share, as it is; what differs (training seconds), dropped */
    const char *kept[][2] = {{"sampling", "guided"},
                             {"seed", "7"},
                             {"sg:max_depth", "8"},
                             {"sg:roulette", "learned"},
                             {"sg:exposure", "2"},
                             {"sg:scene_hash", "00000000000000aa"},
                             {"sg:cache_hash", "00000000000000bb"},
                             {"sg:recipe", "00000000000000cc"}};
    for (size_t a = 0; a < sizeof kept / sizeof kept[0]; a++) {
        const char *v = attribute(out, kept[a][0]);
        cr_assert(v && !strcmp(v, kept[a][1]), "%s: '%s', not '%s'", kept[a][0], v ? v : "(none)", kept[a][1]);
    }
    cr_assert_null(attribute(out, "sg:training_seconds"), "an attribute the shards disagree on was kept");
    /* the summary line: one, with the counts */
    char line[4200];
    snprintf(line, sizeof line, "merge: 4 files, 4 of 4 shards, %dx%d, 16 spp, 4.0 s of rendering -> %s\n", W, H,
             out);
    cr_assert_str_eq(err, line);
    /* --quiet: nothing */
    merge_ok(err, "%s %s %s %s -o %s --quiet", p[1], p[3], p[0], p[2], out);
    cr_assert_str_eq(err, "");
    /* the same through the library */
    SgError e = {0};
    SgMerged *m = sg_merge_files((const char *const *)p, 4, false, &e);
    cr_assert_not_null(m, "%s", e.message);
    int count;
    const SgImageAttribute *a = sg_merged_attributes(m, &count);
    cr_assert(count >= 4 && !strcmp(a[0].name, "spp") && !strcmp(a[0].value, "16"));
    cr_assert_eq(sg_merged_spp(m), 16);
    cr_assert_float_eq(sg_merged_seconds(m), 4.0, 1e-9);
    cr_assert_float_eq(sg_merged_exposure(m), 2.0, 0);
    sg_merged_free(m);
    done(dir, p);
}

Test(merge, partial_merges_what_is_there_and_says_so)
{
    char *p[4], err[2048], out[4096];
    const char *dir = four_shards_and_out(p, out);
    /* the warning is said with --quiet too, and nothing else */
    merge_ok(err, "%s %s -o %s --partial --quiet", p[2], p[0], out);
    cr_assert_str_eq(err, "merge: merged 2 of 4 shards (missing 1,3)\n");
    cr_assert_str_eq(attribute(out, "sg:shards"), "0,2");
    cr_assert_str_eq(attribute(out, "sg:shard_count"), "4");
    cr_assert_str_eq(attribute(out, "spp"), "5");
    float *got = read_image(out);
    const int held[2] = {0, 2};
    for (int i = 0; i < N; i++) {
        float want = expected_value(shard_px, held, 2, i);
        cr_assert(memcmp(&got[i], &want, sizeof want) == 0, "value %d: %.9g, not %.9g", i, got[i], want);
    }
    free(got);
    /* without --quiet: the warning and the summary */
    merge_ok(err, "%s -o %s --partial", p[3], out);
    cr_assert(strstr(err, "merge: merged 1 of 4 shards (missing 0,1,2)\n"), "%s", err);
    cr_assert(strstr(err, "1 of 4 shards"), "%s", err);
    cr_assert_eq(sg_test_count_lines(err), 2, "%s", err);
    done(dir, p);
}

Test(merge, the_png_at_the_shards_exposure_unless_told)
{
    char *p[4], err[2048], out[4096], png[4096], expect[4096];
    const char *dir = four_shards_and_out(p, out);
    snprintf(png, sizeof png, "%s/out.png", dir);
    snprintf(expect, sizeof expect, "%s/expect.png", dir);
    float *merged = NULL;
    float *expected[3] = {NULL};
    const double stops[3] = {2, -1, 0};
    merge_ok(err, "%s %s %s %s -o %s --quiet", p[0], p[1], p[2], p[3], out);
    merged = read_image(out);
    for (int s = 0; s < 3; s++) {
        SgError e = {0};
        cr_assert(sg_image_write_png(expect, W, H, merged, stops[s], &e), "%s", e.message);
        expected[s] = read_image(expect);
    }
    cr_assert(memcmp(expected[0], expected[1], N * sizeof(float)), "the exposures give the same PNG");
    /* no --exposure: the shards' sg:exposure (2) */
    merge_ok(err, "%s %s %s %s -o %s --png %s --quiet", p[0], p[1], p[2], p[3], out, png);
    float *got = read_image(png);
    cr_assert(!memcmp(got, expected[0], N * sizeof(float)), "the PNG is not at the shards' exposure");
    free(got);
    /* --exposure -1 wins */
    merge_ok(err, "%s %s %s %s -o %s --png %s --exposure -1 --quiet", p[0], p[1], p[2], p[3], out,
             png);
    got = read_image(png);
    cr_assert(!memcmp(got, expected[1], N * sizeof(float)), "the PNG is not at --exposure -1");
    free(got);
    /* shards that disagree on sg:exposure: 0, and none in the output */
    char *other = write_shard(dir, "other.exr", 3, (ShardSpec){.exposure = "5"}, shard_px[3]);
    merge_ok(err, "%s %s %s %s -o %s --png %s --quiet", p[0], p[1], p[2], other, out, png);
    got = read_image(png);
    cr_assert(!memcmp(got, expected[2], N * sizeof(float)), "the PNG is not at exposure 0");
    cr_assert_null(attribute(out, "sg:exposure"));
    free(got);
    free(other);
    free(merged);
    for (int s = 0; s < 3; s++)
        free(expected[s]);
    done(dir, p);
}

/* The temporary files a write leaves while it runs (".out.exr.tmp.PID"). */
static int temporaries(const char *dir)
{
    DIR *d = opendir(dir);
    cr_assert_not_null(d);
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)))
        n += strstr(e->d_name, ".tmp.") != NULL;
    closedir(d);
    return n;
}

static bool file_is(const char *path, const char *text)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return false;
    char buf[256];
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    fclose(f);
    buf[n] = 0;
    return !strcmp(buf, text);
}

/* Runs bin/merge on the files (-o out.exr --png out.png in dir, both there
 * before with other contents); expects exit 1, one line containing each of
 * the `says` (NULL-ended), and both files as they were. */
static void refused(const char *dir, const char *files, const char *const *says)
{
    char args[16384], err[4096], out[4096], png[4096];
    snprintf(out, sizeof out, "%s/out.exr", dir);
    snprintf(png, sizeof png, "%s/out.png", dir);
    sg_test_write(dir, "out.exr", "an earlier exr");
    sg_test_write(dir, "out.png", "an earlier png");
    snprintf(args, sizeof args, "%s -o %s --png %s", files, out, png);
    int status = run_merge(args, err, sizeof err);
    cr_assert_eq(status, 1, "merge %s: exit %d (%s)", files, status, err);
    cr_assert_eq(sg_test_count_lines(err), 1, "not one line: %s", err);
    cr_assert(!strncmp(err, "merge: ", 7), "%s", err);
    for (int i = 0; says[i]; i++)
        cr_assert(strstr(err, says[i]), "merge %s said '%s', without '%s'", files, err, says[i]);
    cr_assert(file_is(out, "an earlier exr") && file_is(png, "an earlier png"), "a refused merge touched the output");
    cr_assert_eq(temporaries(dir), 0, "a refused merge left a temporary file");
}

#define SAYS(...) ((const char *const[]){__VA_ARGS__, NULL})

Test(merge, refuses_shards_of_different_renders)
{
    char *p[4], files[16384];
    const char *dir = four_shards_in_a_folder(p);
    const struct {
        ShardSpec spec;
        const char *attribute, *theirs, *mine;
    } other[] = {
        {{.sampling = "bsdf"}, "sampling", "guided", "bsdf"},
        {{.seed = "8"}, "seed", "7", "8"},
        {{.count = 5}, "sg:shard_count", "4", "5"},
        {{.scene_hash = "00000000000000ff"}, "sg:scene_hash", "00000000000000aa", "00000000000000ff"},
        {{.cache_hash = "none"}, "sg:cache_hash", "00000000000000bb", "none"},
        {{.recipe = "00000000000000ff"}, "sg:recipe", "00000000000000cc", "00000000000000ff"},
        {{.width = W + 1}, "size", "16x9", "17x9"},
    };
    for (size_t i = 0; i < sizeof other / sizeof other[0]; i++) {
        char *o = write_shard(dir, "other.exr", 3, other[i].spec, other[i].spec.width ? NULL : shard_px[3]);
        snprintf(files, sizeof files, "%s %s %s %s", p[0], p[1], p[2], o);
        refused(dir, files,
                SAYS(p[0], o, other[i].attribute, other[i].theirs, other[i].mine, "not shards of one render"));
        free(o);
    }
    done(dir, p);
}

Test(merge, refuses_duplicate_and_missing_shards)
{
    char *p[4], files[16384];
    const char *dir = four_shards_in_a_folder(p);
    /* a file twice */
    snprintf(files, sizeof files, "%s %s %s %s %s", p[0], p[1], p[2], p[3], p[1]);
    refused(dir, files, SAYS("both hold shard 1 of 4", p[1]));
    /* a merged image holding a shard given beside it: both files named */
    char *both = write_shard(dir, "both.exr", 0, (ShardSpec){.shards = "0,3"}, shard_px[0]);
    snprintf(files, sizeof files, "%s %s %s %s", p[1], both, p[2], p[3]);
    refused(dir, files, SAYS(both, p[3], "both hold shard 3 of 4"));
    free(both);
    /* missing shards, said by index, with the way out */
    snprintf(files, sizeof files, "%s %s", p[3], p[1]);
    refused(dir, files, SAYS("shards 0,2 of 4 are missing", "--partial merges what is there"));
    snprintf(files, sizeof files, "%s %s %s", p[0], p[1], p[2]);
    refused(dir, files, SAYS("shard 3 of 4 is missing", "--partial"));
    done(dir, p);
}

Test(merge, refuses_what_is_not_a_shard)
{
    char *p[4], files[16384], path[4096];
    const char *dir = four_shards_in_a_folder(p);
    /* a shard index not below the count */
    char *o = write_shard(dir, "high.exr", 3, (ShardSpec){.shards = "4"}, shard_px[3]);
    snprintf(files, sizeof files, "%s %s %s %s", p[0], p[1], p[2], o);
    refused(dir, files, SAYS(o, "shard 4, not below sg:shard_count 4"));
    free(o);
    /* spp 0, negative, not a number */
    const char *bad_spp[] = {"0", "-3", "many"};
    for (int i = 0; i < 3; i++) {
        o = write_shard(dir, "spp.exr", 3, (ShardSpec){.spp = bad_spp[i]}, shard_px[3]);
        snprintf(files, sizeof files, "%s %s %s %s", p[0], p[1], p[2], o);
        refused(dir, files, SAYS(o, "spp", bad_spp[i]));
        free(o);
    }
    /* an EXR not ours (no attributes at all), and one without sg:recipe */
    float one[3] = {1, 2, 3};
    snprintf(path, sizeof path, "%s/plain.exr", dir);
    SgError e = {0};
    cr_assert(sg_image_write_exr(path, 1, 1, one, NULL, 0, &e), "%s", e.message);
    snprintf(files, sizeof files, "%s %s %s %s", p[0], p[1], p[2], path);
    refused(dir, files, SAYS(path, "not a render shard"));
    o = write_shard(dir, "norecipe.exr", 3, (ShardSpec){.omit = "sg:recipe"}, shard_px[3]);
    snprintf(files, sizeof files, "%s %s %s %s", p[0], p[1], p[2], o);
    refused(dir, files, SAYS(o, "not a render shard", "sg:recipe"));
    free(o);
    /* no file, and a file that is no image */
    snprintf(files, sizeof files, "%s %s %s %s/nothing.exr", p[0], p[1], p[2], dir);
    refused(dir, files, SAYS("nothing.exr", "cannot read"));
    char *junk = sg_test_write(dir, "junk.exr", "not an image");
    snprintf(files, sizeof files, "%s %s %s %s", p[0], p[1], p[2], junk);
    refused(dir, files, SAYS(junk, "cannot read"));
    done(dir, p);
}

Test(merge, a_failed_write_leaves_no_output)
{
    char *p[4], args[16384], err[2048], out[4096], png[4096];
    const char *dir = four_shards_in_a_folder(p);
    /* the EXR cannot be written: the PNG (written first) is not left either */
    snprintf(out, sizeof out, "%s/no/such/dir/out.exr", dir);
    snprintf(png, sizeof png, "%s/out.png", dir);
    sg_test_write(dir, "out.png", "an earlier png");
    snprintf(args, sizeof args, "%s %s %s %s -o %s --png %s", p[0], p[1], p[2], p[3], out, png);
    cr_assert_eq(run_merge(args, err, sizeof err), 1, "%s", err);
    cr_assert_eq(sg_test_count_lines(err), 1, "%s", err);
    cr_assert(strstr(err, out), "the message does not name the output: %s", err);
    cr_assert(file_is(png, "an earlier png"), "a failed merge replaced the PNG");
    /* the PNG cannot be written: no EXR */
    snprintf(out, sizeof out, "%s/out.exr", dir);
    snprintf(png, sizeof png, "%s/no/such/dir/out.png", dir);
    snprintf(args, sizeof args, "%s %s %s %s -o %s --png %s", p[0], p[1], p[2], p[3], out, png);
    cr_assert_eq(run_merge(args, err, sizeof err), 1, "%s", err);
    cr_assert(strstr(err, png), "the message does not name the PNG: %s", err);
    cr_assert(!sg_test_exists(out), "a failed merge left its EXR");
    cr_assert_eq(temporaries(dir), 0, "a failed merge left a temporary file");
    done(dir, p);
}

Test(merge, usage_errors_exit_2)
{
    const char *dir = sg_test_tmpdir();
    char err[2048], args[8192], out[4096];
    snprintf(out, sizeof out, "%s/x.exr", dir);
    const char *bad[] = {"a.exr", "-o %s", "a.exr -o %s --frobnicate", "a.exr -o", "a.exr -o %s --exposure lots",
                         "a.exr -o %s --png %s"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        snprintf(args, sizeof args, bad[i], out, out);
        cr_assert_eq(run_merge(args, err, sizeof err), 2, "merge %s: not a usage error: %s", args, err);
        cr_assert_eq(sg_test_count_lines(err), 1, "merge %s: %s", args, err);
        cr_assert(!sg_test_exists(out), "merge %s wrote something", args);
    }
    char help[4096];
    merge_ok(err, "--help > %s/help.txt", dir);
    snprintf(help, sizeof help, "%s/help.txt", dir);
    FILE *f = fopen(help, "r");
    cr_assert_not_null(f);
    char line[256] = "";
    cr_assert_not_null(fgets(line, sizeof line, f));
    fclose(f);
    cr_assert(!strncmp(line, "usage: merge SHARD.exr... -o IMAGE.exr", 38), "%s", line);
    remove_dir(dir);
}
