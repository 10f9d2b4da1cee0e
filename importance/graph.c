/* The skeleton as a graph: adjacency, components, shortest paths toward a
 * light, voxel visibility and the importance points (paper 3.3). */
#include "graph.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "hash.h"
#include "importance_cache_format.h"
#include "memory.h"
#include "threads.h"

/* Bricks of 4^3 voxels; brick (i, j, k) at index i + bx (j + by k). */
static inline size_t brick_at(const SgVisibility *v, const int c[3])
{
    return (size_t)(c[0] >> 2) + v->bx * ((size_t)(c[1] >> 2) + v->by * (size_t)(c[2] >> 2));
}

/* Medium test: with the accelerator, a bit of the voxel's brick word (a
 * brick is 64 bits: x + 4 y + 16 z; the words, an eighth of the grid's
 * bytes, keep a line's next voxels in the same cache line far more often
 * than the byte grid, whose z neighbours are a plane apart). */
static inline bool medium_at(const SgVisibility *v, const int c[3])
{
    const SgGrid *g = v->grid;
    if (!sg_grid_inside(g, c[0], c[1], c[2]))
        return false;
    if (v->bits)
        return v->bits[brick_at(v, c)] >> ((c[0] & 3) | (c[1] & 3) << 2 | (c[2] & 3) << 4) & 1;
    return g->voxels[sg_grid_index(g, c[0], c[1], c[2])] != 0;
}

/* The words of the bricks of z slab bz, row by row of the grid (in its
 * memory order); a slab per task. */
static void brick_words(void *ctx, uint64_t bz, int thread)
{
    (void)thread;
    const SgVisibility *v = ctx;
    const SgGrid *g = v->grid;
    for (int z = (int)bz * 4; z < (int)bz * 4 + 4 && z < g->nz; z++)
        for (int y = 0; y < g->ny; y++) {
            const uint8_t *row = g->voxels + sg_grid_index(g, 0, y, z);
            uint64_t *words = v->bits + v->bx * ((size_t)(y >> 2) + v->by * (size_t)(z >> 2));
            int shift = (y & 3) << 2 | (z & 3) << 4;
            for (int x = 0; x < g->nx; x++)
                words[x >> 2] |= (uint64_t)(row[x] != 0) << (shift | (x & 3));
        }
}

bool sg_visibility_init(SgVisibility *v, const SgGrid *g, int threads, SgError *err)
{
    memset(v, 0, sizeof *v);
    v->grid = g;
    v->bx = ((size_t)g->nx + 3) / 4;
    v->by = ((size_t)g->ny + 3) / 4;
    v->bz = ((size_t)g->nz + 3) / 4;
    const size_t bx = v->bx, by = v->by, bz = v->bz;
    v->clear = malloc(bx * by * bz);
    v->bits = calloc(bx * by * bz, sizeof *v->bits);
    if (!v->clear || !v->bits) {
        sg_visibility_release(v);
        return sg_fail(err, "out of memory for the visibility bricks");
    }
    sg_memory_prefer_huge_pages(v->bits, bx * by * bz * sizeof *v->bits);
    sg_parallel_for(bz, threads, brick_words, v);
    /* A brick is full when its word is all ones (bricks that stick out of
     * the grid never are): clearance 255 for now, 0 for the others. */
    for (size_t b = 0; b < bx * by * bz; b++)
        v->clear[b] = v->bits[b] == UINT64_MAX ? 255 : 0;
    /* Clearance: the chessboard distance, in bricks, to the nearest brick
     * that is not full, the bricks outside the grid counting as not full
     * (capped at 255). Two raster passes of the 26-neighbourhood with unit
     * steps, forward then backward, give it exactly [Rosenfeld & Pfaltz
     * 1966]. Every brick within chessboard distance r - 1 of a brick of
     * clearance r is full (and inside the grid). */
    for (int pass = 0; pass < 2; pass++) {
        int dir = pass ? -1 : 1;
        for (size_t n = 0; n < bx * by * bz; n++) {
            size_t b = pass ? bx * by * bz - 1 - n : n;
            if (!v->clear[b])
                continue;
            long i = (long)(b % bx), j = (long)(b / bx % by), k = (long)(b / (bx * by));
            unsigned best = v->clear[b];
            /* the 13 neighbours before b in this pass's order */
            for (int dz = -1; dz <= 0; dz++)
                for (int dy = -1; dy <= 1; dy++)
                    for (int dx = -1; dx <= 1; dx++) {
                        if (dz == 0 && (dy > 0 || (dy == 0 && dx >= 0)))
                            continue;
                        long x = i + dir * dx, y = j + dir * dy, z = k + dir * dz;
                        unsigned d = 0; /* outside the grid */
                        if (x >= 0 && y >= 0 && z >= 0 && x < (long)bx && y < (long)by &&
                            z < (long)bz)
                            d = v->clear[(size_t)x + bx * ((size_t)y + by * (size_t)z)];
                        if (d + 1 < best)
                            best = d + 1;
                    }
            v->clear[b] = (uint8_t)best;
        }
    }
    return true;
}

void sg_visibility_release(SgVisibility *v)
{
    free(v->clear);
    free(v->bits);
    memset(v, 0, sizeof *v);
}

/* Inside a box of voxels [lo, hi] known to pass the walk's test: advance
 * every axis by its crossings before the first one that leaves the box.
 * Returns true when the segment ends inside the box. */
static inline bool jump_through(int cur[3], int64_t m[3], const int64_t len[3],
                                const int64_t step[3], const int lo[3], const int hi[3])
{
    int exit_axis = -1;
    int64_t exit_index = 0;
    for (int x = 0; x < 3; x++) {
        int64_t k = step[x] > 0 ? hi[x] - cur[x] + 1 : cur[x] - lo[x] + 1; /* crossings to leave */
        int64_t index = m[x] + k - 1;
        if (index >= len[x])
            continue; /* the segment ends before leaving along x */
        /* (2 index + 1) / len_x < (2 exit_index + 1) / len_exit ? */
        if (exit_axis < 0 || (2 * index + 1) * len[exit_axis] < (2 * exit_index + 1) * len[x]) {
            exit_axis = x;
            exit_index = index;
        }
    }
    if (exit_axis < 0)
        return true;
    /* Crossings strictly before T = N / (2 len_e): the count of k with
     * (2k+1) len_e < N len_x, i.e. floor((floor((N len_x - 1) / len_e) + 1) / 2). */
    int64_t N = 2 * exit_index + 1, Q = len[exit_axis];
    for (int x = 0; x < 3; x++) {
        if (len[x] == 0)
            continue;
        int64_t f = (N * len[x] - 1) / Q;
        int64_t count = (f + 1) / 2;
        if (count > len[x])
            count = len[x];
        if (count > m[x]) {
            cur[x] += (int)(step[x] * (count - m[x]));
            m[x] = count;
        }
    }
    return false;
}

/* The voxel walk from a to b. need 0: whether every voxel after a is
 * medium (the visibility test); need >= 1: whether every voxel, a
 * included, lies in a brick of clearance >= need (the chunk test of the
 * importance points; needs the accelerator). */
static bool walk(const SgVisibility *vis, const int a[3], const int b[3], int need)
{
    /* Amanatides & Woo between voxel centres, in exact integer arithmetic:
     * along axis x the segment crosses a voxel boundary at parameters
     * t = (2m + 1) / (2 |dx|), m = 0 .. |dx| - 1; comparing two axes'
     * next crossings is a cross-multiplication. Crossings that coincide
     * (the segment passes through an edge or corner) step diagonally,
     * consistent with the medium's 26-connectivity.
     * In a brick of clearance r every brick within chessboard distance
     * r - max(need, 1) passes the test, so the walk jumps to the exit of
     * that cube of bricks: the first crossing that leaves it is found per
     * axis, and every axis is advanced by its crossings before that one
     * (counted in closed form). */
    int cur[3] = {a[0], a[1], a[2]};
    int64_t len[3], step[3], m[3] = {0, 0, 0};
    for (int x = 0; x < 3; x++) {
        int64_t d = (int64_t)b[x] - a[x];
        len[x] = d < 0 ? -d : d;
        step[x] = d < 0 ? -1 : 1;
    }
    if (!sg_grid_inside(vis->grid, a[0], a[1], a[2]) || !sg_grid_inside(vis->grid, b[0], b[1], b[2]))
        return false;
    const int floor_need = need > 0 ? need : 1;
    if (need > 0 && vis->clear[brick_at(vis, cur)] < need)
        return false;
    for (;;) {
        if (vis->clear) {
            int r = vis->clear[brick_at(vis, cur)] - floor_need;
            if (r >= 0) {
                int lo[3], hi[3];
                for (int x = 0; x < 3; x++) {
                    lo[x] = ((cur[x] >> 2) - r) * 4;
                    hi[x] = ((cur[x] >> 2) + r) * 4 + 3;
                }
                if (jump_through(cur, m, len, step, lo, hi))
                    return true;
            }
        }
        int best = -1;
        for (int x = 0; x < 3; x++) {
            if (m[x] >= len[x])
                continue;
            /* (2 m_x + 1) / len_x < (2 m_best + 1) / len_best ? */
            if (best < 0 || (2 * m[x] + 1) * len[best] < (2 * m[best] + 1) * len[x])
                best = x;
        }
        if (best < 0)
            return true; /* reached b */
        int64_t num = 2 * m[best] + 1, den = len[best];
        for (int x = 0; x < 3; x++)
            if (m[x] < len[x] && (2 * m[x] + 1) * den == num * len[x]) {
                cur[x] += (int)step[x];
                m[x]++;
            }
        if (need > 0 ? vis->clear[brick_at(vis, cur)] < need : !medium_at(vis, cur))
            return false;
    }
}

bool sg_visibility_test(const SgVisibility *vis, const int a[3], const int b[3])
{
    return walk(vis, a, b, 0);
}

bool sg_importance_visible(const SgGrid *grid, const int a[3], const int b[3])
{
    SgVisibility plain = {.grid = grid};
    return sg_visibility_test(&plain, a, b);
}

void sg_graph_release(SgGraph *g)
{
    free(g->first);
    free(g->adjacent);
    free(g->length);
    memset(g, 0, sizeof *g);
}

bool sg_graph_build(const SgSkeleton *s, SgGraph *g, SgError *err)
{
    memset(g, 0, sizeof *g);
    g->node_count = s->node_count;
    g->first = calloc((size_t)s->node_count + 1, sizeof *g->first);
    g->adjacent = malloc(((size_t)s->edge_count * 2 + 1) * sizeof *g->adjacent);
    g->length = malloc(((size_t)s->edge_count * 2 + 1) * sizeof *g->length);
    if (!g->first || !g->adjacent || !g->length) {
        sg_graph_release(g);
        return sg_fail(err, "out of memory for the skeleton graph");
    }
    for (uint32_t e = 0; e < s->edge_count; e++) {
        if (s->edges[e][0] >= s->node_count || s->edges[e][1] >= s->node_count) {
            sg_graph_release(g);
            return sg_fail(err, "skeleton edge %u refers to a missing node", e);
        }
        g->first[s->edges[e][0] + 1]++;
        g->first[s->edges[e][1] + 1]++;
    }
    for (uint32_t n = 0; n < s->node_count; n++)
        g->first[n + 1] += g->first[n];
    uint32_t *fill = malloc(((size_t)s->node_count + 1) * sizeof *fill);
    if (!fill) {
        sg_graph_release(g);
        return sg_fail(err, "out of memory for the skeleton graph");
    }
    memcpy(fill, g->first, (size_t)s->node_count * sizeof *fill);
    for (uint32_t e = 0; e < s->edge_count; e++) {
        uint32_t a = s->edges[e][0], b = s->edges[e][1];
        const float *pa = s->nodes[a].position, *pb = s->nodes[b].position;
        double d[3] = {(double)pa[0] - pb[0], (double)pa[1] - pb[1], (double)pa[2] - pb[2]};
        double l = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        g->adjacent[fill[a]] = b;
        g->length[fill[a]++] = l;
        g->adjacent[fill[b]] = a;
        g->length[fill[b]++] = l;
    }
    free(fill);
    return true;
}

uint32_t sg_graph_components(const SgGraph *g, uint32_t *component, uint32_t *stack)
{
    for (uint32_t n = 0; n < g->node_count; n++)
        component[n] = SG_CACHE_NONE;
    uint32_t count = 0;
    for (uint32_t root = 0; root < g->node_count; root++) {
        if (component[root] != SG_CACHE_NONE)
            continue;
        size_t top = 0;
        stack[top++] = root;
        component[root] = count;
        while (top > 0) {
            uint32_t n = stack[--top];
            for (uint32_t e = g->first[n]; e < g->first[n + 1]; e++)
                if (component[g->adjacent[e]] == SG_CACHE_NONE) {
                    component[g->adjacent[e]] = count;
                    stack[top++] = g->adjacent[e];
                }
        }
        count++;
    }
    return count;
}

/* ---- shortest paths: binary heap keyed by (distance, node) ------------- */

typedef struct HeapItem {
    double key;
    uint32_t node;
} HeapItem;

static bool heap_less(HeapItem a, HeapItem b)
{
    return a.key < b.key || (a.key == b.key && a.node < b.node);
}

void sg_graph_shortest_paths(const SgGraph *g, const uint32_t *sources, uint32_t source_count,
                             double *dist, uint32_t *pred, void *heap_memory)
{
    /* Lazy deletion: at most one entry per edge direction plus sources. */
    HeapItem *heap = heap_memory;
    size_t size = 0;
    for (uint32_t n = 0; n < g->node_count; n++) {
        dist[n] = INFINITY;
        pred[n] = SG_CACHE_NONE;
    }
    for (uint32_t s = 0; s < source_count; s++) {
        if (dist[sources[s]] == 0)
            continue;
        dist[sources[s]] = 0;
        HeapItem it = {0, sources[s]};
        size_t i = size++;
        while (i > 0 && heap_less(it, heap[(i - 1) / 2])) {
            heap[i] = heap[(i - 1) / 2];
            i = (i - 1) / 2;
        }
        heap[i] = it;
    }
    while (size > 0) {
        HeapItem top = heap[0];
        HeapItem last = heap[--size];
        size_t i = 0;
        for (;;) {
            size_t c = 2 * i + 1;
            if (c >= size)
                break;
            if (c + 1 < size && heap_less(heap[c + 1], heap[c]))
                c++;
            if (!heap_less(heap[c], last))
                break;
            heap[i] = heap[c];
            i = c;
        }
        if (size > 0)
            heap[i] = last;
        if (top.key > dist[top.node])
            continue;
        for (uint32_t e = g->first[top.node]; e < g->first[top.node + 1]; e++) {
            uint32_t u = g->adjacent[e];
            double nd = top.key + g->length[e];
            if (nd < dist[u]) {
                dist[u] = nd;
                pred[u] = top.node;
                HeapItem it = {nd, u};
                size_t k = size++;
                while (k > 0 && heap_less(it, heap[(k - 1) / 2])) {
                    heap[k] = heap[(k - 1) / 2];
                    k = (k - 1) / 2;
                }
                heap[k] = it;
            }
        }
    }
}

size_t sg_graph_heap_bytes(const SgGraph *g)
{
    return ((size_t)g->first[g->node_count] + g->node_count + 1) * sizeof(HeapItem);
}

static double voxel_distance(const int a[3], const int b[3])
{
    double d0 = a[0] - b[0], d1 = a[1] - b[1], d2 = a[2] - b[2];
    return sqrt(d0 * d0 + d1 * d1 + d2 * d2);
}

/* Distance from voxel centre p to the segment between voxel centres a and b. */
static double segment_distance(const int p[3], const int a[3], const int b[3])
{
    double ab[3], ap[3], ab2 = 0, t = 0;
    for (int x = 0; x < 3; x++) {
        ab[x] = b[x] - a[x];
        ap[x] = p[x] - a[x];
        ab2 += ab[x] * ab[x];
        t += ab[x] * ap[x];
    }
    t = ab2 > 0 ? t / ab2 : 0;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    double d2 = 0;
    for (int x = 0; x < 3; x++) {
        double e = ap[x] - t * ab[x];
        d2 += e * e;
    }
    return sqrt(d2);
}

/* Whether one walk shows every node of path[lo..hi] visible from voxel
 * n (false: it could not tell). Let reach be the largest distance of those
 * nodes from the segment S = [n, path[hi]]. The distance to S is convex,
 * so each segment [n, path[i]] stays within reach of S; a voxel the walk
 * n -> path[i] visits meets that segment, so its centre is within
 * sqrt(3)/2 + reach of S, hence within sqrt(3) + reach of the centre of a
 * voxel c that the walk n -> path[hi] visits (those voxels cover S). When
 * c's brick has clearance r, every voxel whose centre is nearer to c's
 * than 4 r - 3 is medium, inside the grid. So if every voxel of the walk
 * along S has 4 r - 3 > sqrt(3) + reach, every walk n -> path[i] meets
 * medium voxels only: the same answer as testing them one by one. */
static bool chunk_visible(const SgVisibility *vis, const SgSkeleton *s, const int n[3],
                          const uint32_t *path, size_t lo, size_t hi)
{
    const int *end = s->nodes[path[hi]].voxel;
    double reach = 0;
    for (size_t i = lo; i < hi; i++) {
        double d = segment_distance(s->nodes[path[i]].voxel, n, end);
        reach = d > reach ? d : reach;
    }
    double need = floor((sqrt(3.0) + reach + 3.0) / 4.0 + 1e-9) + 1;
    return need <= 255 && walk(vis, n, end, (int)need);
}

/* Index of the first node of path[lo..hi] hidden from voxel n (hi + 1:
 * none): a chunk shown visible by one walk, else its halves in order. */
static size_t first_hidden(const SgVisibility *vis, const SgSkeleton *s, const int n[3],
                           const uint32_t *path, size_t lo, size_t hi)
{
    if (hi - lo < 2) {
        for (size_t i = lo; i <= hi; i++)
            if (!sg_visibility_test(vis, n, s->nodes[path[i]].voxel))
                return i;
        return hi + 1;
    }
    if (chunk_visible(vis, s, n, path, lo, hi))
        return hi + 1;
    size_t mid = lo + (hi - lo) / 2;
    size_t f = first_hidden(vis, s, n, path, lo, mid);
    return f <= mid ? f : first_hidden(vis, s, n, path, mid + 1, hi);
}

enum { RUN_CHUNK_FIRST = 8, RUN_CHUNK_MOST = 128 };

/* The exact run (every node tested, in effect): the path toward the light
 * in chunks of 8, 16, ... 128 nodes, each settled by first_hidden. Sums
 * the visible nodes' positions in path order; returns their count. */
static uint32_t exact_run(const SgVisibility *vis, const SgSkeleton *s, const uint32_t *pred,
                          const double *dist, uint32_t node, double sum[3])
{
    const int *n = s->nodes[node].voxel;
    uint32_t path[RUN_CHUNK_MOST], count = 0;
    size_t chunk = RUN_CHUNK_FIRST;
    uint32_t x = pred[node];
    while (x != SG_CACHE_NONE) {
        size_t c = 0;
        bool last = false;
        for (;;) {
            path[c++] = x;
            if (dist[x] == 0 || pred[x] == SG_CACHE_NONE) {
                last = true; /* the light's node: the run ends here */
                break;
            }
            x = pred[x];
            if (c == chunk)
                break;
        }
        size_t f = first_hidden(vis, s, n, path, 0, c - 1);
        for (size_t i = 0; i < f; i++, count++)
            for (int a = 0; a < 3; a++)
                sum[a] += s->nodes[path[i]].position[a];
        if (f < c || last)
            break;
        if (chunk < RUN_CHUNK_MOST)
            chunk *= 2;
    }
    return count;
}

void sg_importance_point(const SgVisibility *vis, const SgSkeleton *s, const uint32_t *pred,
                         const double *dist, uint32_t node, const double light_position[3],
                         double tolerance, float point[3])
{
    const SgSkeletonNode *n = &s->nodes[node];
    if (dist[node] == 0) {
        for (int a = 0; a < 3; a++)
            point[a] = (float)light_position[a];
        return;
    }
    /* Walk the path toward the light in chunks: a chunk spans at most
     * `tolerance` times its distance from the node, and when its last
     * node is visible the nodes inside it are taken as visible too (an
     * obstacle would have to hide between two sight lines that close).
     * Otherwise its nodes are tested one by one, so the end of the run is
     * exact. Near the node chunks are single nodes; far away this makes the
     * walk logarithmic instead of linear in the run length. */
    double sum[3] = {0, 0, 0};
    uint32_t count = 0;
    bool reached = false;
    uint32_t m = pred[node];
    if (tolerance <= 0 && vis->clear) {
        count = exact_run(vis, s, pred, dist, node, sum);
        m = SG_CACHE_NONE; /* done */
    }
    while (m != SG_CACHE_NONE && !reached) {
        double budget = tolerance * voxel_distance(n->voxel, s->nodes[m].voxel);
        double span = 0;
        uint32_t last = m;
        while (dist[last] != 0 && pred[last] != SG_CACHE_NONE) {
            double e = voxel_distance(s->nodes[last].voxel, s->nodes[pred[last]].voxel);
            if (span + e > budget)
                break;
            span += e;
            last = pred[last];
        }
        bool whole = last != m && sg_visibility_test(vis, n->voxel, s->nodes[last].voxel);
        bool stop = false;
        for (uint32_t x = m;; x = pred[x]) {
            if (!whole && !sg_visibility_test(vis, n->voxel, s->nodes[x].voxel)) {
                stop = true;
                break;
            }
            for (int a = 0; a < 3; a++)
                sum[a] += s->nodes[x].position[a];
            count++;
            if (dist[x] == 0) {
                reached = true;
                break;
            }
            if (x == last)
                break;
        }
        if (stop)
            break;
        m = pred[last];
    }
    /* A node that sees the light's node also gets the barycenter, as the
     * paper has it (3.3), not the light itself: in view, the light is what
     * next-event estimation already samples, and the run's middle leads to
     * the lit surroundings, which is where indirect light comes from
     * (measured: corridor relMSE 0.00181 against 0.00232 aiming at the light). */
    (void)reached;
    (void)light_position;
    if (count == 0) {
        /* Not even the next node is in sight (a graph edge that cuts a
         * corner): follow the graph. */
        for (int a = 0; a < 3; a++)
            point[a] = s->nodes[pred[node]].position[a];
    } else {
        for (int a = 0; a < 3; a++)
            point[a] = (float)(sum[a] / count);
    }
}

uint64_t sg_importance_skeleton_hash(const SgSkeleton *s)
{
    uint64_t h = sg_hash_bytes(SG_HASH_INIT, &s->node_count, sizeof s->node_count);
    for (uint32_t n = 0; n < s->node_count; n++) {
        const SgSkeletonNode *v = &s->nodes[n];
        h = sg_hash_bytes(h, v->position, sizeof v->position);
        h = sg_hash_bytes(h, v->voxel, sizeof v->voxel);
        h = sg_hash_bytes(h, &v->kind, sizeof v->kind);
        int light = v->kind == SG_NODE_LIGHT ? v->light : -1;
        h = sg_hash_bytes(h, &light, sizeof light);
    }
    h = sg_hash_bytes(h, &s->edge_count, sizeof s->edge_count);
    if (s->edge_count)
        h = sg_hash_bytes(h, s->edges, (size_t)s->edge_count * sizeof s->edges[0]);
    return h;
}
