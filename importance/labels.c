/* Nearest skeleton node of every medium voxel by geodesic distance:
 * multi-source Dijkstra inside the medium over the 26-neighbourhood, with
 * step lengths 1, sqrt 2, sqrt 3 quantized to 29, 41, 50 (errors under
 * 0.5%: the 26-neighbourhood metric itself errs by up to ~13%). Integer
 * weights allow Dial's bucket queue: a ring of 64 buckets, each a flat
 * array, so the whole propagation is linear in the voxels and their
 * neighbours, with no heap. Deterministic: one thread, FIFO buckets,
 * ties keep the label that arrived first. */
#include "labels.h"

#include <stdlib.h>
#include <string.h>

#include "importance_cache_format.h"
#include "progress.h"

enum { W_FACE = 29, W_EDGE = 41, W_CORNER = 50, RING = 64 };

typedef struct Bucket {
    uint32_t *items;
    size_t count, cap;
} Bucket;

static bool bucket_push(Bucket *b, uint32_t v)
{
    if (b->count == b->cap) {
        size_t cap = b->cap ? b->cap * 2 : 4096;
        uint32_t *grown = realloc(b->items, cap * sizeof *grown);
        if (!grown)
            return false;
        b->items = grown;
        b->cap = cap;
    }
    b->items[b->count++] = v;
    return true;
}

void sg_label_grid_release(SgLabelGrid *g)
{
    free(g->label);
    memset(g, 0, sizeof *g);
}

bool sg_label_grid_build(const SgGrid *grid, const SgSkeleton *skeleton, SgLabelGrid *out,
                         SgError *err)
{
    memset(out, 0, sizeof *out);
    /* A one-voxel frame of blocked cells around the grid: no bounds tests
     * in the inner loop. */
    const size_t px = (size_t)grid->nx + 2, py = (size_t)grid->ny + 2, pz = (size_t)grid->nz + 2;
    const size_t total = px * py * pz;
    if (total >= UINT32_MAX)
        return sg_fail(err, "grid of %dx%dx%d voxels is too large for the nearest-node table",
                       grid->nx, grid->ny, grid->nz);
    uint32_t *dist = malloc(total * sizeof *dist);
    uint32_t *label = malloc(total * sizeof *label);
    Bucket ring[RING];
    memset(ring, 0, sizeof ring);
    bool ok = dist && label;
    if (!ok) {
        free(dist);
        free(label);
        return sg_fail(err, "out of memory for the nearest-node labels (%zu voxels)", total);
    }
    /* dist 0 marks both blocked cells and sources: neither is ever relaxed. */
    uint64_t medium = 0;
    memset(dist, 0, total * sizeof *dist);
    for (size_t v = 0; v < total; v++)
        label[v] = SG_CACHE_NONE;
    for (int k = 0; k < grid->nz; k++)
        for (int j = 0; j < grid->ny; j++) {
            const uint8_t *row = grid->voxels + sg_grid_index(grid, 0, j, k);
            uint32_t *drow = dist + 1 + px * ((size_t)(j + 1) + py * (size_t)(k + 1));
            for (int i = 0; i < grid->nx; i++)
                if (row[i]) {
                    drow[i] = UINT32_MAX;
                    medium++;
                }
        }

    long off[26];
    uint32_t weight[26];
    int n = 0;
    for (int dz = -1; dz <= 1; dz++)
        for (int dy = -1; dy <= 1; dy++)
            for (int dx = -1; dx <= 1; dx++) {
                int axes = (dx != 0) + (dy != 0) + (dz != 0);
                if (axes == 0)
                    continue;
                off[n] = dx + (long)px * (dy + (long)py * dz);
                weight[n] = axes == 1 ? W_FACE : axes == 2 ? W_EDGE : W_CORNER;
                n++;
            }

    uint64_t pending = 0;
    for (uint32_t s = 0; ok && s < skeleton->node_count; s++) {
        const int *c = skeleton->nodes[s].voxel;
        if (!sg_grid_inside(grid, c[0], c[1], c[2]) || !sg_grid_get(grid, c[0], c[1], c[2]))
            continue;
        size_t v = (size_t)(c[0] + 1) + px * ((size_t)(c[1] + 1) + py * (size_t)(c[2] + 1));
        if (label[v] != SG_CACHE_NONE)
            continue; /* another node already stands on this voxel */
        dist[v] = 0;
        label[v] = s;
        ok = bucket_push(&ring[0], (uint32_t)v);
        pending++;
    }

    SgProgress progress;
    sg_progress_begin(&progress, "nearest nodes", medium);
    uint64_t settled = 0;
    for (uint32_t d = 0; ok && pending > 0; d++) {
        Bucket *b = &ring[d % RING];
        for (size_t q = 0; ok && q < b->count; q++) {
            uint32_t v = b->items[q];
            if (dist[v] != d)
                continue; /* superseded by a shorter path */
            settled++;
            uint32_t l = label[v];
            for (int e = 0; e < 26; e++) {
                uint32_t u = (uint32_t)((long)v + off[e]);
                uint32_t nd = d + weight[e];
                if (nd < dist[u]) {
                    dist[u] = nd;
                    label[u] = l;
                    if (!bucket_push(&ring[nd % RING], u)) {
                        ok = false;
                        break;
                    }
                    pending++;
                }
            }
        }
        pending -= b->count;
        b->count = 0;
        if ((d & 255) == 0)
            sg_progress_update(&progress, settled);
    }
    sg_progress_end(&progress);
    for (int r = 0; r < RING; r++)
        free(ring[r].items);
    free(dist);
    if (!ok) {
        free(label);
        return sg_fail(err, "out of memory in the nearest-node propagation");
    }
    out->nx = grid->nx;
    out->ny = grid->ny;
    out->nz = grid->nz;
    out->px = px;
    out->py = py;
    out->label = label;
    out->medium_voxels = medium;
    out->labelled_voxels = settled;
    return true;
}

bool sg_importance_label_voxels(const SgGrid *grid, const SgSkeleton *skeleton,
                                uint32_t *labels, SgError *err)
{
    SgLabelGrid g;
    if (!sg_label_grid_build(grid, skeleton, &g, err))
        return false;
    for (int k = 0; k < grid->nz; k++)
        for (int j = 0; j < grid->ny; j++)
            for (int i = 0; i < grid->nx; i++)
                labels[sg_grid_index(grid, i, j, k)] = sg_label_at(&g, i, j, k);
    sg_label_grid_release(&g);
    return true;
}
