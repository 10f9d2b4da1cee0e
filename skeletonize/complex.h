/* The medium as a cubical complex, in Chaussard's compact layout: one byte
 * per lattice vertex whose 8 bits are the cells that vertex owns. Cell
 * (v, m): lattice vertex v, mask m of the axes the cell extends along
 * (bit0 x, bit1 y, bit2 z): m = 0 vertex, 1/2/4 edges, 3/5/6 squares,
 * 7 cube; it spans [v, v + m]. The voxel (i,j,k) is the cube at vertex
 * (i,j,k). The lattice has one vertex of padding on every side so that
 * neighbour lookups need no bounds checks. A cell id is v * 8 + m. */
#ifndef SG_SKELETON_COMPLEX_H
#define SG_SKELETON_COMPLEX_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "error.h"
#include "grid.h"

typedef struct SgComplex {
    int nx, ny, nz;       /* voxels */
    int lx, ly, lz;       /* lattice vertices per axis: n + 3 (padding) */
    size_t stride[3];     /* lattice index steps along x, y, z */
    size_t vertex_count;
    uint8_t *cells;       /* present cells */
} SgComplex;

/* Builds the closed complex of the grid's non-zero voxels (threads for
 * the planes). */
bool sg_complex_build(SgComplex *cx, const SgGrid *grid, int threads, SgError *err);
void sg_complex_release(SgComplex *cx);

static inline size_t sg_complex_vertex(const SgComplex *cx, int x, int y, int z)
{
    return (size_t)(x + 1) + (size_t)cx->lx * ((size_t)(y + 1) + (size_t)cx->ly * (size_t)(z + 1));
}

static inline void sg_complex_coords(const SgComplex *cx, size_t v, int c[3])
{
    c[0] = (int)(v % (size_t)cx->lx) - 1;
    v /= (size_t)cx->lx;
    c[1] = (int)(v % (size_t)cx->ly) - 1;
    c[2] = (int)(v / (size_t)cx->ly) - 1;
}

static inline int sg_cell_dim(unsigned m)
{
    return (int)(m & 1) + (int)(m >> 1 & 1) + (int)(m >> 2 & 1);
}

/* Euler characteristic of the closed complex of the grid's non-zero
 * voxels (vertices - edges + squares - cubes), counted per lattice vertex
 * from its 2x2x2 voxel configuration. */
int64_t sg_complex_euler(const SgGrid *grid);

/* The cells owned by a lattice vertex whose 8 surrounding voxels are
 * given as a bit set (bit d: voxel at vertex - d, d = dx | dy<<1 | dz<<2). */
uint8_t sg_complex_cells_of_config(unsigned config);

#endif
