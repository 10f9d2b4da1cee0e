/* bin/render with a real importance cache, built by the other programs
 * (skipped when they are not built): guided agrees with bsdf within three
 * standard errors on the dark corridor and the Cornell box; a cache built
 * for other geometry is refused. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "image_io.h"
#include "support_files.h"

static bool have_programs(void)
{
    const char *names[] = {"voxelize", "skeletonize", "importance", "render"};
    char buf[4096];
    for (int i = 0; i < 4; i++)
        if (!sg_test_exists(sg_test_program(names[i], buf, sizeof buf)))
            return false;
    return true;
}

static const char *prog(const char *name)
{
    static char bufs[4][4096];
    static int k;
    k = (k + 1) % 4;
    return sg_test_program(name, bufs[k], sizeof bufs[k]);
}

/* voxelize, skeletonize, importance into dir; returns the cache path */
static const char *precompute(const char *scene, const char *dir)
{
    static char cache[4200];
    char cmd[16384], err[4096];
    snprintf(cmd, sizeof cmd,
             "%s %s -o %s/medium.vdb >/dev/null && %s %s/medium.vdb -o %s/skeleton.ply >/dev/null && "
             "%s %s/medium.vdb %s/skeleton.ply -o %s/importance.cache >/dev/null",
             prog("voxelize"), scene, dir, prog("skeletonize"), dir, dir, prog("importance"), dir, dir, dir);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 0, "precompute of %s: %s", scene, err);
    snprintf(cache, sizeof cache, "%s/importance.cache", dir);
    return cache;
}

/* Mean over seeds of the image mean, and its standard error. */
static void image_means(const char *scene, const char *cache, const char *mode, int seeds, int spp,
                        const char *dir, double *mean, double *se)
{
    double s = 0, ss = 0;
    for (int k = 0; k < seeds; k++) {
        char cmd[16384], err[4096], out[4200];
        snprintf(out, sizeof out, "%s/%s-%d.exr", dir, mode, k);
        snprintf(cmd, sizeof cmd, "%s %s --cache %s --sampling %s --spp %d --seed %d --size 80x60 -o %s --quiet",
                 prog("render"), scene, cache, mode, spp, 1000 + k, out);
        cr_assert_eq(sg_test_run(cmd, err, sizeof err), 0, "%s", err);
        int w, h;
        float *rgb;
        SgError e = {0};
        cr_assert(sg_image_read(out, &w, &h, &rgb, &e), "%s", e.message);
        double m = 0;
        for (int i = 0; i < 3 * w * h; i++)
            m += rgb[i];
        m /= 3.0 * w * h;
        free(rgb);
        s += m;
        ss += m * m;
    }
    *mean = s / seeds;
    *se = sqrt(fmax(0.0, ss / seeds - *mean * *mean) / (seeds - 1));
}

static void agreement(const char *scene)
{
    if (!have_programs())
        cr_skip_test("needs bin/voxelize, bin/skeletonize, bin/importance");
    const char *dir = sg_test_tmpdir();
    const char *cache = precompute(scene, dir);
    double mb, sb, mg, sg, ms, ss;
    image_means(scene, cache, "bsdf", 8, 16, dir, &mb, &sb);
    image_means(scene, cache, "guided", 8, 16, dir, &mg, &sg);
    image_means(scene, cache, "skeleton", 4, 16, dir, &ms, &ss);
    double se = sqrt(sb * sb + sg * sg);
    cr_log_info("%s: bsdf %.6f +- %.6f, guided %.6f +- %.6f (%.2f se apart); skeleton (the paper's "
                "rule, biased) %.6f +- %.6f", scene, mb, sb, mg, sg, fabs(mb - mg) / se, ms, ss);
    cr_assert_gt(mb, 0.0);
    cr_assert(fabs(mb - mg) < 3.0 * se, "%s: bsdf %.6f vs guided %.6f, 3 se = %.6f", scene, mb, mg, 3 * se);
}

Test(render_pipeline, guided_agrees_with_bsdf_on_the_corridor, .timeout = 240)
{
    agreement("data/corridor/corridor.json");
}

Test(render_pipeline, guided_agrees_with_bsdf_on_the_cornell_box, .timeout = 240)
{
    agreement("data/cornell-box/cornell-box.json");
}

Test(render_pipeline, cache_for_other_geometry_is_refused)
{
    if (!have_programs())
        cr_skip_test("needs bin/voxelize, bin/skeletonize, bin/importance");
    const char *dir = sg_test_tmpdir();
    const char *cache = precompute("data/corridor/corridor.json", dir);
    char cmd[16384], err[4096];
    snprintf(cmd, sizeof cmd, "%s data/cornell-box/cornell-box.json --cache %s -o %s/x.exr", prog("render"),
             cache, dir);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 1);
    cr_assert(strstr(err, "other geometry") != NULL, "%s", err);
    cr_assert_eq(sg_test_count_lines(err), 1, "%s", err);
    char out[4200];
    snprintf(out, sizeof out, "%s/x.exr", dir);
    cr_assert_not(sg_test_exists(out));
}
