/* bin/render as a program: the contract's options, outputs, metadata,
 * error curve, and one-line errors without partial outputs; and the real
 * Cornell box through the scene loader renders without NaN. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../render/guides/openpgl_field.h"
#include "../render/renderer.h"
#include "image_io.h"
#include "scene_load.h"
#include "support_files.h"
#include "support_render.h"

static const char *render_bin(void)
{
    static char buf[4096];
    return sg_test_program("render", buf, sizeof buf);
}

static const char *tiny_scene(const char *dir)
{
    /* a closed room with a ceiling light, inline geometry */
    return sg_test_write(dir, "room.json",
        "{ \"meshes\": [ { \"vertices\": [0,0,0, 2,0,0, 2,0,2, 0,0,2, 0,2,0, 2,2,0, 2,2,2, 0,2,2],\n"
        "    \"triangles\": [0,1,2, 0,2,3, 4,6,5, 4,7,6, 0,4,5, 0,5,1, 3,2,6, 3,6,7, 0,3,7, 0,7,4, 1,5,6, 1,6,2],\n"
        "    \"material\": \"white\" } ],\n"
        "  \"materials\": { \"white\": { \"type\": \"diffuse\", \"albedo\": [0.6, 0.6, 0.6] } },\n"
        "  \"lights\": [ { \"type\": \"quad\", \"corners\": [[0.8,1.99,0.8],[1.2,1.99,0.8],[1.2,1.99,1.2],[0.8,1.99,1.2]],\n"
        "                \"radiance\": [10, 10, 10] } ],\n"
        "  \"camera\": { \"position\": [1, 1, 0.2], \"look_at\": [1, 1, 2], \"up\": [0, 1, 0], \"fov\": 60 },\n"
        "  \"image\": { \"width\": 32, \"height\": 24 } }\n");
}

Test(render_cli, help_and_usage_errors)
{
    char cmd[8192], err[4096];
    snprintf(cmd, sizeof cmd, "%s --help >/dev/null", render_bin());
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 0);
    const char *dir = sg_test_tmpdir();
    const char *scene = tiny_scene(dir);
    const char *bad[] = {"--spp 4 --time 1", "--spp zero", "--sampling fancy", "--sampling guided",
                         "--bogus", "--reference x.exr", "--threads -2", "--roulette sometimes",
                         "--edge-rays 17", "--edge-rays -1", "--edge-rays many"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        snprintf(cmd, sizeof cmd, "%s %s %s -o %s/bad.exr", render_bin(), scene, bad[i], dir);
        cr_assert_eq(sg_test_run(cmd, err, sizeof err), 2, "'%s' accepted (or not as a usage error, 2)", bad[i]);
        cr_assert_eq(sg_test_count_lines(err), 1, "'%s': %s", bad[i], err);
        cr_assert(strncmp(err, "render: ", 8) == 0, "%s", err);
    }
    char out[4200];
    snprintf(out, sizeof out, "%s/bad.exr", dir);
    cr_assert_not(sg_test_exists(out), "a failed run left an output");
}

Test(render_cli, missing_or_broken_scene_is_one_line_naming_the_file)
{
    char cmd[8192], err[4096];
    const char *dir = sg_test_tmpdir();
    snprintf(cmd, sizeof cmd, "%s %s/none.json -o %s/x.exr", render_bin(), dir, dir);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 1);
    cr_assert(strstr(err, "none.json") != NULL, "%s", err);
    const char *broken = sg_test_write(dir, "broken.json", "{ \"mesh\": ");
    snprintf(cmd, sizeof cmd, "%s %s -o %s/x.exr", render_bin(), broken, dir);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 1);
    cr_assert(strstr(err, "broken.json") != NULL, "%s", err);
    cr_assert_eq(sg_test_count_lines(err), 1, "%s", err);
    /* cache that is not a cache */
    const char *scene = tiny_scene(dir);
    const char *junk = sg_test_write(dir, "junk.cache", "this is not an importance cache");
    snprintf(cmd, sizeof cmd, "%s %s --cache %s -o %s/x.exr", render_bin(), scene, junk, dir);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 1);
    cr_assert(strstr(err, "junk.cache") != NULL, "%s", err);
    char out[4200];
    snprintf(out, sizeof out, "%s/x.exr", dir);
    cr_assert_not(sg_test_exists(out));
}

Test(render_cli, writes_exr_png_metadata_and_error_curve)
{
    char cmd[16384], err[4096];
    const char *dir = sg_test_tmpdir();
    const char *scene = tiny_scene(dir);
    snprintf(cmd, sizeof cmd, "%s %s --spp 16 --seed 3 --threads 2 -o %s/ref.exr --quiet", render_bin(),
             scene, dir);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 0, "%s", err);
    snprintf(cmd, sizeof cmd,
             "%s %s --spp 4 --seed 4 -o %s/a.exr --png %s/a.png --reference %s/ref.exr --log %s/a.csv",
             render_bin(), scene, dir, dir, dir, dir);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 0, "%s", err);
    char path[4200];
    snprintf(path, sizeof path, "%s/a.png", dir);
    cr_assert(sg_test_exists(path));
    /* metadata: read it back with OpenImageIO's iinfo */
    snprintf(cmd, sizeof cmd,
             "iinfo -v %s/a.exr | grep -E '^ +(spp|seconds|sampling|seed|sg:edge_rays_per_sample|sg:nonfinite_samples):'"
             " > %s/meta.txt", dir, dir);
    cr_assert_eq(system(cmd), 0);
    snprintf(path, sizeof path, "%s/meta.txt", dir);
    FILE *f = fopen(path, "r");
    char meta[2048] = {0};
    cr_assert_gt(fread(meta, 1, sizeof meta - 1, f), 0);
    fclose(f);
    cr_assert(strstr(meta, "spp: \"4\"") && strstr(meta, "sampling: \"bsdf\"") &&
              strstr(meta, "seed: \"4\"") && strstr(meta, "seconds:") && strstr(meta, "sg:edge_rays_per_sample:") &&
              strstr(meta, "sg:nonfinite_samples: \"0\""),
              "%s", meta);
    /* the curve: header + one row per pass, error falling overall */
    snprintf(path, sizeof path, "%s/a.csv", dir);
    f = fopen(path, "r");
    char line[256];
    cr_assert(fgets(line, sizeof line, f));
    cr_assert_str_eq(line, "seconds,spp,mse,relmse,mse8,relmse_trimmed\n");
    int rows = 0;
    double first = 0, last = 0, first8 = 0, last8 = 0, t, mse, rel, mse8, trimmed;
    int spp;
    while (fscanf(f, "%lf,%d,%lf,%lf,%lf,%lf", &t, &spp, &mse, &rel, &mse8, &trimmed) == 6) {
        rows++;
        cr_assert_eq(spp, rows);
        cr_assert(mse > 0 && rel > 0 && t > 0 && mse8 >= 0 && mse8 <= 255.0 * 255.0);
        /* the worst 0.1 % of the pixels left out: never more than all of them */
        cr_assert(trimmed > 0 && trimmed <= rel * (1 + 1e-9), "trimmed %g, relmse %g", trimmed, rel);
        if (rows == 1)
            first = mse, first8 = mse8;
        last = mse, last8 = mse8;
    }
    fclose(f);
    cr_assert_eq(rows, 4);
    cr_assert_lt(last, first);
    cr_assert_lt(last8, first8);
}

Test(render_cli, same_seed_same_file_for_1_and_2_threads)
{
    char cmd[8192], err[4096];
    const char *dir = sg_test_tmpdir();
    const char *scene = tiny_scene(dir);
    for (int t = 1; t <= 2; t++) {
        snprintf(cmd, sizeof cmd, "%s %s --spp 3 --seed 9 --threads %d -o %s/t%d.exr --quiet", render_bin(),
                 scene, t, dir, t);
        cr_assert_eq(sg_test_run(cmd, err, sizeof err), 0, "%s", err);
    }
    int w1, h1, w2, h2;
    float *a, *b;
    char p1[4200], p2[4200];
    snprintf(p1, sizeof p1, "%s/t1.exr", dir);
    snprintf(p2, sizeof p2, "%s/t2.exr", dir);
    SgError e = {0};
    cr_assert(sg_image_read(p1, &w1, &h1, &a, &e), "%s", e.message);
    cr_assert(sg_image_read(p2, &w2, &h2, &b, &e), "%s", e.message);
    cr_assert(w1 == w2 && h1 == h2);
    cr_assert(memcmp(a, b, sizeof(float) * 3 * w1 * h1) == 0);
    free(a);
    free(b);
}

Test(render_cli, cornell_box_renders_without_nan)
{
    const char *path = "data/cornell-box/cornell-box.json";
    SgError err = {0};
    SgScene *s = sg_scene_load(path, &err);
    cr_assert_not_null(s, "%s", err.message);
    SgRenderOptions o;
    sg_render_options_default(&o, s);
    o.width = 80;
    o.height = 60;
    SgRenderer *r = sg_renderer_create(s, &o, &err);
    cr_assert_not_null(r, "%s", err.message);
    for (int p = 0; p < 8; p++)
        sg_renderer_pass(r);
    float *img = malloc(sizeof(float) * 3 * o.width * o.height);
    sg_renderer_image(r, img);
    double sum = 0;
    for (int i = 0; i < 3 * o.width * o.height; i++) {
        cr_assert(isfinite(img[i]) && img[i] >= 0);
        sum += img[i];
    }
    cr_assert_gt(sum, 0.0);
    cr_assert_eq(sgt_stats(r).nonfinite, 0);
    cr_assert_lt(sgt_stats(r).backface_fraction, 0.5);
    free(img);
    sg_renderer_free(r);
    sg_scene_free(s);
}

/* Without Open PGL, --sampling openpgl says how to get it, in one line,
 * before reading the scene, and writes nothing. */
Test(render_cli, openpgl_without_the_peer_says_how_to_build_it)
{
    if (sg_pgl_available())
        cr_skip_test("this build has Open PGL: the message for a build without it cannot show");
    char cmd[8192], err[4096];
    const char *dir = sg_test_tmpdir();
    snprintf(cmd, sizeof cmd, "%s %s/no-such-scene.json --sampling openpgl -o %s/pgl.exr", render_bin(), dir, dir);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 1, "%s", err);
    cr_assert_eq(sg_test_count_lines(err), 1, "%s", err);
    cr_assert(strstr(err, "make openpgl") != NULL, "%s", err);
    char out[4200];
    snprintf(out, sizeof out, "%s/pgl.exr", dir);
    cr_assert_not(sg_test_exists(out));
}
