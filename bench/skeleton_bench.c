/* Skeleton benchmark: the furnished synthetic room (walls, table, sofa,
 * pillar, hanging lamp) at a given grid size, through sg_skeletonize.
 *   skeleton_bench NX NY NZ [THREADS [par]]   (par: parallel collapse too)
 * prints one markdown table row: grid, threads, medium voxels, wall seconds (distance,
 * collapse, total), CPU seconds of the skeleton (user + system, all
 * threads), peak RSS in MB (VmHWM, the whole process including the
 * 1-byte-per-voxel input grid), nodes, edges, loops, cavities broken, mean
 * centredness. Building the room is not timed. */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

#include "../tests/support_shapes.h"
#include "../skeletonize/skeletonize.h"

static double peak_rss_mb(void)
{
    FILE *f = fopen("/proc/self/status", "r");
    if (!f)
        return -1;
    char line[256];
    double mb = -1;
    while (fgets(line, sizeof line, f))
        if (!strncmp(line, "VmHWM:", 6))
            mb = strtod(line + 6, NULL) / 1024.0;
    fclose(f);
    return mb;
}

static double cpu_seconds(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec +
           (double)ru.ru_stime.tv_sec + 1e-6 * (double)ru.ru_stime.tv_usec;
}

int main(int argc, char **argv)
{
    if (argc < 4) {
        fprintf(stderr, "usage: skeleton_bench NX NY NZ [THREADS [par]]\n");
        return 2;
    }
    int nx = atoi(argv[1]), ny = atoi(argv[2]), nz = atoi(argv[3]);
    SgMedium medium;
    if (nx < 8 || ny < 8 || nz < 8 || !sg_shape_furnished_room(nx, ny, nz, &medium)) {
        fprintf(stderr, "skeleton_bench: cannot build a %dx%dx%d room\n", nx, ny, nz);
        return 1;
    }
    SgSkeletonOptions opt;
    sg_skeleton_options_default(&opt);
    opt.progress = false;
    opt.threads = argc > 4 ? atoi(argv[4]) : 0;
    opt.parallel_grain = argc > 5 && !strcmp(argv[5], "par") ? SG_SKELETON_PARALLEL_GRAIN : 0;
    SgSkeleton skeleton;
    SgSkeletonStats st;
    SgError err = {0};
    double cpu0 = cpu_seconds();
    if (!sg_skeletonize(&medium, &opt, &skeleton, &st, &err)) {
        sg_error_print("skeleton_bench", &err);
        return 1;
    }
    double cpu = cpu_seconds() - cpu0;
    char grid[64];
    snprintf(grid, sizeof grid, "%dx%dx%d", nx, ny, nz);
    char threads[16];
    snprintf(threads, sizeof threads, "%d%s", opt.threads, opt.parallel_grain ? "+par" : "");
    printf("| %s | %s | %" PRIu64 " | %.2f | %.2f | %.2f | %.2f | %.0f | %u | %u | %" PRId64 " | %u | %.3f |\n",
           grid, threads, st.medium_voxels, st.seconds_distance, st.seconds_collapse,
           st.seconds_total, cpu, peak_rss_mb(), st.nodes, st.edges, st.loops,
           st.cavities_broken, st.mean_centredness);
    sg_skeleton_release(&skeleton);
    sg_shape_medium_free(&medium);
    return 0;
}
