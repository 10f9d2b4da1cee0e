/* bin/skeletonize medium.vdb -o skeleton.ply: step 2. */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "cli.h"

#include "medium.h"
#include "memory.h"
#include "progress.h"
#include "skeleton_graph.h"
#include "skeletonize.h"
#include "threads.h"

static void usage(FILE *out)
{
    fprintf(out,
            "usage: skeletonize medium.vdb -o skeleton.ply [--camera-constraint] [--threads N]\n"
            "                   [--serial-collapse]\n"
            "\n"
            "Thins the medium (the air light can reach) to its curvilinear skeleton: a\n"
            "graph with the medium's components and tunnels, centred in the air, passing\n"
            "through every light (and the camera with --camera-constraint). Collapse in\n"
            "cubical complexes [Chaussard & Couprie 2009], filtered by the parameter-free\n"
            "lifespan/opening rule [Chaussard 2010]. Cavities (solids floating in the air)\n"
            "are opened so that the result is 1D; their number is reported.\n"
            "\n"
            "  -o FILE              output PLY (binary little-endian; vertices with world\n"
            "                       position, voxel, kind, opening radius, lifespan, light)\n"
            "  --camera-constraint  the camera's voxel is a constraint too (kind 2)\n"
            "  --threads N          worker threads (default: every core)\n"
            "  --serial-collapse    run the collapse on one thread\n"
            "  --parallel-collapse  run the collapse on the threads even when other\n"
            "                       work holds the cores (default: parallel when they were\n"
            "                       idle at the start; the same result either way)\n"
            "  -q, --quiet          no summary line\n"
            "  -h, --help           this help\n");
}

/* Cores idle over the next `ms` milliseconds (from /proc/stat), or -1. */
static double idle_cores(int ms)
{
    unsigned long long a[2][8];
    for (int t = 0; t < 2; t++) {
        FILE *f = fopen("/proc/stat", "r");
        if (!f)
            return -1;
        int got = fscanf(f, "cpu %llu %llu %llu %llu %llu %llu %llu %llu", &a[t][0], &a[t][1],
                         &a[t][2], &a[t][3], &a[t][4], &a[t][5], &a[t][6], &a[t][7]);
        fclose(f);
        if (got != 8)
            return -1;
        if (t == 0) {
            struct timespec pause = {0, (long)ms * 1000000L};
            nanosleep(&pause, NULL);
        }
    }
    unsigned long long total = 0, idle = a[1][3] + a[1][4] - a[0][3] - a[0][4];
    for (int i = 0; i < 8; i++)
        total += a[1][i] - a[0][i];
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    return total && cores > 0 ? (double)idle / (double)total * (double)cores : -1;
}

typedef struct OwnOptions {
    SgSkeletonOptions *options;
    bool collapse_choice; /* --parallel-collapse or --serial-collapse given */
} OwnOptions;

static SgCliArg own_option(void *ctx, int argc, char **argv, int *i)
{
    (void)argc;
    OwnOptions *own = ctx;
    const char *a = argv[*i];
    if (!strcmp(a, "--parallel-collapse")) {
        own->options->parallel_grain = SG_SKELETON_PARALLEL_GRAIN;
        own->collapse_choice = true;
    } else if (!strcmp(a, "--serial-collapse")) {
        own->options->parallel_grain = 0;
        own->collapse_choice = true;
    } else if (!strcmp(a, "--camera-constraint")) {
        own->options->camera_constraint = true;
    } else {
        return SG_CLI_OTHER;
    }
    return SG_CLI_TAKEN;
}

int main(int argc, char **argv)
{
    SgSkeletonOptions options;
    sg_skeleton_options_default(&options);
    OwnOptions own = {.options = &options};
    SgStepArguments args = {.program = "skeletonize", .usage = usage, .threads = options.threads,
                            .min_inputs = 1, .max_inputs = 1, .out_required = true};
    SgCliArg got = sg_cli_step_arguments(&args, argc, argv, own_option, &own);
    if (got != SG_CLI_TAKEN)
        return got == SG_CLI_HELP ? 0 : 2;
    const char *in_path = args.inputs[0], *out_path = args.out_path;
    bool quiet = args.quiet, collapse_choice = own.collapse_choice;
    options.threads = args.threads;

    SgError err = {0};
    double t0 = sg_seconds();
    SgMedium medium;
    if (!sg_medium_read(&medium, in_path, &err)) {
        sg_error_print("skeletonize", &err);
        return 1;
    }
    double t_read = sg_seconds() - t0;
    /* The parallel collapse's threads wait for each other only where their
     * slabs meet, but when other work holds the cores a descheduled thread
     * still holds up the slabs around its own, and the collapse runs slower
     * than on one thread (Sponza 1000 at load 3 to 4 on 2 cores: 67.7 s
     * against 59.7 s; with a barrier per sub-step it was 209 s against
     * 28 s at Sponza 500, load 15). Unless told, a large medium's collapse
     * goes parallel only when the cores were idle over a fifth of a second.
     * Same result either way. */
    bool busy = false;
    int cores = sg_thread_count(options.threads);
    if (!collapse_choice && options.parallel_grain && cores > 1 &&
        sg_grid_count(&medium.grid) >= ((size_t)1 << 24)) {
        double idle = idle_cores(200);
        busy = idle >= 0 && idle < cores - 0.5;
        if (busy)
            options.parallel_grain = 0;
    }
    /* Peak about 9 bytes per voxel (distance maps, complex, queues; measured):
     * refuse up front what the machine cannot hold rather than be killed. */
    if (!sg_memory_check(12.0 * (double)sg_grid_count(&medium.grid), in_path,
                         "skeletonizing this medium", &err)) {
        sg_error_print("skeletonize", &err);
        sg_medium_release(&medium);
        return 1;
    }
    SgSkeleton skeleton;
    SgSkeletonStats stats;
    if (!sg_skeletonize(&medium, &options, &skeleton, &stats, &err)) {
        /* name the input: the library's messages speak of the medium */
        SgError named = {0};
        sg_fail(&named, "%s: %s", in_path, err.message);
        sg_error_print("skeletonize", &named);
        sg_medium_release(&medium);
        return 1;
    }
    bool ok = sg_skeleton_write_ply(&skeleton, out_path, &err);
    if (!ok) {
        sg_error_print("skeletonize", &err);
    } else if (!quiet) {
        if (options.camera_constraint && !stats.camera_constrained)
            fprintf(stderr, "skeletonize: %s: note: the camera is not in the medium; "
                            "it is not a constraint\n", in_path);
        fprintf(stderr,
                "skeletonize: %" PRIu64 " medium voxels -> %u nodes, %u edges, %" PRId64
                " loops, %u components, %u cavities broken%s; %u constraints, %u steps, "
                "centredness %.3f; read %.2f s, distance %.2f s, collapse %.2f s%s, total %.2f s\n",
                stats.medium_voxels, stats.nodes, stats.edges, stats.loops, stats.components,
                stats.cavities_broken, stats.forced_breaks ? " (+ forced breaks)" : "",
                stats.constraints, stats.steps, stats.mean_centredness, t_read,
                stats.seconds_distance, stats.seconds_collapse,
                busy ? " (one thread: the cores are busy)" : "", sg_seconds() - t0);
    }
    sg_skeleton_release(&skeleton);
    sg_medium_release(&medium);
    return ok ? 0 : 1;
}
