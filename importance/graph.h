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

/* Segment visibility with an occupancy accelerator (4x4x4 bricks). */
typedef struct SgVisibility {
    const SgGrid *grid;
    uint64_t *full; /* bit per brick: all medium; NULL: none */
    size_t bx, by;
} SgVisibility;

bool sg_visibility_init(SgVisibility *vis, const SgGrid *grid, SgError *err);
void sg_visibility_release(SgVisibility *vis);
bool sg_visibility_test(const SgVisibility *vis, const int a[3], const int b[3]);

/* Chunks of the path toward the light whose far end is visible count as
 * visible when they span at most this fraction of their distance. */
#define SG_RUN_TOLERANCE 0.125

/* Importance point of `node` for the light whose shortest-path tree is
 * (pred, dist) (dist 0 at the light's nodes). */
void sg_importance_point(const SgVisibility *vis, const SgSkeleton *skeleton, const uint32_t *pred,
                         const double *dist, uint32_t node, const double light_position[3],
                         float point[3]);

#endif
