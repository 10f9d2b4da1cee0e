/* Step 2, the skeleton: topology kept on every test shape (components and
 * loops of the graph = b0 and b1 of the medium, cavities counted), light
 * nodes present, nodes in the medium and centred, stability across
 * resolutions and wall noise, distance and opening against brute force. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "support_shapes.h"
#include "../skeletonize/skeletonize.h"
#include "support_topology.h"

static SgSkeletonOptions quiet_options(int threads)
{
    SgSkeletonOptions o;
    sg_skeleton_options_default(&o);
    o.progress = false;
    o.threads = threads;
    /* the collapse on the threads, in slabs of two planes (the thinnest:
     * most work crosses a slab's border), so that small shapes cover the
     * blocked and parallel paths; deterministic_across_threads and
     * blocked_collapse_matches_one_sweep compare them with the sequential
     * sweep */
    o.parallel_grain = 1;
    o.collapse_slab_planes = 2;
    return o;
}

static uint32_t *node_degrees(const SgSkeleton *s)
{
    uint32_t *deg = calloc(s->node_count + 1, sizeof *deg);
    cr_assert_not_null(deg);
    for (uint32_t e = 0; e < s->edge_count; e++) {
        deg[s->edges[e][0]]++;
        deg[s->edges[e][1]]++;
    }
    return deg;
}

/* Leaves that are not constraints: the hairs a filter must prevent. */
static uint32_t free_leaves(const SgSkeleton *s)
{
    uint32_t *deg = node_degrees(s), n = 0;
    for (uint32_t i = 0; i < s->node_count; i++)
        n += deg[i] == 1 && s->nodes[i].kind == SG_NODE_PLAIN;
    free(deg);
    return n;
}

/* Everything the contract promises about a skeleton of medium m. */
static void check_skeleton(const SgMedium *m, const SgSkeleton *s, const SgSkeletonStats *st,
                           const char *name)
{
    const SgGrid *g = &m->grid;
    SgBetti air, graph;
    SgError err = {0};
    cr_assert(sg_voxel_betti(g, &air, &err), "%s", err.message);
    cr_assert(sg_graph_betti(s, &graph, &err), "%s", err.message);
    cr_expect_eq(graph.b0, air.b0, "%s: graph has %ld components, medium %ld", name,
                 (long)graph.b0, (long)air.b0);
    cr_expect_eq(graph.b1, air.b1, "%s: graph has %ld loops, medium %ld tunnels", name,
                 (long)graph.b1, (long)air.b1);
    cr_expect_eq((int64_t)st->cavities_broken, air.b2, "%s: %u cavities broken, medium b2 %ld",
                 name, st->cavities_broken, (long)air.b2);
    cr_expect_eq(st->forced_breaks, 0, "%s: forced breaks", name);
    cr_expect_eq(st->components, (uint32_t)graph.b0, "%s: stats components", name);
    cr_expect_eq(st->loops, graph.b1, "%s: stats loops", name);
    cr_expect_eq(st->nodes, s->node_count);
    cr_expect_eq(st->edges, s->edge_count);

    /* every node in the medium, at its voxel's centre; edges join 26-neighbours */
    for (uint32_t i = 0; i < s->node_count; i++) {
        const SgSkeletonNode *n = &s->nodes[i];
        cr_assert(sg_grid_get(g, n->voxel[0], n->voxel[1], n->voxel[2]),
                  "%s: node %u at voxel (%d,%d,%d) is not in the medium", name, i, n->voxel[0],
                  n->voxel[1], n->voxel[2]);
        double c[3];
        sg_grid_voxel_center(g, n->voxel[0], n->voxel[1], n->voxel[2], c);
        for (int a = 0; a < 3; a++)
            cr_expect_float_eq(n->position[a], c[a], 1e-4, "%s: node %u position", name, i);
        cr_expect(n->radius > 0, "%s: node %u has opening radius %g", name, i, n->radius);
        cr_expect(n->lifespan >= 0);
        if (n->kind == SG_NODE_LIGHT)
            cr_expect(n->light >= 0 && (uint32_t)n->light < m->light_count);
        else
            cr_expect_eq(n->light, -1);
    }
    for (uint32_t e = 0; e < s->edge_count; e++) {
        const SgSkeletonNode *a = &s->nodes[s->edges[e][0]], *b = &s->nodes[s->edges[e][1]];
        cr_expect_neq(s->edges[e][0], s->edges[e][1], "%s: self-loop edge", name);
        for (int k = 0; k < 3; k++)
            cr_expect(abs(a->voxel[k] - b->voxel[k]) <= 2,
                      "%s: edge %u joins far-apart voxels", name, e);
    }
    /* every light with a seed in the medium is a node standing on its seed */
    for (uint32_t l = 0; l < m->light_count; l++) {
        const int *seed = m->lights[l].seed;
        if (!sg_grid_get(g, seed[0], seed[1], seed[2]))
            continue;
        int found = 0;
        for (uint32_t i = 0; i < s->node_count; i++)
            if (s->nodes[i].kind == SG_NODE_LIGHT && s->nodes[i].light == (int)l) {
                found++;
                cr_expect(!memcmp(s->nodes[i].voxel, seed, sizeof(int[3])),
                          "%s: light %u node is not on its seed", name, l);
            }
        cr_expect_eq(found, 1, "%s: light %u has %d nodes", name, l, found);
    }
    cr_log_info("%s %dx%dx%d: %u nodes, %u edges, b0 %ld b1 %ld b2 %ld, %u cavities broken, "
                "%u steps, centredness %.3f",
                name, g->nx, g->ny, g->nz, s->node_count, s->edge_count, (long)air.b0,
                (long)air.b1, (long)air.b2, st->cavities_broken, st->steps, st->mean_centredness);
}

/* m skeletonized under o, which must succeed, and checked (check_skeleton). */
static void skeletonize_checked(const SgMedium *m, const SgSkeletonOptions *o, SgSkeleton *s,
                                SgSkeletonStats *st, const char *name)
{
    SgError err = {0};
    cr_assert(sg_skeletonize(m, o, s, st, &err), "%s: %s", name, err.message);
    check_skeleton(m, s, st, name);
}

static void run_shape(SgShape shape, int scale, double min_centredness)
{
    SgMedium m;
    cr_assert(sg_shape_medium(shape, scale, &m));
    const SgShapeInfo *info = sg_shape_info(shape);
    SgBetti air;
    SgError err = {0};
    cr_assert(sg_voxel_betti(&m.grid, &air, &err));
    /* the Betti helper itself against the shape's known topology */
    cr_expect_eq(air.b0, info->b0, "%s: b0 %ld, expected %d", info->name, (long)air.b0, info->b0);
    cr_expect_eq(air.b1, info->b1, "%s: b1 %ld, expected %d", info->name, (long)air.b1, info->b1);
    cr_expect_eq(air.b2, info->b2, "%s: b2 %ld, expected %d", info->name, (long)air.b2, info->b2);
    SgSkeletonOptions o = quiet_options(2);
    SgSkeleton s;
    SgSkeletonStats st;
    skeletonize_checked(&m, &o, &s, &st, info->name);
    cr_expect(st.mean_centredness >= min_centredness, "%s at scale %d: centredness %.3f < %.2f",
              info->name, scale, st.mean_centredness, min_centredness);
    sg_skeleton_release(&s);
    sg_shape_medium_free(&m);
}

/* Every shape at scale 1 and at a finer scale: test name, shape, the finer
 * scale, the least mean centredness its skeleton must reach. */
#define SHAPE_CASES(X)                                                                             \
    X(bar_4x4, SG_SHAPE_BAR, 3, 0.95)                                                              \
    X(cube, SG_SHAPE_CUBE, 3, 0.5)                                                                 \
    X(torus, SG_SHAPE_TORUS, 2, 0.9)                                                               \
    X(room_one_pillar, SG_SHAPE_PILLAR_ROOM, 2, 0.85)                                              \
    X(room_three_pillars, SG_SHAPE_THREE_PILLARS, 2, 0.85)                                         \
    X(ring_corridor, SG_SHAPE_RING, 2, 0.9)                                                        \
    X(room_floating_lamp, SG_SHAPE_LAMP_ROOM, 2, 0.8)                                              \
    X(u_corridor, SG_SHAPE_U, 2, 0.9)                                                              \
    X(hollow_sphere, SG_SHAPE_SHELL, 2, 0.8)                                                       \
    X(two_rooms, SG_SHAPE_TWO_ROOMS, 2, 0.5)                                                       \
    X(room_floating_ring_cavity_keeps_its_loop, SG_SHAPE_RING_LAMP, 2, 0.8)

#define SHAPE_TEST(name, shape, fine_scale, min_centredness)                                       \
    Test(skeleton, name)                                                                           \
    {                                                                                              \
        run_shape(shape, 1, min_centredness);                                                      \
        run_shape(shape, fine_scale, min_centredness);                                             \
    }
SHAPE_CASES(SHAPE_TEST)

Test(skeleton, furnished_room_small)
{
    SgMedium m;
    cr_assert(sg_shape_furnished_room(40, 60, 80, &m));
    SgSkeletonOptions o = quiet_options(2);
    SgSkeleton s;
    SgSkeletonStats st;
    skeletonize_checked(&m, &o, &s, &st, "furnished room");
    sg_skeleton_release(&s);
    sg_shape_medium_free(&m);
}

/* The same scene at two resolutions: same loops, components, cavities. */
Test(skeleton, stable_across_resolutions)
{
    SgShape shapes[] = {SG_SHAPE_THREE_PILLARS, SG_SHAPE_RING_LAMP, SG_SHAPE_TWO_ROOMS, SG_SHAPE_U};
    for (size_t i = 0; i < sizeof shapes / sizeof shapes[0]; i++) {
        SgSkeletonStats st[2];
        for (int r = 0; r < 2; r++) {
            SgMedium m;
            cr_assert(sg_shape_medium(shapes[i], r == 0 ? 2 : 3, &m));
            SgSkeletonOptions o = quiet_options(2);
            SgSkeleton s;
            SgError err = {0};
            cr_assert(sg_skeletonize(&m, &o, &s, &st[r], &err), "%s", err.message);
            sg_skeleton_release(&s);
            sg_shape_medium_free(&m);
        }
        const char *name = sg_shape_info(shapes[i])->name;
        cr_expect_eq(st[0].loops, st[1].loops, "%s: loops %ld vs %ld", name, (long)st[0].loops,
                     (long)st[1].loops);
        cr_expect_eq(st[0].components, st[1].components, "%s: components", name);
        cr_expect_eq(st[0].cavities_broken, st[1].cavities_broken, "%s: cavities", name);
    }
}

/* Noise on the walls must not grow hairs: the filter keeps the number of
 * free leaves close to that of the clean skeleton. */
Test(skeleton, no_hairs_on_noisy_walls)
{
    SgShape shapes[] = {SG_SHAPE_PILLAR_ROOM, SG_SHAPE_U, SG_SHAPE_RING};
    for (size_t i = 0; i < sizeof shapes / sizeof shapes[0]; i++) {
        uint32_t leaves[2];
        for (int noisy = 0; noisy < 2; noisy++) {
            SgMedium m;
            cr_assert(sg_shape_medium(shapes[i], 3, &m));
            if (noisy)
                sg_shape_roughen(&m, 0.25, 12345 + i);
            SgSkeletonOptions o = quiet_options(2);
            SgSkeleton s;
            SgSkeletonStats st;
            skeletonize_checked(&m, &o, &s, &st, noisy ? "noisy" : "clean");
            leaves[noisy] = free_leaves(&s);
            sg_skeleton_release(&s);
            sg_shape_medium_free(&m);
        }
        cr_log_info("%s: free leaves clean %u, noisy %u", sg_shape_info(shapes[i])->name,
                    leaves[0], leaves[1]);
        cr_expect(leaves[1] <= leaves[0] + 2, "%s: %u free leaves on noisy walls, %u on clean",
                  sg_shape_info(shapes[i])->name, leaves[1], leaves[0]);
    }
}

/* The same without the filter (every isolated edge kept at once) does
 * grow hairs: the previous test can fail. */
Test(skeleton, unfiltered_skeleton_is_hairy)
{
    SgMedium m;
    cr_assert(sg_shape_medium(SG_SHAPE_PILLAR_ROOM, 3, &m));
    sg_shape_roughen(&m, 0.25, 12345);
    uint32_t leaves[2];
    for (int filtered = 0; filtered < 2; filtered++) {
        SgSkeletonOptions o = quiet_options(2);
        o.filter_scale = filtered ? 1.0 : 0.0;
        SgSkeleton s;
        SgSkeletonStats st;
        skeletonize_checked(&m, &o, &s, &st, filtered ? "filtered" : "unfiltered");
        leaves[filtered] = free_leaves(&s);
        sg_skeleton_release(&s);
    }
    cr_log_info("noisy pillar room: free leaves unfiltered %u, filtered %u", leaves[0], leaves[1]);
    cr_expect(leaves[0] >= leaves[1] + 5, "unfiltered %u leaves, filtered %u", leaves[0],
              leaves[1]);
    sg_shape_medium_free(&m);
}

/* The lifespan rule on edges due within DUE_MOST steps (held until their
 * step) and on edges due later (tested every step) answers alike: with
 * scales so large that no edge lives long enough, both keep none and give
 * the same skeleton, smaller than a weakly filtered one. */
Test(skeleton, lifespan_rule_far_and_near_agree)
{
    SgMedium m;
    cr_assert(sg_shape_medium(SG_SHAPE_PILLAR_ROOM, 3, &m));
    sg_shape_roughen(&m, 0.25, 4242);
    /* a hairy skeleton; near (edges due within open8 x 250 steps); far */
    const double scales[3] = {0.25, 2000.0, 100000.0};
    SgSkeleton s[3];
    for (int i = 0; i < 3; i++) {
        SgSkeletonOptions o = quiet_options(2);
        o.filter_scale = scales[i];
        SgSkeletonStats st;
        skeletonize_checked(&m, &o, &s[i], &st, "scaled filter");
    }
    cr_assert_lt(s[1].node_count, s[0].node_count);
    cr_assert_eq(s[1].node_count, s[2].node_count);
    cr_assert_eq(s[1].edge_count, s[2].edge_count);
    cr_assert(!memcmp(s[1].nodes, s[2].nodes, s[1].node_count * sizeof *s[1].nodes));
    cr_assert(!memcmp(s[1].edges, s[2].edges, s[1].edge_count * sizeof *s[1].edges));
    for (int i = 0; i < 3; i++)
        sg_skeleton_release(&s[i]);
    sg_shape_medium_free(&m);
}

/* Results do not depend on the thread count (distance transform,
 * opening, complex build and the collapse's slabs run on threads), on
 * shapes with loops, cavities and constraints. */
Test(skeleton, deterministic_across_threads)
{
    SgShape shapes[] = {SG_SHAPE_RING_LAMP, SG_SHAPE_THREE_PILLARS, SG_SHAPE_SHELL, SG_SHAPE_TWO_ROOMS};
    for (size_t i = 0; i < sizeof shapes / sizeof shapes[0]; i++) {
        SgSkeleton s[2];
        SgSkeletonStats st[2];
        SgMedium m;
        cr_assert(sg_shape_medium(shapes[i], 2, &m));
        sg_shape_roughen(&m, 0.2, 77);
        for (int t = 0; t < 2; t++) {
            SgSkeletonOptions o = quiet_options(t + 1);
            SgError err = {0};
            cr_assert(sg_skeletonize(&m, &o, &s[t], &st[t], &err));
        }
        const char *name = sg_shape_info(shapes[i])->name;
        check_skeleton(&m, &s[1], &st[1], name);
        cr_assert_eq(s[0].node_count, s[1].node_count, "%s", name);
        cr_assert_eq(s[0].edge_count, s[1].edge_count, "%s", name);
        cr_expect(!memcmp(s[0].nodes, s[1].nodes, s[0].node_count * sizeof *s[0].nodes), "%s", name);
        cr_expect(!memcmp(s[0].edges, s[1].edges, s[0].edge_count * sizeof *s[0].edges), "%s", name);
        cr_expect_eq(st[0].steps, st[1].steps);
        sg_skeleton_release(&s[0]);
        sg_skeleton_release(&s[1]);
        sg_shape_medium_free(&m);
    }
}

/* The collapse in slabs (a wavefront of sub-steps over slabs of z planes,
 * on one or two threads) removes the same pairs at the same sub-steps as
 * one sweep of the whole lattice per sub-step (a single slab): the same
 * skeleton, to the byte, on shapes with loops, cavities and noise. */
Test(skeleton, blocked_collapse_matches_one_sweep)
{
    SgShape shapes[] = {SG_SHAPE_RING_LAMP, SG_SHAPE_THREE_PILLARS, SG_SHAPE_SHELL, SG_SHAPE_TWO_ROOMS};
    struct {
        int threads;
        uint32_t planes;
    } runs[] = {{1, 1u << 30}, {1, 2}, {2, 2}, {2, 3}, {1, 5}};
    size_t run_count = sizeof runs / sizeof runs[0];
    for (size_t i = 0; i < sizeof shapes / sizeof shapes[0]; i++) {
        SgMedium m;
        cr_assert(sg_shape_medium(shapes[i], 2, &m));
        sg_shape_roughen(&m, 0.2, 91);
        const char *name = sg_shape_info(shapes[i])->name;
        SgSkeleton one_sweep;
        SgSkeletonStats one_sweep_stats;
        for (size_t r = 0; r < run_count; r++) {
            SgSkeletonOptions o = quiet_options(runs[r].threads);
            o.collapse_slab_planes = runs[r].planes;
            SgSkeleton s;
            SgSkeletonStats st;
            SgError err = {0};
            cr_assert(sg_skeletonize(&m, &o, r == 0 ? &one_sweep : &s,
                                     r == 0 ? &one_sweep_stats : &st, &err), "%s", err.message);
            if (r == 0)
                continue;
            cr_assert_eq(s.node_count, one_sweep.node_count, "%s, %u planes, %d threads", name,
                         runs[r].planes, runs[r].threads);
            cr_assert_eq(s.edge_count, one_sweep.edge_count, "%s", name);
            cr_expect(!memcmp(s.nodes, one_sweep.nodes, s.node_count * sizeof *s.nodes),
                      "%s, %u planes, %d threads: nodes differ", name, runs[r].planes,
                      runs[r].threads);
            cr_expect(!memcmp(s.edges, one_sweep.edges, s.edge_count * sizeof *s.edges),
                      "%s, %u planes, %d threads: edges differ", name, runs[r].planes,
                      runs[r].threads);
            cr_expect_eq(st.steps, one_sweep_stats.steps, "%s", name);
            cr_expect_eq(st.cavities_broken, one_sweep_stats.cavities_broken, "%s", name);
            sg_skeleton_release(&s);
        }
        sg_skeleton_release(&one_sweep);
        sg_shape_medium_free(&m);
    }
}

/* The threads may run the ready (slab, sub-step)s in any order the
 * collapse's readiness rule allows (a slab's sub-step s after sub-step
 * s - 1 of its neighbours, before their s + 1, never beside a running
 * neighbour), and which one a thread takes is a matter of timing: the
 * shuffled schedule takes random ready ones, two in flight, on one thread,
 * so that an order the rule should not allow shows reproducibly. Slabs of
 * two planes on rough shapes: the sub-steps of neighbouring slabs touch
 * the same cells. */
Test(skeleton, any_ready_order_matches_one_sweep)
{
    SgShape shapes[] = {SG_SHAPE_RING_LAMP, SG_SHAPE_THREE_PILLARS, SG_SHAPE_SHELL, SG_SHAPE_TWO_ROOMS};
    for (size_t i = 0; i < sizeof shapes / sizeof shapes[0]; i++) {
        SgMedium m;
        cr_assert(sg_shape_medium(shapes[i], 2, &m));
        sg_shape_roughen(&m, 0.2, 91);
        const char *name = sg_shape_info(shapes[i])->name;
        SgSkeletonOptions o = quiet_options(1);
        o.collapse_slab_planes = 1u << 30; /* one slab: one sweep per sub-step */
        SgSkeleton one_sweep;
        SgSkeletonStats one_sweep_stats;
        SgError err = {0};
        cr_assert(sg_skeletonize(&m, &o, &one_sweep, &one_sweep_stats, &err), "%s", err.message);
        for (uint64_t seed = 1; seed <= 4; seed++) {
            o.collapse_slab_planes = 2 + (uint32_t)(seed & 1);
            o.collapse_schedule_seed = seed * 0x9E3779B97F4A7C15ull;
            SgSkeleton s;
            SgSkeletonStats st;
            cr_assert(sg_skeletonize(&m, &o, &s, &st, &err), "%s: %s", name, err.message);
            bool same = s.node_count == one_sweep.node_count &&
                        s.edge_count == one_sweep.edge_count &&
                        !memcmp(s.nodes, one_sweep.nodes, s.node_count * sizeof *s.nodes) &&
                        !memcmp(s.edges, one_sweep.edges, s.edge_count * sizeof *s.edges);
            cr_expect(same, "%s, seed %llu, %u planes: %u nodes, %u edges; one sweep %u, %u", name,
                      (unsigned long long)seed, o.collapse_slab_planes, s.node_count, s.edge_count,
                      one_sweep.node_count, one_sweep.edge_count);
            cr_expect_eq(st.steps, one_sweep_stats.steps, "%s, seed %llu", name,
                         (unsigned long long)seed);
            sg_skeleton_release(&s);
        }
        sg_skeleton_release(&one_sweep);
        sg_shape_medium_free(&m);
    }
}

Test(skeleton, camera_constraint)
{
    SgMedium m;
    cr_assert(sg_shape_medium(SG_SHAPE_U, 2, &m));
    m.has_camera = true;
    m.camera_position[0] = 19.0; /* far end of the other arm */
    m.camera_position[1] = 4.0;
    m.camera_position[2] = 16.0;
    int cam[3];
    sg_grid_world_to_voxel(&m.grid, m.camera_position, cam);
    cr_assert(sg_grid_get(&m.grid, cam[0], cam[1], cam[2]));
    for (int with = 0; with < 2; with++) {
        SgSkeletonOptions o = quiet_options(2);
        o.camera_constraint = with;
        SgSkeleton s;
        SgSkeletonStats st;
        skeletonize_checked(&m, &o, &s, &st, with ? "U with camera" : "U");
        int cameras = 0;
        for (uint32_t i = 0; i < s.node_count; i++)
            if (s.nodes[i].kind == SG_NODE_CAMERA) {
                cameras++;
                cr_expect(!memcmp(s.nodes[i].voxel, cam, sizeof cam));
            }
        cr_expect_eq(cameras, with);
        cr_expect_eq(st.constraints, 1u + (unsigned)with);
        cr_expect_eq(st.camera_constrained, (bool)with);
        sg_skeleton_release(&s);
    }
    /* a camera inside a wall is no constraint (and no failure) */
    m.camera_position[0] = 12.0;
    m.camera_position[2] = 12.0;
    SgSkeletonOptions o = quiet_options(2);
    o.camera_constraint = true;
    SgSkeleton s;
    SgSkeletonStats st;
    SgError err = {0};
    cr_assert(sg_skeletonize(&m, &o, &s, &st, &err));
    cr_expect(!st.camera_constrained);
    for (uint32_t i = 0; i < s.node_count; i++)
        cr_expect_neq(s.nodes[i].kind, SG_NODE_CAMERA);
    sg_skeleton_release(&s);
    sg_shape_medium_free(&m);
}

Test(skeleton, bad_input)
{
    SgMedium m;
    cr_assert(sg_shape_medium(SG_SHAPE_CUBE, 1, &m));
    memset(m.grid.voxels, 0, sg_grid_count(&m.grid));
    SgSkeletonOptions o = quiet_options(1);
    SgSkeleton s;
    SgError err = {0};
    cr_expect(!sg_skeletonize(&m, &o, &s, NULL, &err));
    cr_expect(err.failed && strstr(err.message, "no voxel"), "message: %s", err.message);
    cr_expect_eq(s.node_count, 0);
    cr_expect_null(s.nodes);
    sg_shape_medium_free(&m);
}

/* ---- Betti numbers of small hand-made sets ---- */

static SgGrid small_grid(int n)
{
    SgGrid g;
    SgError err = {0};
    double o[3] = {0, 0, 0};
    cr_assert(sg_grid_init(&g, n, n, n, o, 1.0, &err));
    return g;
}

Test(topology, hand_made_sets)
{
    SgError err = {0};
    SgBetti b;
    SgGrid g = small_grid(3);
    g.voxels[sg_grid_index(&g, 1, 1, 1)] = 1;
    cr_assert(sg_voxel_betti(&g, &b, &err));
    cr_expect(b.b0 == 1 && b.b1 == 0 && b.b2 == 0 && b.chi == 1);
    /* two voxels touching at a corner: one component (closed cubes) */
    g.voxels[sg_grid_index(&g, 0, 0, 0)] = 1;
    cr_assert(sg_voxel_betti(&g, &b, &err));
    cr_expect(b.b0 == 1 && b.b1 == 0 && b.b2 == 0, "corner pair: %ld %ld %ld", (long)b.b0,
              (long)b.b1, (long)b.b2);
    /* a ring of 8 voxels in a plane: one tunnel */
    memset(g.voxels, 0, 27);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            if (i != 1 || j != 1)
                g.voxels[sg_grid_index(&g, i, j, 1)] = 1;
    cr_assert(sg_voxel_betti(&g, &b, &err));
    cr_expect(b.b0 == 1 && b.b1 == 1 && b.b2 == 0, "ring: %ld %ld %ld", (long)b.b0, (long)b.b1,
              (long)b.b2);
    /* 3x3x3 with the centre removed: one cavity */
    memset(g.voxels, 1, 27);
    g.voxels[sg_grid_index(&g, 1, 1, 1)] = 0;
    cr_assert(sg_voxel_betti(&g, &b, &err));
    cr_expect(b.b0 == 1 && b.b1 == 0 && b.b2 == 1, "shell: %ld %ld %ld", (long)b.b0, (long)b.b1,
              (long)b.b2);
    sg_grid_release(&g);
}

/* ---- distance and opening against brute force ---- */

static uint32_t squared_distance(const int a[3], const int b[3])
{
    int d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    return (uint32_t)(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

/* Brute force: the squared distance from medium voxel v to the nearest
 * voxel outside the medium (the padding counts). */
static uint32_t brute_distance2(const SgGrid *g, size_t v)
{
    int c[3];
    sg_grid_coords(g, v, c);
    uint32_t best = UINT32_MAX;
    for (int z = -1; z <= g->nz; z++)
        for (int y = -1; y <= g->ny; y++)
            for (int x = -1; x <= g->nx; x++) {
                uint32_t d = squared_distance(c, (int[3]){x, y, z});
                if (!sg_grid_get(g, x, y, z) && d < best)
                    best = d;
            }
    return best;
}

/* Brute force: the largest squared radius d2[q] of the medium's balls
 * (centre q, radius its distance) that hold medium voxel v. */
static uint32_t brute_opening2(const SgGrid *g, const uint32_t *d2, size_t v)
{
    int c[3], p[3];
    sg_grid_coords(g, v, c);
    uint32_t best = 0;
    for (size_t q = 0; q < sg_grid_count(g); q++) {
        if (!g->voxels[q] || d2[q] <= best)
            continue;
        sg_grid_coords(g, q, p);
        if (squared_distance(c, p) < d2[q])
            best = d2[q];
    }
    return best;
}

Test(distance, exact_edt_and_opening_bound)
{
    SgMedium m;
    cr_assert(sg_shape_medium(SG_SHAPE_PILLAR_ROOM, 1, &m));
    sg_shape_roughen(&m, 0.3, 99);
    const SgGrid *g = &m.grid;
    uint16_t *dist8, *open8;
    SgError err = {0};
    cr_assert(sg_distance_opening(g, 2, &dist8, &open8, &err));
    size_t n = sg_grid_count(g);
    uint32_t *d2 = calloc(n, sizeof *d2);
    cr_assert_not_null(d2);
    for (size_t v = 0; v < n; v++)
        if (g->voxels[v])
            d2[v] = brute_distance2(g, v);
    for (size_t v = 0; v < n; v++) {
        uint16_t expect = g->voxels[v] ? (uint16_t)(8.0 * sqrt(d2[v]) + 0.5) : 0;
        cr_assert_eq(dist8[v], expect, "distance at %zu: %u, brute force %u", v, dist8[v], expect);
    }
    /* opening: exact = max R(q) over balls containing v */
    double error_sum = 0;
    size_t count = 0, exact_hits = 0;
    for (size_t v = 0; v < n; v++) {
        if (!g->voxels[v])
            continue;
        uint16_t exact = (uint16_t)(8.0 * sqrt(brute_opening2(g, d2, v)) + 0.5);
        cr_assert(open8[v] <= exact, "opening overestimated at %zu", v);
        cr_assert(open8[v] >= dist8[v], "opening below the distance at %zu", v);
        error_sum += (exact - open8[v]) / 8.0;
        exact_hits += open8[v] == exact;
        count++;
    }
    double mean_error = error_sum / (double)count;
    cr_log_info("opening: mean underestimate %.3f voxel, exact at %.1f%% of %zu voxels",
                mean_error, 100.0 * (double)exact_hits / (double)count, count);
    /* propagation is blocked in places by larger balls: a bounded underestimate */
    cr_expect(mean_error < 0.75, "mean opening error %.3f voxel", mean_error);
    cr_expect((double)exact_hits / (double)count > 0.5, "opening exact at too few voxels");
    free(d2);
    free(dist8);
    free(open8);
    sg_shape_medium_free(&m);
}

/* ---- a real scene: Sponza (third-party, in ../shared/scenes) ---- */

/* The lattice layout's values (the collapse's: sizes n + 3, voxel (x,y,z)
 * at vertex (x+1, y+1, z+1)) are the grid layout's, with zero padding. */
static void check_lattice_layout(const SgGrid *g)
{
    uint16_t *d8, *o8, *ld8, *lo8;
    SgError err = {0};
    cr_assert(sg_distance_opening(g, 2, &d8, &o8, &err));
    cr_assert(sg_distance_opening_lattice(g, 1, &ld8, &lo8, &err));
    const size_t lx = (size_t)g->nx + 3, ly = (size_t)g->ny + 3, lz = (size_t)g->nz + 3;
    size_t nonzero = 0;
    for (size_t v = 0; v < lx * ly * lz; v++) {
        int x = (int)(v % lx) - 1, y = (int)(v / lx % ly) - 1, z = (int)(v / (lx * ly)) - 1;
        bool in = sg_grid_inside(g, x, y, z);
        size_t i = in ? sg_grid_index(g, x, y, z) : 0;
        cr_assert_eq(ld8[v], in ? d8[i] : 0, "%dx%dx%d: distance at (%d %d %d)", g->nx, g->ny,
                     g->nz, x, y, z);
        cr_assert_eq(lo8[v], in ? o8[i] : 0, "%dx%dx%d: opening at (%d %d %d)", g->nx, g->ny,
                     g->nz, x, y, z);
        nonzero += ld8[v] != 0;
    }
    cr_assert_gt(nonzero, 0);
    free(d8);
    free(o8);
    free(ld8);
    free(lo8);
}

Test(distance, lattice_layout_matches_grid_layout)
{
    /* a rough room (written in place, planes upwards and downwards), a tiny
     * grid (its padding outweighs the halved values: an array of its own),
     * and a slab whose in-plane distances pass 256 voxels (the 32-bit path) */
    SgMedium m;
    cr_assert(sg_shape_medium(SG_SHAPE_PILLAR_ROOM, 1, &m));
    sg_shape_roughen(&m, 0.3, 7);
    check_lattice_layout(&m.grid);
    sg_shape_medium_free(&m);
    SgGrid tiny = small_grid(3);
    tiny.voxels[sg_grid_index(&tiny, 1, 1, 1)] = 1;
    tiny.voxels[sg_grid_index(&tiny, 1, 2, 1)] = 1;
    check_lattice_layout(&tiny);
    sg_grid_release(&tiny);
    SgGrid slab;
    SgError err = {0};
    double o[3] = {0, 0, 0};
    cr_assert(sg_grid_init(&slab, 600, 560, 3, o, 1.0, &err));
    memset(slab.voxels, 1, sg_grid_count(&slab));
    check_lattice_layout(&slab);
    sg_grid_release(&slab);
}

#include "../voxelize/voxelize.h"
#include "scene_load.h"
#include "support_files.h"

Test(skeleton, sponza_topology)
{
    const char *path = "data/external/sponza.json";
    if (!sg_test_have_shared_scenes() || !sg_test_exists("../shared/scenes/sponza-dabrovic/sponza.obj"))
        cr_skip_test("../shared/scenes/sponza-dabrovic is absent");
    SgError err = {0};
    SgScene *scene = sg_scene_load(path, &err);
    cr_assert_not_null(scene, "%s", err.message);
    SgVoxelizeOptions vo = {.resolution = 128, .threads = 2};
    SgMedium m;
    SgVoxelizeStats vs;
    cr_assert(sg_voxelize(scene, &vo, &m, &vs, &err), "%s", err.message);
    sg_scene_free(scene);
    SgSkeletonOptions o = quiet_options(2);
    SgSkeleton s;
    SgSkeletonStats st;
    cr_assert(sg_skeletonize(&m, &o, &s, &st, &err), "%s", err.message);
    check_skeleton(&m, &s, &st, "sponza 128");
    cr_expect(st.loops > 10, "sponza's arcades give many loops, got %ld", (long)st.loops);
    cr_expect(st.mean_centredness > 0.85, "centredness %.3f", st.mean_centredness);
    sg_skeleton_release(&s);
    sg_medium_release(&m);
}
