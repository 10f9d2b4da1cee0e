#include "openings.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct Patch {
    int lo[2], hi[2]; /* cells, inclusive, along the face's two axes */
    int face_axis, side;
    long cells;
} Patch;

static bool is_medium(uint32_t entry) { return entry != SG_CACHE_NONE && !(entry & SG_CACHE_WALL_BIT); }

static int compare_patches(const void *a, const void *b)
{
    long ca = ((const Patch *)a)->cells, cb = ((const Patch *)b)->cells;
    return ca < cb ? 1 : ca > cb ? -1 : 0;
}

bool openings_find(const SgImportanceCache *cache, const double bounds_min[3], const double bounds_max[3],
                   const double centre[3], Vec3 (**corners)[4], uint32_t *count)
{
    *corners = NULL;
    *count = 0;
    const uint32_t *decoded = sg_cache_decoded(cache);
    if (!decoded)
        return true;
    int dims[3];
    double origin[3], h = sg_cache_voxel_size(cache);
    sg_cache_grid(cache, dims, origin);
    /* the margin: voxels below the bounds' minimum; the inner box [m, dims - m) */
    int lo[3], hi[3];
    for (int a = 0; a < 3; a++) {
        lo[a] = (int)lround((bounds_min[a] - origin[a]) / h);
        hi[a] = dims[a] - (int)lround((origin[a] + dims[a] * h - bounds_max[a]) / h);
        if (lo[a] < 1 || hi[a] > dims[a] - 1 || hi[a] <= lo[a])
            return true; /* no margin on this axis: not built for light from outside */
    }
    Patch *patches = NULL;
    size_t patch_count = 0, patch_cap = 0;
    for (int axis = 0; axis < 3; axis++)
        for (int side = 0; side < 2; side++) {
            int u = (axis + 1) % 3, v = (axis + 2) % 3;
            int nu = hi[u] - lo[u], nv = hi[v] - lo[v];
            uint8_t *open = calloc((size_t)nu * nv, 1);
            int *stack = malloc(sizeof(int) * 2 * (size_t)nu * nv);
            if (!open || !stack) {
                free(open), free(stack), free(patches);
                return false;
            }
            int inner = side ? hi[axis] - 1 : lo[axis], outer = side ? hi[axis] : lo[axis] - 1;
            for (int j = 0; j < nv; j++)
                for (int i = 0; i < nu; i++) {
                    int c[3];
                    c[u] = lo[u] + i, c[v] = lo[v] + j;
                    c[axis] = inner;
                    size_t a = (size_t)c[0] + (size_t)dims[0] * (c[1] + (size_t)dims[1] * c[2]);
                    c[axis] = outer;
                    size_t b = (size_t)c[0] + (size_t)dims[0] * (c[1] + (size_t)dims[1] * c[2]);
                    open[(size_t)j * nu + i] = is_medium(decoded[a]) && is_medium(decoded[b]);
                }
            /* 4-connected patches, by a flood from each open cell */
            for (int j0 = 0; j0 < nv; j0++)
                for (int i0 = 0; i0 < nu; i0++) {
                    if (open[(size_t)j0 * nu + i0] != 1)
                        continue;
                    Patch p = {{i0, j0}, {i0, j0}, axis, side, 0}; /* in the face's cells, then voxels */
                    int top = 0;
                    stack[top++] = i0, stack[top++] = j0;
                    open[(size_t)j0 * nu + i0] = 2;
                    while (top) {
                        int j = stack[--top], i = stack[--top];
                        p.cells++;
                        p.lo[0] = i < p.lo[0] ? i : p.lo[0], p.hi[0] = i > p.hi[0] ? i : p.hi[0];
                        p.lo[1] = j < p.lo[1] ? j : p.lo[1], p.hi[1] = j > p.hi[1] ? j : p.hi[1];
                        const int di[4] = {1, -1, 0, 0}, dj[4] = {0, 0, 1, -1};
                        for (int k = 0; k < 4; k++) {
                            int x = i + di[k], y = j + dj[k];
                            if (x >= 0 && y >= 0 && x < nu && y < nv && open[(size_t)y * nu + x] == 1) {
                                open[(size_t)y * nu + x] = 2;
                                stack[top++] = x, stack[top++] = y;
                            }
                        }
                    }
                    if (patch_count == patch_cap) {
                        size_t cap = patch_cap ? 2 * patch_cap : 16;
                        Patch *grown = realloc(patches, cap * sizeof *grown);
                        if (!grown) {
                            free(open), free(stack), free(patches);
                            return false;
                        }
                        patches = grown, patch_cap = cap;
                    }
                    p.lo[0] += lo[u], p.hi[0] += lo[u];
                    p.lo[1] += lo[v], p.hi[1] += lo[v];
                    patches[patch_count++] = p;
                }
            free(open);
            free(stack);
        }
    if (!patch_count) {
        free(patches);
        return true;
    }
    qsort(patches, patch_count, sizeof *patches, compare_patches);
    uint32_t n = patch_count < OPENINGS_MAX ? (uint32_t)patch_count : OPENINGS_MAX;
    Vec3(*out)[4] = calloc(n, sizeof *out);
    if (!out) {
        free(patches);
        return false;
    }
    for (uint32_t k = 0; k < n; k++) {
        const Patch *p = &patches[k];
        int axis = p->face_axis, u = (axis + 1) % 3, v = (axis + 2) % 3;
        /* on the face of the bounds; the rectangle spans its cells' extent */
        double plane = p->side ? bounds_max[axis] : bounds_min[axis];
        /* grown by a voxel each way: the conservative voxelization makes
         * the voxels an opening's edges pass through solid, so the patch
         * falls short of the window by up to one */
        double u0 = fmax(origin[u] + (p->lo[0] - 1) * h, bounds_min[u]);
        double u1 = fmin(origin[u] + (p->hi[0] + 2) * h, bounds_max[u]);
        double v0 = fmax(origin[v] + (p->lo[1] - 1) * h, bounds_min[v]);
        double v1 = fmin(origin[v] + (p->hi[1] + 2) * h, bounds_max[v]);
        const double uv[4][2] = {{u0, v0}, {u1, v0}, {u1, v1}, {u0, v1}};
        for (int c = 0; c < 4; c++) {
            double w[3];
            w[axis] = plane, w[u] = uv[c][0], w[v] = uv[c][1];
            out[k][c] = v3((float)(w[0] - centre[0]), (float)(w[1] - centre[1]), (float)(w[2] - centre[2]));
        }
    }
    free(patches);
    *corners = out;
    *count = n;
    return true;
}
