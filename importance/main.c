/* bin/importance medium.vdb skeleton.ply -o importance.cache [--vectors vectors.ply]
 * bin/importance --info importance.cache [SCENE.json]: step 3. */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "importance.h"
#include "importance_cache.h"
#include "medium.h"
#include "memory.h"
#include "scene_load.h"
#include "skeleton_graph.h"

static void usage(FILE *out)
{
    fprintf(out,
            "usage: importance medium.vdb skeleton.ply -o importance.cache [--vectors vectors.ply]\n"
            "       importance --info importance.cache [SCENE.json]\n"
            "\n"
            "Step 3 (Biri & Chaussard 2012, section 3.3): the nearest skeleton node of every\n"
            "medium voxel (geodesic, inside the air), shortest paths on the skeleton from\n"
            "every light, and each node's importance point per light: the barycenter of the\n"
            "first run of nodes on its path toward the light that it sees. Writes one\n"
            "little-endian file that render maps in place (docs/cache-format.md).\n"
            "\n"
            "  -o FILE           output cache (written to a temporary name, then renamed)\n"
            "  --vectors FILE    also write node -> importance point edges as PLY (figure 2)\n"
            "  --threads N       worker threads (default: every core)\n"
            "  --run-tolerance T test the path toward the light in chunks spanning T times\n"
            "                    their distance (0 < T <= 1; e.g. 0.125): faster on long\n"
            "                    runs, approximate; default: every node tested (exact)\n"
            "  --info CACHE [SCENE.json]\n"
            "                    validate a cache and print one JSON object: lights_total,\n"
            "                    lights_reachable (with a scene: lights that can reach its\n"
            "                    camera; without: lights that have a place on the skeleton),\n"
            "                    nodes, components, medium_voxels, bytes, grid, hashes\n"
            "  -q, --quiet       no summary line\n"
            "  -h, --help        this help\n");
}

static int info(const char *cache_path, const char *scene_path)
{
    SgError err = {0};
    SgImportanceCache *cache = sg_cache_open(cache_path, &err);
    if (!cache) {
        sg_error_print("importance", &err);
        return 1;
    }
    SgScene *scene = NULL;
    if (scene_path) {
        scene = sg_scene_load(scene_path, &err);
        if (!scene) {
            sg_error_print("importance", &err);
            sg_cache_close(cache);
            return 1;
        }
        if (!scene->has_camera) {
            fprintf(stderr, "importance: %s: the scene has no camera\n", scene_path);
            sg_scene_free(scene);
            sg_cache_close(cache);
            return 1;
        }
    }
    uint32_t lights = sg_cache_light_count(cache), reachable = 0;
    bool camera_in_medium = false;
    if (scene) {
        uint32_t node;
        camera_in_medium = sg_cache_nearest_node(cache, scene->camera.position, &node);
        for (uint32_t k = 0; k < lights; k++)
            reachable += sg_cache_light_reaches(cache, k, scene->camera.position);
    } else {
        for (uint32_t k = 0; k < lights; k++)
            reachable += sg_cache_light_has_paths(cache, k);
    }
    int dims[3];
    double origin[3];
    sg_cache_grid(cache, dims, origin);
    printf("{\"lights_total\": %u, \"lights_reachable\": %u, \"nodes\": %u, \"components\": %u, "
           "\"medium_voxels\": %" PRIu64 ", \"bytes\": %" PRIu64 ", \"grid\": [%d, %d, %d], "
           "\"voxel_size\": %.17g, \"geometry_hash\": \"%016" PRIx64 "\", "
           "\"skeleton_hash\": \"%016" PRIx64 "\"",
           lights, reachable, sg_cache_node_count(cache), sg_cache_component_count(cache),
           sg_cache_medium_voxels(cache), sg_cache_bytes(cache), dims[0], dims[1], dims[2],
           sg_cache_voxel_size(cache), sg_cache_geometry_hash(cache),
           sg_cache_skeleton_hash(cache));
    if (scene)
        printf(", \"scene\": \"%s\", \"camera_in_medium\": %s, \"geometry_matches\": %s",
               scene_path, camera_in_medium ? "true" : "false",
               scene->geometry_hash == sg_cache_geometry_hash(cache) ? "true" : "false");
    printf("}\n");
    sg_scene_free(scene);
    sg_cache_close(cache);
    return 0;
}

typedef struct OwnOptions {
    SgImportanceOptions *options;
    const char *info_path; /* --info CACHE */
} OwnOptions;

static SgCliArg own_option(void *ctx, int argc, char **argv, int *i)
{
    OwnOptions *own = ctx;
    const char *a = argv[*i];
    if (*i + 1 >= argc)
        return SG_CLI_OTHER; /* every one of them takes a value */
    if (!strcmp(a, "--vectors")) {
        own->options->vectors_path = argv[++*i];
    } else if (!strcmp(a, "--run-tolerance")) {
        double t;
        if (!sg_parse_double(argv[++*i], 0, 1, &t) || t <= 0) {
            fprintf(stderr, "importance: --run-tolerance takes a number in (0, 1]\n");
            return SG_CLI_BAD;
        }
        own->options->run_tolerance = t;
    } else if (!strcmp(a, "--info")) {
        own->info_path = argv[++*i];
    } else {
        return SG_CLI_OTHER;
    }
    return SG_CLI_TAKEN;
}

int main(int argc, char **argv)
{
    SgImportanceOptions options = {0};
    OwnOptions own = {.options = &options};
    SgStepArguments args = {.program = "importance", .usage = usage, .max_inputs = 2};
    SgCliArg got = sg_cli_step_arguments(&args, argc, argv, own_option, &own);
    if (got != SG_CLI_TAKEN)
        return got == SG_CLI_HELP ? 0 : 2;
    const char *info_path = own.info_path;
    bool want_info = info_path != NULL;
    const char *const *inputs = args.inputs, *out_path = args.out_path;
    int input_count = args.input_count;
    bool quiet = args.quiet;
    options.threads = args.threads;
    if (want_info) {
        if (input_count > 1 || out_path) {
            fprintf(stderr, "importance: --info takes a cache and an optional scene only\n");
            return 2;
        }
        return info(info_path, input_count ? inputs[0] : NULL);
    }
    if (input_count != 2 || !out_path) {
        fprintf(stderr, "importance: need medium.vdb, skeleton.ply and -o importance.cache "
                        "(see --help)\n");
        return 2;
    }
    options.quiet = quiet;
    options.medium_name = inputs[0];
    options.skeleton_name = inputs[1];

    SgError err = {0};
    SgMedium medium;
    memset(&medium, 0, sizeof medium);
    if (!sg_medium_read(&medium, inputs[0], &err)) {
        sg_error_print("importance", &err);
        return 1;
    }
    SgSkeleton skeleton;
    if (!sg_skeleton_read_ply(&skeleton, inputs[1], &err)) {
        sg_error_print("importance", &err);
        sg_medium_release(&medium);
        return 1;
    }
    /* Peak about 5 bytes per voxel with 32-bit nearest-node keys (up to
     * 2^18 nodes), 9 with 64-bit ones (measured): refuse up front what the
     * machine cannot hold rather than be killed. */
    double per_voxel = skeleton.node_count < (1u << 18) - 1 ? 6.0 : 10.0;
    if (!sg_memory_check(per_voxel * (double)sg_grid_count(&medium.grid), inputs[0],
                         "the nearest-node table of this medium", &err)) {
        sg_error_print("importance", &err);
        sg_skeleton_release(&skeleton);
        sg_medium_release(&medium);
        return 1;
    }
    SgImportanceStats stats;
    bool ok = sg_importance_build(&medium, &skeleton, &options, out_path, &stats, &err);
    if (!ok) {
        sg_error_print("importance", &err);
    } else if (!quiet) {
        fprintf(stderr,
                "importance: %s: %u nodes (%u components), %u/%u lights on the skeleton, "
                "%" PRIu64 " medium voxels (%" PRIu64 " labelled), %" PRIu64 " blocks, "
                "%.1f MB, %.2f s (labels %.2f in %u rounds, points %.2f, table %.2f, write %.2f)\n",
                out_path, stats.nodes, stats.components, stats.lights_reachable, stats.lights,
                stats.medium_voxels, stats.labelled_voxels, stats.blocks, stats.bytes / 1e6,
                stats.seconds_total, stats.seconds_labels, stats.label_rounds, stats.seconds_points,
                stats.seconds_table, stats.seconds_write);
    }
    sg_skeleton_release(&skeleton);
    sg_medium_release(&medium);
    return ok ? 0 : 1;
}
