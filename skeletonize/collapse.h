/* Directional parallel collapse [CC09] restricted to 1D output by the
 * lifespan/opening rule [Cha10], with cavity breaking. Internal to the
 * skeletonize library. */
#ifndef SG_SKELETON_COLLAPSE_H
#define SG_SKELETON_COLLAPSE_H

#include "complex.h"
#include "progress.h"

/* One edge that has lost its last square: when, and how thick the medium
 * around it is. */
typedef struct SgIsolatedEdge {
    uint32_t cell;
    int32_t birth;   /* step at which it stopped being a face of any square */
    int32_t kept;    /* step at which it joined the constraint set, -1 if not */
    uint16_t open8;  /* 8 x opening value (max over the voxels around it) */
} SgIsolatedEdge;

typedef struct SgCollapseResult {
    uint32_t steps;
    uint32_t cavities_broken;
    uint32_t forced_breaks;
    SgIsolatedEdge *edges; /* every edge that became isolated and survived, sorted by cell */
    size_t edge_count;
} SgCollapseResult;

/* Collapses cx in place until only 0- and 1-cells are left. constrained
 * lists cell ids that are never removed. dist8/open8 are the medium's
 * distance and opening in lattice layout (voxel (i,j,k) at the index of
 * vertex (i,j,k), 0 elsewhere). An isolated edge joins the constraint set
 * when lifespan > filter_scale x opening (1: [Cha10]). parallel_grain > 0:
 * the collapse runs on `threads` threads (<= 0: every core); 0: on one.
 * slab_planes: the z planes per slab of the temporal blocking (0: two, the
 * fewest). schedule_seed: 0, the usual schedule; else (tests) one
 * thread takes random ready (slab, sub-step)s, two at a time. The result
 * is the same for any. */
bool sg_collapse(SgComplex *cx, const uint32_t *constrained, size_t constrained_count,
                 const uint16_t *dist8, const uint16_t *open8, double filter_scale,
                 int threads, uint32_t parallel_grain, uint32_t slab_planes,
                 uint64_t schedule_seed, SgProgress *progress,
                 SgCollapseResult *result, SgError *err);
void sg_collapse_result_release(SgCollapseResult *r);

#endif
