/* Nearest skeleton node of every medium voxel by geodesic distance:
 * multi-source Dijkstra inside the medium over the 26-neighbourhood, with
 * step lengths 1, sqrt 2, sqrt 3 quantized to 29, 41, 50 (errors under
 * 0.5%: the 26-neighbourhood metric itself errs by up to ~13%). Integer
 * weights allow Dial's bucket queue (a ring of flat arrays): linear in the
 * voxels and their neighbours, no heap.
 *
 * Parallel and deterministic: each voxel holds one 64-bit key
 * (distance << 32 | node) lowered with compare-and-swap, so the result is
 * the minimum over all paths of (distance, node) whatever the order of the
 * updates. Since every step weighs at least 29, the buckets d .. d+28 are
 * final when the first of them is reached and relaxing them only touches
 * buckets >= d+29: a batch of 29 buckets is processed by all threads at
 * once, with two barriers per batch. */
#include "labels.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "importance_cache_format.h"
#include "progress.h"
#include "threads.h"

enum { W_FACE = 29, W_EDGE = 41, W_CORNER = 50, BATCH = W_FACE, RING = 128, MAX_THREADS = 16 };

/* A blocked cell: distance 0 (never improved), no node. */
#define KEY_BLOCKED ((uint64_t)SG_CACHE_NONE)
#define KEY_UNSEEN UINT64_MAX

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

typedef struct Propagation {
    _Atomic uint64_t *key;
    long off[26];
    uint32_t weight[26];
    int threads;
    Bucket ring[MAX_THREADS][RING];
    uint64_t settled[MAX_THREADS];
    bool failed[MAX_THREADS];
    uint32_t batch; /* first distance of the current batch */
    bool done;
    pthread_barrier_t barrier;
    pthread_mutex_t gate_lock;
    pthread_cond_t gate;
    bool go;
    SgProgress progress;
} Propagation;

typedef struct Worker {
    Propagation *p;
    int t;
} Worker;

static void process_batch(Propagation *p, int t)
{
    Bucket *mine = p->ring[t];
    for (uint32_t d = p->batch; d < p->batch + BATCH; d++) {
        size_t total = 0;
        for (int s = 0; s < p->threads; s++)
            total += p->ring[s][d % RING].count;
        size_t lo = total * (size_t)t / (size_t)p->threads;
        size_t hi = total * (size_t)(t + 1) / (size_t)p->threads;
        /* Items [lo, hi) of the concatenation of every thread's bucket d. */
        size_t base = 0;
        for (int s = 0; s < p->threads && base < hi; s++) {
            const Bucket *b = &p->ring[s][d % RING];
            size_t from = lo > base ? lo - base : 0, to = hi - base < b->count ? hi - base : b->count;
            for (size_t q = from; q < to; q++) {
                uint32_t v = b->items[q];
                uint64_t k = atomic_load_explicit(&p->key[v], memory_order_relaxed);
                if ((uint32_t)(k >> 32) != d)
                    continue; /* superseded by a shorter path */
                p->settled[t]++;
                uint64_t label = (uint32_t)k;
                for (int e = 0; e < 26; e++) {
                    uint32_t u = (uint32_t)((long)v + p->off[e]);
                    uint32_t nd = d + p->weight[e];
                    uint64_t want = (uint64_t)nd << 32 | label;
                    uint64_t cur = atomic_load_explicit(&p->key[u], memory_order_relaxed);
                    while (want < cur) {
                        if (atomic_compare_exchange_weak_explicit(&p->key[u], &cur, want,
                                                                  memory_order_relaxed,
                                                                  memory_order_relaxed)) {
                            /* Queue it once per distance: a lower node at the
                             * same distance is already queued. */
                            if ((uint32_t)(cur >> 32) > nd &&
                                !bucket_push(&mine[nd % RING], u))
                                p->failed[t] = true;
                            break;
                        }
                    }
                }
            }
            base += b->count;
        }
    }
}

static void *run_worker(void *arg)
{
    Worker *w = arg;
    Propagation *p = w->p;
    pthread_mutex_lock(&p->gate_lock);
    while (!p->go)
        pthread_cond_wait(&p->gate, &p->gate_lock);
    pthread_mutex_unlock(&p->gate_lock);
    for (;;) {
        process_batch(p, w->t);
        pthread_barrier_wait(&p->barrier);
        if (w->t == 0) {
            bool pending = false, failed = false;
            uint64_t settled = 0;
            for (int s = 0; s < p->threads; s++) {
                for (uint32_t d = p->batch; d < p->batch + BATCH; d++)
                    p->ring[s][d % RING].count = 0;
                for (int r = 0; r < RING; r++)
                    pending |= p->ring[s][r].count > 0;
                failed |= p->failed[s];
                settled += p->settled[s];
            }
            p->batch += BATCH;
            p->done = !pending || failed;
            sg_progress_update(&p->progress, settled);
        }
        pthread_barrier_wait(&p->barrier);
        if (p->done)
            return NULL;
    }
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
    Propagation *p = calloc(1, sizeof *p);
    _Atomic uint64_t *key = malloc(total * sizeof *key);
    if (!p || !key) {
        free(p);
        free(key);
        return sg_fail(err, "out of memory for the nearest-node labels (%zu voxels)", total);
    }
    p->key = key;
    pthread_mutex_init(&p->gate_lock, NULL);
    pthread_cond_init(&p->gate, NULL);
    p->threads = sg_thread_count(threads);
    if (p->threads > MAX_THREADS)
        p->threads = MAX_THREADS;

    uint64_t medium = 0;
    for (size_t v = 0; v < total; v++)
        atomic_init(&key[v], KEY_BLOCKED);
    for (int k = 0; k < grid->nz; k++)
        for (int j = 0; j < grid->ny; j++) {
            const uint8_t *row = grid->voxels + sg_grid_index(grid, 0, j, k);
            _Atomic uint64_t *krow = key + 1 + px * ((size_t)(j + 1) + py * (size_t)(k + 1));
            for (int i = 0; i < grid->nx; i++)
                if (row[i]) {
                    atomic_init(&krow[i], KEY_UNSEEN);
                    medium++;
                }
        }
    int n = 0;
    for (int dz = -1; dz <= 1; dz++)
        for (int dy = -1; dy <= 1; dy++)
            for (int dx = -1; dx <= 1; dx++) {
                int axes = (dx != 0) + (dy != 0) + (dz != 0);
                if (axes == 0)
                    continue;
                p->off[n] = dx + (long)px * (dy + (long)py * dz);
                p->weight[n] = axes == 1 ? W_FACE : axes == 2 ? W_EDGE : W_CORNER;
                n++;
            }

    bool ok = true;
    for (uint32_t s = 0; ok && s < skeleton->node_count; s++) {
        const int *c = skeleton->nodes[s].voxel;
        if (!sg_grid_inside(grid, c[0], c[1], c[2]) || !sg_grid_get(grid, c[0], c[1], c[2]))
            continue;
        size_t v = (size_t)(c[0] + 1) + px * ((size_t)(c[1] + 1) + py * (size_t)(c[2] + 1));
        if (atomic_load(&key[v]) != KEY_UNSEEN)
            continue; /* a lower node already stands on this voxel */
        atomic_store(&key[v], (uint64_t)s);
        ok = bucket_push(&p->ring[0][0], (uint32_t)v);
    }

    sg_progress_begin(&p->progress, "nearest nodes", medium);
    if (ok && p->ring[0][0].count > 0) {
        /* Workers wait at a gate until the thread count (and so the
         * barrier) is known: a thread that fails to start is simply left
         * out. */
        Worker workers[MAX_THREADS];
        pthread_t ids[MAX_THREADS];
        int wanted = p->threads, started = 1;
        for (int t = 0; t < wanted; t++)
            workers[t] = (Worker){p, t};
        pthread_mutex_lock(&p->gate_lock);
        for (int t = 1; t < wanted; t++) {
            if (pthread_create(&ids[started], NULL, run_worker, &workers[started]) != 0)
                break;
            started++;
        }
        p->threads = started;
        pthread_barrier_init(&p->barrier, NULL, (unsigned)started);
        p->go = true;
        pthread_cond_broadcast(&p->gate);
        pthread_mutex_unlock(&p->gate_lock);
        run_worker(&workers[0]);
        for (int t = 1; t < started; t++)
            pthread_join(ids[t], NULL);
        pthread_barrier_destroy(&p->barrier);
        for (int t = 0; t < started; t++)
            ok = ok && !p->failed[t];
    }
    sg_progress_end(&p->progress);
    uint64_t settled = 0;
    for (int t = 0; t < MAX_THREADS; t++) {
        settled += p->settled[t];
        for (int r = 0; r < RING; r++)
            free(p->ring[t][r].items);
    }
    pthread_mutex_destroy(&p->gate_lock);
    pthread_cond_destroy(&p->gate);
    free(p);
    if (!ok) {
        free(key);
        return sg_fail(err, "out of memory in the nearest-node propagation");
    }
    out->nx = grid->nx;
    out->ny = grid->ny;
    out->nz = grid->nz;
    out->px = px;
    out->py = py;
    out->key = (uint64_t *)key;
    out->medium_voxels = medium;
    out->labelled_voxels = settled;
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
