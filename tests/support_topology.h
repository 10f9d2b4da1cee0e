/* Betti numbers of a voxel set (closed unit cubes, hence 26-connected) and
 * of a skeleton graph, to check that the skeleton keeps the topology. */
#ifndef SG_TESTS_SUPPORT_TOPOLOGY_H
#define SG_TESTS_SUPPORT_TOPOLOGY_H

#include <stdbool.h>
#include <stdint.h>

#include "error.h"
#include "grid.h"
#include "skeleton_graph.h"

typedef struct SgBetti {
    int64_t b0;  /* components (26-connectivity) */
    int64_t b1;  /* tunnels: b0 + b2 - chi */
    int64_t b2;  /* cavities: 6-components of the background in a padded frame, minus 1 */
    int64_t chi; /* Euler characteristic of the closed cubical complex */
} SgBetti;

/* Voxels with a non-zero value form the set. */
bool sg_voxel_betti(const SgGrid *grid, SgBetti *out, SgError *err);

/* b0 = components, b1 = E - V + b0, b2 = 0; fails on an edge with a bad
 * node index. */
bool sg_graph_betti(const SgSkeleton *skeleton, SgBetti *out, SgError *err);

#endif
