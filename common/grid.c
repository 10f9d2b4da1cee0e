#include "grid.h"

#include "memory.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

bool sg_grid_init(SgGrid *grid, int nx, int ny, int nz, const double origin[3],
                  double voxel_size, SgError *err)
{
    memset(grid, 0, sizeof *grid);
    if (nx <= 0 || ny <= 0 || nz <= 0)
        return sg_fail(err, "grid of %dx%dx%d voxels is empty", nx, ny, nz);
    if (!(voxel_size > 0) || !isfinite(voxel_size))
        return sg_fail(err, "voxel size %g is not a positive finite number", voxel_size);
    /* Refuse sizes whose byte count would overflow or that no machine has. */
    double bytes = (double)nx * (double)ny * (double)nz;
    if (bytes > (double)((size_t)1 << 40))
        return sg_fail(err, "grid of %dx%dx%d voxels is too large (%.3g bytes)", nx, ny, nz, bytes);
    /* calloc of more than the machine has may succeed (overcommit) and the
     * process be killed later: refuse it here with the size in the message */
    char what[96];
    snprintf(what, sizeof what, "a grid of %dx%dx%d voxels", nx, ny, nz);
    if (!sg_memory_check(bytes, NULL, what, err))
        return false;
    grid->voxels = calloc((size_t)bytes, 1);
    if (!grid->voxels)
        return sg_fail(err, "out of memory for a %dx%dx%d grid (%.0f MB)", nx, ny, nz, bytes / 1e6);
    /* 2 MB pages: the first touch of a large grid (the medium's read) was
     * mostly page faults, one per 4 KB */
    sg_memory_prefer_huge_pages(grid->voxels, (size_t)bytes);
    grid->nx = nx;
    grid->ny = ny;
    grid->nz = nz;
    memcpy(grid->origin, origin, sizeof grid->origin);
    grid->voxel_size = voxel_size;
    return true;
}

void sg_grid_release(SgGrid *grid)
{
    if (!grid)
        return;
    free(grid->voxels);
    memset(grid, 0, sizeof *grid);
}

void sg_grid_world_to_voxel(const SgGrid *g, const double p[3], int ijk[3])
{
    for (int a = 0; a < 3; a++) {
        double t = floor((p[a] - g->origin[a]) / g->voxel_size);
        if (t < -1e9) t = -1e9;
        if (t > 1e9) t = 1e9;
        ijk[a] = (int)t;
    }
}

void sg_grid_voxel_center(const SgGrid *g, int i, int j, int k, double p[3])
{
    p[0] = g->origin[0] + (i + 0.5) * g->voxel_size;
    p[1] = g->origin[1] + (j + 0.5) * g->voxel_size;
    p[2] = g->origin[2] + (k + 0.5) * g->voxel_size;
}

size_t sg_grid_count_nonzero(const SgGrid *g)
{
    size_t n = 0, total = sg_grid_count(g);
    for (size_t v = 0; v < total; v++)
        n += g->voxels[v] != 0;
    return n;
}
