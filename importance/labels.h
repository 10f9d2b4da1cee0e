/* Internal to step 3: the nearest-node label of every voxel, kept in a grid
 * padded by one voxel on each side (the propagation's layout). */
#ifndef SG_IMPORTANCE_LABELS_H
#define SG_IMPORTANCE_LABELS_H

#include <stddef.h>
#include <stdint.h>

#include "importance.h"

typedef struct SgLabelGrid {
    int nx, ny, nz;
    size_t px, py;      /* padded sizes along x and y */
    uint64_t *key;      /* (nx+2)(ny+2)(nz+2): distance << 32 | node; node SG_CACHE_NONE:
                           no node / not medium */
    uint64_t medium_voxels;
    uint64_t labelled_voxels;
    uint32_t rounds;           /* slab rounds until the boundaries were stable */
    uint64_t settled;          /* voxels settled over all rounds (>= labelled) */
} SgLabelGrid;

bool sg_label_grid_build(const SgGrid *grid, const SgSkeleton *skeleton, int threads,
                         SgLabelGrid *out, SgError *err);
void sg_label_grid_release(SgLabelGrid *g);

static inline uint32_t sg_label_at(const SgLabelGrid *g, int i, int j, int k)
{
    return (uint32_t)g->key[(size_t)(i + 1) + g->px * ((size_t)(j + 1) + g->py * (size_t)(k + 1))];
}

#endif
