/* Synthetic media for the skeleton's tests and benchmark: shapes described
 * in a continuous box (1 unit = 1 voxel at scale 1), voxelized at any
 * scale, with light seeds. World units = description units. */
#ifndef SG_TESTS_SUPPORT_SHAPES_H
#define SG_TESTS_SUPPORT_SHAPES_H

#include <stdbool.h>
#include <stdint.h>

#include "grid.h"
#include "medium.h"

typedef enum SgShape {
    SG_SHAPE_BAR,          /* 4x4 section bar */
    SG_SHAPE_CUBE,         /* full cube */
    SG_SHAPE_TORUS,        /* solid torus of air */
    SG_SHAPE_PILLAR_ROOM,  /* room with one floor-to-ceiling pillar */
    SG_SHAPE_THREE_PILLARS,
    SG_SHAPE_RING,         /* square ring corridor in rock */
    SG_SHAPE_LAMP_ROOM,    /* room with a floating box lamp */
    SG_SHAPE_U,            /* U-shaped corridor */
    SG_SHAPE_SHELL,        /* hollow sphere of air: b2 = 1 */
    SG_SHAPE_TWO_ROOMS,    /* two separate rooms */
    SG_SHAPE_RING_LAMP,    /* room with a floating solid ring (b1 = 1, b2 = 1) */
    SG_SHAPE_COUNT
} SgShape;

typedef struct SgShapeInfo {
    const char *name;
    int b0, b1, b2; /* of the air */
} SgShapeInfo;

const SgShapeInfo *sg_shape_info(SgShape shape);

/* Voxelizes the shape with `scale` voxels per unit of its description
 * (scale 1 = the smallest sensible size); fills a medium with one light
 * seed per component. Returns false on allocation failure. */
bool sg_shape_medium(SgShape shape, int scale, SgMedium *out);

/* Adds 1-voxel bumps on the walls: each medium voxel touching a wall turns
 * solid with probability p (deterministic for a seed), keeping seeds. */
void sg_shape_roughen(SgMedium *m, double p, uint64_t seed);

/* The benchmark's furnished room (walls, table, sofa, pillar, lamp shade
 * on a cord) at nx x ny x nz voxels, one light under the ceiling. */
bool sg_shape_furnished_room(int nx, int ny, int nz, SgMedium *out);

/* Frees what sg_shape_* allocated (grid + lights). */
void sg_shape_medium_free(SgMedium *m);

#endif
