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

/* The medium in units of the full-size grid, scaled by 1/d. */
static void carve_atrium(SgMedium *m, int d)
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
}

/* A straight chain of nodes along z: its first node and how many. */
typedef struct Chain {
    uint32_t first, count;
} Chain;

/* The skeleton's layout in voxels of the scaled grid, st voxels a step. */
typedef struct Layout {
    int d, st, zlo, zhi, yc, yu;
} Layout;

static Chain chain_along_z(SgSkeleton *s, const SgGrid *g, const Layout *L, int x, int y)
{
    int a[3] = {x, y, L->zlo}, b[3] = {x, y, L->zhi};
    Chain c = {s->node_count, 0};
    branch(s, g, SG_CACHE_NONE, a, b, L->st);
    c.count = s->node_count - c.first;
    return c;
}

/* A branch across from node `from` (a spine's) to node `to` (an aisle's),
 * side 1 toward +x. */
static void link_across(SgSkeleton *s, const SgGrid *g, uint32_t from, uint32_t to, int side, int st)
{
    const int *vs = s->nodes[from].voxel, *va = s->nodes[to].voxel;
    int p0[3] = {vs[0] + (side ? st : -st), vs[1], vs[2]};
    int p1[3] = {va[0] + (side ? -st : st), va[1], vs[2]};
    uint32_t last = branch(s, g, from, p0, p1, st);
    add_edge(s, last, to);
}

/* One side's aisle spines, both storeys, with cross links to the centre
 * spines between the pillars (z = 40 + 40 k, between 30 and 50). */
static void aisle(SgSkeleton *s, const SgGrid *g, const Layout *L, int side, int x, Chain lo_spine, Chain up_spine)
{
    Chain lo = chain_along_z(s, g, L, x, L->yc), up = chain_along_z(s, g, L, x, L->yu);
    for (int z = 40; z < 480; z += 40) {
        uint32_t at = (uint32_t)((z / L->d - L->zlo) / L->st);
        if (at >= lo_spine.count || at >= lo.count || at >= up_spine.count || at >= up.count)
            continue;
        link_across(s, g, lo_spine.first + at, lo.first + at, side, L->st);
        link_across(s, g, up_spine.first + at, up.first + at, side, L->st);
    }
}

/* Four lights: at both ends of the upper spine, at both ends of the lower
 * one, as skeleton nodes just in front of the walls. */
static void place_lights(SgMedium *m, SgSkeleton *s, Chain lo, Chain up)
{
    uint32_t light_nodes[4] = {up.first, up.first + up.count - 1, lo.first + lo.count - 1, lo.first};
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
        l->position[2] += (k == 0 || k == 3 ? -1 : 1) * 0.5 * m->grid.voxel_size * 6;
        l->power = 1;
        l->radiance[0] = l->radiance[1] = l->radiance[2] = 10;
    }
}

/* The scene in units of the full-size grid, scaled by 1/d. Skeleton:
 * centre spines on both storeys, aisle spines, cross links between the
 * pillars, vertical links in the atrium; st voxels a step. */
static void build_scene(SgMedium *m, SgSkeleton *s, int d, int st)
{
    carve_atrium(m, d);
    memset(s, 0, sizeof *s);
    const SgGrid *g = &m->grid;
    const int NZ = 500 / d;
    Layout L = {d, st, 6 / d, NZ - 1 - 6 / d, 75 / d, 230 / d};
    int xc = 105 / d, aisle_x[2] = {25 / d, 185 / d};
    Chain lo = chain_along_z(s, g, &L, xc, L.yc), up = chain_along_z(s, g, &L, xc, L.yu);
    for (int side = 0; side < 2; side++)
        aisle(s, g, &L, side, aisle_x[side], lo, up);
    /* Vertical links in the atrium: spine to spine, five of them. */
    for (int t = 1; t <= 5; t++) {
        uint32_t from = lo.first + lo.count * (uint32_t)t / 6, to = up.first + up.count * (uint32_t)t / 6;
        const int *v0 = s->nodes[from].voxel, *v1 = s->nodes[to].voxel;
        int p0[3] = {v0[0], v0[1] + st, v0[2]}, p1[3] = {v1[0], v1[1] - st, v0[2]};
        uint32_t last = branch(s, g, from, p0, p1, st);
        add_edge(s, last, to);
    }
    place_lights(m, s, lo, up);
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

typedef struct BenchOptions {
    int d, threads;   /* d: 1 full size, 2 quick */
    double tolerance; /* 0: exact runs */
    int node_step;    /* voxels between skeleton nodes along a branch */
    const char *keep;
} BenchOptions;

static bool parse_options(int argc, char **argv, BenchOptions *o)
{
    *o = (BenchOptions){.d = 1, .threads = 2, .tolerance = 0, .node_step = 2, .keep = NULL};
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--quick"))
            o->d = 2;
        else if (!strcmp(argv[i], "--threads") && i + 1 < argc)
            o->threads = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--node-step") && i + 1 < argc)
            o->node_step = atoi(argv[++i]) > 0 ? atoi(argv[i]) : 2;
        else if (!strcmp(argv[i], "--run-tolerance") && i + 1 < argc)
            o->tolerance = atof(argv[++i]);
        else if (!strcmp(argv[i], "--keep") && i + 1 < argc)
            o->keep = argv[++i];
        else {
            fprintf(stderr, "usage: importance_bench [--quick] [--threads N] [--node-step N] [--run-tolerance T] "
                            "[--keep FILE]\n");
            return false;
        }
    }
    return true;
}

/* What one run measured. */
typedef struct Measures {
    SgImportanceStats st;
    double t_scene, cpu, rss_before, rss, t_open;
    double ns, sns;          /* lookup ns: random points, surface points */
    double found, sfound;    /* of those answered, in % */
} Measures;

/* Lookups of random points of the grid's box: ns each; *answered in %. */
static double time_random_lookups(const SgImportanceCache *c, const SgGrid *g, SgRng *rng, double *answered)
{
    enum { LOOKUPS = 4000000 };
    double *pts = malloc(LOOKUPS * 3 * sizeof *pts);
    for (int i = 0; i < LOOKUPS; i++)
        for (int a = 0; a < 3; a++)
            pts[3 * i + a] =
                g->origin[a] + sg_rng_float(rng) * g->voxel_size * (a == 0 ? g->nx : a == 1 ? g->ny : g->nz);
    uint64_t found = 0;
    double q[3];
    double t = sg_seconds();
    for (int i = 0; i < LOOKUPS; i++)
        found += sg_cache_importance_point(c, pts + 3 * i, (uint32_t)(i & 3), q);
    double ns = (sg_seconds() - t) / LOOKUPS * 1e9;
    free(pts);
    *answered = 100.0 * found / LOOKUPS;
    return ns;
}

/* Surface points: in a solid voxel, 0.05 voxel from a face it shares with
 * the medium (where render's hits are under conservative voxelization).
 * ns a lookup; *answered in %. */
static double time_surface_lookups(const SgImportanceCache *c, const SgGrid *g, SgRng *rng, double *answered)
{
    enum { SURFACE = 1000000 };
    double *spts = malloc(SURFACE * 3 * sizeof *spts);
    int count = 0;
    for (int tries = 0; count < SURFACE && tries < 100 * SURFACE; tries++) {
        int v[3] = {(int)(sg_rng_float(rng) * g->nx), (int)(sg_rng_float(rng) * g->ny),
                    (int)(sg_rng_float(rng) * g->nz)};
        if (sg_grid_get(g, v[0], v[1], v[2]))
            continue;
        int axis = tries % 3, side = (tries / 3) % 2 ? 1 : -1;
        int w[3] = {v[0], v[1], v[2]};
        w[axis] += side;
        if (!sg_grid_get(g, w[0], w[1], w[2]))
            continue;
        for (int a = 0; a < 3; a++) {
            double f = a == axis ? (side > 0 ? 0.95 : 0.05) : sg_rng_float(rng);
            spts[3 * count + a] = g->origin[a] + (v[a] + f) * g->voxel_size;
        }
        count++;
    }
    uint64_t found = 0;
    double q[3];
    double t = sg_seconds();
    for (int i = 0; i < count; i++)
        found += sg_cache_importance_point(c, spts + 3 * i, (uint32_t)(i & 3), q);
    double ns = count ? (sg_seconds() - t) / count * 1e9 : 0;
    free(spts);
    *answered = count ? 100.0 * found / count : 0;
    return ns;
}

static void print_report(const BenchOptions *o, const SgGrid *g, const SgSkeleton *s, const Measures *r)
{
    const SgImportanceStats *st = &r->st;
    int d = o->d;
    printf("load average at the end: %s\n", load_average());
    printf("grid %dx%dx%d, %llu medium voxels (%.1f%% labelled), %u nodes, %u edges, "
           "%u components, %u lights, %d threads; scene built in %.2f s\n",
           g->nx, g->ny, g->nz, (unsigned long long)st->medium_voxels,
           100.0 * st->labelled_voxels / (st->medium_voxels ? st->medium_voxels : 1), st->nodes, s->edge_count,
           st->components, st->lights, o->threads, r->t_scene);
    if (o->tolerance > 0)
        printf("run walk: chunked, tolerance %g of the distance\n", o->tolerance);
    else
        printf("run walk: exact (every node tested)\n");
    printf("\n| metric | value | target |\n|---|---|---|\n");
    printf("| %s | %.2f | %s |\n", "build seconds (total)", st->seconds_total, d == 1 ? "< 4" : "-");
    printf("| %s | %.2f | %s |\n", "&nbsp;&nbsp;CPU seconds (all threads)", r->cpu, "");
    printf("| %s | %.2f | %s |\n", "&nbsp;&nbsp;nearest-node labels (Dijkstra)", st->seconds_labels, "");
    printf("| %s | %.2f | %s |\n", "&nbsp;&nbsp;paths + importance points", st->seconds_points, "");
    printf("| %s | %.2f | %s |\n", "&nbsp;&nbsp;block table", st->seconds_table, "");
    printf("| %s | %.2f | %s |\n", "&nbsp;&nbsp;write", st->seconds_write, "");
    printf("| %s | %.1f | %s |\n", "cache MB", st->bytes / 1e6, d == 1 ? "< 32 (paper 130)" : "-");
    printf("| %s | %llu | %s |\n", "&nbsp;&nbsp;present 8^3 blocks", (unsigned long long)st->blocks, "");
    printf("| %s | %.2f | %s |\n", "&nbsp;&nbsp;palette entries per block",
           (double)st->palette_entries / (st->blocks ? st->blocks : 1), "");
    printf("| %s | %.1f | %s |\n", "peak RSS MB (scene alone)", r->rss_before, "");
    printf("| %s | %.1f | %s |\n", "peak RSS MB (with build)", r->rss, "");
    printf("| %s | %.3f | %s |\n", "open + validate seconds", r->t_open, "");
    printf("| %s | %.1f | %s |\n", "lookup ns (random point, light)", r->ns, "");
    printf("| %s | %.1f | %s |\n", "&nbsp;&nbsp;lookups answered %", r->found, "");
    printf("| %s | %.1f | %s |\n", "lookup ns (surface point, light)", r->sns, "");
    printf("| %s | %.1f | %s |\n", "&nbsp;&nbsp;lookups answered %", r->sfound, "");
    bool pass = d != 1 || (st->seconds_total < 4 && st->bytes < 32e6);
    printf("\ntargets: %s\n", d != 1 ? "(quick run: not checked)" : pass ? "met" : "NOT met");
}

int main(int argc, char **argv)
{
    BenchOptions o;
    if (!parse_options(argc, argv, &o))
        return 2;
    SgMedium m;
    SgSkeleton s;
    Measures r = {0};
    double t0 = sg_seconds();
    build_scene(&m, &s, o.d, o.node_step);
    r.t_scene = sg_seconds() - t0;
    r.rss_before = peak_rss_mb();

    char path[4096];
    if (o.keep)
        snprintf(path, sizeof path, "%s", o.keep);
    else
        snprintf(path, sizeof path, "/tmp/importance_bench_%ld.cache", (long)getpid());
    SgImportanceOptions opt = {.threads = o.threads, .quiet = true, .run_tolerance = o.tolerance};
    SgError err = {0};
    struct timespec c0, c1;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c0);
    if (!sg_importance_build(&m, &s, &opt, path, &r.st, &err)) {
        fprintf(stderr, "importance_bench: %s\n", err.message);
        return 1;
    }
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c1);
    r.cpu = (double)(c1.tv_sec - c0.tv_sec) + 1e-9 * (double)(c1.tv_nsec - c0.tv_nsec);
    r.rss = peak_rss_mb();

    /* Open (validate) and look up random medium positions. */
    double t1 = sg_seconds();
    SgImportanceCache *c = sg_cache_open(path, &err);
    r.t_open = sg_seconds() - t1;
    if (!c) {
        fprintf(stderr, "importance_bench: %s\n", err.message);
        return 1;
    }
    SgRng rng;
    sg_rng_seed(&rng, 42, 1);
    r.ns = time_random_lookups(c, &m.grid, &rng, &r.found);
    r.sns = time_surface_lookups(c, &m.grid, &rng, &r.sfound);
    print_report(&o, &m.grid, &s, &r);
    sg_cache_close(c);
    if (!o.keep)
        unlink(path);
    sg_skeleton_release(&s);
    sg_grid_release(&m.grid);
    free(m.lights);
    return 0;
}
