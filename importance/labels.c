/* Nearest skeleton node of every medium voxel by geodesic distance:
 * multi-source Dijkstra inside the medium over the 26-neighbourhood, with
 * step lengths 1, sqrt 2, sqrt 3 quantized to 29, 41, 50 (errors under
 * 0.5%: the 26-neighbourhood metric itself errs by up to ~13%). Integer
 * weights allow Dial's bucket queue (a ring of flat arrays): linear in the
 * voxels and their neighbours, no heap.
 *
 * Each voxel holds one 64-bit key, distance << 32 | node. The answer is the
 * fixpoint of "key(u) = min over neighbours v of key(v) + step": unique, so
 * any order of relaxations that reaches it gives the same labels (among
 * nodes at the shortest distance the lowest id wins).
 *
 * Parallel without locks: the grid is cut into z slabs of equal medium, one
 * per thread; each slab runs its own Dijkstra touching only its voxels.
 * Then the keys across each slab boundary are relaxed (serially, two planes
 * per boundary), the voxels that improved seed the next round, and the
 * slabs run again until nothing crosses: usually two or three rounds, the
 * later ones touching only the bands where a node on the other side is
 * nearer. Same fixpoint, so the same bytes for any thread count.
 *
 * Keys are 32 bits when the node ids leave room for the distances met
 * (node in the low bits, distance above: the same order as the 64-bit
 * key, so the same fixpoint): half the memory and half the cache misses
 * of the propagation, which is bound by them. A distance that would not
 * fit stops that attempt and the labels are built again with 64-bit keys. */
#include "labels.h"

#include <stdlib.h>
#include <string.h>

#include "importance_cache_format.h"
#include "progress.h"
#include "memory.h"
#include "threads.h"

enum { W_FACE = 29, W_EDGE = 41, W_CORNER = 50, RING = 64, MAX_SLABS = 16 };


typedef struct Buffer {
    uint64_t *items;
    size_t count, cap;
} Buffer;

static bool buffer_push(Buffer *b, uint64_t v)
{
    if (b->count == b->cap) {
        size_t cap = b->cap ? b->cap * 2 : 1024;
        uint64_t *grown = realloc(b->items, cap * sizeof *grown);
        if (!grown)
            return false;
        b->items = grown;
        b->cap = cap;
    }
    b->items[b->count++] = v;
    return true;
}

typedef struct Slab {
    size_t lo, hi;      /* padded indices of its voxels: whole z planes */
    Buffer seeds;       /* distance << 32 | voxel, for the next round */
    Buffer ring[RING];  /* Dial's buckets (voxel indices in the low 32 bits) */
    uint64_t relaxed;   /* voxels settled, over all rounds */
    bool failed;
    bool overflow;      /* a distance did not fit the key */
} Slab;

typedef struct Labeller {
    void *key;          /* uint32_t or uint64_t per padded voxel */
    int shift;          /* key = distance << shift | node */
    uint64_t node_mask; /* node field; all ones: no node */
    uint32_t distance_limit;
    long off[26];
    uint32_t weight[26];
    size_t plane; /* padded voxels per z plane */
    bool first_round;
    int slab_count;
    Slab slabs[MAX_SLABS];
} Labeller;

static int compare_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

#define KEY_T uint32_t
#define PASS(name) name##_32
#include "labels_pass.h"
#undef KEY_T
#undef PASS
#define KEY_T uint64_t
#define PASS(name) name##_64
#include "labels_pass.h"
#undef KEY_T
#undef PASS

void sg_label_grid_release(SgLabelGrid *g)
{
    free(g->key);
    free(g->key32);
    memset(g, 0, sizeof *g);
}

static int bit_width(uint64_t n)
{
    int b = 1;
    while (b < 64 && ((uint64_t)1 << b) < n)
        b++;
    return b;
}

/* One attempt with keys of key_bits (32 or 64). *overflow: a distance did
 * not fit (32 only); the caller tries again wider. */
static bool build_attempt(const SgGrid *grid, const SgSkeleton *skeleton, int threads,
                          int key_bits, uint32_t distance_limit, SgLabelGrid *out,
                          bool *overflow, SgError *err)
{
    memset(out, 0, sizeof *out);
    *overflow = false;
    const bool wide = key_bits == 64;
    /* A one-voxel frame of blocked cells around the grid: no bounds tests
     * in the inner loop. */
    const size_t px = (size_t)grid->nx + 2, py = (size_t)grid->ny + 2, pz = (size_t)grid->nz + 2;
    const size_t total = px * py * pz;
    Labeller *L = calloc(1, sizeof *L);
    void *key = malloc(total * (wide ? sizeof(uint64_t) : sizeof(uint32_t)));
    uint64_t *plane_medium = calloc(pz, sizeof *plane_medium);
    if (!L || !key || !plane_medium) {
        free(L);
        free(key);
        free(plane_medium);
        return sg_fail(err, "out of memory for the nearest-node labels (%zu voxels)", total);
    }
    L->key = key;
    L->plane = px * py;
    sg_memory_prefer_huge_pages(key, total * (wide ? sizeof(uint64_t) : sizeof(uint32_t)));
    if (wide) {
        L->shift = 32;
        L->node_mask = 0xffffffffu;
        L->distance_limit = UINT32_MAX - 64;
    } else {
        /* node ids 0 .. count-1 below the all-ones "no node" */
        L->shift = bit_width((uint64_t)skeleton->node_count + 1);
        L->node_mask = ((uint64_t)1 << L->shift) - 1;
        L->distance_limit = (uint32_t)(((uint64_t)1 << (32 - L->shift)) - 2);
        if (distance_limit && distance_limit < L->distance_limit)
            L->distance_limit = distance_limit;
    }

    uint64_t medium = 0;
    if (wide)
        fill_64(L, grid, px, py, total, plane_medium);
    else
        fill_32(L, grid, px, py, total, plane_medium);
    for (size_t z = 0; z < pz; z++)
        medium += plane_medium[z];
    int n = 0;
    for (int dz = -1; dz <= 1; dz++)
        for (int dy = -1; dy <= 1; dy++)
            for (int dx = -1; dx <= 1; dx++) {
                int axes = (dx != 0) + (dy != 0) + (dz != 0);
                if (axes == 0)
                    continue;
                L->off[n] = dx + (long)px * (dy + (long)py * dz);
                L->weight[n] = axes == 1 ? W_FACE : axes == 2 ? W_EDGE : W_CORNER;
                n++;
            }

    /* Slabs of whole z planes holding about equal medium. */
    int slabs = sg_thread_count(threads);
    if (slabs > MAX_SLABS)
        slabs = MAX_SLABS;
    if (slabs > grid->nz / 8)
        slabs = grid->nz / 8 > 1 ? grid->nz / 8 : 1;
    size_t z = 1;
    uint64_t acc = 0;
    for (int s = 0; s < slabs; s++) {
        L->slabs[s].lo = z * L->plane;
        uint64_t goal = medium * (uint64_t)(s + 1) / (uint64_t)slabs;
        if (s == slabs - 1) {
            z = pz - 1;
        } else {
            /* Leave at least one plane to each later slab. */
            size_t limit = pz - 1 - (size_t)(slabs - 1 - s);
            while (z < limit && (acc + plane_medium[z] <= goal || z * L->plane == L->slabs[s].lo))
                acc += plane_medium[z++];
        }
        L->slabs[s].hi = z * L->plane;
    }
    L->slab_count = slabs;
    free(plane_medium);

    bool ok = true;
    for (uint32_t s = 0; ok && s < skeleton->node_count; s++) {
        const int *c = skeleton->nodes[s].voxel;
        if (!sg_grid_inside(grid, c[0], c[1], c[2]) || !sg_grid_get(grid, c[0], c[1], c[2]))
            continue;
        size_t v = (size_t)(c[0] + 1) + px * ((size_t)(c[1] + 1) + py * (size_t)(c[2] + 1));
        /* a lower node may already stand on this voxel */
        if (!(wide ? seed_64(L, v, s) : seed_32(L, v, s)))
            continue;
        for (int t = 0; t < slabs; t++)
            if (v >= L->slabs[t].lo && v < L->slabs[t].hi)
                ok = buffer_push(&L->slabs[t].seeds, v);
    }

    SgProgress progress;
    sg_progress_begin(&progress, "nearest nodes", medium);
    uint32_t rounds = 0;
    uint64_t settled = 0;
    for (int round = 0; ok && !*overflow; round++) {
        rounds++;
        L->first_round = round == 0;
        sg_parallel_for((uint64_t)slabs, slabs, wide ? run_slab_64 : run_slab_32, L);
        uint64_t relaxed = 0;
        for (int s = 0; s < slabs; s++) {
            ok = ok && !L->slabs[s].failed;
            *overflow |= L->slabs[s].overflow;
            relaxed += L->slabs[s].relaxed;
        }
        settled = relaxed;
        sg_progress_update(&progress, relaxed < medium ? relaxed : medium);
        bool more = false;
        for (int s = 0; ok && s + 1 < slabs; s++) {
            size_t last_a = L->slabs[s].hi - L->plane, first_b = L->slabs[s].hi;
            if (wide)
                ok = exchange_64(L, last_a, first_b, &L->slabs[s + 1], px) &&
                     exchange_64(L, first_b, last_a, &L->slabs[s], px);
            else
                ok = exchange_32(L, last_a, first_b, &L->slabs[s + 1], px) &&
                     exchange_32(L, first_b, last_a, &L->slabs[s], px);
        }
        for (int s = 0; s < slabs; s++) {
            more |= L->slabs[s].seeds.count > 0;
            *overflow |= L->slabs[s].overflow;
        }
        if (!more)
            break;
    }
    sg_progress_end(&progress);

    uint64_t labelled = ok && !*overflow ? (wide ? count_labelled_64(L, total)
                                                 : count_labelled_32(L, total))
                                         : 0;
    uint64_t node_mask = L->node_mask;
    for (int s = 0; s < MAX_SLABS; s++) {
        free(L->slabs[s].seeds.items);
        for (int r = 0; r < RING; r++)
            free(L->slabs[s].ring[r].items);
    }
    free(L);
    if (!ok || *overflow) {
        free(key);
        return ok || sg_fail(err, "out of memory in the nearest-node propagation");
    }
    out->nx = grid->nx;
    out->ny = grid->ny;
    out->nz = grid->nz;
    out->px = px;
    out->py = py;
    if (wide)
        out->key = key;
    else
        out->key32 = key;
    out->node_mask = (uint32_t)node_mask;
    out->medium_voxels = medium;
    out->labelled_voxels = labelled;
    out->rounds = rounds;
    out->settled = settled;
    return true;
}

bool sg_label_grid_build_keys(const SgGrid *grid, const SgSkeleton *skeleton, int threads,
                              int key_bits, uint32_t distance_limit, SgLabelGrid *out,
                              SgError *err)
{
    memset(out, 0, sizeof *out);
    const size_t total = ((size_t)grid->nx + 2) * ((size_t)grid->ny + 2) * ((size_t)grid->nz + 2);
    if (total >= UINT32_MAX)
        return sg_fail(err, "grid of %dx%dx%d voxels is too large for the nearest-node table",
                       grid->nx, grid->ny, grid->nz);
    /* narrow keys when at least 14 bits are left for the distance (564
     * voxels of geodesic distance to the nearest node) */
    bool narrow = key_bits != 64 && bit_width((uint64_t)skeleton->node_count + 1) <= 18;
    bool overflow = false;
    if (narrow) {
        if (!build_attempt(grid, skeleton, threads, 32, distance_limit, out, &overflow, err))
            return false;
        if (!overflow)
            return true;
    }
    if (!build_attempt(grid, skeleton, threads, 64, 0, out, &overflow, err))
        return false;
    out->widened = narrow;
    return true;
}

bool sg_label_grid_build(const SgGrid *grid, const SgSkeleton *skeleton, int threads,
                         SgLabelGrid *out, SgError *err)
{
    return sg_label_grid_build_keys(grid, skeleton, threads, 0, 0, out, err);
}

bool sg_importance_label_voxels(const SgGrid *grid, const SgSkeleton *skeleton, int threads,
                                uint32_t *labels, SgError *err)
{
    SgLabelGrid g;
    if (!sg_label_grid_build(grid, skeleton, threads, &g, err))
        return false;
    for (int k = 0; k < grid->nz; k++)
        for (int j = 0; j < grid->ny; j++)
            for (int i = 0; i < grid->nx; i++)
                labels[sg_grid_index(grid, i, j, k)] = sg_label_at(&g, i, j, k);
    sg_label_grid_release(&g);
    return true;
}
