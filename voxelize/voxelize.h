/* Step 1: the medium, the air that light can reach.
 * Conservative voxelization (every voxel a triangle touches is solid, by an
 * exact separating-axis test), then 26-connected components of the air;
 * only components that hold a light's seed voxel are kept. */
#ifndef SG_VOXELIZE_H
#define SG_VOXELIZE_H

#include <stdbool.h>
#include <stdint.h>

#include "error.h"
#include "grid.h"
#include "medium.h"
#include "scene.h"

#define SG_VOXELIZE_DEFAULT_RESOLUTION 128
/* Bumped when the voxelization rules change, so that make redoes it. */
#define SG_VOXELIZE_VERSION 1
/* Voxels of air round a scene lit from outside (a sky, a sun): enough for
 * the skeleton to pass round the building from one opening to another. */
#define SG_VOXELIZE_OUTSIDE_MARGIN 3

typedef struct SgVoxelizeOptions {
    int resolution; /* voxels along the longest side; 0: scene's, else default */
    int threads;    /* 0: every core */
} SgVoxelizeOptions;

typedef struct SgVoxelizeStats {
    uint64_t solid_voxels;
    uint64_t air_voxels;
    uint64_t medium_voxels;
    uint32_t air_components;    /* 26-connected components of all the air */
    uint32_t medium_components; /* of those, the ones a light reaches */
    uint32_t sealed_lights;     /* lights with no air voxel in front of them */
    bool camera_in_grid;
    uint8_t camera_voxel_state; /* 0 unreachable air, 1 solid, 2 medium */
    double seconds_voxelize, seconds_fill;
} SgVoxelizeStats;

/* Exact overlap of a triangle and the axis-aligned box centre +- half
 * (closed: touching counts). Coordinates in any unit. */
bool sg_triangle_box_overlap(const double centre[3], double half, const double a[3],
                             const double b[3], const double c[3]);

/* Grid placement for a scene: `resolution` voxels along the longest side of
 * its bounding box. */
bool sg_voxelize_grid_for(const SgScene *scene, int resolution, SgGrid *grid, SgError *err);

/* Marks solid voxels (value 1) of every triangle into grid (zeroed);
 * dielectric (glass) triangles are skipped: light passes through them. */
void sg_voxelize_surface(const SgScene *scene, SgGrid *grid, int threads);

/* Builds the medium of a scene. options and stats may be NULL. */
bool sg_voxelize(const SgScene *scene, const SgVoxelizeOptions *options, SgMedium *medium,
                 SgVoxelizeStats *stats, SgError *err);

#endif
