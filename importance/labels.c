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
 * nearer. Same fixpoint, so the same bytes for any thread count. */
#include "labels.h"

#include <stdlib.h>
#include <string.h>

#include "importance_cache_format.h"
#include "progress.h"
#include "threads.h"

enum { W_FACE = 29, W_EDGE = 41, W_CORNER = 50, RING = 64, MAX_SLABS = 16 };

/* A blocked cell: distance 0 (never improved), no node. */
#define KEY_BLOCKED ((uint64_t)SG_CACHE_NONE)
#define KEY_UNSEEN UINT64_MAX

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
} Slab;

typedef struct Labeller {
    uint64_t *key;
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

/* Dijkstra inside one slab from its seeds (sorted by distance, fed into the
 * ring as the distance reaches them). */
static void run_slab(void *ctx, uint64_t index, int thread)
{
    (void)thread;
    Labeller *L = ctx;
    Slab *s = &L->slabs[index];
    uint64_t *key = L->key;
    if (s->seeds.count == 0)
        return;
    qsort(s->seeds.items, s->seeds.count, sizeof *s->seeds.items, compare_u64);
    size_t next_seed = 0, pending = 0;
    uint32_t d = (uint32_t)(s->seeds.items[0] >> 32);
    for (;;) {
        while (next_seed < s->seeds.count && (uint32_t)(s->seeds.items[next_seed] >> 32) == d) {
            if (!buffer_push(&s->ring[d % RING], (uint32_t)s->seeds.items[next_seed]))
                s->failed = true;
            next_seed++;
            pending++;
        }
        if (pending == 0) {
            if (next_seed == s->seeds.count)
                break;
            d = (uint32_t)(s->seeds.items[next_seed] >> 32);
            continue;
        }
        Buffer *b = &s->ring[d % RING];
        for (size_t q = 0; q < b->count; q++) {
            uint32_t v = (uint32_t)b->items[q];
            uint64_t k = key[v];
            if ((uint32_t)(k >> 32) != d)
                continue; /* superseded by a shorter path */
            s->relaxed++;
            uint64_t label = (uint32_t)k;
            for (int e = 0; e < 26; e++) {
                size_t u = (size_t)((long)v + L->off[e]);
                if (u < s->lo || u >= s->hi)
                    continue; /* the neighbouring slab's: exchanged later */
                uint32_t nd = d + L->weight[e];
                uint64_t want = (uint64_t)nd << 32 | label;
                uint64_t cur = key[u];
                if (want < cur) {
                    key[u] = want;
                    /* In the first round every reached voxel was queued at
                     * its distance when it got it: a lower node at the same
                     * distance needs no new entry. Later rounds start from
                     * keys set before, so any change is queued. */
                    if ((uint32_t)(cur >> 32) > nd || !L->first_round) {
                        if (!buffer_push(&s->ring[nd % RING], u))
                            s->failed = true;
                        pending++;
                    }
                }
            }
        }
        pending -= b->count;
        b->count = 0;
        d++;
    }
    s->seeds.count = 0;
}

/* Relaxes plane `from` into the adjacent plane `to` (z differs by one),
 * seeding `slab` with every voxel that improved. */
static bool exchange(Labeller *L, size_t from, size_t to, Slab *slab, size_t px)
{
    uint64_t *key = L->key;
    long dz = to > from ? (long)L->plane : -(long)L->plane;
    bool ok = true;
    for (size_t v = from; v < from + L->plane; v++) {
        uint64_t k = key[v];
        if ((uint32_t)k == SG_CACHE_NONE)
            continue; /* blocked or not reached */
        uint32_t d = (uint32_t)(k >> 32);
        for (int dy = -1; dy <= 1; dy++)
            for (int dx = -1; dx <= 1; dx++) {
                long o = dz + dx + (long)px * dy;
                size_t u = (size_t)((long)v + o);
                if (u < to || u >= to + L->plane)
                    continue;
                uint32_t nd = d + (dx == 0 && dy == 0 ? W_FACE : dx == 0 || dy == 0 ? W_EDGE
                                                                                    : W_CORNER);
                uint64_t want = (uint64_t)nd << 32 | (uint32_t)k;
                if (want < key[u]) {
                    key[u] = want;
                    ok = ok && buffer_push(&slab->seeds, (uint64_t)nd << 32 | u);
                }
            }
    }
    return ok;
}

void sg_label_grid_release(SgLabelGrid *g)
{
    free(g->key);
    memset(g, 0, sizeof *g);
}

bool sg_label_grid_build(const SgGrid *grid, const SgSkeleton *skeleton, int threads,
                         SgLabelGrid *out, SgError *err)
{
    memset(out, 0, sizeof *out);
    /* A one-voxel frame of blocked cells around the grid: no bounds tests
     * in the inner loop. */
    const size_t px = (size_t)grid->nx + 2, py = (size_t)grid->ny + 2, pz = (size_t)grid->nz + 2;
    const size_t total = px * py * pz;
    if (total >= UINT32_MAX)
        return sg_fail(err, "grid of %dx%dx%d voxels is too large for the nearest-node table",
                       grid->nx, grid->ny, grid->nz);
    Labeller *L = calloc(1, sizeof *L);
    uint64_t *key = malloc(total * sizeof *key);
    uint64_t *plane_medium = calloc(pz, sizeof *plane_medium);
    if (!L || !key || !plane_medium) {
        free(L);
        free(key);
        free(plane_medium);
        return sg_fail(err, "out of memory for the nearest-node labels (%zu voxels)", total);
    }
    L->key = key;
    L->plane = px * py;

    uint64_t medium = 0;
    for (size_t v = 0; v < total; v++)
        key[v] = KEY_BLOCKED;
    for (int k = 0; k < grid->nz; k++)
        for (int j = 0; j < grid->ny; j++) {
            const uint8_t *row = grid->voxels + sg_grid_index(grid, 0, j, k);
            uint64_t *krow = key + 1 + px * ((size_t)(j + 1) + py * (size_t)(k + 1));
            for (int i = 0; i < grid->nx; i++)
                if (row[i]) {
                    krow[i] = KEY_UNSEEN;
                    plane_medium[k + 1]++;
                }
        }
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
        if (key[v] != KEY_UNSEEN)
            continue; /* a lower node already stands on this voxel */
        key[v] = s;
        for (int t = 0; t < slabs; t++)
            if (v >= L->slabs[t].lo && v < L->slabs[t].hi)
                ok = buffer_push(&L->slabs[t].seeds, v);
    }

    SgProgress progress;
    sg_progress_begin(&progress, "nearest nodes", medium);
    uint32_t rounds = 0;
    uint64_t settled = 0;
    for (int round = 0; ok; round++) {
        rounds++;
        L->first_round = round == 0;
        sg_parallel_for((uint64_t)slabs, slabs, run_slab, L);
        uint64_t relaxed = 0;
        for (int s = 0; s < slabs; s++) {
            ok = ok && !L->slabs[s].failed;
            relaxed += L->slabs[s].relaxed;
        }
        settled = relaxed;
        sg_progress_update(&progress, relaxed < medium ? relaxed : medium);
        bool more = false;
        for (int s = 0; ok && s + 1 < slabs; s++) {
            size_t last_a = L->slabs[s].hi - L->plane, first_b = L->slabs[s].hi;
            ok = exchange(L, last_a, first_b, &L->slabs[s + 1], px) &&
                 exchange(L, first_b, last_a, &L->slabs[s], px);
        }
        for (int s = 0; s < slabs; s++)
            more |= L->slabs[s].seeds.count > 0;
        if (!more)
            break;
    }
    sg_progress_end(&progress);

    for (int s = 0; s < MAX_SLABS; s++) {
        free(L->slabs[s].seeds.items);
        for (int r = 0; r < RING; r++)
            free(L->slabs[s].ring[r].items);
    }
    free(L);
    if (!ok) {
        free(key);
        return sg_fail(err, "out of memory in the nearest-node propagation");
    }
    uint64_t labelled = 0;
    for (size_t v = 0; v < total; v++)
        labelled += (uint32_t)key[v] != SG_CACHE_NONE;
    out->nx = grid->nx;
    out->ny = grid->ny;
    out->nz = grid->nz;
    out->px = px;
    out->py = py;
    out->key = key;
    out->medium_voxels = medium;
    out->labelled_voxels = labelled;
    out->rounds = rounds;
    out->settled = settled;
    return true;
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
