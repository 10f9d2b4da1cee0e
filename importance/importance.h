/* Step 3: importance points (paper 3.3 and the end of 3.2).
 *   1. nearest skeleton node of every medium voxel, by geodesic distance
 *      (multi-source Dijkstra in the air, 26-neighbourhood);
 *   2. shortest paths on the skeleton graph from every light's node;
 *   3. for every node and light: the barycenter of the first run of nodes,
 *      along the path toward the light, that the node sees;
 *   4. importance.cache (docs/cache-format.md), read by importance_cache.h.
 * The work is split so that tests can check each part on in-memory data. */
#ifndef SG_IMPORTANCE_H
#define SG_IMPORTANCE_H

#include <stdbool.h>
#include <stdint.h>

#include "error.h"
#include "grid.h"
#include "medium.h"
#include "skeleton_graph.h"

#ifdef __cplusplus
extern "C" {
#endif

/* By default every node of a run is tested (the paper's rule). With a run
 * tolerance T > 0 the path is walked in chunks instead: a chunk whose far
 * end is visible counts as visible when it spans at most T times its
 * distance from the node; otherwise its nodes are tested one by one, so the
 * end of the run found is still a real first invisible node. Faster on
 * long runs, but an obstacle hidden between two close sight lines is
 * missed: on a real staircase (23k nodes) T = 1/8 changed 1.3% of the
 * points by more than 10 degrees. */
typedef struct SgImportanceOptions {
    int threads;              /* <= 0: every core */
    double run_tolerance;     /* 0: exact (every node of the run tested) */
    const char *vectors_path; /* optional: figure 2 as a PLY of node -> point edges */
    const char *medium_name;   /* the inputs' names in messages (default "medium", */
    const char *skeleton_name; /* "skeleton") */
    bool quiet;               /* no summary line on stderr */
} SgImportanceOptions;

/* What the build found, for the summary line and the benchmark. */
typedef struct SgImportanceStats {
    uint64_t medium_voxels;
    uint64_t labelled_voxels; /* medium voxels reached from some node */
    uint32_t label_rounds;    /* rounds of tile phases of the nearest-node propagation */
    uint64_t label_settled;   /* voxels settled over all rounds */
    uint32_t nodes, components, lights, lights_reachable;
    uint64_t blocks, palette_entries, bytes;
    double seconds_labels, seconds_points, seconds_table, seconds_write, seconds_total;
} SgImportanceStats;

/* Step 1: label[v] = nearest node of medium voxel v (SG_CACHE_NONE where no
 * node is reachable or the voxel is not medium). labels: sg_grid_count(grid)
 * entries, filled. Nodes whose voxel is outside the grid or not medium are
 * not sources. Deterministic for any thread count: among the nodes at the
 * shortest distance the lowest id wins. */
bool sg_importance_label_voxels(const SgGrid *grid, const SgSkeleton *skeleton, int threads,
                                uint32_t *labels, SgError *err);

/* Straight segment between voxel centres a and b stays inside the medium
 * (exact voxel traversal, Amanatides & Woo; in voxel units). */
bool sg_importance_visible(const SgGrid *grid, const int a[3], const int b[3]);

/* Identity of a skeleton graph (positions, voxels, kinds, lights, edges). */
uint64_t sg_importance_skeleton_hash(const SgSkeleton *skeleton);

/* Steps 1-4: builds and writes the cache at out_path (atomically). */
bool sg_importance_build(const SgMedium *medium, const SgSkeleton *skeleton,
                         const SgImportanceOptions *options, const char *out_path,
                         SgImportanceStats *stats, SgError *err);

#ifdef __cplusplus
}
#endif
#endif
