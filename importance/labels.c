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
 * By tiles, in cache, on every core: the grid is cut into tiles of 32^3
 * voxels. A tile runs its own Dijkstra on a copy of itself and its
 * one-voxel halo (157 KB with 32-bit keys: in the core's L2 cache, where a
 * Dijkstra over the whole key array missed the cache on nearly every
 * neighbour), from its seeds: the voxels whose keys changed since its last
 * run (a bit each in the tile's bitmap). Keys that improve in its halo are
 * sent after the run and, once applied, seed the tiles that own them.
 * Rounds of 8 phases: in a phase the tiles of one parity along x, y and z
 * run at once on the threads (no two of them share a voxel or a halo
 * voxel), then their outboxes are applied in tile order; rounds go on
 * until no tile has a seed, usually five to seven. A voxel can be settled
 * more than once (a nearer node arrives from another tile later); the
 * fixpoint is the same, so are the bytes, for any thread count.
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

enum { W_FACE = 29, W_EDGE = 41, W_CORNER = 50, RING = 64 };
/* Tiles of TILE^3 voxels; a tile and its halo, TL^3 keys, fit a core's L2
 * cache and their indices 16 bits. */
enum { TILE = 32, TL = TILE + 2 };

typedef struct Buffer {
    uint64_t *items;
    size_t count, cap;
} Buffer;

/* Room for one more item of `size` bytes at the end of *items: its
 * address, or NULL when memory runs out. */
static void *push_slot(void **items, size_t *count, size_t *cap, size_t size, size_t first)
{
    if (*count == *cap && !sg_reserve(items, cap, *count + 1, size, first))
        return NULL;
    return (char *)*items + size * (*count)++;
}

static bool buffer_push(Buffer *b, uint64_t v)
{
    uint64_t *slot = push_slot((void **)&b->items, &b->count, &b->cap, sizeof v, 256);
    return slot && (*slot = v, true);
}

/* One of Dial's buckets: local voxel indices. */
typedef struct Ring {
    uint16_t *items;
    size_t count, cap;
} Ring;

static bool ring_push(Ring *b, uint16_t v)
{
    uint16_t *slot = push_slot((void **)&b->items, &b->count, &b->cap, sizeof v, 1024);
    return slot && (*slot = v, true);
}

typedef struct Tile {
    int x0, y0, z0;     /* padded coordinates of its halo's low corner */
    int ex, ey, ez;     /* its voxels per axis (TILE, less at the far ends) */
    bool dirty;         /* some key changed since its last run */
    bool ran;
    int out_thread;     /* its last run's outbox entries: */
    size_t out_begin, out_end; /* work[out_thread].outbox.items[begin, end) */
} Tile;

/* A thread's tile copy, seeds, buckets and outbox. */
typedef struct Workspace {
    void *local;        /* TL^3 keys */
    Buffer seeds;       /* distance << 16 | local index */
    Ring ring[RING];
    Buffer outbox;      /* padded index and key of halo voxels that improved */
    uint64_t relaxed;   /* voxels settled */
    bool failed;
    bool overflow;      /* a distance did not fit the key */
} Workspace;

typedef struct Labeller {
    void *key;          /* uint32_t or uint64_t per padded voxel */
    int shift;          /* key = distance << shift | node */
    uint64_t node_mask; /* node field; all ones: no node */
    uint32_t distance_limit;
    int local_off[26];
    uint32_t weight[26];
    size_t px, py, plane; /* padded sizes; padded voxels per z plane */
    int tx, ty, tz;     /* tiles per axis */
    Tile *tiles;
    uint32_t *changed;  /* per tile TILE^2 rows of TILE bits: keys changed since its run */
    Tile **phase;       /* the tiles of the running phase */
    Workspace *work;
    int threads;
} Labeller;

static int compare_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

/* Marks padded voxel g (not on the padding frame) as changed in its tile. */
static void mark_changed(Labeller *L, size_t g)
{
    size_t x = g % L->px - 1, y = g / L->px % L->py - 1, z = g / L->plane - 1;
    size_t tile = x / TILE + (size_t)L->tx * (y / TILE + (size_t)L->ty * (z / TILE));
    L->tiles[tile].dirty = true;
    L->changed[tile * TILE * TILE + y % TILE + TILE * (z % TILE)] |= (uint32_t)1 << (x % TILE);
}

/* A pass over the padded z planes, a plane per task: count[k] is plane k's. */
typedef struct PlaneJob {
    const Labeller *L;
    const SgGrid *grid;
    uint64_t *count;
} PlaneJob;

/* Runs body on every padded z plane (pz of them) and sums their counts. */
static uint64_t each_plane(const Labeller *L, const SgGrid *grid, size_t pz, uint64_t *count,
                           SgParallelBody body)
{
    PlaneJob job = {L, grid, count};
    sg_parallel_for(pz, L->threads, body, &job);
    uint64_t sum = 0;
    for (size_t k = 0; k < pz; k++)
        sum += count[k];
    return sum;
}

/* An outbox entry: padded index and key, one word when the key is 32 bits. */
#define KEY_T uint32_t
#define PASS(name) name##_32
#define OUTBOX_WORDS 1
#define OUTBOX_PUSH(b, g, want) buffer_push(b, (uint64_t)(g) << 32 | (want))
#define OUTBOX_READ(p, g, want) ((g) = (size_t)((p)[0] >> 32), (want) = (p)[0] & 0xffffffffu)
#include "labels_pass.h"
#undef KEY_T
#undef PASS
#undef OUTBOX_WORDS
#undef OUTBOX_PUSH
#undef OUTBOX_READ
#define KEY_T uint64_t
#define PASS(name) name##_64
#define OUTBOX_WORDS 2
#define OUTBOX_PUSH(b, g, want) (buffer_push(b, g) && buffer_push(b, want))
#define OUTBOX_READ(p, g, want) ((g) = (size_t)(p)[0], (want) = (p)[1])
#include "labels_pass.h"
#undef KEY_T
#undef PASS
#undef OUTBOX_WORDS
#undef OUTBOX_PUSH
#undef OUTBOX_READ

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

static void labeller_free(Labeller *L)
{
    for (int t = 0; L->work && t < L->threads; t++) {
        free(L->work[t].local);
        free(L->work[t].seeds.items);
        free(L->work[t].outbox.items);
        for (int r = 0; r < RING; r++)
            free(L->work[t].ring[r].items);
    }
    free(L->tiles);
    free(L->phase);
    free(L->changed);
    free(L->work);
    free(L);
}

/* The labeller's arrays for the grid with a one-voxel frame of blocked
 * cells around it (no bounds tests in the inner loop), keys of key_size
 * bytes; its keys in *key. NULL when out of memory. */
static Labeller *labeller_create(const SgGrid *grid, int threads, size_t key_size, void **key)
{
    const size_t px = (size_t)grid->nx + 2, py = (size_t)grid->ny + 2, pz = (size_t)grid->nz + 2;
    const size_t total = px * py * pz;
    Labeller *L = calloc(1, sizeof *L);
    *key = malloc(total * key_size);
    if (!L || !*key) {
        free(L);
        free(*key);
        *key = NULL;
        return NULL;
    }
    L->tx = (grid->nx + TILE - 1) / TILE;
    L->ty = (grid->ny + TILE - 1) / TILE;
    L->tz = (grid->nz + TILE - 1) / TILE;
    size_t tile_count = (size_t)L->tx * (size_t)L->ty * (size_t)L->tz;
    L->threads = sg_thread_count(threads);
    L->tiles = calloc(tile_count, sizeof *L->tiles);
    L->phase = malloc(tile_count * sizeof *L->phase);
    L->changed = calloc(tile_count * TILE * TILE, sizeof *L->changed);
    L->work = calloc((size_t)L->threads, sizeof *L->work);
    bool ok = L->tiles && L->phase && L->changed && L->work;
    for (int t = 0; ok && t < L->threads; t++)
        ok = (L->work[t].local = malloc((size_t)TL * TL * TL * key_size)) != NULL;
    if (!ok) {
        labeller_free(L);
        free(*key);
        *key = NULL;
        return NULL;
    }
    L->key = *key;
    L->px = px;
    L->py = py;
    L->plane = px * py;
    sg_memory_prefer_huge_pages(*key, total * key_size);
    sg_memory_prefer_huge_pages(L->changed, tile_count * TILE * TILE * sizeof *L->changed);
    return L;
}

/* How a key splits into distance and node, and the neighbours' offsets in
 * a tile's local copy and their distances. */
static void labeller_set_keys(Labeller *L, const SgSkeleton *skeleton, bool wide, uint32_t distance_limit)
{
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
    int n = 0;
    for (int dz = -1; dz <= 1; dz++)
        for (int dy = -1; dy <= 1; dy++)
            for (int dx = -1; dx <= 1; dx++) {
                int axes = (dx != 0) + (dy != 0) + (dz != 0);
                if (axes == 0)
                    continue;
                L->local_off[n] = dx + TL * (dy + TL * dz);
                L->weight[n] = axes == 1 ? W_FACE : axes == 2 ? W_EDGE : W_CORNER;
                n++;
            }
}

/* Every tile's corner and extent, then the skeleton's nodes as seeds. */
static void labeller_seed(Labeller *L, const SgGrid *grid, const SgSkeleton *skeleton, bool wide)
{
    for (int k = 0; k < L->tz; k++)
        for (int j = 0; j < L->ty; j++)
            for (int i = 0; i < L->tx; i++) {
                Tile *t = &L->tiles[i + (size_t)L->tx * (j + (size_t)L->ty * k)];
                t->x0 = i * TILE;
                t->y0 = j * TILE;
                t->z0 = k * TILE;
                t->ex = grid->nx - t->x0 < TILE ? grid->nx - t->x0 : TILE;
                t->ey = grid->ny - t->y0 < TILE ? grid->ny - t->y0 : TILE;
                t->ez = grid->nz - t->z0 < TILE ? grid->nz - t->z0 : TILE;
            }
    for (uint32_t s = 0; s < skeleton->node_count; s++) {
        const int *c = skeleton->nodes[s].voxel;
        if (!sg_grid_inside(grid, c[0], c[1], c[2]) || !sg_grid_get(grid, c[0], c[1], c[2]))
            continue;
        size_t v = (size_t)(c[0] + 1) + L->px * ((size_t)(c[1] + 1) + L->py * (size_t)(c[2] + 1));
        /* a lower node may already stand on this voxel */
        if (!(wide ? seed_64(L, v, s) : seed_32(L, v, s)))
            continue;
        mark_changed(L, v);
    }
}

/* The dirty tiles of one parity along each axis, into L->phase. */
static size_t phase_tiles(Labeller *L, int parity)
{
    size_t count = 0;
    for (int k = parity >> 2 & 1; k < L->tz; k += 2)
        for (int j = parity >> 1 & 1; j < L->ty; j += 2)
            for (int i = parity & 1; i < L->tx; i += 2) {
                Tile *t = &L->tiles[i + (size_t)L->tx * (j + (size_t)L->ty * k)];
                if (t->dirty)
                    L->phase[count++] = t;
            }
    return count;
}

/* Rounds of 8 phases: the tiles of one parity along each axis run at once
 * (no two of them touch: each reads its halo, in tiles of other parities,
 * and writes its own voxels), then their outboxes are applied in tile
 * order. Which thread runs a tile changes nothing. False when out of
 * memory. */
static bool labeller_propagate(Labeller *L, bool wide, uint64_t medium, uint32_t *rounds_out,
                               uint64_t *settled_out, bool *overflow)
{
    SgThreadPool *pool = sg_thread_pool_create(L->threads);
    SgProgress progress;
    sg_progress_begin(&progress, "nearest nodes", medium);
    uint32_t rounds = 0;
    uint64_t settled = 0;
    bool ok = true, more = true;
    while (ok && !*overflow && more) {
        more = false;
        rounds++;
        for (int parity = 0; parity < 8 && ok && !*overflow; parity++) {
            size_t count = phase_tiles(L, parity);
            if (count == 0)
                continue;
            more = true;
            sg_thread_pool_run(pool, count, wide ? run_tile_64 : run_tile_32, L);
            settled = 0;
            for (int t = 0; t < L->threads; t++) {
                ok = ok && !L->work[t].failed;
                *overflow |= L->work[t].overflow;
                settled += L->work[t].relaxed;
            }
            sg_progress_update(&progress, settled < medium ? settled : medium);
            if (ok && !*overflow) {
                if (wide)
                    apply_64(L, count);
                else
                    apply_32(L, count);
            }
        }
    }
    sg_progress_end(&progress);
    sg_thread_pool_free(pool);
    if (rounds > 0 && !more)
        rounds--; /* the last round found nothing to do */
    *rounds_out = rounds;
    *settled_out = settled;
    return ok;
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
    const size_t pz = (size_t)grid->nz + 2;
    void *key;
    Labeller *L = labeller_create(grid, threads, wide ? sizeof(uint64_t) : sizeof(uint32_t), &key);
    uint64_t *plane_count = calloc(pz, sizeof *plane_count); /* per padded z plane */
    if (!L || !plane_count) {
        if (L)
            labeller_free(L);
        free(key);
        free(plane_count);
        return sg_fail(err, "out of memory for the nearest-node labels (%zu voxels)",
                       ((size_t)grid->nx + 2) * ((size_t)grid->ny + 2) * pz);
    }
    labeller_set_keys(L, skeleton, wide, distance_limit);
    uint64_t medium = each_plane(L, grid, pz, plane_count, wide ? fill_plane_64 : fill_plane_32);
    labeller_seed(L, grid, skeleton, wide);
    uint32_t rounds;
    uint64_t settled;
    bool ok = labeller_propagate(L, wide, medium, &rounds, &settled, overflow);
    uint64_t labelled = ok && !*overflow
                            ? each_plane(L, grid, pz, plane_count, wide ? count_plane_64 : count_plane_32)
                            : 0;
    free(plane_count);
    uint64_t node_mask = L->node_mask;
    size_t px = L->px, py = L->py;
    labeller_free(L);
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
