/* Internal to step 3: the skeleton graph in compressed adjacency form. */
#ifndef SG_IMPORTANCE_GRAPH_H
#define SG_IMPORTANCE_GRAPH_H

#include <stddef.h>
#include <stdint.h>

#include "importance.h"

typedef struct SgGraph {
    uint32_t node_count;
    uint32_t *first;   /* node_count + 1: neighbours of n are adjacent[first[n] .. first[n+1]) */
    uint32_t *adjacent;
    double *length;    /* Euclidean length of each half-edge */
} SgGraph;

bool sg_graph_build(const SgSkeleton *skeleton, SgGraph *graph, SgError *err);
void sg_graph_release(SgGraph *graph);
/* stack: node_count entries of scratch. Returns the component count. */
uint32_t sg_graph_components(const SgGraph *graph, uint32_t *component, uint32_t *stack);
/* Multi-source Dijkstra; heap_memory: sg_graph_heap_bytes(graph) bytes. */
void sg_graph_shortest_paths(const SgGraph *graph, const uint32_t *sources,
                             uint32_t source_count, double *dist, uint32_t *pred,
                             void *heap_memory);
size_t sg_graph_heap_bytes(const SgGraph *graph);

/* Segment visibility with an accelerator: per 4^3 brick, its medium
 * voxels as the bits of a word, and its clearance, the chessboard distance
 * in bricks to the nearest brick that is not all medium (0 for those). */
typedef struct SgVisibility {
    const SgGrid *grid;
    uint64_t *bits;    /* bx * by * bz bricks; NULL: no accelerator */
    uint8_t *clear;
    size_t bx, by, bz;
} SgVisibility;

/* threads: for the bricks' words (<= 0: every core) */
bool sg_visibility_init(SgVisibility *vis, const SgGrid *grid, int threads, SgError *err);
void sg_visibility_release(SgVisibility *vis);
bool sg_visibility_test(const SgVisibility *vis, const int a[3], const int b[3]);

/* Importance point of `node` for the light whose shortest-path tree is
 * (pred, dist) (dist 0 at the light's nodes). tolerance: see
 * SgImportanceOptions.run_tolerance (0: every node tested). */
void sg_importance_point(const SgVisibility *vis, const SgSkeleton *skeleton, const uint32_t *pred,
                         const double *dist, uint32_t node, const double light_position[3],
                         double tolerance, float point[3]);

#endif
