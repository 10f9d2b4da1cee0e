/* Internal to step 3: the nearest-node label of every voxel, kept in a grid
 * padded by one voxel on each side (the propagation's layout). */
#ifndef SG_IMPORTANCE_LABELS_H
#define SG_IMPORTANCE_LABELS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "importance.h"

typedef struct SgLabelGrid {
    int nx, ny, nz;
    size_t px, py;      /* padded sizes along x and y */
    /* (nx+2)(ny+2)(nz+2) keys, one of the two arrays: key = distance << 32 |
     * node, or key32 = distance << bits | node when the node ids leave room;
     * a node field of all ones (node_mask): no node / not medium */
    uint64_t *key;
    uint32_t *key32;
    uint32_t node_mask;
    bool widened;              /* 32-bit keys were tried and a distance did not fit */
    uint64_t medium_voxels;
    uint64_t labelled_voxels;
    uint32_t rounds;           /* rounds of tile phases until no tile had a seed */
    uint64_t settled;          /* voxels settled over all rounds (>= labelled) */
} SgLabelGrid;

bool sg_label_grid_build(const SgGrid *grid, const SgSkeleton *skeleton, int threads,
                         SgLabelGrid *out, SgError *err);
/* The same with the key width forced (for tests): key_bits 64 (wide keys
 * only) or 0 (automatic, as above); distance_limit > 0 lowers the largest
 * distance 32-bit keys take before the build falls back to 64-bit ones.
 * The labels do not depend on either. */
bool sg_label_grid_build_keys(const SgGrid *grid, const SgSkeleton *skeleton, int threads,
                              int key_bits, uint32_t distance_limit, SgLabelGrid *out,
                              SgError *err);
void sg_label_grid_release(SgLabelGrid *g);

static inline uint32_t sg_label_at(const SgLabelGrid *g, int i, int j, int k)
{
    size_t v = (size_t)(i + 1) + g->px * ((size_t)(j + 1) + g->py * (size_t)(k + 1));
    if (g->key)
        return (uint32_t)g->key[v];
    uint32_t node = g->key32[v] & g->node_mask;
    return node == g->node_mask ? UINT32_MAX : node;
}

#endif
