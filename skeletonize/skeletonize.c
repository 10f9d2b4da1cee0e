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

    uint16_t *dist8 = NULL, *open8 = NULL;
    SgComplex cx = {0};
    SgCollapseResult col = {0};
    Anchor *anchors = NULL;
    uint32_t *anchor_cells = NULL, *vertex_cells = NULL, *parent = NULL;
    size_t anchor_count = 0;
    bool ok = false;

    SgProgress progress;
    sg_progress_begin(&progress, "skeleton: distance", 0);
    if (!opt.progress)
        progress.enabled = false;
    if (!sg_distance_opening_lattice(g, opt.threads, &dist8, &open8, err))
        goto done;
    stats.seconds_distance = sg_seconds() - t0;
    /* dist8 and open8 come in lattice layout (voxel (i,j,k) at vertex
     * (i,j,k)): the collapse reads the voxels around a cell without
     * dividing indices */
    if (!sg_complex_build(&cx, g, opt.threads, err))
        goto done;

    anchors = calloc(constraint_count ? constraint_count : 1, sizeof *anchors);
    anchor_cells = calloc(constraint_count ? constraint_count : 1, sizeof *anchor_cells);
    if (!anchors || !anchor_cells) {
        sg_fail(err, "skeleton: out of memory");
        goto done;
    }
    for (uint32_t i = 0; i < constraint_count; i++) {
        const int *p = voxels[i];
        if (!sg_grid_inside(g, p[0], p[1], p[2]) || !g->voxels[grid_index3(g, p)])
            continue; /* not in the medium: nothing to pass through */
        anchors[anchor_count].vertex_cell = choose_anchor(&cx, g, dist8, p, anchors, anchor_count);
        anchors[anchor_count].constraint = i;
        anchor_cells[anchor_count] = anchors[anchor_count].vertex_cell;
        anchor_count++;
    }
    stats.constraints = (uint32_t)anchor_count;

    double t1 = sg_seconds();
    sg_progress_end(&progress);
    sg_progress_begin(&progress, "skeleton: collapse", 0);
    if (!opt.progress)
        progress.enabled = false;
    if (!sg_collapse(&cx, anchor_cells, anchor_count, dist8, open8, opt.filter_scale, opt.threads,
                     opt.parallel_grain, opt.collapse_slab_planes, opt.collapse_schedule_seed,
                     &progress,
                     &col, err))
        goto done;
    sg_progress_end(&progress);
    stats.seconds_collapse = sg_seconds() - t1;
    stats.steps = col.steps;
    stats.cavities_broken = col.cavities_broken;
    stats.forced_breaks = col.forced_breaks;

    /* ---- the graph ---- */
    size_t vertex_count = 0, edge_count = 0;
    for (size_t v = 0; v < cx.vertex_count; v++) {
        unsigned bits = cx.cells[v];
        if (!bits)
            continue;
        if (bits & ~0x17u) {
            sg_fail(err, "skeleton: internal error: 2- or 3-cells left after the collapse");
            goto done;
        }
        vertex_count += bits & 1;
        edge_count += (bits >> 1 & 1) + (bits >> 2 & 1) + (bits >> 4 & 1);
    }
    if (vertex_count >= UINT32_MAX || edge_count >= UINT32_MAX) {
        sg_fail(err, "skeleton: graph too large");
        goto done;
    }
    vertex_cells = malloc((vertex_count ? vertex_count : 1) * sizeof *vertex_cells);
    out->nodes = calloc(vertex_count ? vertex_count : 1, sizeof *out->nodes);
    out->edges = calloc(edge_count ? edge_count : 1, sizeof *out->edges);
    parent = malloc((vertex_count ? vertex_count : 1) * sizeof *parent);
    if (!vertex_cells || !out->nodes || !out->edges || !parent) {
        sg_fail(err, "skeleton: out of memory for a graph of %zu nodes", vertex_count);
        goto done;
    }
    size_t nv = 0, ne = 0;
    for (size_t v = 0; v < cx.vertex_count; v++)
        if (cx.cells[v] & 1)
            vertex_cells[nv++] = (uint32_t)(v * 8);
    for (size_t i = 0; i < nv; i++) {
        SgSkeletonNode *node = &out->nodes[i];
        int c[3];
        sg_complex_coords(&cx, vertex_cells[i] >> 3, c);
        int best[3] = {-1, -1, -1};
        uint16_t best_d = 0;
        for (unsigned d = 0; d < 8; d++) {
            int r[3] = {c[0] - (int)(d & 1), c[1] - (int)(d >> 1 & 1), c[2] - (int)(d >> 2)};
            if (!sg_grid_inside(g, r[0], r[1], r[2]))
                continue;
            uint16_t dd = dist8[lattice_index3(&cx, r)];
            if (dd > best_d)
                best_d = dd, memcpy(best, r, sizeof best);
        }
        node->kind = SG_NODE_PLAIN;
        node->light = -1;
        for (size_t a = 0; a < anchor_count; a++)
            if (anchors[a].vertex_cell == vertex_cells[i]) {
                uint32_t k = anchors[a].constraint;
                memcpy(best, voxels[k], sizeof best);
                node->kind = kinds ? kinds[k] : SG_NODE_LIGHT;
                node->light = lights ? lights[k] : -1;
                break;
            }
        memcpy(node->voxel, best, sizeof best);
        double w[3];
        sg_grid_voxel_center(g, best[0], best[1], best[2], w);
        for (int a = 0; a < 3; a++)
            node->position[a] = (float)w[a];
        node->radius = (float)(open8[lattice_index3(&cx, best)] / 8.0 * g->voxel_size);
        node->lifespan = -1; /* set from its edges below */
    }
    for (size_t v = 0; v < cx.vertex_count; v++) {
        unsigned bits = cx.cells[v];
        for (int a = 0; a < 3; a++) {
            unsigned m = 1u << a;
            if (!(bits >> m & 1))
                continue;
            uint32_t cell = (uint32_t)(v * 8 + m);
            size_t i0 = find_u32(vertex_cells, nv, (uint32_t)(v * 8));
            size_t i1 = find_u32(vertex_cells, nv, (uint32_t)((v + cx.stride[a]) * 8));
            if (i0 == SIZE_MAX || i1 == SIZE_MAX) {
                sg_fail(err, "skeleton: internal error: an edge without its vertices");
                goto done;
            }
            out->edges[ne][0] = (uint32_t)i0;
            out->edges[ne][1] = (uint32_t)i1;
            ne++;
            /* lifespan: steps between losing its last square and joining the skeleton */
            size_t lo = 0, hi = col.edge_count;
            while (lo < hi) {
                size_t mid = (lo + hi) / 2;
                if (col.edges[mid].cell < cell)
                    lo = mid + 1;
                else
                    hi = mid;
            }
            int life = (int)col.steps;
            if (lo < col.edge_count && col.edges[lo].cell == cell) {
                int32_t until = col.edges[lo].kept >= 0 ? col.edges[lo].kept : (int32_t)col.steps;
                life = until - col.edges[lo].birth;
            }
            if (life > out->nodes[i0].lifespan) out->nodes[i0].lifespan = life;
            if (life > out->nodes[i1].lifespan) out->nodes[i1].lifespan = life;
        }
    }
    out->node_count = (uint32_t)nv;
    out->edge_count = (uint32_t)ne;

    /* components, loops, centredness */
    for (size_t i = 0; i < nv; i++)
        parent[i] = (uint32_t)i;
    uint32_t components = (uint32_t)nv;
    for (size_t e = 0; e < ne; e++) {
        if (sg_set_union(parent, out->edges[e][0], out->edges[e][1]))
            components--;
    }
    double ratio_sum = 0;
    for (size_t i = 0; i < nv; i++) {
        if (out->nodes[i].lifespan < 0) /* no edge: it lasted the whole collapse */
            out->nodes[i].lifespan = (int)col.steps;
        const int *p = out->nodes[i].voxel;
        uint16_t here = dist8[lattice_index3(&cx, p)], around = here;
        for (int dz = -1; dz <= 1; dz++)
            for (int dy = -1; dy <= 1; dy++)
                for (int dx = -1; dx <= 1; dx++) {
                    int q[3] = {p[0] + dx, p[1] + dy, p[2] + dz};
                    if (sg_grid_inside(g, q[0], q[1], q[2]) && dist8[lattice_index3(&cx, q)] > around)
                        around = dist8[lattice_index3(&cx, q)];
                }
        ratio_sum += around ? (double)here / around : 1.0;
    }
    stats.nodes = (uint32_t)nv;
    stats.edges = (uint32_t)ne;
    stats.components = components;
    stats.loops = (int64_t)ne - (int64_t)nv + components;
    stats.mean_centredness = nv ? ratio_sum / (double)nv : 0;
    ok = true;
done:
    sg_progress_end(&progress);
    free(dist8);
    free(open8);
    sg_complex_release(&cx);
    sg_collapse_result_release(&col);
    free(anchors);
    free(anchor_cells);
    free(vertex_cells);
    free(parent);
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
