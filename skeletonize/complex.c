#include "complex.h"

#include "memory.h"
#include <stdlib.h>
#include <string.h>

#include "threads.h"

/* Voxel at corner v - d owns cell (v, m) iff m and d share no axis. */
static uint8_t cells_of_voxel_offset(unsigned d)
{
    uint8_t bits = 0;
    for (unsigned m = 0; m < 8; m++)
        if ((m & d) == 0)
            bits |= (uint8_t)(1u << m);
    return bits;
}

uint8_t sg_complex_cells_of_config(unsigned config)
{
    uint8_t bits = 0;
    for (unsigned d = 0; d < 8; d++)
        if (config >> d & 1)
            bits |= cells_of_voxel_offset(d);
    return bits;
}

static unsigned config_at(const SgGrid *g, int x, int y, int z)
{
    unsigned config = 0;
    for (unsigned d = 0; d < 8; d++)
        if (sg_grid_get(g, x - (int)(d & 1), y - (int)(d >> 1 & 1), z - (int)(d >> 2 & 1)))
            config |= 1u << d;
    return config;
}

typedef struct BuildContext {
    SgComplex *cx;
    const SgGrid *grid;
    uint8_t table[256];
} BuildContext;

static void build_plane(void *vctx, uint64_t z, int thread)
{
    (void)thread;
    BuildContext *b = vctx;
    SgComplex *cx = b->cx;
    const SgGrid *g = b->grid;
    for (int y = 0; y <= g->ny; y++) {
        uint8_t *row = cx->cells + sg_complex_vertex(cx, 0, y, (int)z);
        /* interior rows fast path: read the 4 voxel rows directly */
        bool inside = y >= 1 && y < g->ny && z >= 1 && z < (uint64_t)g->nz;
        if (inside) {
            const uint8_t *r[4];
            for (int d = 0; d < 4; d++)
                r[d] = g->voxels + sg_grid_index(g, 0, y - (d & 1), (int)z - (d >> 1));
            unsigned prev = 0; /* voxels at x-1 as bits 1,3,5,7 */
            for (int x = 0; x <= g->nx; x++) {
                unsigned cur = 0;
                if (x < g->nx)
                    cur = (r[0][x] != 0) | (r[1][x] != 0) << 2 | (r[2][x] != 0) << 4 |
                          (r[3][x] != 0) << 6;
                row[x] = b->table[cur | prev];
                prev = cur << 1;
            }
        } else {
            for (int x = 0; x <= g->nx; x++)
                row[x] = b->table[config_at(g, x, y, (int)z)];
        }
    }
}

bool sg_complex_build(SgComplex *cx, const SgGrid *g, int threads, SgError *err)
{
    memset(cx, 0, sizeof *cx);
    cx->nx = g->nx;
    cx->ny = g->ny;
    cx->nz = g->nz;
    cx->lx = g->nx + 3;
    cx->ly = g->ny + 3;
    cx->lz = g->nz + 3;
    cx->stride[0] = 1;
    cx->stride[1] = (size_t)cx->lx;
    cx->stride[2] = (size_t)cx->lx * (size_t)cx->ly;
    cx->vertex_count = cx->stride[2] * (size_t)cx->lz;
    if ((double)cx->vertex_count * 8.0 >= 4294967295.0)
        return sg_fail(err, "cubical complex: grid %dx%dx%d too large for 32-bit cell ids",
                       g->nx, g->ny, g->nz);
    cx->cells = calloc(cx->vertex_count, 1);
    if (!cx->cells)
        return sg_fail(err, "cubical complex: out of memory (%zu MB)", cx->vertex_count >> 20);
    sg_memory_prefer_huge_pages(cx->cells, cx->vertex_count);
    BuildContext b = {.cx = cx, .grid = g};
    for (unsigned c = 0; c < 256; c++)
        b.table[c] = sg_complex_cells_of_config(c);
    sg_parallel_for((uint64_t)g->nz + 1, threads, build_plane, &b);
    return true;
}

void sg_complex_release(SgComplex *cx)
{
    if (!cx)
        return;
    free(cx->cells);
    memset(cx, 0, sizeof *cx);
}

int64_t sg_complex_euler(const SgGrid *g)
{
    int chi_of_config[256];
    for (unsigned c = 0; c < 256; c++) {
        uint8_t bits = sg_complex_cells_of_config(c);
        int chi = 0;
        for (unsigned m = 0; m < 8; m++)
            if (bits >> m & 1)
                chi += (sg_cell_dim(m) & 1) ? -1 : 1;
        chi_of_config[c] = chi;
    }
    int64_t chi = 0;
    for (int z = 0; z <= g->nz; z++)
        for (int y = 0; y <= g->ny; y++)
            for (int x = 0; x <= g->nx; x++)
                chi += chi_of_config[config_at(g, x, y, z)];
    return chi;
}
