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

typedef struct PatchList {
    Patch *items;
    size_t count, capacity;
} PatchList;

static bool patch_list_add(PatchList *list, const Patch *p)
{
    if (list->count == list->capacity) {
        size_t cap = list->capacity ? 2 * list->capacity : 16;
        Patch *grown = realloc(list->items, cap * sizeof *grown);
        if (!grown)
            return false;
        list->items = grown, list->capacity = cap;
    }
    list->items[list->count++] = *p;
    return true;
}

/* One face of the inner box [lo, hi): its cells (nu x nv, along axes u and
 * v) and whether each is open, medium on both sides of the face. */
typedef struct Face {
    int axis, side, u, v, nu, nv;
    uint8_t *open; /* 1: open, 2: open and in a patch already */
    int *stack;    /* the flood's cells to visit */
} Face;

static void mark_open(Face *f, const uint32_t *decoded, const int dims[3], const int lo[3], const int hi[3])
{
    int inner = f->side ? hi[f->axis] - 1 : lo[f->axis], outer = f->side ? hi[f->axis] : lo[f->axis] - 1;
    for (int j = 0; j < f->nv; j++)
        for (int i = 0; i < f->nu; i++) {
            int c[3];
            c[f->u] = lo[f->u] + i, c[f->v] = lo[f->v] + j;
            c[f->axis] = inner;
            size_t a = (size_t)c[0] + (size_t)dims[0] * (c[1] + (size_t)dims[1] * c[2]);
            c[f->axis] = outer;
            size_t b = (size_t)c[0] + (size_t)dims[0] * (c[1] + (size_t)dims[1] * c[2]);
            f->open[(size_t)j * f->nu + i] = is_medium(decoded[a]) && is_medium(decoded[b]);
        }
}

/* The 4-connected patch of open cells from (i0, j0), in the face's cells. */
static Patch flood(Face *f, int i0, int j0)
{
    Patch p = {{i0, j0}, {i0, j0}, f->axis, f->side, 0};
    int top = 0, nu = f->nu, nv = f->nv;
    f->stack[top++] = i0, f->stack[top++] = j0;
    f->open[(size_t)j0 * nu + i0] = 2;
    while (top) {
        int j = f->stack[--top], i = f->stack[--top];
        p.cells++;
        p.lo[0] = i < p.lo[0] ? i : p.lo[0], p.hi[0] = i > p.hi[0] ? i : p.hi[0];
        p.lo[1] = j < p.lo[1] ? j : p.lo[1], p.hi[1] = j > p.hi[1] ? j : p.hi[1];
        const int di[4] = {1, -1, 0, 0}, dj[4] = {0, 0, 1, -1};
        for (int k = 0; k < 4; k++) {
            int x = i + di[k], y = j + dj[k];
            if (x >= 0 && y >= 0 && x < nu && y < nv && f->open[(size_t)y * nu + x] == 1) {
                f->open[(size_t)y * nu + x] = 2;
                f->stack[top++] = x, f->stack[top++] = y;
            }
        }
    }
    return p;
}

/* The patches of one face (axis, side) added to `list`, in voxels; false:
 * out of memory. */
static bool face_patches(const uint32_t *decoded, const int dims[3], const int lo[3], const int hi[3], int axis,
                         int side, PatchList *list)
{
    Face f = {.axis = axis, .side = side, .u = (axis + 1) % 3, .v = (axis + 2) % 3};
    f.nu = hi[f.u] - lo[f.u], f.nv = hi[f.v] - lo[f.v];
    f.open = calloc((size_t)f.nu * f.nv, 1);
    f.stack = malloc(sizeof(int) * 2 * (size_t)f.nu * f.nv);
    bool ok = f.open && f.stack;
    if (ok)
        mark_open(&f, decoded, dims, lo, hi);
    /* 4-connected patches, by a flood from each open cell */
    for (int j0 = 0; ok && j0 < f.nv; j0++)
        for (int i0 = 0; ok && i0 < f.nu; i0++) {
            if (f.open[(size_t)j0 * f.nu + i0] != 1)
                continue;
            Patch p = flood(&f, i0, j0);
            p.lo[0] += lo[f.u], p.hi[0] += lo[f.u];
            p.lo[1] += lo[f.v], p.hi[1] += lo[f.v];
            ok = patch_list_add(list, &p);
        }
    free(f.open);
    free(f.stack);
    return ok;
}

/* Patch p's rectangle (local coordinates), on the face of the bounds. */
static void patch_corners(const Patch *p, const double origin[3], double h, const double bounds_min[3],
                          const double bounds_max[3], const double centre[3], Vec3 out[4])
{
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
        out[c] = v3((float)(w[0] - centre[0]), (float)(w[1] - centre[1]), (float)(w[2] - centre[2]));
    }
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
    PatchList patches = {0};
    for (int axis = 0; axis < 3; axis++)
        for (int side = 0; side < 2; side++)
            if (!face_patches(decoded, dims, lo, hi, axis, side, &patches)) {
                free(patches.items);
                return false;
            }
    if (!patches.count) {
        free(patches.items);
        return true;
    }
    qsort(patches.items, patches.count, sizeof *patches.items, compare_patches);
    uint32_t n = patches.count < OPENINGS_MAX ? (uint32_t)patches.count : OPENINGS_MAX;
    Vec3(*out)[4] = calloc(n, sizeof *out);
    if (!out) {
        free(patches.items);
        return false;
    }
    for (uint32_t k = 0; k < n; k++)
        patch_corners(&patches.items[k], origin, h, bounds_min, bounds_max, centre, out[k]);
    free(patches.items);
    *corners = out;
    *count = n;
    return true;
}
