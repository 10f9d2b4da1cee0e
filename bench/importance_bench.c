/* Step 3 benchmark: the importance cache of a synthetic Sponza-sized scene
 * (the paper's 210x308x500 grid): a two-storey atrium with colonnades,
 * side aisles and a gallery, and a hand-made curvilinear skeleton of a few
 * thousand nodes (one every 2 voxels along its branches) with 4 lights.
 * Prints build seconds, peak RSS, cache bytes and lookup cost, with the
 * targets beside them.
 *   importance_bench [--quick] [--threads N] [--node-step N] [--run-tolerance T] [--keep FILE]
 * --node-step 1 gives a node on every voxel of a branch, as a thinning does. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include "../importance/importance.h"
#include "importance_cache.h"
#include "importance_cache_format.h"
#include "progress.h"
#include "rng.h"

typedef struct Builder {
    SgMedium *m;
    SgSkeleton *s;
    int scale_div; /* 1 full size, 2 quick */
} Builder;

static void box(SgMedium *m, int i0, int j0, int k0, int i1, int j1, int k1, uint8_t v)
{
    const SgGrid *g = &m->grid;
    if (i0 < 0) i0 = 0;
    if (j0 < 0) j0 = 0;
    if (k0 < 0) k0 = 0;
    if (i1 >= g->nx) i1 = g->nx - 1;
    if (j1 >= g->ny) j1 = g->ny - 1;
    if (k1 >= g->nz) k1 = g->nz - 1;
    for (int k = k0; k <= k1; k++)
        for (int j = j0; j <= j1; j++)
            memset(m->grid.voxels + sg_grid_index(g, i0, j, k), v, (size_t)(i1 - i0 + 1));
}

static uint32_t add_node(SgSkeleton *s, const SgGrid *g, const int v[3], int kind, int light)
{
    static uint32_t cap;
    if (s->node_count == cap) {
        cap = cap ? cap * 2 : 1024;
        s->nodes = realloc(s->nodes, cap * sizeof *s->nodes);
    }
    SgSkeletonNode *n = &s->nodes[s->node_count];
    memset(n, 0, sizeof *n);
    memcpy(n->voxel, v, sizeof n->voxel);
    double p[3];
    sg_grid_voxel_center(g, v[0], v[1], v[2], p);
    for (int a = 0; a < 3; a++)
        n->position[a] = (float)p[a];
    n->kind = (uint8_t)kind;
    n->light = light;
    n->radius = 1;
    return s->node_count++;
}

static void add_edge(SgSkeleton *s, uint32_t a, uint32_t b)
{
    static uint32_t cap;
    if (s->edge_count == cap) {
        cap = cap ? cap * 2 : 1024;
        s->edges = realloc(s->edges, cap * sizeof *s->edges);
    }
    s->edges[s->edge_count][0] = a;
    s->edges[s->edge_count][1] = b;
    s->edge_count++;
}

/* Nodes every `step` voxels on the segment a-b (inclusive), chained; the
 * first node joins `from` if given. Returns the last node. */
static uint32_t branch(SgSkeleton *s, const SgGrid *g, uint32_t from, const int a[3],
                       const int b[3], int step)
{
    int len = 0;
    for (int x = 0; x < 3; x++) {
        int d = abs(b[x] - a[x]);
        if (d > len)
            len = d;
    }
    int count = len / step + 1;
    uint32_t last = from;
    for (int t = 0; t < count; t++) {
        int v[3];
        for (int x = 0; x < 3; x++)
            v[x] = a[x] + (count > 1 ? (b[x] - a[x]) * t / (count - 1) : 0);
        if (!sg_grid_get(g, v[0], v[1], v[2])) {
            fprintf(stderr, "importance_bench: skeleton node (%d,%d,%d) is not in the medium\n",
                    v[0], v[1], v[2]);
            exit(1);
        }
        uint32_t n = add_node(s, g, v, SG_NODE_PLAIN, -1);
        if (last != SG_CACHE_NONE)
            add_edge(s, last, n);
        last = n;
    }
    return last;
}

/* The scene in units of the full-size grid, scaled by 1/d. */
static void build_scene(SgMedium *m, SgSkeleton *s, int d, int st)
{
    const int NX = 210 / d, NY = 308 / d, NZ = 500 / d;
    memset(m, 0, sizeof *m);
    double origin[3] = {-10.5, 0, -25};
    SgError err = {0};
    if (!sg_grid_init(&m->grid, NX, NY, NZ, origin, 0.1 * d, &err)) {
        fprintf(stderr, "importance_bench: %s\n", err.message);
        exit(1);
    }
#define S(v) ((v) / d)
    /* Air inside 2-voxel walls, floor and roof. */
    box(m, S(2), S(2), S(2), NX - 1 - S(2), NY - 1 - S(2), NZ - 1 - S(2), 1);
    /* Gallery floor at y 150..157 leaving an atrium x 60..150 open. */
    box(m, S(2), S(150), S(2), S(59), S(157), NZ - 1 - S(2), 0);
    box(m, S(151), S(150), S(2), NX - 1 - S(2), S(157), NZ - 1 - S(2), 0);
    /* Colonnades: 10x10 pillars at x 50..59 and 151..160, every 40 in z,
     * on both storeys; arches close the space above y 130 between them. */
    for (int z = 20; z + 10 < 500; z += 40)
        for (int side = 0; side < 2; side++) {
            int x0 = side ? 151 : 50;
            box(m, S(x0), S(2), S(z), S(x0 + 9), NY - 1, S(z + 9), 0);
        }
    box(m, S(50), S(130), S(2), S(59), S(149), NZ - 1, 0);
    box(m, S(151), S(130), S(2), S(160), S(149), NZ - 1, 0);
    /* Some furniture on the ground floor: benches. */
    for (int z = 60; z + 20 < 480; z += 80)
        box(m, S(80), S(2), S(z), S(130), S(12), S(z + 6), 0);
#undef S

    /* Skeleton: centre spines on both storeys, aisle spines, cross links
     * between the pillars, vertical links in the atrium. Step 2 voxels. */
    memset(s, 0, sizeof *s);
    const SgGrid *g = &m->grid;
    int zlo = 6 / d, zhi = NZ - 1 - 6 / d;
    int yc = 75 / d, yu = 230 / d, xc = 105 / d, xa = 25 / d, xb = 185 / d;
    int a0[3] = {xc, yc, zlo}, a1[3] = {xc, yc, zhi};
    uint32_t spine_lo_first = s->node_count;
    branch(s, g, SG_CACHE_NONE, a0, a1, st);
    uint32_t spine_lo_count = s->node_count - spine_lo_first;
    int u0[3] = {xc, yu, zlo}, u1[3] = {xc, yu, zhi};
    uint32_t spine_up_first = s->node_count;
    branch(s, g, SG_CACHE_NONE, u0, u1, st);
    uint32_t spine_up_count = s->node_count - spine_up_first;
    int aisle_x[2] = {xa, xb};
    for (int side = 0; side < 2; side++) {
        int b0[3] = {aisle_x[side], yc, zlo}, b1[3] = {aisle_x[side], yc, zhi};
        uint32_t first = s->node_count;
        branch(s, g, SG_CACHE_NONE, b0, b1, st);
        uint32_t count = s->node_count - first;
        int c0[3] = {aisle_x[side], yu, zlo}, c1[3] = {aisle_x[side], yu, zhi};
        uint32_t ufirst = s->node_count;
        branch(s, g, SG_CACHE_NONE, c0, c1, st);
        uint32_t ucount = s->node_count - ufirst;
        /* Cross links between pillars (z = 40 + 40 k, between 30 and 50). */
        for (int z = 40; z < 480; z += 40) {
            int zz = z / d;
            uint32_t lo_spine = spine_lo_first + (uint32_t)((zz - zlo) / st);
            uint32_t lo_aisle = first + (uint32_t)((zz - zlo) / st);
            uint32_t up_spine = spine_up_first + (uint32_t)((zz - zlo) / st);
            uint32_t up_aisle = ufirst + (uint32_t)((zz - zlo) / st);
            if (lo_spine >= spine_lo_first + spine_lo_count || lo_aisle >= first + count ||
                up_spine >= spine_up_first + spine_up_count || up_aisle >= ufirst + ucount)
                continue;
            const int *vs = s->nodes[lo_spine].voxel, *va = s->nodes[lo_aisle].voxel;
            int p0[3] = {vs[0] + (side ? st : -st), vs[1], vs[2]};
            int p1[3] = {va[0] + (side ? -st : st), va[1], vs[2]};
            uint32_t last = branch(s, g, lo_spine, p0, p1, st);
            add_edge(s, last, lo_aisle);
            const int *ws = s->nodes[up_spine].voxel, *wa = s->nodes[up_aisle].voxel;
            int q0[3] = {ws[0] + (side ? st : -st), ws[1], ws[2]};
            int q1[3] = {wa[0] + (side ? -st : st), wa[1], ws[2]};
            last = branch(s, g, up_spine, q0, q1, st);
            add_edge(s, last, up_aisle);
        }
    }
    /* Vertical links in the atrium: spine to spine, five of them. */
    for (int t = 1; t <= 5; t++) {
        uint32_t lo = spine_lo_first + spine_lo_count * (uint32_t)t / 6;
        uint32_t up = spine_up_first + spine_up_count * (uint32_t)t / 6;
        const int *v0 = s->nodes[lo].voxel, *v1 = s->nodes[up].voxel;
        int p0[3] = {v0[0], v0[1] + st, v0[2]}, p1[3] = {v1[0], v1[1] - st, v0[2]};
        uint32_t last = branch(s, g, lo, p0, p1, st);
        add_edge(s, last, up);
    }
    /* Four lights: at both ends of the upper spine, at one end of each lower
     * aisle... as skeleton nodes just in front of the walls. */
    uint32_t light_nodes[4] = {spine_up_first, spine_up_first + spine_up_count - 1,
                               spine_lo_first + spine_lo_count - 1, spine_lo_first};
    m->lights = calloc(4, sizeof *m->lights);
    m->light_count = 4;
    for (int k = 0; k < 4; k++) {
        SgSkeletonNode *n = &s->nodes[light_nodes[k]];
        n->kind = SG_NODE_LIGHT;
        n->light = k;
        SgMediumLight *l = &m->lights[k];
        for (int a = 0; a < 3; a++) {
            l->position[a] = n->position[a];
            l->seed[a] = n->voxel[a];
        }
        l->position[2] += (k == 0 || k == 3 ? -1 : 1) * 0.5 * g->voxel_size * 6;
        l->power = 1;
        l->radiance[0] = l->radiance[1] = l->radiance[2] = 10;
    }
    m->geometry_hash = 0x5090a5090a5ULL;
    m->resolution = NZ;
}

/* Other work on the machine skews the seconds: say how busy it was. */
static const char *load_average(void)
{
    static char text[128] = "unknown\n";
    FILE *f = fopen("/proc/loadavg", "r");
    if (f) {
        if (!fgets(text, sizeof text, f))
            snprintf(text, sizeof text, "unknown\n");
        fclose(f);
    }
    return text;
}

static double peak_rss_mb(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return ru.ru_maxrss / 1024.0;
}

int main(int argc, char **argv)
{
    int d = 1, threads = 2;
    double tolerance = 0; /* exact runs */
    int node_step = 2; /* voxels between skeleton nodes along a branch */
    const char *keep = NULL;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--quick"))
            d = 2;
        else if (!strcmp(argv[i], "--threads") && i + 1 < argc)
            threads = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--node-step") && i + 1 < argc)
            node_step = atoi(argv[++i]) > 0 ? atoi(argv[i]) : 2;
        else if (!strcmp(argv[i], "--run-tolerance") && i + 1 < argc)
            tolerance = atof(argv[++i]);
        else if (!strcmp(argv[i], "--keep") && i + 1 < argc)
            keep = argv[++i];
        else {
            fprintf(stderr, "usage: importance_bench [--quick] [--threads N] [--node-step N] [--run-tolerance T] "
                            "[--keep FILE]\n");
            return 2;
        }
    }
    SgMedium m;
    SgSkeleton s;
    double t0 = sg_seconds();
    build_scene(&m, &s, d, node_step);
    double t_scene = sg_seconds() - t0;
    double rss_before = peak_rss_mb();

    char path[4096];
    if (keep)
        snprintf(path, sizeof path, "%s", keep);
    else
        snprintf(path, sizeof path, "/tmp/importance_bench_%ld.cache", (long)getpid());
    SgImportanceOptions opt = {.threads = threads, .quiet = true, .run_tolerance = tolerance};
    SgImportanceStats st;
    SgError err = {0};
    struct timespec c0, c1;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c0);
    if (!sg_importance_build(&m, &s, &opt, path, &st, &err)) {
        fprintf(stderr, "importance_bench: %s\n", err.message);
        return 1;
    }
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c1);
    double cpu = (double)(c1.tv_sec - c0.tv_sec) + 1e-9 * (double)(c1.tv_nsec - c0.tv_nsec);
    double rss = peak_rss_mb();

    /* Open (validate) and look up random medium positions. */
    double t1 = sg_seconds();
    SgImportanceCache *c = sg_cache_open(path, &err);
    double t_open = sg_seconds() - t1;
    if (!c) {
        fprintf(stderr, "importance_bench: %s\n", err.message);
        return 1;
    }
    SgRng rng;
    sg_rng_seed(&rng, 42, 1);
    const SgGrid *g = &m.grid;
    enum { LOOKUPS = 4000000 };
    double *pts = malloc(LOOKUPS * 3 * sizeof *pts);
    for (int i = 0; i < LOOKUPS; i++)
        for (int a = 0; a < 3; a++)
            pts[3 * i + a] = g->origin[a] + sg_rng_float(&rng) * g->voxel_size *
                                                (a == 0 ? g->nx : a == 1 ? g->ny : g->nz);
    uint64_t found = 0;
    double q[3];
    double t2 = sg_seconds();
    for (int i = 0; i < LOOKUPS; i++)
        found += sg_cache_importance_point(c, pts + 3 * i, (uint32_t)(i & 3), q);
    double ns = (sg_seconds() - t2) / LOOKUPS * 1e9;

    /* Surface points: in a solid voxel, 0.05 voxel from a face it shares
     * with the medium (where render's hits are under conservative
     * voxelization). */
    enum { SURFACE = 1000000 };
    double *spts = malloc(SURFACE * 3 * sizeof *spts);
    int ns_count = 0;
    for (int tries = 0; ns_count < SURFACE && tries < 100 * SURFACE; tries++) {
        int v[3] = {(int)(sg_rng_float(&rng) * g->nx), (int)(sg_rng_float(&rng) * g->ny),
                    (int)(sg_rng_float(&rng) * g->nz)};
        if (sg_grid_get(g, v[0], v[1], v[2]))
            continue;
        int axis = tries % 3, side = (tries / 3) % 2 ? 1 : -1;
        int w[3] = {v[0], v[1], v[2]};
        w[axis] += side;
        if (!sg_grid_get(g, w[0], w[1], w[2]))
            continue;
        for (int a = 0; a < 3; a++) {
            double f = a == axis ? (side > 0 ? 0.95 : 0.05) : sg_rng_float(&rng);
            spts[3 * ns_count + a] = g->origin[a] + (v[a] + f) * g->voxel_size;
        }
        ns_count++;
    }
    uint64_t sfound = 0;
    double t3 = sg_seconds();
    for (int i = 0; i < ns_count; i++)
        sfound += sg_cache_importance_point(c, spts + 3 * i, (uint32_t)(i & 3), q);
    double sns = ns_count ? (sg_seconds() - t3) / ns_count * 1e9 : 0;
    free(spts);

    printf("load average at the end: %s\n", load_average());
    printf("grid %dx%dx%d, %llu medium voxels (%.1f%% labelled), %u nodes, %u edges, "
           "%u components, %u lights, %d threads; scene built in %.2f s\n",
           g->nx, g->ny, g->nz, (unsigned long long)st.medium_voxels,
           100.0 * st.labelled_voxels / (st.medium_voxels ? st.medium_voxels : 1), st.nodes,
           s.edge_count, st.components, st.lights, threads, t_scene);
    if (tolerance > 0)
        printf("run walk: chunked, tolerance %g of the distance\n", tolerance);
    else
        printf("run walk: exact (every node tested)\n");
    printf("\n| metric | value | target |\n|---|---|---|\n");
    printf("| %s | %.2f | %s |\n", "build seconds (total)", st.seconds_total,
           d == 1 ? "< 4" : "-");
    printf("| %s | %.2f | %s |\n", "&nbsp;&nbsp;CPU seconds (all threads)", cpu, "");
    printf("| %s | %.2f | %s |\n", "&nbsp;&nbsp;nearest-node labels (Dijkstra)", st.seconds_labels, "");
    printf("| %s | %.2f | %s |\n", "&nbsp;&nbsp;paths + importance points", st.seconds_points, "");
    printf("| %s | %.2f | %s |\n", "&nbsp;&nbsp;block table", st.seconds_table, "");
    printf("| %s | %.2f | %s |\n", "&nbsp;&nbsp;write", st.seconds_write, "");
    printf("| %s | %.1f | %s |\n", "cache MB", st.bytes / 1e6, d == 1 ? "< 32 (paper 130)" : "-");
    printf("| %s | %llu | %s |\n", "&nbsp;&nbsp;present 8^3 blocks", (unsigned long long)st.blocks, "");
    printf("| %s | %.2f | %s |\n", "&nbsp;&nbsp;palette entries per block",
           (double)st.palette_entries / (st.blocks ? st.blocks : 1), "");
    printf("| %s | %.1f | %s |\n", "peak RSS MB (scene alone)", rss_before, "");
    printf("| %s | %.1f | %s |\n", "peak RSS MB (with build)", rss, "");
    printf("| %s | %.3f | %s |\n", "open + validate seconds", t_open, "");
    printf("| %s | %.1f | %s |\n", "lookup ns (random point, light)", ns, "");
    printf("| %s | %.1f | %s |\n", "&nbsp;&nbsp;lookups answered %", 100.0 * found / LOOKUPS, "");
    printf("| %s | %.1f | %s |\n", "lookup ns (surface point, light)", sns, "");
    printf("| %s | %.1f | %s |\n", "&nbsp;&nbsp;lookups answered %", ns_count ? 100.0 * sfound / ns_count : 0, "");
    bool pass = d != 1 || (st.seconds_total < 4 && st.bytes < 32e6);
    printf("\ntargets: %s\n", d != 1 ? "(quick run: not checked)" : pass ? "met" : "NOT met");
    sg_cache_close(c);
    free(pts);
    if (!keep)
        unlink(path);
    sg_skeleton_release(&s);
    sg_grid_release(&m.grid);
    free(m.lights);
    return 0;
}
