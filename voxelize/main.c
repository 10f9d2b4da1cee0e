/* bin/voxelize SCENE.json -o medium.vdb [--resolution N]: step 1. */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

#include "medium.h"
#include "progress.h"
#include "scene_load.h"
#include "voxelize.h"

static void usage(FILE *out)
{
    fprintf(out,
            "usage: voxelize SCENE -o medium.vdb [--resolution N] [--threads N]\n"
            "       voxelize SCENE --key [--resolution N]\n"
            "\n"
            "Voxelizes the scene's air that light can reach into an OpenVDB file: a bool\n"
            "grid named \"medium\" (active voxels = medium), with the lights, camera and\n"
            "input identity in the file metadata (see vdb_print -metadata).\n"
            "\n"
            "  -o FILE           output .vdb (written to a temporary name, then renamed)\n"
            "  --resolution N    voxels along the longest side of the scene's bounding box\n"
            "                    (default: the scene's \"voxel\": {\"resolution\"}, else %d)\n"
            "  --threads N       worker threads (default: every core)\n"
            "  --key             print the identity of what the medium depends on\n"
            "                    (geometry, lights, resolution; not the camera) and exit\n"
            "  -q, --quiet       no summary line\n"
            "  -h, --help        this help\n",
            SG_VOXELIZE_DEFAULT_RESOLUTION);
}

typedef struct OwnOptions {
    SgVoxelizeOptions *options;
    bool key;
} OwnOptions;

static SgCliArg own_option(void *ctx, int argc, char **argv, int *i)
{
    OwnOptions *own = ctx;
    const char *a = argv[*i];
    if (!strcmp(a, "--resolution") && *i + 1 < argc) {
        if (sg_parse_int(argv[++*i], 1, SG_VOXEL_RESOLUTION_MAX, &own->options->resolution))
            return SG_CLI_TAKEN;
        fprintf(stderr, "voxelize: --resolution takes a whole number in [1, %d]\n", SG_VOXEL_RESOLUTION_MAX);
        return SG_CLI_BAD;
    }
    if (!strcmp(a, "--key")) {
        own->key = true;
        return SG_CLI_TAKEN;
    }
    return SG_CLI_OTHER;
}

int main(int argc, char **argv)
{
    SgVoxelizeOptions options = {0};
    OwnOptions own = {.options = &options};
    SgStepArguments args = {.program = "voxelize", .usage = usage, .min_inputs = 1, .max_inputs = 1};
    SgCliArg got = sg_cli_step_arguments(&args, argc, argv, own_option, &own);
    if (got != SG_CLI_TAKEN)
        return got == SG_CLI_HELP ? 0 : 2;
    const char *scene_path = args.inputs[0], *out_path = args.out_path;
    bool quiet = args.quiet, key = own.key;
    if (!out_path && !key) {
        usage(stderr);
        return 2;
    }
    options.threads = args.threads;

    SgError err = {0};
    double t0 = sg_seconds();
    SgScene *scene = sg_scene_load(scene_path, &err);
    if (!scene) {
        sg_error_print("voxelize", &err);
        return 1;
    }
    if (!key) /* make scene runs --key first: say it once */
        sg_scene_print_warnings(scene, "voxelize", stderr);
    if (key) {
        int resolution = options.resolution > 0        ? options.resolution
                         : scene->voxel_resolution > 0 ? scene->voxel_resolution
                                                       : SG_VOXELIZE_DEFAULT_RESOLUTION;
        printf("voxelize %d geometry %016" PRIx64 " resolution %d\n", SG_VOXELIZE_VERSION,
               scene->geometry_hash, resolution);
        sg_scene_free(scene);
        return 0;
    }
    double t_load = sg_seconds() - t0;
    if (scene->degenerate_dropped && !quiet)
        fprintf(stderr, "voxelize: %s: %u degenerate (zero-area) triangles ignored\n", scene_path,
                scene->degenerate_dropped);

    SgMedium medium;
    SgVoxelizeStats stats;
    if (!sg_voxelize(scene, &options, &medium, &stats, &err)) {
        sg_error_print("voxelize", &err);
        sg_scene_free(scene);
        return 1;
    }
    if (!quiet) {
        if (stats.sealed_lights)
            fprintf(stderr,
                    "voxelize: %s: %u of %u lights are sealed (no air voxel in front of them "
                    "at this resolution): they are left out\n",
                    scene_path, stats.sealed_lights, sg_scene_guide_light_count(scene));
        if (scene->has_camera && !stats.camera_in_grid)
            fprintf(stderr, "voxelize: %s: note: the camera is outside the scene's bounding box\n",
                    scene_path);
        else if (scene->has_camera && stats.camera_voxel_state == 1)
            fprintf(stderr, "voxelize: %s: warning: the camera is inside a solid voxel\n",
                    scene_path);
        else if (scene->has_camera && stats.camera_voxel_state == 0)
            fprintf(stderr, "voxelize: %s: warning: no light reaches the camera's voxel\n",
                    scene_path);
    }
    double t1 = sg_seconds();
    bool ok = sg_medium_write(&medium, out_path, &err);
    double t_write = sg_seconds() - t1;
    if (!ok) {
        sg_error_print("voxelize", &err);
    } else if (!quiet) {
        const SgGrid *g = &medium.grid;
        fprintf(stderr,
                "voxelize: %dx%dx%d voxels of %.4g; medium %" PRIu64 " voxels in %u of %u air "
                "components, %u light(s); load %.2f s, voxelize %.2f s, fill %.2f s, write %.2f s\n",
                g->nx, g->ny, g->nz, g->voxel_size, stats.medium_voxels, stats.medium_components,
                stats.air_components, sg_scene_guide_light_count(scene) - stats.sealed_lights, t_load,
                stats.seconds_voxelize, stats.seconds_fill, t_write);
    }
    sg_medium_release(&medium);
    sg_scene_free(scene);
    return ok ? 0 : 1;
}
