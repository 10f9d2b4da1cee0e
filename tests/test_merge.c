/* bin/merge (merge/merge.h) on synthetic shards: the spp-weighted mean bit
 * for bit, order independence, associativity, the merged attributes, and
 * every refusal with no output left behind. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "image_io.h"
#include "merge/merge.h"
#include "support_files.h"

#define W 7
#define H 5
#define N (W * H * 3)

typedef struct ShardSpec {
    int shard, count;
    long spp;
    const char *sampling, *scene_hash, *cache_hash, *recipe;
    int width;
    const char *shards; /* sg:shards override (a merged image's list) */
} ShardSpec;

static float g_pixels[8][N];

/* Writes shard k's EXR (random pixels, kept in g_pixels[k]) and returns its path. */
static char *write_shard(const char *dir, const char *name, ShardSpec s, int k)
{
    for (int i = 0; i < N; i++)
        g_pixels[k][i] = (float)rand() / RAND_MAX * (i % 5 == 0 ? 100.0f : 1.0f);
    char spp[32], count[32], shard[32], seconds[32];
    snprintf(spp, sizeof spp, "%ld", s.spp);
    snprintf(count, sizeof count, "%d", s.count);
    snprintf(shard, sizeof shard, "%d", s.shard);
    snprintf(seconds, sizeof seconds, "%.3f", 0.5 * s.spp);
    SgImageAttribute attrs[] = {
        {"spp", spp},
        {"seconds", seconds},
        {"sampling", s.sampling ? s.sampling : "guided"},
        {"seed", "7"},
        {"sg:shards", s.shards ? s.shards : shard},
        {"sg:shard_count", count},
        {"sg:scene_hash", s.scene_hash ? s.scene_hash : "00000000000000aa"},
        {"sg:cache_hash", s.cache_hash ? s.cache_hash : "00000000000000bb"},
        {"sg:recipe", s.recipe ? s.recipe : "00000000000000cc"},
        {"sg:exposure", "2"},
        {"sg:max_depth", "8"},
        {"sg:guide_share", "0.2500"},
    };
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    SgError err = {0};
    int width = s.width ? s.width : W;
    cr_assert(sg_image_write_exr(path, width, H, g_pixels[k], attrs, (int)(sizeof attrs / sizeof attrs[0]), &err),
              "%s", err.message);
    return strdup(path);
}

static ShardSpec shard(int k, int count, long spp) { return (ShardSpec){.shard = k, .count = count, .spp = spp}; }

/* Four shards of different spp in dir: paths[k] holds shard k. */
static void four_shards(const char *dir, char *paths[4])
{
    const long spp[4] = {3, 5, 2, 6};
    for (int k = 0; k < 4; k++) {
        char name[32];
        snprintf(name, sizeof name, "s%d.exr", k);
        paths[k] = write_shard(dir, name, shard(k, 4, spp[k]), k);
    }
}

Test(merge, the_spp_weighted_mean_bit_for_bit_in_any_order)
{
    const char *dir = sg_test_tmpdir();
    char *p[4];
    four_shards(dir, p);
    const long spp[4] = {3, 5, 2, 6};
    const char *shuffled[4] = {p[2], p[0], p[3], p[1]};
    SgError err = {0};
    SgMerged *m = sg_merge_files((const char *const *)shuffled, 4, false, &err);
    cr_assert_not_null(m, "%s", err.message);
    cr_assert_eq(sg_merged_spp(m), 16);
    int wrong = 0, unweighted_equal = 0;
    for (int i = 0; i < N; i++) {
        double s = 0;
        for (int k = 0; k < 4; k++)
            s += (double)spp[k] * g_pixels[k][i];
        wrong += sg_merged_rgb(m)[i] != (float)(s / 16.0);
        double plain = (g_pixels[0][i] + g_pixels[1][i] + g_pixels[2][i] + g_pixels[3][i]) / 4.0;
        unweighted_equal += fabs(sg_merged_rgb(m)[i] - plain) < 1e-6 * fabs(plain);
    }
    cr_assert_eq(wrong, 0, "%d values are not the spp-weighted mean", wrong);
    cr_assert_lt(unweighted_equal, N / 2, "the weights make no difference: the test could not see them");
    sg_merged_free(m);
    for (int k = 0; k < 4; k++)
        free(p[k]);
}

Test(merge, merging_merged_images_is_the_same_merge)
{
    const char *dir = sg_test_tmpdir();
    char *p[4];
    four_shards(dir, p);
    char ab[4096], cd[4096], all[4096], cmd[40000], err_text[1024];
    snprintf(ab, sizeof ab, "%s/ab.exr", dir);
    snprintf(cd, sizeof cd, "%s/cd.exr", dir);
    snprintf(all, sizeof all, "%s/all.exr", dir);
    char bin[4096];
    sg_test_program("merge", bin, sizeof bin);
    snprintf(cmd, sizeof cmd, "%s %s %s -o %s --partial --quiet", bin, p[0], p[1], ab);
    cr_assert_eq(sg_test_run(cmd, err_text, sizeof err_text), 0, "%s", err_text);
    cr_assert(strstr(err_text, "merged 2 of 4 shards (missing 2,3)"), "--partial said: %s", err_text);
    snprintf(cmd, sizeof cmd, "%s %s %s -o %s --partial --quiet", bin, p[2], p[3], cd);
    cr_assert_eq(sg_test_run(cmd, err_text, sizeof err_text), 0, "%s", err_text);
    snprintf(cmd, sizeof cmd, "%s %s %s -o %s --quiet", bin, ab, cd, all);
    cr_assert_eq(sg_test_run(cmd, err_text, sizeof err_text), 0, "%s", err_text);
    SgError err = {0};
    SgMerged *direct = sg_merge_files((const char *const *)p, 4, false, &err);
    cr_assert_not_null(direct, "%s", err.message);
    int w, h;
    float *rgb;
    cr_assert(sg_image_read(all, &w, &h, &rgb, &err), "%s", err.message);
    double worst = 0;
    for (int i = 0; i < N; i++)
        worst = fmax(worst, fabs((double)rgb[i] - sg_merged_rgb(direct)[i]) / fmax(1e-12, fabs(rgb[i])));
    cr_log_info("merge(merge(a,b), merge(c,d)) against merge(a,b,c,d): worst relative difference %.3g", worst);
    cr_assert(worst < 1e-6, "relative difference %.3g", worst);
    char v[64];
    cr_assert(sg_image_read_attribute(all, "spp", v, sizeof v, &err));
    cr_assert_str_eq(v, "16");
    cr_assert(sg_image_read_attribute(all, "sg:shards", v, sizeof v, &err));
    cr_assert_str_eq(v, "0,1,2,3");
    cr_assert(sg_image_read_attribute(all, "seconds", v, sizeof v, &err));
    cr_assert_str_eq(v, "8.000");
    cr_assert(sg_image_read_attribute(all, "sg:max_depth", v, sizeof v, &err), "a shared attribute was dropped");
    cr_assert_str_eq(v, "8");
    cr_assert(sg_image_read_attribute(all, "sg:guide_share", v, sizeof v, &err));
    cr_assert_str_eq(v, "0.2500");
    free(rgb);
    sg_merged_free(direct);
    for (int k = 0; k < 4; k++)
        free(p[k]);
}

/* Runs bin/merge on the files; expects exit 1, a message containing
 * `says`, and no output at all. */
static void refused(const char *dir, const char *files, const char *says)
{
    char bin[4096], cmd[16384], err[2048], out[4096], png[4096];
    sg_test_program("merge", bin, sizeof bin);
    snprintf(out, sizeof out, "%s/out.exr", dir);
    snprintf(png, sizeof png, "%s/out.png", dir);
    remove(out);
    remove(png);
    snprintf(cmd, sizeof cmd, "%s %s -o %s --png %s", bin, files, out, png);
    int status = sg_test_run(cmd, err, sizeof err);
    cr_assert_eq(status, 1, "merge %s: exit %d (%s)", files, status, err);
    cr_assert(strstr(err, says), "merge %s said '%s', not '%s'", files, err, says);
    cr_assert_eq(sg_test_count_lines(err), 1, "not one line: %s", err);
    cr_assert(!sg_test_exists(out) && !sg_test_exists(png), "a refused merge left output");
}

Test(merge, refuses_what_is_not_one_render)
{
    const char *dir = sg_test_tmpdir();
    char *p[4];
    four_shards(dir, p);
    char files[16384];
#define OTHER(field, value, says)                                                                   \
    do {                                                                                            \
        ShardSpec s = shard(3, 4, 4);                                                               \
        s.field = value;                                                                            \
        char *o = write_shard(dir, "other.exr", s, 5);                                              \
        snprintf(files, sizeof files, "%s %s %s %s", p[0], p[1], p[2], o);                          \
        refused(dir, files, says);                                                                  \
        free(o);                                                                                    \
    } while (0)
    OTHER(scene_hash, "00000000000000ff", "sg:scene_hash");
    OTHER(cache_hash, "00000000000000ff", "sg:cache_hash");
    OTHER(recipe, "00000000000000ff", "sg:recipe");
    OTHER(sampling, "bsdf", "sampling");
    OTHER(width, W + 1, "not shards of one render");
    OTHER(count, 5, "sg:shard_count");
    /* a shard twice, and a merged image holding one given beside it */
    snprintf(files, sizeof files, "%s %s %s %s %s", p[0], p[1], p[2], p[3], p[1]);
    refused(dir, files, "both hold shard 1 of 4");
    ShardSpec s = shard(0, 4, 8);
    s.shards = "0,3";
    char *both = write_shard(dir, "both.exr", s, 6);
    snprintf(files, sizeof files, "%s %s %s %s", both, p[1], p[2], p[3]);
    refused(dir, files, "both hold shard 3 of 4");
    /* missing shards, said by index */
    snprintf(files, sizeof files, "%s %s", p[1], p[3]);
    refused(dir, files, "shards 0,2 of 4 are missing");
    /* an EXR that is not ours, and no file at all */
    float px[3] = {1, 2, 3};
    char plain[4096];
    snprintf(plain, sizeof plain, "%s/plain.exr", dir);
    SgError err = {0};
    cr_assert(sg_image_write_exr(plain, 1, 1, px, NULL, 0, &err));
    snprintf(files, sizeof files, "%s %s", p[0], plain);
    refused(dir, files, "not a render shard");
    snprintf(files, sizeof files, "%s %s/nothing.exr", p[0], dir);
    refused(dir, files, "nothing.exr");
    free(both);
    for (int k = 0; k < 4; k++)
        free(p[k]);
}

Test(merge, usage_errors_exit_2)
{
    char bin[4096], cmd[8192], err[1024];
    sg_test_program("merge", bin, sizeof bin);
    snprintf(cmd, sizeof cmd, "%s a.exr", bin);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 2, "no -o: %s", err);
    snprintf(cmd, sizeof cmd, "%s -o x.exr", bin);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 2, "no input: %s", err);
    snprintf(cmd, sizeof cmd, "%s a.exr -o x.exr --frobnicate", bin);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 2, "unknown option: %s", err);
    snprintf(cmd, sizeof cmd, "%s --help >/dev/null", bin);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 0);
}
