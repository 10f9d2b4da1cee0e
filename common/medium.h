/* The medium: the air that light can reach, as a voxel grid plus what the
 * later steps need to know about how it was made. Stored as an OpenVDB
 * file (a BoolGrid named "medium"; file metadata holds the rest) through a
 * thin C++ wrapper, medium_vdb.cpp; nothing of OpenVDB leaks out. */
#ifndef SG_MEDIUM_H
#define SG_MEDIUM_H

#include <stdbool.h>
#include <stdint.h>

#include "error.h"
#include "grid.h"

#ifdef __cplusplus
extern "C" {
#endif

#define SG_MEDIUM_GRID_NAME "medium"

typedef struct SgMediumLight {
    double position[3]; /* world centroid of the emitter */
    double normal[3];
    double power;       /* scalar power used to choose lights */
    float radiance[3];
    int seed[3];        /* the air voxel in front of the emitter: flood-fill seed
                           and skeleton constraint; (-1,-1,-1) if sealed */
    bool outside;       /* the sky: every air voxel of the grid's outside
                           margin is this light (SgGuideLight) */
    bool sun;           /* a sun (normal: the way its rays travel): every
                           medium voxel its rays reach through the medium */
} SgMediumLight;

typedef struct SgMedium {
    SgGrid grid;               /* voxels: 1 = medium, 0 = solid or unreachable air */
    uint32_t light_count;
    SgMediumLight *lights;
    bool has_camera;
    double camera_position[3];
    int resolution;            /* voxels along the longest side */
    int outside_margin;        /* voxels of air added round the scene's bounds
                                  for light from outside; 0: none */
    uint64_t geometry_hash;    /* SgScene.geometry_hash of the input */
    char scene_path[4096];
} SgMedium;

/* Writes atomically (temporary name, then rename). Only voxels with a
 * non-zero value become active in the VDB grid. */
bool sg_medium_write(const SgMedium *medium, const char *path, SgError *err);
/* Reads a file written by sg_medium_write (or any VDB with a bool/mask
 * grid named "medium"); fails with a one-line message otherwise. */
bool sg_medium_read(SgMedium *medium, const char *path, SgError *err);
void sg_medium_release(SgMedium *medium);

#ifdef __cplusplus
}
#endif
#endif
