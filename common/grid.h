/* A dense voxel grid over an axis-aligned box, one byte per voxel.
 * Voxel (i,j,k) covers the world box
 *   [origin + (i,j,k) * voxel_size, origin + (i+1,j+1,k+1) * voxel_size].
 * Dense bytes are cheap at the sizes we use (the paper's largest grid,
 * 210x308x500, is 32 MB) and give O(1) access without hashing. */
#ifndef SG_GRID_H
#define SG_GRID_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "error.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct SgGrid {
    int nx, ny, nz;
    double origin[3];  /* world position of the min corner of voxel (0,0,0) */
    double voxel_size; /* world length of a voxel edge */
    uint8_t *voxels;   /* nx*ny*nz values, x fastest */
} SgGrid;

/* Allocates a zeroed grid; fails cleanly (no abort) when too large. */
bool sg_grid_init(SgGrid *grid, int nx, int ny, int nz, const double origin[3],
                  double voxel_size, SgError *err);
void sg_grid_release(SgGrid *grid);

static inline size_t sg_grid_index(const SgGrid *g, int i, int j, int k)
{
    return (size_t)i + (size_t)g->nx * ((size_t)j + (size_t)g->ny * (size_t)k);
}

/* The voxel (i,j,k) at index v: the inverse of sg_grid_index. */
static inline void sg_grid_coords(const SgGrid *g, size_t v, int ijk[3])
{
    ijk[0] = (int)(v % (size_t)g->nx);
    ijk[1] = (int)(v / (size_t)g->nx % (size_t)g->ny);
    ijk[2] = (int)(v / (size_t)g->nx / (size_t)g->ny);
}

static inline size_t sg_grid_count(const SgGrid *g)
{
    return (size_t)g->nx * (size_t)g->ny * (size_t)g->nz;
}

static inline bool sg_grid_inside(const SgGrid *g, int i, int j, int k)
{
    return i >= 0 && j >= 0 && k >= 0 && i < g->nx && j < g->ny && k < g->nz;
}

/* Value at (i,j,k); 0 outside the grid. */
static inline uint8_t sg_grid_get(const SgGrid *g, int i, int j, int k)
{
    return sg_grid_inside(g, i, j, k) ? g->voxels[sg_grid_index(g, i, j, k)] : 0;
}

/* World point -> voxel that contains it (may be outside the grid). */
void sg_grid_world_to_voxel(const SgGrid *g, const double p[3], int ijk[3]);
/* Centre of voxel (i,j,k) in world space. */
void sg_grid_voxel_center(const SgGrid *g, int i, int j, int k, double p[3]);

size_t sg_grid_count_nonzero(const SgGrid *g);

#ifdef __cplusplus
}
#endif
#endif
