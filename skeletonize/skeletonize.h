/* Step 2: the curvilinear skeleton of the medium.
 *
 * The medium's voxels are closed unit cubes of a cubical complex (so the
 * medium is 26-connected); a directional parallel collapse [CC09] removes
 * free pairs layer by layer, and the lifespan/opening rule of [Cha10]
 * restricts the result to 1D: after step l, an edge that has belonged to no
 * square for more than opening(e) steps joins the constraint set (opening
 * = radius of the largest ball in the medium containing the voxels around
 * the edge). What is left is a graph: 0-cells are nodes, 1-cells edges.
 *
 * Guarantees (tested in tests/test_skeleton.c):
 * - the collapse is homotopic, so the graph has the medium's components,
 *   and E - V + components = b1 of the medium (its tunnels);
 * - cavities: when the collapse stalls with squares left, those squares
 *   bound regions of space; a square with different regions on its two
 *   sides lies on a closed surface, and removing it merges the regions:
 *   b2 drops by one and b1 does not change. One such square is removed per
 *   cavity (union-find over regions, thinnest air first), so
 *   cavities_broken = b2 of the medium and the loops are untouched. If a
 *   stuck 2D part had no such square (a non-collapsible contractible
 *   complex: never seen), one square is removed anyway and counted in
 *   forced_breaks, which adds a loop;
 * - every light (and with camera_constraint the camera) voxel in the
 *   medium gives a node of its kind standing on that voxel: a corner of the
 *   voxel is a constrained 0-cell;
 * - every node stands on a medium voxel (of the up to 8 voxels around its
 *   lattice vertex, the one farthest from the walls) and sits at its centre;
 * - the result does not depend on the thread count.
 * A node's lifespan is the largest, over its edges, of the steps between
 * the edge losing its last square and joining the constraint set (or the
 * end of the collapse); an isolated node's is the number of steps. */
#ifndef SG_SKELETONIZE_H
#define SG_SKELETONIZE_H

#include <stdbool.h>
#include <stdint.h>

#include "error.h"
#include "grid.h"
#include "medium.h"
#include "skeleton_graph.h"

#ifdef __cplusplus
extern "C" {
#endif

#define SG_SKELETON_PARALLEL_GRAIN 16384

typedef struct SgSkeletonOptions {
    bool camera_constraint; /* the camera's voxel joins the constraint set */
    int threads;            /* <= 0: every core */
    bool progress;          /* progress line on a terminal (stderr) */
    uint32_t parallel_grain; /* > 0: the collapse runs on the threads (same
                               result; default SG_SKELETON_PARALLEL_GRAIN, the
                               value no longer matters); 0: the collapse runs
                               on one thread: skeletonize --serial-collapse */
    uint32_t collapse_slab_planes; /* the collapse's slabs of z planes: 0 two
                               (default), n >= 2 n planes, more than the
                               grid's: one slab; same result (the tests
                               compare them) */
    uint64_t collapse_schedule_seed; /* tests: 0 (default) the usual
                               schedule; else one thread plays two, taking
                               random ready (slab, sub-step)s: any order the
                               collapse's readiness rule allows gives the
                               same result */
    double filter_scale;    /* the lifespan rule keeps an edge when
                               lifespan > filter_scale x opening; 1 is [Cha10]'s
                               parameter-free rule (default), 0 keeps every
                               edge as soon as it is isolated (no filter) */
} SgSkeletonOptions;

typedef struct SgSkeletonStats {
    uint64_t medium_voxels;
    uint32_t nodes, edges;
    uint32_t components;     /* of the graph */
    int64_t loops;           /* E - V + components */
    uint32_t cavities_broken;  /* squares removed to open cavities (b2 of the medium) */
    uint32_t forced_breaks;    /* squares removed although no cavity was behind them
                                  (a stuck, non-collapsible 2D part); 0 in practice */
    uint32_t constraints;      /* light (+ camera) constraint cells */
    bool camera_constrained;   /* the camera's voxel was in the medium and is a node */
    uint32_t steps;            /* collapse steps */
    double mean_centredness;   /* mean over nodes of dist(node voxel) / max dist in its 3x3x3 */
    double seconds_distance, seconds_collapse, seconds_total;
} SgSkeletonStats;

void sg_skeleton_options_default(SgSkeletonOptions *opt);

/* Thins medium->grid (1 = medium voxel). Light i with a seed inside the
 * medium gives a node of kind SG_NODE_LIGHT, light = i, voxel = seed.
 * On failure *out is left empty. stats may be NULL. */
bool sg_skeletonize(const SgMedium *medium, const SgSkeletonOptions *opt, SgSkeleton *out,
                    SgSkeletonStats *stats, SgError *err);

/* Same on a bare grid with explicit constraint voxels (kind[i] is the
 * SgNodeKind, light[i] the light index or -1). */
bool sg_skeletonize_grid(const SgGrid *grid, uint32_t constraint_count, const int (*voxels)[3],
                         const uint8_t *kinds, const int *lights, const SgSkeletonOptions *opt,
                         SgSkeleton *out, SgSkeletonStats *stats, SgError *err);

/* Free-space measures used by the skeleton (exposed for tests and step 3).
 * dist8[v]: 8 x Euclidean distance from voxel v's centre to the nearest
 * centre of a voxel outside the medium (the grid's outside counts as
 * outside), 0 outside the medium, saturated at 65535.
 * open8[v]: 8 x opening value: the radius of the largest such ball that
 * lies in the medium and contains v (approximate propagation, see
 * distance.c). Arrays have nx*ny*nz entries, x fastest; free() them. */
bool sg_distance_opening(const SgGrid *grid, int threads, uint16_t **dist8, uint16_t **open8,
                         SgError *err);
/* The same values in the collapse's lattice layout (complex.h: sizes
 * n + 3, voxel (x, y, z) at vertex (x + 1, y + 1, z + 1), zero on the
 * padding), written there in place of a second array. */
bool sg_distance_opening_lattice(const SgGrid *grid, int threads, uint16_t **dist8,
                                 uint16_t **open8, SgError *err);

#ifdef __cplusplus
}
#endif
#endif
