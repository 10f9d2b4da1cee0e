/* sg_skeletonize: distance and opening, the complex, the collapse, then
 * the graph that is left (0-cells become nodes, 1-cells edges). */
#include "skeletonize.h"

#include <stdlib.h>
#include <string.h>

#include "collapse.h"
#include "complex.h"
#include "memory.h"
#include "progress.h"
#include "union_find.h"

void sg_skeleton_options_default(SgSkeletonOptions *opt)
{
    memset(opt, 0, sizeof *opt);
    opt->threads = 0;
    opt->progress = true;
    opt->filter_scale = 1.0;
    opt->parallel_grain = SG_SKELETON_PARALLEL_GRAIN;
}

static size_t grid_index3(const SgGrid *g, const int p[3])
{
    return sg_grid_index(g, p[0], p[1], p[2]);
}

static size_t lattice_index3(const SgComplex *cx, const int p[3])
{
    return sg_complex_vertex(cx, p[0], p[1], p[2]);
}

typedef struct Anchor {
    uint32_t vertex_cell; /* cell id of the constrained 0-cell */
    uint32_t constraint;  /* index into the caller's constraint list */
} Anchor;

static size_t find_u32(const uint32_t *a, size_t n, uint32_t x)
{
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = (lo + hi) / 2;
        if (a[mid] < x)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < n && a[lo] == x ? lo : SIZE_MAX;
}

/* Of the 8 corners of a constraint voxel, the one deepest in the medium
 * (largest summed distance of its 8 voxels) that no other constraint took. */
static uint32_t choose_anchor(const SgComplex *cx, const SgGrid *g, const uint16_t *dist8,
                              const int p[3], const Anchor *taken, size_t taken_count)
{
    uint32_t best = UINT32_MAX;
    uint64_t best_score = 0;
    for (unsigned e = 0; e < 8; e++) {
        int q[3] = {p[0] + (int)(e & 1), p[1] + (int)(e >> 1 & 1), p[2] + (int)(e >> 2)};
        uint32_t cell = (uint32_t)(sg_complex_vertex(cx, q[0], q[1], q[2]) * 8);
        bool used = false;
        for (size_t t = 0; t < taken_count; t++)
            used |= taken[t].vertex_cell == cell;
        if (used)
            continue;
        uint64_t score = 1;
        for (unsigned d = 0; d < 8; d++) {
            int r[3] = {q[0] - (int)(d & 1), q[1] - (int)(d >> 1 & 1), q[2] - (int)(d >> 2)};
            if (sg_grid_inside(g, r[0], r[1], r[2]))
                score += dist8[lattice_index3(cx, r)];
        }
        if (best == UINT32_MAX || score > best_score)
            best = cell, best_score = score;
    }
    if (best == UINT32_MAX) /* all 8 corners taken: share the lowest */
        best = (uint32_t)(sg_complex_vertex(cx, p[0], p[1], p[2]) * 8);
    return best;
}

/* One skeletonization: the distances, the complex and its collapse, the
 * constraints' anchors and the graph being built. */
typedef struct Skeletonizer {
    const SgGrid *g;
    const int (*voxels)[3];
    const uint8_t *kinds;
    const int *lights;
    uint16_t *dist8, *open8; /* lattice layout: voxel (i,j,k) at vertex (i,j,k) */
    SgComplex cx;
    SgCollapseResult col;
    Anchor *anchors;
    uint32_t *anchor_cells, *vertex_cells;
    size_t anchor_count, nv, ne;
    SgSkeleton *out;
} Skeletonizer;

/* Each constraint voxel in the medium pins one 0-cell of the complex. */
static bool place_anchors(Skeletonizer *s, uint32_t constraint_count, SgError *err)
{
    s->anchors = calloc(constraint_count ? constraint_count : 1, sizeof *s->anchors);
    s->anchor_cells = calloc(constraint_count ? constraint_count : 1, sizeof *s->anchor_cells);
    if (!s->anchors || !s->anchor_cells)
        return sg_fail(err, "skeleton: out of memory");
    for (uint32_t i = 0; i < constraint_count; i++) {
        const int *p = s->voxels[i];
        if (!sg_grid_inside(s->g, p[0], p[1], p[2]) || !s->g->voxels[grid_index3(s->g, p)])
            continue; /* not in the medium: nothing to pass through */
        Anchor *an = &s->anchors[s->anchor_count];
        an->vertex_cell = choose_anchor(&s->cx, s->g, s->dist8, p, s->anchors, s->anchor_count);
        an->constraint = i;
        s->anchor_cells[s->anchor_count++] = an->vertex_cell;
    }
    return true;
}

/* The 0-cells and 1-cells left after the collapse (nothing else may be). */
static bool count_cells(const SgComplex *cx, size_t *vertex_count, size_t *edge_count, SgError *err)
{
    *vertex_count = *edge_count = 0;
    for (size_t v = 0; v < cx->vertex_count; v++) {
        unsigned bits = cx->cells[v];
        if (!bits)
            continue;
        if (bits & ~0x17u)
            return sg_fail(err, "skeleton: internal error: 2- or 3-cells left after the collapse");
        *vertex_count += bits & 1;
        *edge_count += (bits >> 1 & 1) + (bits >> 2 & 1) + (bits >> 4 & 1);
    }
    if (*vertex_count >= UINT32_MAX || *edge_count >= UINT32_MAX)
        return sg_fail(err, "skeleton: graph too large");
    return true;
}

/* Node i, at 0-cell vertex_cells[i]: the deepest of its 8 voxels, or the
 * constraint voxel anchored there with its kind and light. */
static void make_node(Skeletonizer *s, size_t i)
{
    const SgGrid *g = s->g;
    SgSkeletonNode *node = &s->out->nodes[i];
    int c[3];
    sg_complex_coords(&s->cx, s->vertex_cells[i] >> 3, c);
    int best[3] = {-1, -1, -1};
    uint16_t best_d = 0;
    for (unsigned d = 0; d < 8; d++) {
        int r[3] = {c[0] - (int)(d & 1), c[1] - (int)(d >> 1 & 1), c[2] - (int)(d >> 2)};
        if (!sg_grid_inside(g, r[0], r[1], r[2]))
            continue;
        uint16_t dd = s->dist8[lattice_index3(&s->cx, r)];
        if (dd > best_d)
            best_d = dd, memcpy(best, r, sizeof best);
    }
    node->kind = SG_NODE_PLAIN;
    node->light = -1;
    for (size_t a = 0; a < s->anchor_count; a++)
        if (s->anchors[a].vertex_cell == s->vertex_cells[i]) {
            uint32_t k = s->anchors[a].constraint;
            memcpy(best, s->voxels[k], sizeof best);
            node->kind = s->kinds ? s->kinds[k] : SG_NODE_LIGHT;
            node->light = s->lights ? s->lights[k] : -1;
            break;
        }
    memcpy(node->voxel, best, sizeof best);
    double w[3];
    sg_grid_voxel_center(g, best[0], best[1], best[2], w);
    for (int a = 0; a < 3; a++)
        node->position[a] = (float)w[a];
    node->radius = (float)(s->open8[lattice_index3(&s->cx, best)] / 8.0 * g->voxel_size);
    node->lifespan = -1; /* set from its edges */
}

/* An edge's lifespan: steps between losing its last square and joining
 * the skeleton. */
static int edge_lifespan(const SgCollapseResult *col, uint32_t cell)
{
    size_t lo = 0, hi = col->edge_count;
    while (lo < hi) {
        size_t mid = (lo + hi) / 2;
        if (col->edges[mid].cell < cell)
            lo = mid + 1;
        else
            hi = mid;
    }
    int life = (int)col->steps;
    if (lo < col->edge_count && col->edges[lo].cell == cell) {
        int32_t until = col->edges[lo].kept >= 0 ? col->edges[lo].kept : (int32_t)col->steps;
        life = until - col->edges[lo].birth;
    }
    return life;
}

/* Every 1-cell left becomes an edge; its nodes live as long as their
 * longest-lived edge. */
static bool make_edges(Skeletonizer *s, SgError *err)
{
    const SgComplex *cx = &s->cx;
    SgSkeleton *out = s->out;
    for (size_t v = 0; v < cx->vertex_count; v++) {
        unsigned bits = cx->cells[v];
        for (int a = 0; a < 3; a++) {
            unsigned m = 1u << a;
            if (!(bits >> m & 1))
                continue;
            size_t i0 = find_u32(s->vertex_cells, s->nv, (uint32_t)(v * 8));
            size_t i1 = find_u32(s->vertex_cells, s->nv, (uint32_t)((v + cx->stride[a]) * 8));
            if (i0 == SIZE_MAX || i1 == SIZE_MAX)
                return sg_fail(err, "skeleton: internal error: an edge without its vertices");
            out->edges[s->ne][0] = (uint32_t)i0;
            out->edges[s->ne][1] = (uint32_t)i1;
            s->ne++;
            int life = edge_lifespan(&s->col, (uint32_t)(v * 8 + m));
            if (life > out->nodes[i0].lifespan) out->nodes[i0].lifespan = life;
            if (life > out->nodes[i1].lifespan) out->nodes[i1].lifespan = life;
        }
    }
    return true;
}

/* The graph that is left: 0-cells become nodes, 1-cells edges. */
static bool make_graph(Skeletonizer *s, SgError *err)
{
    size_t vertex_count, edge_count;
    if (!count_cells(&s->cx, &vertex_count, &edge_count, err))
        return false;
    SgSkeleton *out = s->out;
    s->vertex_cells = malloc((vertex_count ? vertex_count : 1) * sizeof *s->vertex_cells);
    out->nodes = calloc(vertex_count ? vertex_count : 1, sizeof *out->nodes);
    out->edges = calloc(edge_count ? edge_count : 1, sizeof *out->edges);
    if (!s->vertex_cells || !out->nodes || !out->edges)
        return sg_fail(err, "skeleton: out of memory for a graph of %zu nodes", vertex_count);
    for (size_t v = 0; v < s->cx.vertex_count; v++)
        if (s->cx.cells[v] & 1)
            s->vertex_cells[s->nv++] = (uint32_t)(v * 8);
    for (size_t i = 0; i < s->nv; i++)
        make_node(s, i);
    if (!make_edges(s, err))
        return false;
    out->node_count = (uint32_t)s->nv;
    out->edge_count = (uint32_t)s->ne;
    return true;
}

/* How far node p's voxel is from the walls, over the most of its 26
 * neighbours' (1: it is on the medial surface). */
static double centredness(const Skeletonizer *s, const int p[3])
{
    uint16_t here = s->dist8[lattice_index3(&s->cx, p)], around = here;
    for (int dz = -1; dz <= 1; dz++)
        for (int dy = -1; dy <= 1; dy++)
            for (int dx = -1; dx <= 1; dx++) {
                int q[3] = {p[0] + dx, p[1] + dy, p[2] + dz};
                if (sg_grid_inside(s->g, q[0], q[1], q[2]) && s->dist8[lattice_index3(&s->cx, q)] > around)
                    around = s->dist8[lattice_index3(&s->cx, q)];
            }
    return around ? (double)here / around : 1.0;
}

/* components, loops, centredness; nodes without an edge lasted the whole
 * collapse */
static bool graph_statistics(Skeletonizer *s, SgSkeletonStats *stats, SgError *err)
{
    size_t nv = s->nv, ne = s->ne;
    SgSkeleton *out = s->out;
    uint32_t *parent = malloc((nv ? nv : 1) * sizeof *parent);
    if (!parent)
        return sg_fail(err, "skeleton: out of memory for a graph of %zu nodes", nv);
    for (size_t i = 0; i < nv; i++)
        parent[i] = (uint32_t)i;
    uint32_t components = (uint32_t)nv;
    for (size_t e = 0; e < ne; e++) {
        if (sg_set_union(parent, out->edges[e][0], out->edges[e][1]))
            components--;
    }
    free(parent);
    double ratio_sum = 0;
    for (size_t i = 0; i < nv; i++) {
        if (out->nodes[i].lifespan < 0)
            out->nodes[i].lifespan = (int)s->col.steps;
        ratio_sum += centredness(s, out->nodes[i].voxel);
    }
    stats->nodes = (uint32_t)nv;
    stats->edges = (uint32_t)ne;
    stats->components = components;
    stats->loops = (int64_t)ne - (int64_t)nv + components;
    stats->mean_centredness = nv ? ratio_sum / (double)nv : 0;
    return true;
}

static void progress_phase(SgProgress *progress, const char *label, bool enabled)
{
    sg_progress_begin(progress, label, 0);
    if (!enabled)
        progress->enabled = false;
}

/* Distance and opening, the complex, the anchors, then the collapse. */
static bool collapse_medium(Skeletonizer *s, uint32_t constraint_count, const SgSkeletonOptions *opt,
                            SgProgress *progress, SgSkeletonStats *stats, double t0, SgError *err)
{
    progress_phase(progress, "skeleton: distance", opt->progress);
    if (!sg_distance_opening_lattice(s->g, opt->threads, &s->dist8, &s->open8, err))
        return false;
    stats->seconds_distance = sg_seconds() - t0;
    /* dist8 and open8 come in lattice layout (voxel (i,j,k) at vertex
     * (i,j,k)): the collapse reads the voxels around a cell without
     * dividing indices */
    if (!sg_complex_build(&s->cx, s->g, opt->threads, err) || !place_anchors(s, constraint_count, err))
        return false;
    stats->constraints = (uint32_t)s->anchor_count;
    double t1 = sg_seconds();
    sg_progress_end(progress);
    progress_phase(progress, "skeleton: collapse", opt->progress);
    if (!sg_collapse(&s->cx, s->anchor_cells, s->anchor_count, s->dist8, s->open8, opt->filter_scale,
                     opt->threads, opt->parallel_grain, opt->collapse_slab_planes, opt->collapse_schedule_seed,
                     progress, &s->col, err))
        return false;
    sg_progress_end(progress);
    stats->seconds_collapse = sg_seconds() - t1;
    stats->steps = s->col.steps;
    stats->cavities_broken = s->col.cavities_broken;
    stats->forced_breaks = s->col.forced_breaks;
    return true;
}

bool sg_skeletonize_grid(const SgGrid *g, uint32_t constraint_count, const int (*voxels)[3],
                         const uint8_t *kinds, const int *lights, const SgSkeletonOptions *opt_in,
                         SgSkeleton *out, SgSkeletonStats *stats_out, SgError *err)
{
    memset(out, 0, sizeof *out);
    SgSkeletonOptions opt;
    if (opt_in)
        opt = *opt_in;
    else
        sg_skeleton_options_default(&opt);
    SgSkeletonStats stats = {0};
    double t0 = sg_seconds();
    if (!g || !g->voxels || sg_grid_count(g) == 0)
        return sg_fail(err, "skeleton: the medium grid is empty");
    stats.medium_voxels = sg_grid_count_nonzero(g);
    if (stats.medium_voxels == 0)
        return sg_fail(err, "skeleton: the medium has no voxel");

    Skeletonizer s = {.g = g, .voxels = voxels, .kinds = kinds, .lights = lights, .out = out};
    SgProgress progress;
    bool ok = collapse_medium(&s, constraint_count, &opt, &progress, &stats, t0, err) && make_graph(&s, err) &&
              graph_statistics(&s, &stats, err);
    sg_progress_end(&progress);
    free(s.dist8);
    free(s.open8);
    sg_complex_release(&s.cx);
    sg_collapse_result_release(&s.col);
    free(s.anchors);
    free(s.anchor_cells);
    free(s.vertex_cells);
    if (!ok) {
        free(out->nodes);
        free(out->edges);
        memset(out, 0, sizeof *out);
        return false;
    }
    stats.seconds_total = sg_seconds() - t0;
    if (stats_out)
        *stats_out = stats;
    return true;
}

bool sg_skeletonize(const SgMedium *m, const SgSkeletonOptions *opt, SgSkeleton *out,
                    SgSkeletonStats *stats, SgError *err)
{
    uint32_t n = m->light_count + 1;
    int (*voxels)[3] = calloc(n, sizeof *voxels);
    uint8_t *kinds = calloc(n, 1);
    int *lights = calloc(n, sizeof *lights);
    if (!voxels || !kinds || !lights) {
        free(voxels), free(kinds), free(lights);
        return sg_fail(err, "skeleton: out of memory");
    }
    uint32_t count = 0;
    for (uint32_t i = 0; i < m->light_count; i++) {
        const int *s = m->lights[i].seed;
        if (s[0] < 0 && s[1] < 0 && s[2] < 0)
            continue; /* sealed light: no air in front of it */
        memcpy(voxels[count], s, sizeof voxels[count]);
        kinds[count] = SG_NODE_LIGHT;
        lights[count] = (int)i;
        count++;
    }
    if (opt && opt->camera_constraint && m->has_camera) {
        int c[3];
        sg_grid_world_to_voxel(&m->grid, m->camera_position, c);
        if (sg_grid_get(&m->grid, c[0], c[1], c[2])) {
            memcpy(voxels[count], c, sizeof c);
            kinds[count] = SG_NODE_CAMERA;
            lights[count] = -1;
            count++;
        }
    }
    bool camera = count > 0 && kinds[count - 1] == SG_NODE_CAMERA;
    bool ok = sg_skeletonize_grid(&m->grid, count, (const int(*)[3])voxels, kinds, lights, opt,
                                  out, stats, err);
    if (ok && stats)
        stats->camera_constrained = camera;
    free(voxels);
    free(kinds);
    free(lights);
    return ok;
}
