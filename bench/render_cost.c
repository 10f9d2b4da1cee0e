/* The per-sample cost of guided sampling over bsdf (bench/sections/40-render.sh),
 * measured so that the shared machine's slow spells fall on both alike:
 *
 *   render_cost SCENE CACHE SPP [--max-depth N] [--threads N] [--field FIELD | --save-field FIELD]
 *
 * renders SCENE twice at once, with bsdf and with guided sampling under
 * bsdf's own roulette (guided --roulette albedo: the same kind of paths,
 * so that the difference is the guide's cost), one pass of each in turn,
 * the order swapped every pass; each renderer's seconds are the sum of its
 * passes (as bin/render counts them). Separate runs of ~10 s each, even
 * interleaved and best of 3, put the same binaries' corridor anywhere from
 * +8.7% to +12.0% in one evening (Sponza +5.6% to +13.8%). With --field,
 * guided starts from that stored field (render --save-field, the same depth
 * and roulette) and learns no more: the frozen guide's own cost, without
 * its learning passes. With --save-field, guided's field is written to FIELD
 * after the passes: what this run learned, for a run with --field.
 * Prints a line per mode: its name, µs per sample, µs per ray, rays per
 * sample. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../render/guides/importance_file.h"
#include "../render/renderer.h"
#include "error.h"
#include "progress.h"
#include "scene_load.h"

int main(int argc, char **argv)
{
    if (argc < 4) {
        fputs("usage: render_cost SCENE CACHE SPP [--max-depth N] [--threads N] [--field FIELD | --save-field FIELD]\n",
              stderr);
        return 2;
    }
    const char *scene_path = argv[1], *cache_path = argv[2];
    int spp = atoi(argv[3]), max_depth = 0, threads = 0;
    const char *field = NULL, *save_field = NULL;
    for (int i = 4; i + 1 < argc; i += 2) {
        if (!strcmp(argv[i], "--field"))
            field = argv[i + 1];
        else if (!strcmp(argv[i], "--save-field"))
            save_field = argv[i + 1];
        else if (!strcmp(argv[i], "--max-depth"))
            max_depth = atoi(argv[i + 1]);
        else if (!strcmp(argv[i], "--threads"))
            threads = atoi(argv[i + 1]);
    }
    SgError err = {0};
    SgImportanceFile guide = {0};
    SgRenderer *r[2] = {NULL, NULL};
    int status = 1;
    SgScene *scene = sg_scene_load(scene_path, &err);
    if (!scene)
        goto done;
    if (spp < 1) {
        sg_fail(&err, "SPP: '%s' is not a positive number", argv[3]);
        goto done;
    }
    SgRenderOptions o;
    sg_render_options_default(&o, scene);
    if (max_depth > 0)
        o.max_depth = max_depth;
    o.threads = threads;
    if (!sg_importance_file_open(&guide, cache_path, scene, scene_path, &o.importance, &err))
        goto done;
    o.sampling = SG_SAMPLING_BSDF;
    r[0] = sg_renderer_create(scene, &o, &err);
    o.sampling = SG_SAMPLING_GUIDED;
    o.roulette = SG_ROULETTE_ALBEDO;
    if (!r[0] || !(r[1] = sg_renderer_create(scene, &o, &err)))
        goto done;
    /* the budget bin/render gives them from --spp: guided learns as long as
     * learning pays within it */
    sg_renderer_set_budget(r[0], spp, 0.0);
    sg_renderer_set_budget(r[1], spp, 0.0);
    if (field && !sg_renderer_read_field(r[1], field, &err))
        goto done;
    double seconds[2] = {0.0, 0.0};
    for (int pass = 0; pass < spp; pass++)
        for (int k = 0; k < 2; k++) {
            int which = k ^ (pass & 1);
            double t0 = sg_seconds();
            sg_renderer_pass(r[which]);
            seconds[which] += sg_seconds() - t0;
        }
    if (save_field) {
        sg_renderer_stop_learning(r[1]);
        if (!sg_renderer_write_field(r[1], save_field, &err))
            goto done;
    }
    double samples = (double)o.width * o.height * spp;
    const char *names[2] = {"bsdf", "guided-albedo"};
    for (int k = 0; k < 2; k++) {
        SgRenderStats stats;
        sg_renderer_stats(r[k], &stats);
        double rays = (double)stats.rays;
        printf("%s %.4f %.4f %.2f\n", names[k], seconds[k] / samples * 1e6, seconds[k] / rays * 1e6, rays / samples);
    }
    status = 0;
done:
    if (status)
        sg_error_print("render_cost", &err);
    sg_renderer_free(r[0]);
    sg_renderer_free(r[1]);
    sg_importance_file_close(&guide);
    if (scene)
        sg_scene_free(scene);
    return status;
}
