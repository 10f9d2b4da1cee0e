/* The skeleton as a graph: adjacency, components, shortest paths toward a
 * light, voxel visibility and the importance points (paper 3.3). */
#include "graph.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "hash.h"
#include "importance_cache_format.h"

static inline bool level_full(const SgVisibility *v, int level, const int c[3])
{
    int sh = level ? 4 : 2;
    size_t b = (size_t)(c[0] >> sh) +
               v->bx[level] * ((size_t)(c[1] >> sh) + v->by[level] * (size_t)(c[2] >> sh));
    return v->full[level][b >> 6] >> (b & 63) & 1;
}

/* Medium test: the brick bits (a few hundred KB, cache resident) spare
 * most loads from the byte grid, whose z neighbours are far apart. */
static inline bool medium_at(const SgVisibility *v, const int c[3])
{
    const SgGrid *g = v->grid;
    if (!sg_grid_inside(g, c[0], c[1], c[2]))
        return false;
    if (v->full[0] && level_full(v, 0, c))
        return true;
    return g->voxels[sg_grid_index(g, c[0], c[1], c[2])] != 0;
}

bool sg_visibility_init(SgVisibility *v, const SgGrid *g, SgError *err)
{
    memset(v, 0, sizeof *v);
    v->grid = g;
    size_t bz[2];
    for (int level = 0; level < 2; level++) {
        int size = level ? 16 : 4;
        v->bx[level] = ((size_t)g->nx + size - 1) / size;
        v->by[level] = ((size_t)g->ny + size - 1) / size;
        bz[level] = ((size_t)g->nz + size - 1) / size;
        size_t count = v->bx[level] * v->by[level] * bz[level];
        v->full[level] = calloc((count + 63) / 64, sizeof *v->full[level]);
        if (!v->full[level]) {
            sg_visibility_release(v);
            return sg_fail(err, "out of memory for the visibility bricks");
        }
    }
    /* A brick is full when each of its 16 x-rows is 4 medium voxels (bricks
     * that stick out of the grid are never full). */
    for (size_t bk = 0; bk < bz[0]; bk++)
        for (size_t bj = 0; bj < v->by[0]; bj++)
            for (size_t bi = 0; bi < v->bx[0]; bi++) {
                if ((bi + 1) * 4 > (size_t)g->nx || (bj + 1) * 4 > (size_t)g->ny ||
                    (bk + 1) * 4 > (size_t)g->nz)
                    continue;
                bool full = true;
                for (int z = 0; z < 4 && full; z++)
                    for (int y = 0; y < 4 && full; y++) {
                        const uint8_t *row = g->voxels + sg_grid_index(g, (int)bi * 4,
                                                                       (int)bj * 4 + y,
                                                                       (int)bk * 4 + z);
                        full = row[0] && row[1] && row[2] && row[3];
                    }
                if (full) {
                    size_t b = bi + v->bx[0] * (bj + v->by[0] * bk);
                    v->full[0][b >> 6] |= (uint64_t)1 << (b & 63);
                }
            }
    /* A super-brick is full when its 64 bricks are. */
    for (size_t sk = 0; sk < bz[1]; sk++)
        for (size_t sj = 0; sj < v->by[1]; sj++)
            for (size_t si = 0; si < v->bx[1]; si++) {
                bool full = true;
                for (int z = 0; z < 4 && full; z++)
                    for (int y = 0; y < 4 && full; y++)
                        for (int x = 0; x < 4 && full; x++) {
                            int c[3] = {(int)(si * 16) + 4 * x, (int)(sj * 16) + 4 * y,
                                        (int)(sk * 16) + 4 * z};
                            full = c[0] < g->nx && c[1] < g->ny && c[2] < g->nz &&
                                   level_full(v, 0, c);
                        }
                if (full) {
                    size_t b = si + v->bx[1] * (sj + v->by[1] * sk);
                    v->full[1][b >> 6] |= (uint64_t)1 << (b & 63);
                }
            }
    return true;
}

void sg_visibility_release(SgVisibility *v)
{
    free(v->full[0]);
    free(v->full[1]);
    memset(v, 0, sizeof *v);
}

/* Inside an all-medium cube of `size` voxels (aligned): advance every axis
 * by its crossings before the first one that leaves the cube. Returns true
 * when the segment ends inside the cube. */
static inline bool jump_through(int cur[3], int64_t m[3], const int64_t len[3],
                                const int64_t step[3], int size)
{
    int exit_axis = -1;
    int64_t exit_index = 0;
    for (int x = 0; x < 3; x++) {
        int in = cur[x] & (size - 1);
        int64_t k = step[x] > 0 ? size - in : in + 1; /* crossings to leave */
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

bool sg_visibility_test(const SgVisibility *vis, const int a[3], const int b[3])
{
    /* Amanatides & Woo between voxel centres, in exact integer arithmetic:
     * along axis x the segment crosses a voxel boundary at parameters
     * t = (2m + 1) / (2 |dx|), m = 0 .. |dx| - 1; comparing two axes'
     * next crossings is a cross-multiplication. Crossings that coincide
     * (the segment passes through an edge or corner) step diagonally,
     * consistent with the medium's 26-connectivity.
     * Inside an all-medium brick or super-brick the walk jumps to its exit:
     * the first crossing that leaves it is found per axis, and every axis
     * is advanced by its crossings before that one (counted in closed form). */
    int cur[3] = {a[0], a[1], a[2]};
    int64_t len[3], step[3], m[3] = {0, 0, 0};
    for (int x = 0; x < 3; x++) {
        int64_t d = (int64_t)b[x] - a[x];
        len[x] = d < 0 ? -d : d;
        step[x] = d < 0 ? -1 : 1;
    }
    if (!sg_grid_inside(vis->grid, a[0], a[1], a[2]) || !sg_grid_inside(vis->grid, b[0], b[1], b[2]))
        return false;
    for (;;) {
        if (vis->full[1] && level_full(vis, 1, cur)) {
            if (jump_through(cur, m, len, step, 16))
                return true;
        } else if (vis->full[0] && level_full(vis, 0, cur)) {
            if (jump_through(cur, m, len, step, 4))
                return true;
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
        if (!medium_at(vis, cur))
            return false;
    }
}

bool sg_importance_visible(const SgGrid *grid, const int a[3], const int b[3])
{
    SgVisibility plain = {grid, {NULL, NULL}, {0, 0}, {0, 0}};
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
