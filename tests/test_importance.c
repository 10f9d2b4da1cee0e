/* Step 3 on synthetic media with hand-made skeletons: geodesic labels,
 * visibility, importance points (L corridor, two rooms and a door, two
 * sealed rooms), the cache lookups, determinism. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "../importance/graph.h"
#include "../importance/importance.h"
#include "../importance/labels.h"
#include "importance_cache.h"
#include "importance_cache_format.h"
#include "rng.h"
#include "support_importance.h"

/* ---- scenes --------------------------------------------------------------- */

/* L corridor: leg A along x (y 1..4), leg B along y (x 37..40), z 1..3; the
 * light at the far end of leg B. Skeleton: the centre line of A, then of B,
 * ending on the light's node. */
typedef struct LScene {
    SgMedium medium;
    SgSkeleton skeleton;
    uint32_t corner; /* node at the corner (38,2,2) */
    SgImportanceCache *cache; /* l_scene_cache's, at path */
    char path[256];
} LScene;

static void l_scene(LScene *s)
{
    memset(s, 0, sizeof *s);
    sgt_medium_init(&s->medium, 48, 48, 5);
    sgt_box(&s->medium, 1, 1, 1, 40, 4, 3, 1);
    sgt_box(&s->medium, 37, 1, 1, 40, 46, 3, 1);
    double light[3] = {38.5, 47.0, 2.5};
    int seed[3] = {38, 46, 2};
    sgt_add_light(&s->medium, light, seed);
    int a0[3] = {2, 2, 2}, a1[3] = {38, 2, 2}, b0[3] = {38, 3, 2}, b1[3] = {38, 46, 2};
    s->corner = sgt_line(&s->skeleton, SG_CACHE_NONE, a0, a1);
    uint32_t last = sgt_line(&s->skeleton, s->corner, b0, b1);
    s->skeleton.nodes[last].kind = SG_NODE_LIGHT;
    s->skeleton.nodes[last].light = 0;
}

static SgImportanceCache *build_and_open(const SgMedium *m, const SgSkeleton *sk,
                                         const char *tag, int threads, char *path, size_t cap)
{
    sgt_temp_path(path, cap, tag);
    SgImportanceOptions opt = {.threads = threads, .quiet = true};
    SgError err = {0};
    SgImportanceStats stats;
    cr_assert(sg_importance_build(m, sk, &opt, path, &stats, &err), "%s", err.message);
    SgImportanceCache *c = sg_cache_open(path, &err);
    cr_assert_not_null(c, "%s", err.message);
    return c;
}

/* The L scene's cache, built with `threads` at a temporary path named by
 * tag; l_scene_free closes and removes it. */
static SgImportanceCache *l_scene_cache(LScene *s, const char *tag, int threads)
{
    s->cache = build_and_open(&s->medium, &s->skeleton, tag, threads, s->path, sizeof s->path);
    return s->cache;
}

static void l_scene_free(LScene *s)
{
    if (s->cache) {
        sg_cache_close(s->cache);
        unlink(s->path);
    }
    sgt_medium_free(&s->medium);
    sg_skeleton_release(&s->skeleton);
}

static void node_point(const SgImportanceCache *c, uint32_t n, uint32_t light, double point[3])
{
    cr_assert(sg_cache_node_importance_point(c, n, light, point), "node %u light %u", n, light);
}

/* The segment from node n's voxel to the voxel of p stays in the medium
 * (p pulled a quarter voxel toward the node: a light sits on a wall). */
static bool segment_in_medium(const SgMedium *m, const SgSkeleton *s, uint32_t n,
                              const double p[3])
{
    int v[3];
    double d[3], q[3], len = 0;
    for (int a = 0; a < 3; a++) {
        d[a] = s->nodes[n].position[a] - p[a];
        len += d[a] * d[a];
    }
    len = sqrt(len);
    for (int a = 0; a < 3; a++)
        q[a] = p[a] + (len > 0.25 ? d[a] * 0.25 / len : 0);
    sg_grid_world_to_voxel(&m->grid, q, v);
    return sg_importance_visible(&m->grid, s->nodes[n].voxel, v);
}

/* ---- labels --------------------------------------------------------------- */

Test(importance_labels, geodesic_not_euclidean)
{
    /* A partition wall at x = 15 open only at the far end (y 17..18): the
     * voxel just left of the wall is 3 voxels from Q (right of the wall)
     * and 4 from P, but Q is far around the wall: it belongs to P. */
    SgMedium m;
    const int boxes[][7] = {{1, 1, 1, 28, 18, 3, 1}, {15, 1, 1, 15, 16, 3, 0}};
    sgt_medium_boxes(&m, 30, 20, 5, boxes, 2);
    SgSkeleton s = {0};
    uint32_t p = sgt_node(&s, 10, 2, 2, SG_NODE_PLAIN, -1);
    uint32_t q = sgt_node(&s, 17, 2, 2, SG_NODE_PLAIN, -1);
    sgt_edge(&s, p, q);
    uint32_t *labels = malloc(sg_grid_count(&m.grid) * sizeof *labels);
    SgError err = {0};
    cr_assert(sg_importance_label_voxels(&m.grid, &s, 2, labels, &err), "%s", err.message);
    cr_assert_eq(labels[sg_grid_index(&m.grid, 14, 2, 2)], p);
    cr_assert_eq(labels[sg_grid_index(&m.grid, 16, 2, 2)], q);
    cr_assert_eq(labels[sg_grid_index(&m.grid, 14, 8, 3)], p);
    cr_assert_eq(labels[sg_grid_index(&m.grid, 15, 2, 2)], SG_CACHE_NONE); /* the wall */
    cr_assert_eq(labels[sg_grid_index(&m.grid, 0, 0, 0)], SG_CACHE_NONE);
    /* Every medium voxel is labelled (one connected medium). */
    for (size_t v = 0; v < sg_grid_count(&m.grid); v++)
        cr_assert_eq(m.grid.voxels[v] != 0, labels[v] != SG_CACHE_NONE, "voxel %zu", v);
    free(labels);
    sg_skeleton_release(&s);
    sgt_medium_free(&m);
}

Test(importance_labels, open_box_follows_euclidean_bisector)
{
    /* In open space the 26-neighbour metric is within ~8% of Euclidean:
     * voxels clearly closer to one node get that node. */
    SgMedium m;
    sgt_medium_open(&m, 31, 31, 31);
    SgSkeleton s = {0};
    int c[2][3] = {{6, 15, 15}, {24, 9, 20}};
    sgt_node(&s, c[0][0], c[0][1], c[0][2], SG_NODE_PLAIN, -1);
    sgt_node(&s, c[1][0], c[1][1], c[1][2], SG_NODE_PLAIN, -1);
    uint32_t *labels = malloc(sg_grid_count(&m.grid) * sizeof *labels);
    SgError err = {0};
    cr_assert(sg_importance_label_voxels(&m.grid, &s, 2, labels, &err), "%s", err.message);
    int checked = 0;
    for (int k = 0; k < 31; k++)
        for (int j = 0; j < 31; j++)
            for (int i = 0; i < 31; i++) {
                double d[2];
                for (int n = 0; n < 2; n++)
                    d[n] = sqrt((double)(i - c[n][0]) * (i - c[n][0]) +
                                (double)(j - c[n][1]) * (j - c[n][1]) +
                                (double)(k - c[n][2]) * (k - c[n][2]));
                uint32_t want = d[0] < d[1] ? 0 : 1;
                if (fabs(d[0] - d[1]) < 0.1 * fmin(d[0], d[1]) + 1)
                    continue; /* near the bisector: either is fine */
                cr_assert_eq(labels[sg_grid_index(&m.grid, i, j, k)], want, "voxel %d %d %d", i,
                             j, k);
                checked++;
            }
    cr_assert_gt(checked, 20000);
    free(labels);
    sg_skeleton_release(&s);
    sgt_medium_free(&m);
}

/* Reference: plain Dijkstra with a binary heap on (distance, node) keys,
 * same quantized steps (29, 41, 50), no bounds tricks. */
static void reference_labels(const SgGrid *g, const SgSkeleton *s, uint32_t *label)
{
    size_t n = sg_grid_count(g);
    uint64_t *key = malloc(n * sizeof *key);
    uint64_t *heap = malloc((27 * n + s->node_count + 1) * sizeof *heap * 2);
    size_t size = 0;
    for (size_t v = 0; v < n; v++)
        key[v] = UINT64_MAX;
#define HEAP_PUSH(kk, vv)                                                                  \
    do {                                                                                   \
        size_t i_ = size++;                                                                \
        uint64_t k_ = (kk), v_ = (vv);                                                     \
        while (i_ > 0 && (heap[2 * ((i_ - 1) / 2)] > k_ ||                                 \
                          (heap[2 * ((i_ - 1) / 2)] == k_ && heap[2 * ((i_ - 1) / 2) + 1] > v_))) { \
            heap[2 * i_] = heap[2 * ((i_ - 1) / 2)];                                       \
            heap[2 * i_ + 1] = heap[2 * ((i_ - 1) / 2) + 1];                               \
            i_ = (i_ - 1) / 2;                                                             \
        }                                                                                  \
        heap[2 * i_] = k_;                                                                 \
        heap[2 * i_ + 1] = v_;                                                             \
    } while (0)
    for (uint32_t i = 0; i < s->node_count; i++) {
        const int *c = s->nodes[i].voxel;
        if (!sg_grid_get(g, c[0], c[1], c[2]))
            continue;
        size_t v = sg_grid_index(g, c[0], c[1], c[2]);
        if (key[v] > i) {
            key[v] = i;
            HEAP_PUSH(key[v], v);
        }
    }
    while (size > 0) {
        uint64_t k = heap[0], v = heap[1];
        size--;
        uint64_t lk = heap[2 * size], lv = heap[2 * size + 1];
        size_t i = 0;
        for (;;) {
            size_t c = 2 * i + 1;
            if (c >= size)
                break;
            if (c + 1 < size && (heap[2 * (c + 1)] < heap[2 * c] ||
                                 (heap[2 * (c + 1)] == heap[2 * c] && heap[2 * (c + 1) + 1] < heap[2 * c + 1])))
                c++;
            if (heap[2 * c] > lk || (heap[2 * c] == lk && heap[2 * c + 1] >= lv))
                break;
            heap[2 * i] = heap[2 * c];
            heap[2 * i + 1] = heap[2 * c + 1];
            i = c;
        }
        heap[2 * i] = lk;
        heap[2 * i + 1] = lv;
        if (key[v] != k)
            continue;
        int c[3];
        sg_grid_coords(g, v, c);
        int x = c[0], y = c[1], z = c[2];
        for (int dz = -1; dz <= 1; dz++)
            for (int dy = -1; dy <= 1; dy++)
                for (int dx = -1; dx <= 1; dx++) {
                    int axes = (dx != 0) + (dy != 0) + (dz != 0);
                    if (!axes || !sg_grid_get(g, x + dx, y + dy, z + dz))
                        continue;
                    uint64_t w = axes == 1 ? 29 : axes == 2 ? 41 : 50;
                    uint64_t want = ((k >> 32) + w) << 32 | (uint32_t)k;
                    size_t u = sg_grid_index(g, x + dx, y + dy, z + dz);
                    if (want < key[u]) {
                        key[u] = want;
                        HEAP_PUSH(want, u);
                    }
                }
    }
#undef HEAP_PUSH
    for (size_t v = 0; v < n; v++)
        label[v] = key[v] == UINT64_MAX ? SG_CACHE_NONE : (uint32_t)key[v];
    free(heap);
    free(key);
}

/* How many of n labels differ. */
static size_t differences(const uint32_t *got, const uint32_t *want, size_t n)
{
    size_t wrong = 0;
    for (size_t v = 0; v < n; v++)
        wrong += got[v] != want[v];
    return wrong;
}

/* sg_importance_label_voxels gives reference_labels' table at each thread
 * count given; the number of voxels labelled. */
static size_t labels_match_reference(SgMedium *m, const SgSkeleton *s, const int *threads, int runs)
{
    size_t n = sg_grid_count(&m->grid);
    uint32_t *want = malloc(n * sizeof *want), *got = malloc(n * sizeof *got);
    reference_labels(&m->grid, s, want);
    size_t labelled = 0;
    for (size_t v = 0; v < n; v++)
        labelled += want[v] != SG_CACHE_NONE;
    for (int r = 0; r < runs; r++) {
        SgError err = {0};
        cr_assert(sg_importance_label_voxels(&m->grid, s, threads[r], got, &err), "%s", err.message);
        size_t wrong = differences(got, want, n);
        cr_assert_eq(wrong, 0, "threads %d: %zu voxels differ from the reference", threads[r], wrong);
    }
    free(want);
    free(got);
    return labelled;
}

/* A serpentine: z-running corridors joined alternately at y = 0 and y = 39,
 * so that geodesics cross the slab boundaries many times; and its first
 * `count` nodes of a few, some in one slab and nearest to voxels of another. */
static void serpentine(SgMedium *m, SgSkeleton *s, size_t count)
{
    sgt_medium_init(m, 24, 40, 48);
    for (int k = 1; k < 47; k += 4) {
        sgt_box(m, 1, 1, k, 22, 38, k + 1, 1);
        int j = (k / 4) % 2 ? 1 : 36;
        sgt_box(m, 1, j, k + 2, 22, j + 2, k + 3, 1);
    }
    static const int nodes[][3] = {{3, 20, 1}, {20, 3, 45}, {12, 30, 21}, {12, 30, 22}, {2, 37, 3}, {5, 10, 30}};
    *s = (SgSkeleton){0};
    for (size_t i = 0; i < count && i < sizeof nodes / sizeof nodes[0]; i++)
        sgt_node(s, nodes[i][0], nodes[i][1], nodes[i][2], SG_NODE_PLAIN, -1);
}

Test(importance_labels, slabs_match_plain_dijkstra_for_any_thread_count)
{
    SgMedium m;
    SgSkeleton s;
    serpentine(&m, &s, 6);
    sgt_box(&m, 5, 5, 1, 8, 30, 46, 1); /* a shaft through everything */
    sgt_box(&m, 6, 6, 2, 7, 29, 45, 0); /* hollow: the shaft is a tube */
    sgt_node(&s, 3, 20, 1, SG_NODE_PLAIN, -1); /* same voxel as node 0: never a source */
    const int threads[] = {1, 2, 3, 4, 5};
    cr_assert_gt(labels_match_reference(&m, &s, threads, 5), 10000);
    sg_skeleton_release(&s);
    sgt_medium_free(&m);
}

Test(importance_labels, ties_across_slabs_match_plain_dijkstra)
{
    /* Many nodes on a coarse lattice in open space: distances tie along
     * every bisector, and many bisectors cross slab boundaries, where a
     * later round changes the node of voxels at an unchanged distance. */
    SgMedium m;
    const int boxes[][7] = {{0, 0, 0, 15, 15, 95, 1}, {0, 7, 30, 11, 8, 33, 0}, {4, 0, 60, 15, 11, 61, 0}};
    sgt_medium_boxes(&m, 16, 16, 96, boxes, 3);
    SgSkeleton s = {0};
    for (int k = 3; k < 96; k += 12)
        for (int j = 2; j < 16; j += 6)
            for (int i = 1 + (k / 12) % 3; i < 16; i += 7)
                sgt_node(&s, i, j, k, SG_NODE_PLAIN, -1);
    const int threads[] = {1, 2, 3, 4, 8, 12};
    labels_match_reference(&m, &s, threads, 6);
    sg_skeleton_release(&s);
    sgt_medium_free(&m);
}

/* 32-bit keys (the default when node ids leave room), 64-bit keys, and a
 * 32-bit attempt whose distances overflow and falls back to 64-bit keys: the
 * same labels as the reference, for 1 and 3 threads. */
static void labels_of(const SgGrid *g, const SgLabelGrid *l, uint32_t *out)
{
    for (int k = 0; k < g->nz; k++)
        for (int j = 0; j < g->ny; j++)
            for (int i = 0; i < g->nx; i++)
                out[sg_grid_index(g, i, j, k)] = sg_label_at(l, i, j, k);
}

Test(importance_labels, key_widths_and_overflow_fallback_agree)
{
    SgMedium m;
    SgSkeleton s;
    serpentine(&m, &s, 3);
    size_t n = sg_grid_count(&m.grid);
    uint32_t *want = malloc(n * sizeof *want), *got = malloc(n * sizeof *got);
    reference_labels(&m.grid, &s, want);
    struct { int key_bits; uint32_t limit; bool narrow, widened; } cases[] = {
        {0, 0, true, false},    /* automatic: 3 nodes, 32-bit keys */
        {64, 0, false, false},  /* forced wide */
        {0, 300, false, true},  /* 32-bit keys up to 300 (~10 voxels): overflow, retried */
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++)
        for (int threads = 1; threads <= 3; threads += 2) {
            SgLabelGrid l;
            SgError err = {0};
            cr_assert(sg_label_grid_build_keys(&m.grid, &s, threads, cases[c].key_bits,
                                               cases[c].limit, &l, &err), "%s", err.message);
            cr_expect_eq(l.key32 != NULL, cases[c].narrow, "case %zu: 32-bit keys", c);
            cr_expect_eq(l.widened, cases[c].widened, "case %zu: widened", c);
            labels_of(&m.grid, &l, got);
            size_t wrong = differences(got, want, n);
            cr_expect_eq(wrong, 0, "case %zu, threads %d: %zu voxels differ", c, threads, wrong);
            sg_label_grid_release(&l);
        }
    free(want);
    free(got);
    sg_skeleton_release(&s);
    sgt_medium_free(&m);
}

/* ---- visibility ------------------------------------------------------------ */

Test(importance_visibility, blocked_by_one_voxel_and_symmetric)
{
    SgMedium m;
    sgt_medium_open(&m, 20, 20, 20);
    int a[3] = {1, 1, 1}, b[3] = {18, 12, 5};
    cr_assert(sg_importance_visible(&m.grid, a, b));
    sgt_box(&m, 10, 7, 3, 10, 7, 3, 0); /* on the segment: x=10 -> y = 1+11*9.5/17 */
    int hits = 0;
    /* The voxel the segment passes at x = 10: find it by sampling. */
    sgt_box(&m, 10, 7, 3, 10, 7, 3, 1);
    for (double t = 0; t <= 1; t += 1e-4) {
        double p[3] = {1.5 + 17 * t, 1.5 + 11 * t, 1.5 + 4 * t};
        if ((int)p[0] == 10) {
            sgt_box(&m, 10, (int)p[1], (int)p[2], 10, (int)p[1], (int)p[2], 0);
            hits++;
            break;
        }
    }
    cr_assert_eq(hits, 1);
    cr_assert_not(sg_importance_visible(&m.grid, a, b));
    cr_assert_not(sg_importance_visible(&m.grid, b, a));
    /* Axis-aligned: a wall across the x axis blocks, the side stays clear. */
    sgt_box(&m, 0, 0, 0, 19, 19, 19, 1);
    sgt_box(&m, 5, 0, 0, 5, 19, 10, 0);
    int c[3] = {2, 4, 4}, d[3] = {9, 4, 4}, e[3] = {2, 4, 12}, f[3] = {9, 4, 12};
    cr_assert_not(sg_importance_visible(&m.grid, c, d));
    cr_assert(sg_importance_visible(&m.grid, e, f));
    sgt_medium_free(&m);
}

/* A random segment in g: its ends drawn axis by axis (a, then b); b within
 * 4 voxels of a along each axis when `near`. */
static void random_segment(const SgGrid *g, SgRng *rng, bool near, int a[3], int b[3])
{
    const int dims[3] = {g->nx, g->ny, g->nz};
    for (int x = 0; x < 3; x++) {
        a[x] = (int)(sg_rng_float(rng) * dims[x]);
        b[x] = near ? a[x] + (int)(sg_rng_float(rng) * 9) - 4 : (int)(sg_rng_float(rng) * dims[x]);
        b[x] = b[x] < 0 ? 0 : b[x] >= dims[x] ? dims[x] - 1 : b[x];
    }
}

Test(importance_visibility, agrees_with_dense_sampling)
{
    SgMedium m;
    sgt_medium_init(&m, 24, 24, 24);
    SgRng rng;
    sg_rng_seed(&rng, 7, 1);
    for (size_t v = 0; v < sg_grid_count(&m.grid); v++)
        m.grid.voxels[v] = sg_rng_float(&rng) < 0.97f;
    int agree = 0, total = 400, unsafe = 0;
    for (int t = 0; t < total; t++) {
        int a[3], b[3];
        random_segment(&m.grid, &rng, false, a, b);
        m.grid.voxels[sg_grid_index(&m.grid, a[0], a[1], a[2])] = 1;
        m.grid.voxels[sg_grid_index(&m.grid, b[0], b[1], b[2])] = 1;
        bool sampled = true;
        /* Irrational-ish sample offsets: samples exactly on a voxel edge
         * (which the segment only grazes) would be floored to either side. */
        for (int s = 0; s < 20000 && sampled; s++) {
            double u = (s + 0.3183099) / 20000.0;
            int v[3];
            for (int x = 0; x < 3; x++)
                v[x] = (int)floor(a[x] + 0.5 + (b[x] - a[x]) * u);
            sampled = sg_grid_get(&m.grid, v[0], v[1], v[2]) != 0;
        }
        bool dda = sg_importance_visible(&m.grid, a, b);
        cr_assert_eq(dda, sg_importance_visible(&m.grid, b, a), "not symmetric");
        agree += dda == sampled;
        unsafe += dda && !sampled;
    }
    /* Disagreement only where the segment grazes a voxel corner. */
    cr_assert_geq(agree, total * 97 / 100, "agree %d of %d", agree, total);
    cr_assert_leq(unsafe, total / 100, "DDA sees through %d solid samples", unsafe);
    sgt_medium_free(&m);
}

/* An open medium of dims with count solid boxes at random places (rng
 * seeded with seed, stream), w voxels more than one along x (and along y
 * and z when thick), w below widths; every long_every-th box long_size
 * voxels longer along long_axis. vis: its accelerator. */
typedef struct Scatter {
    int dims[3];
    uint64_t seed, stream;
    int count, widths;
    bool thick;
    int long_every, long_axis, long_size;
} Scatter;

static void scattered_medium(const Scatter *sc, SgMedium *m, SgRng *rng, SgVisibility *vis)
{
    sgt_medium_open(m, sc->dims[0], sc->dims[1], sc->dims[2]);
    sg_rng_seed(rng, sc->seed, sc->stream);
    for (int i = 0; i < sc->count; i++) {
        int lo[3], hi[3];
        for (int a = 0; a < 3; a++)
            lo[a] = (int)(sg_rng_float(rng) * sc->dims[a]);
        int w = (int)(sg_rng_float(rng) * sc->widths);
        for (int a = 0; a < 3; a++)
            hi[a] = lo[a] + (a == 0 || sc->thick ? w : 0) +
                    (a == sc->long_axis && i % sc->long_every == 0 ? sc->long_size : 0);
        sgt_box(m, lo[0], lo[1], lo[2], hi[0], hi[1], hi[2], 0);
    }
    SgError err = {0};
    cr_assert(sg_visibility_init(vis, &m->grid, 2, &err));
}

Test(importance_visibility, brick_jumps_agree_with_plain_walk)
{
    /* Open rooms with scattered solid voxels and slabs: the accelerated walk
     * (jumps through all-medium 4x4x4 bricks) answers like the plain one. */
    SgMedium m;
    SgRng rng;
    SgVisibility fast;
    scattered_medium(&(Scatter){{61, 45, 38}, 11, 2, 60, 4, false, 3, 1, 12}, &m, &rng, &fast);
    int visible = 0, total = 20000;
    for (int t = 0; t < total; t++) {
        int a[3], b[3];
        random_segment(&m.grid, &rng, t % 4 == 0, a, b);
        if (t % 7 == 0)
            b[t % 3] = a[t % 3]; /* axis-parallel and diagonal-in-a-plane cases */
        bool plain = sg_importance_visible(&m.grid, a, b);
        cr_assert_eq(sg_visibility_test(&fast, a, b), plain, "(%d %d %d)-(%d %d %d)", a[0],
                     a[1], a[2], b[0], b[1], b[2]);
        visible += plain;
    }
    cr_assert(visible > total / 10 && visible < total * 9 / 10, "visible %d", visible);
    sg_visibility_release(&fast);
    sgt_medium_free(&m);
}

Test(importance_visibility, brick_clearance_is_the_chessboard_distance)
{
    /* Each brick's clearance against brute force: the chessboard distance,
     * in bricks, to the nearest brick that is not all medium or lies
     * outside the grid (bricks sticking out of it are not full). */
    SgMedium m;
    SgRng rng;
    SgVisibility vis;
    scattered_medium(&(Scatter){{70, 45, 38}, 5, 3, 6, 1, false, 1, 0, 0}, &m, &rng, &vis);
    const long bx = (long)vis.bx, by = (long)vis.by, bz = (long)vis.bz;
    int deepest = 0;
    for (long k = 0; k < bz; k++)
        for (long j = 0; j < by; j++)
            for (long i = 0; i < bx; i++) {
                long best = 255;
                for (long z = -1; z <= bz; z++)
                    for (long y = -1; y <= by; y++)
                        for (long x = -1; x <= bx; x++) {
                            bool outside = x < 0 || y < 0 || z < 0 || x >= bx || y >= by || z >= bz;
                            bool full = !outside && (x + 1) * 4 <= 70 && (y + 1) * 4 <= 45 &&
                                        (z + 1) * 4 <= 38;
                            for (int v = 0; v < 64 && full; v++)
                                full = sg_grid_get(&m.grid, (int)x * 4 + (v & 3),
                                                   (int)y * 4 + (v >> 2 & 3), (int)z * 4 + (v >> 4)) != 0;
                            if (full)
                                continue;
                            long d = labs(x - i);
                            d = labs(y - j) > d ? labs(y - j) : d;
                            d = labs(z - k) > d ? labs(z - k) : d;
                            best = d < best ? d : best;
                        }
                int got = vis.clear[i + bx * (j + by * k)];
                cr_assert_eq(got, best, "brick (%ld %ld %ld): %d, brute force %ld", i, j, k, got, best);
                deepest = got > deepest ? got : deepest;
            }
    cr_assert_geq(deepest, 3, "no deep brick: the test would not check the jumps");
    sg_visibility_release(&vis);
    sgt_medium_free(&m);
}

Test(importance_points, chunked_runs_match_every_node_tested)
{
    /* A winding skeleton path through rooms with pillars and thin slabs:
     * each node's importance point found by the accelerated walk (whole
     * chunks of the run shown visible by one walk along a clear tube) is
     * the same float for float as with every node of its run tested. */
    SgMedium m;
    SgRng rng;
    SgVisibility fast, plain = {.grid = &m.grid};
    scattered_medium(&(Scatter){{96, 64, 48}, 13, 4, 40, 3, true, 4, 2, 20}, &m, &rng, &fast);
    SgSkeleton s = {0};
    int p[6][3] = {{4, 4, 4}, {80, 10, 8}, {90, 50, 20}, {30, 58, 40}, {10, 30, 44}, {60, 32, 24}};
    uint32_t last = SG_CACHE_NONE;
    for (int i = 0; i + 1 < 6; i++)
        last = sgt_line(&s, last, p[i], p[i + 1]);
    SgGraph graph;
    SgError err = {0};
    cr_assert(sg_graph_build(&s, &graph, &err));
    uint32_t N = s.node_count;
    double *dist = malloc(N * sizeof *dist);
    uint32_t *pred = malloc(N * sizeof *pred);
    void *heap = malloc(sg_graph_heap_bytes(&graph));
    cr_assert(dist && pred && heap);
    sg_graph_shortest_paths(&graph, &last, 1, dist, pred, heap);
    const double light[3] = {60.5, 32.5, 24.5};
    int far_sighted = 0;
    for (uint32_t n = 0; n < N; n++) {
        float a[3], b[3];
        sg_importance_point(&plain, &s, pred, dist, n, light, 0, a);
        sg_importance_point(&fast, &s, pred, dist, n, light, 0, b);
        cr_assert(memcmp(a, b, sizeof a) == 0, "node %u: (%g %g %g) against (%g %g %g)", n,
                  b[0], b[1], b[2], a[0], a[1], a[2]);
        double d = 0;
        for (int x = 0; x < 3; x++)
            d += (a[x] - s.nodes[n].position[x]) * (a[x] - s.nodes[n].position[x]);
        far_sighted += d > 20 * 20;
    }
    /* many runs span several chunks (the point is their barycenter) */
    cr_assert_gt(far_sighted, (int)N / 10, "%d of %u nodes see far", far_sighted, N);
    sg_visibility_release(&fast);
    free(dist);
    free(pred);
    free(heap);
    sg_graph_release(&graph);
    sg_skeleton_release(&s);
    sgt_medium_free(&m);
}

/* ---- importance points ----------------------------------------------------- */

Test(importance_points, l_corridor_points_to_the_corner_never_through_the_wall)
{
    LScene s;
    l_scene(&s);
    SgImportanceCache *c = l_scene_cache(&s, "l", 2);
    cr_assert_eq(sg_cache_node_count(c), s.skeleton.node_count);
    cr_assert_eq(sg_cache_light_count(c), 1);
    int far_nodes = 0;
    for (uint32_t n = 0; n < s.skeleton.node_count; n++) {
        const SgSkeletonNode *v = &s.skeleton.nodes[n];
        double q[3];
        node_point(c, n, 0, q);
        cr_assert(segment_in_medium(&s.medium, &s.skeleton, n, q),
                  "node %u (%d,%d,%d) -> (%g,%g,%g) crosses a wall", n, v->voxel[0], v->voxel[1],
                  v->voxel[2], q[0], q[1], q[2]);
        if (v->voxel[1] == 2 && v->voxel[0] <= 20) {
            /* Far end of leg A: down the corridor toward the corner, inside leg A. */
            cr_assert(q[1] >= 1 && q[1] < 5, "node %u point y %g leaves leg A", n, q[1]);
            cr_assert_gt(q[0], v->position[0] + 5, "node %u point x %g", n, q[0]);
            double dx = q[0] - v->position[0], dy = q[1] - v->position[1];
            cr_assert_lt(fabs(atan2(dy, dx)), 10 * M_PI / 180, "node %u", n);
            far_nodes++;
        }
        if (v->voxel[0] == 38 && v->voxel[1] >= 2 && v->voxel[1] < 45) {
            /* Leg B and the corner see the light's node: the point is the
             * barycenter of the rest of the leg (the paper's rule), halfway
             * between the node and the light, on the leg's axis. */
            cr_assert_float_eq(q[0], 38.5, 1e-4, "node %u", n);
            cr_assert_float_eq(q[2], 2.5, 1e-4, "node %u", n);
            double half = 0.5 * (v->position[1] + 46.5);
            cr_assert(fabs(q[1] - half) < 1.0, "node %u at y %g: point y %g, not halfway to the light",
                      n, v->position[1], q[1]);
        }
    }
    cr_assert_eq(far_nodes, 19);
    l_scene_free(&s);
}

Test(importance_points, two_rooms_point_at_the_door)
{
    /* Room A (x 1..19) and room B (x 22..42) behind a 2-voxel wall with a
     * door at y 2..4; the light on B's far wall. The skeleton runs from A's
     * centre down to the door, through it, up to B's centre and the light. */
    SgMedium m;
    const int boxes[][7] = {{1, 1, 1, 19, 22, 3, 1}, {22, 1, 1, 42, 22, 3, 1}, {20, 2, 1, 21, 4, 3, 1}};
    sgt_medium_boxes(&m, 44, 24, 5, boxes, 3);
    double lp[3] = {43.0, 12.5, 2.5};
    int seed[3] = {42, 12, 2};
    sgt_add_light(&m, lp, seed);
    SgSkeleton s = {0};
    int p0[3] = {10, 12, 2}, p1[3] = {16, 3, 2}, p2[3] = {25, 3, 2}, p3[3] = {32, 12, 2},
        p4[3] = {42, 12, 2};
    uint32_t n = sgt_line(&s, SG_CACHE_NONE, p0, p1);
    n = sgt_line(&s, n, p1, p2);
    n = sgt_line(&s, n, p2, p3);
    n = sgt_line(&s, n, p3, p4);
    s.nodes[n].kind = SG_NODE_LIGHT;
    s.nodes[n].light = 0;
    char path[256];
    SgImportanceCache *c = build_and_open(&m, &s, "door", 2, path, sizeof path);
    const double door[3] = {21.0, 3.5, 2.5};
    int in_room_a = 0;
    for (uint32_t v = 0; v < s.node_count; v++) {
        double q[3];
        node_point(c, v, 0, q);
        cr_assert(segment_in_medium(&m, &s, v, q), "node %u crosses a wall", v);
        const float *x = s.nodes[v].position;
        if (s.nodes[v].voxel[0] > 14)
            continue;
        /* Room A: the importance point is in room A or the door, and
         * the direction is the door's. */
        cr_assert_lt(q[0], 22, "node %u point beyond the wall", v);
        double a = atan2(q[1] - x[1], q[0] - x[0]), b = atan2(door[1] - x[1], door[0] - x[0]);
        cr_assert_lt(fabs(a - b), 25 * M_PI / 180, "node %u: %g deg off the door", v,
                     (a - b) * 180 / M_PI);
        in_room_a++;
    }
    cr_assert_geq(in_room_a, 5);
    /* A point in room A, near the door wall, looks up the same way. */
    double p[3] = {12.2, 15.7, 2.5}, q[3];
    cr_assert(sg_cache_importance_point(c, p, 0, q));
    cr_assert_lt(q[0], 22);
    sg_cache_close(c);
    unlink(path);
    sg_skeleton_release(&s);
    sgt_medium_free(&m);
}

Test(importance_points, sealed_rooms_light_unreachable_from_camera)
{
    /* Two rooms with no opening (wall x 14..16), a light and a skeleton in each; a third
     * light is sealed inside the wall (no seed, no node). */
    SgMedium m;
    SgSkeleton s;
    sgt_sealed_rooms(&m, &s);
    char path[256];
    SgImportanceCache *c = build_and_open(&m, &s, "sealed", 1, path, sizeof path);
    cr_assert_eq(sg_cache_component_count(c), 2);
    double camera[3] = {5.5, 6.5, 2.5};
    cr_assert(sg_cache_light_reaches(c, 0, camera));
    cr_assert_not(sg_cache_light_reaches(c, 1, camera));
    cr_assert_not(sg_cache_light_reaches(c, 2, camera));
    cr_assert(sg_cache_light_has_paths(c, 0));
    cr_assert(sg_cache_light_has_paths(c, 1));
    cr_assert_not(sg_cache_light_has_paths(c, 2));
    uint32_t reachable = 0;
    for (uint32_t k = 0; k < sg_cache_light_count(c); k++)
        reachable += sg_cache_light_reaches(c, k, camera);
    cr_assert_eq(reachable, 1);
    double q[3];
    cr_assert(sg_cache_importance_point(c, camera, 0, q));
    cr_assert_not(sg_cache_importance_point(c, camera, 1, q));
    cr_assert_not(sg_cache_importance_point(c, camera, 2, q));
    double in_b[3] = {20.5, 5.5, 1.5};
    cr_assert(sg_cache_importance_point(c, in_b, 1, q));
    /* room B's nodes all see their light's node: the barycenter of the
     * nodes x = 21..28 (centres 21.5..28.5) beyond in_b's node */
    cr_assert_float_eq(q[0], 25.0, 1e-5);
    cr_assert_not(sg_cache_light_reaches(c, 0, in_b));
    /* In the middle of the 3-voxel wall between the rooms: nothing. */
    double wall[3] = {15.5, 6.5, 2.5};
    uint32_t node;
    cr_assert_not(sg_cache_nearest_node(c, wall, &node));
    sg_cache_close(c);
    unlink(path);
    sg_skeleton_release(&s);
    sgt_medium_free(&m);
}

/* ---- lookups --------------------------------------------------------------- */

/* Four random points in each voxel of g that is medium (or, with !medium,
 * solid), in memory order, each with its voxel: *count of them. */
typedef struct VoxelPoint {
    int voxel[3];
    double p[3];
} VoxelPoint;

static VoxelPoint *random_points(const SgGrid *g, bool medium, uint64_t seed, uint64_t stream, size_t *count)
{
    SgRng rng;
    sg_rng_seed(&rng, seed, stream);
    VoxelPoint *points = malloc(4 * sg_grid_count(g) * sizeof *points);
    cr_assert_not_null(points);
    size_t n = 0;
    for (size_t v = 0; v < sg_grid_count(g); v++) {
        if ((g->voxels[v] != 0) != medium)
            continue;
        for (int t = 0; t < 4; t++, n++) {
            sg_grid_coords(g, v, points[n].voxel);
            for (int a = 0; a < 3; a++)
                points[n].p[a] = points[n].voxel[a] + sg_rng_float(&rng);
        }
    }
    *count = n;
    return points;
}

Test(importance_cache, every_medium_position_finds_a_node_on_its_side)
{
    LScene s;
    l_scene(&s);
    SgImportanceCache *c = l_scene_cache(&s, "lookup", 2);
    const SgGrid *g = &s.medium.grid;
    cr_assert_eq(sg_cache_medium_voxels(c), sg_grid_count_nonzero(g));
    size_t count;
    VoxelPoint *points = random_points(g, true, 3, 9, &count);
    for (size_t t = 0; t < count; t++) {
        const double *p = points[t].p;
        int i = points[t].voxel[0], j = points[t].voxel[1], k = points[t].voxel[2];
        uint32_t n;
        cr_assert(sg_cache_nearest_node(c, p, &n), "voxel %d %d %d", i, j, k);
        cr_assert_lt(n, s.skeleton.node_count);
        const int *nv = s.skeleton.nodes[n].voxel;
        /* Geodesically nearest on this skeleton = the centre-line node
         * beside the voxel. */
        if (i <= 33)
            cr_assert(nv[1] == 2 && abs(nv[0] - i) <= 2, "voxel %d %d %d", i, j, k);
        if (j >= 8)
            cr_assert(nv[0] == 38 && abs(nv[1] - j) <= 2, "voxel %d %d %d", i, j, k);
        double q[3];
        cr_assert(sg_cache_importance_point(c, p, 0, q));
    }
    cr_assert_eq(count, 4 * sg_grid_count_nonzero(g));
    free(points);
    /* A point on a wall surface (in a solid voxel next to the corridor)
     * uses the corridor voxel beside it; far outside: nothing. */
    double wall[3] = {10.3, 5.02, 2.5}, far[3] = {10.5, 20.5, 2.5}, out[3] = {-5, 2, 2};
    uint32_t n;
    cr_assert(sg_cache_nearest_node(c, wall, &n));
    cr_assert_eq(s.skeleton.nodes[n].voxel[1], 2);
    cr_assert_not(sg_cache_nearest_node(c, far, &n));
    cr_assert_not(sg_cache_nearest_node(c, out, &n));
    double nan3[3] = {NAN, 1, 1};
    cr_assert_not(sg_cache_nearest_node(c, nan3, &n));
    cr_assert_eq(sg_cache_geometry_hash(c), s.medium.geometry_hash);
    cr_assert_eq(sg_cache_skeleton_hash(c), sg_importance_skeleton_hash(&s.skeleton));
    l_scene_free(&s);
}

/* A point in a solid voxel takes the node of the medium neighbour (of 26)
 * whose centre is nearest: checked against every neighbour, on random
 * points in the solid voxels that touch the medium. */
Test(importance_cache, a_point_in_a_wall_takes_the_nearest_medium_neighbour)
{
    LScene s;
    l_scene(&s);
    SgImportanceCache *c = l_scene_cache(&s, "wall", 1);
    const SgGrid *g = &s.medium.grid;
    size_t count;
    VoxelPoint *points = random_points(g, false, 5, 1, &count);
    int checked = 0;
    for (size_t t = 0; t < count; t++) {
        const double *p = points[t].p;
        int i = points[t].voxel[0], j = points[t].voxel[1], k = points[t].voxel[2];
        /* every medium neighbour: its squared distance and node */
        double d2[27], best = INFINITY;
        uint32_t node[27];
        int neighbours = 0;
        for (int dz = -1; dz <= 1; dz++)
            for (int dy = -1; dy <= 1; dy++)
                for (int dx = -1; dx <= 1; dx++) {
                    int a = i + dx, b = j + dy, e = k + dz;
                    if (a < 0 || b < 0 || e < 0 || a >= g->nx || b >= g->ny || e >= g->nz ||
                        !sg_grid_get(g, a, b, e))
                        continue;
                    double centre[3] = {a + 0.5, b + 0.5, e + 0.5};
                    double t0 = p[0] - centre[0], t1 = p[1] - centre[1], t2 = p[2] - centre[2];
                    cr_assert(sg_cache_nearest_node(c, centre, &node[neighbours]));
                    d2[neighbours] = t0 * t0 + t1 * t1 + t2 * t2;
                    best = fmin(best, d2[neighbours++]);
                }
        uint32_t n;
        bool found = sg_cache_nearest_node(c, p, &n);
        cr_assert_eq(found, neighbours > 0, "voxel %d %d %d", i, j, k);
        if (!found)
            continue;
        /* the node is that of a neighbour at the least distance (ties: any) */
        bool matched = false;
        for (int q = 0; q < neighbours && !matched; q++)
            matched = fabs(d2[q] - best) < 1e-12 && node[q] == n;
        cr_assert(matched, "voxel %d %d %d: node %u is no nearest neighbour's", i, j, k, n);
        checked++;
    }
    free(points);
    cr_assert_gt(checked, 100);
    l_scene_free(&s);
}

/* sg_cache_decode unpacks the node table for render: every lookup answers
 * as from the packed blocks (medium voxels, wall points, points outside),
 * the table holds each voxel's node, a wall's entry (one node, or one per
 * octant) is what the search gives anywhere in the wall or its octant, and
 * a budget too small leaves the cache packed and working. */
Test(importance_cache, the_unpacked_node_table_answers_as_the_packed_blocks)
{
    LScene s;
    l_scene(&s);
    SgImportanceCache *c = l_scene_cache(&s, "decode", 1);
    SgError err = {0};
    SgImportanceCache *packed = sg_cache_open(s.path, &err); /* never decoded: searches */
    cr_assert_not_null(packed, "%s", err.message);
    const SgGrid *g = &s.medium.grid;
    enum { POINTS = 20000 };
    double (*p)[3] = malloc(sizeof *p * POINTS);
    uint32_t *node = malloc(sizeof *node * POINTS);
    bool *found = malloc(sizeof *found * POINTS);
    cr_assert(p && node && found);
    const int dims[3] = {g->nx, g->ny, g->nz};
    SgRng rng;
    sg_rng_seed(&rng, 9, 2);
    for (int i = 0; i < POINTS; i++) {
        for (int a = 0; a < 3; a++) /* the grid and a voxel and a half around it */
            p[i][a] = -1.5 + (dims[a] + 3.0) * sg_rng_float(&rng);
        found[i] = sg_cache_nearest_node(c, p[i], &node[i]);
    }
    cr_assert_not(sg_cache_decode(c, 1024), "a 1 KB budget cannot hold %d voxels", g->nx * g->ny * g->nz);
    cr_assert_null(sg_cache_decoded(c));
    cr_assert(sg_cache_decode(c, 1u << 20));
    const uint32_t *table = sg_cache_decoded(c), *octants = sg_cache_decoded_octants(c);
    cr_assert_not_null(table);
    for (int i = 0; i < POINTS; i++) {
        uint32_t n = SG_CACHE_NONE;
        cr_assert_eq(sg_cache_nearest_node(c, p[i], &n), found[i], "point %d", i);
        if (found[i])
            cr_assert_eq(n, node[i], "point %d: node %u unpacked, %u packed", i, n, node[i]);
        float v[3] = {(float)p[i][0], (float)p[i][1], (float)p[i][2]}; /* origin 0, voxel 1 */
        uint32_t nv = SG_CACHE_NONE;
        cr_assert_eq(sg_cache_nearest_node_voxel(c, v, &nv), found[i], "point %d in voxel units", i);
        if (found[i])
            cr_assert_eq(nv, node[i]);
    }
    int medium = 0, walls = 0, marked = 0, mixed = 0, resolved = 0;
    for (int k = 0; k < g->nz; k++)
        for (int j = 0; j < g->ny; j++)
            for (int i = 0; i < g->nx; i++) {
                uint32_t t = table[i + g->nx * (j + g->ny * k)];
                if (!sg_grid_get(g, i, j, k)) {
                    cr_assert(t & SG_CACHE_WALL_BIT, "solid voxel %d %d %d", i, j, k);
                    walls++;
                    if (t == SG_CACHE_NONE)
                        continue;
                    bool split = t & SG_CACHE_MIXED_BIT;
                    cr_assert(!split || octants, "a mixed wall and no octants");
                    mixed += split;
                    marked += !split;
                    /* in each octant, its corner and random points: the search's answer */
                    for (unsigned o = 0; o < 8; o++) {
                        uint32_t want = split ? octants[8 * (size_t)(t & SG_CACHE_MIXED_INDEX) + o]
                                              : t & ~SG_CACHE_WALL_BIT;
                        if (want == SG_CACHE_NONE)
                            continue;
                        resolved += split;
                        for (int q = 0; q < 9; q++) {
                            double x[3];
                            const int ijk[3] = {i, j, k};
                            for (int a = 0; a < 3; a++) {
                                double f = q ? 0.5 * sg_rng_float(&rng) : 0.49; /* from the centre */
                                x[a] = ijk[a] + 0.5 + ((o >> a & 1) ? f : -f - 1e-9);
                            }
                            uint32_t n;
                            cr_assert(sg_cache_nearest_node(packed, x, &n));
                            cr_assert_eq(n, want, "wall voxel %d %d %d octant %u", i, j, k, o);
                        }
                    }
                    continue;
                }
                double centre[3] = {i + 0.5, j + 0.5, k + 0.5};
                uint32_t n;
                cr_assert(sg_cache_nearest_node(c, centre, &n));
                cr_assert_eq(t, n, "voxel %d %d %d", i, j, k);
                medium++;
            }
    cr_assert_gt(medium, 100);
    cr_assert_gt(walls, 100);
    cr_assert_gt(marked, 50, "walls whose neighbours agree: %d", marked);
    cr_assert_gt(mixed, 5, "walls whose neighbours disagree: %d", mixed);
    cr_assert_gt(resolved, 7 * mixed, "of %d mixed walls' octants, %d have one node", 8 * mixed, resolved);
    free(p);
    free(node);
    free(found);
    sg_cache_close(packed);
    l_scene_free(&s);
}

Test(importance_cache, build_is_deterministic_across_thread_counts)
{
    LScene s;
    l_scene(&s);
    char p1[256], p2[256];
    SgImportanceCache *c1 = build_and_open(&s.medium, &s.skeleton, "det1", 1, p1, sizeof p1);
    SgImportanceCache *c2 = build_and_open(&s.medium, &s.skeleton, "det2", 2, p2, sizeof p2);
    size_t n1, n2;
    uint8_t *a = sgt_read_file(p1, &n1), *b = sgt_read_file(p2, &n2);
    cr_assert_eq(n1, n2);
    cr_assert(memcmp(a, b, n1) == 0);
    free(a);
    free(b);
    sg_cache_close(c1);
    sg_cache_close(c2);
    unlink(p1);
    unlink(p2);
    l_scene_free(&s);
}

Test(importance_cache, vectors_ply_has_one_edge_per_node_and_light)
{
    LScene s;
    l_scene(&s);
    char path[256], vec[256];
    sgt_temp_path(path, sizeof path, "vcache");
    sgt_temp_path(vec, sizeof vec, "vectors.ply");
    SgImportanceOptions opt = {.threads = 2, .vectors_path = vec, .quiet = true};
    SgError err = {0};
    cr_assert(sg_importance_build(&s.medium, &s.skeleton, &opt, path, NULL, &err), "%s",
              err.message);
    size_t size;
    uint8_t *data = sgt_read_file(vec, &size);
    cr_assert_not_null(data);
    char want[64];
    snprintf(want, sizeof want, "element edge %u\n", s.skeleton.node_count);
    data[size - 1] = 0;
    cr_assert(strstr((char *)data, want) != NULL);
    free(data);
    unlink(path);
    unlink(vec);
    l_scene_free(&s);
}

Test(importance_cache, refuses_mismatched_inputs)
{
    LScene s;
    l_scene(&s);
    s.skeleton.nodes[3].kind = SG_NODE_LIGHT;
    s.skeleton.nodes[3].light = 5; /* the medium has one light */
    char path[256];
    sgt_temp_path(path, sizeof path, "mismatch");
    unlink(path);
    SgError err = {0};
    cr_assert_not(sg_importance_build(&s.medium, &s.skeleton, NULL, path, NULL, &err));
    cr_assert(strstr(err.message, "light 5") != NULL, "%s", err.message);
    cr_assert_neq(access(path, F_OK), 0, "a failed build left a file");
    l_scene_free(&s);
}

Test(importance_cache, light_found_by_its_seed_and_no_lights_at_all)
{
    /* A skeleton read from a PLY without the `light` property has no light
     * nodes: each light then hangs on the nearest node of its seed voxel. */
    LScene s;
    l_scene(&s);
    for (uint32_t n = 0; n < s.skeleton.node_count; n++) {
        s.skeleton.nodes[n].kind = SG_NODE_PLAIN;
        s.skeleton.nodes[n].light = -1;
    }
    char path[256];
    SgImportanceCache *c = build_and_open(&s.medium, &s.skeleton, "seed", 2, path, sizeof path);
    cr_assert(sg_cache_light_has_paths(c, 0));
    double q[3], p[3] = {10.5, 2.5, 2.5};
    cr_assert(sg_cache_importance_point(c, p, 0, q));
    cr_assert_gt(q[0], 15);
    uint32_t last = s.skeleton.node_count - 1; /* the seed's own node sees the light */
    cr_assert(sg_cache_node_importance_point(c, last, 0, q));
    cr_assert_float_eq(q[1], 47.0, 1e-4);
    sg_cache_close(c);
    unlink(path);

    /* No lights: a valid cache whose lookups find nodes but no points. */
    s.medium.light_count = 0;
    c = build_and_open(&s.medium, &s.skeleton, "nolight", 1, path, sizeof path);
    cr_assert_eq(sg_cache_light_count(c), 0);
    uint32_t node;
    cr_assert(sg_cache_nearest_node(c, p, &node));
    cr_assert_not(sg_cache_importance_point(c, p, 0, q));
    cr_assert_not(sg_cache_light_reaches(c, 0, p));
    sg_cache_close(c);
    unlink(path);
    s.medium.light_count = 1;
    l_scene_free(&s);
}

Test(importance_cache, failed_vectors_leave_no_cache)
{
    LScene s;
    l_scene(&s);
    char path[256];
    sgt_temp_path(path, sizeof path, "novec");
    unlink(path);
    SgImportanceOptions opt = {.threads = 1, .vectors_path = "/nonexistent/dir/vectors.ply"};
    SgError err = {0};
    cr_assert_not(sg_importance_build(&s.medium, &s.skeleton, &opt, path, NULL, &err));
    cr_assert(strstr(err.message, "/nonexistent/dir/vectors.ply") == err.message, "%s",
              err.message);
    cr_assert_neq(access(path, F_OK), 0, "the cache was written although the build failed");
    l_scene_free(&s);
}
