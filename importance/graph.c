/* The skeleton as a graph: adjacency, components, shortest paths toward a
 * light, voxel visibility and the importance points (paper 3.3). */
#include "graph.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "hash.h"
#include "importance_cache_format.h"

bool sg_importance_visible(const SgGrid *grid, const int a[3], const int b[3])
{
    /* Amanatides & Woo between voxel centres, in exact integer arithmetic:
     * along axis x the segment crosses a voxel boundary at parameters
     * t = (2m + 1) / (2 |dx|), m = 0 .. |dx| - 1; comparing two axes'
     * next crossings is a cross-multiplication. Crossings that coincide
     * (the segment passes through an edge or corner) step diagonally,
     * consistent with the medium's 26-connectivity. */
    int cur[3] = {a[0], a[1], a[2]};
    int64_t len[3], step[3], m[3] = {0, 0, 0};
    for (int x = 0; x < 3; x++) {
        int64_t d = (int64_t)b[x] - a[x];
        len[x] = d < 0 ? -d : d;
        step[x] = d < 0 ? -1 : 1;
    }
    for (;;) {
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
        if (!sg_grid_get(grid, cur[0], cur[1], cur[2]))
            return false;
    }
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

uint32_t sg_importance_components(const SgSkeleton *skeleton, uint32_t *component, SgError *err)
{
    SgGraph g;
    if (!sg_graph_build(skeleton, &g, err))
        return 0;
    uint32_t *stack = malloc(((size_t)skeleton->node_count + 1) * sizeof *stack);
    if (!stack) {
        sg_graph_release(&g);
        sg_fail(err, "out of memory for the skeleton components");
        return 0;
    }
    uint32_t count = sg_graph_components(&g, component, stack);
    free(stack);
    sg_graph_release(&g);
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

void sg_importance_point(const SgGrid *grid, const SgSkeleton *s, const uint32_t *pred,
                         const double *dist, uint32_t node, const double light_position[3],
                         float point[3])
{
    const SgSkeletonNode *n = &s->nodes[node];
    if (dist[node] == 0) {
        for (int a = 0; a < 3; a++)
            point[a] = (float)light_position[a];
        return;
    }
    double sum[3] = {0, 0, 0};
    uint32_t count = 0;
    bool reached = false;
    for (uint32_t m = pred[node]; m != SG_CACHE_NONE; m = pred[m]) {
        if (!sg_importance_visible(grid, n->voxel, s->nodes[m].voxel))
            break;
        for (int a = 0; a < 3; a++)
            sum[a] += s->nodes[m].position[a];
        count++;
        if (dist[m] == 0) {
            reached = true;
            break;
        }
    }
    if (reached) {
        /* The node sees the light itself: aim at the light, not at the
         * middle of the way there. */
        for (int a = 0; a < 3; a++)
            point[a] = (float)light_position[a];
    } else if (count == 0) {
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
