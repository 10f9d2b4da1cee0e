/* bin/importance as a program: build, --vectors, --info (with and without a
 * scene), bad input, and the real corridor scene through bin/voxelize with a
 * lattice skeleton. */
#include <cjson/cJSON.h>
#include <criterion/criterion.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "../importance/importance.h"
#include "importance_cache.h"
#include "importance_cache_format.h"
#include "support_files.h"
#include "support_importance.h"

static char program[4096];

static void setup(void) { sg_test_program("importance", program, sizeof program); }

static cJSON *read_json(const char *path)
{
    FILE *f = fopen(path, "rb");
    cr_assert_not_null(f, "%s", path);
    static char text[65536];
    size_t n = fread(text, 1, sizeof text - 1, f);
    fclose(f);
    text[n] = 0;
    cr_assert_eq(sg_test_count_lines(text), 1, "one line of JSON: %s", text);
    cJSON *j = cJSON_Parse(text);
    cr_assert_not_null(j, "not JSON: %s", text);
    return j;
}

static double json_number(const cJSON *j, const char *name)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(j, name);
    cr_assert(cJSON_IsNumber(v), "no number %s", name);
    return v->valuedouble;
}

static long file_size(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 ? (long)st.st_size : -1;
}

/* The sealed rooms of test_importance.c, written as medium.vdb + skeleton.ply. */
static void write_sealed_rooms(const char *dir, char *medium_path, char *skeleton_path)
{
    SgMedium m;
    SgSkeleton s;
    sgt_sealed_rooms(&m, &s);
    sprintf(medium_path, "%s/medium.vdb", dir);
    sprintf(skeleton_path, "%s/skeleton.ply", dir);
    SgError err = {0};
    cr_assert(sg_medium_write(&m, medium_path, &err), "%s", err.message);
    cr_assert(sg_skeleton_write_ply(&s, skeleton_path, &err), "%s", err.message);
    sg_skeleton_release(&s);
    sgt_medium_free(&m);
}

/* importance --info CACHE [SCENE] > info, read back. */
static cJSON *info_json(const char *cache, const char *scene, const char *info)
{
    char cmd[16384], err[4096];
    snprintf(cmd, sizeof cmd, "%s --info %s %s > %s", program, cache, scene ? scene : "", info);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 0, "%s", err);
    return read_json(info);
}

/* A scene over the sealed rooms (one triangle; the camera is what counts)
 * with the camera at `position` (JSON), looking along the rooms. */
static const char *rooms_scene(const char *dir, const char *name, const char *position)
{
    char text[1024];
    snprintf(text, sizeof text,
             "{ \"meshes\": [ { \"vertices\": [0,0,0, 30,0,0, 0,12,0], \"triangles\": [0,1,2] } ],\n"
             "  \"camera\": { \"position\": %s, \"look_at\": [10, 6.5, 2.5], \"fov\": 50 },\n"
             "  \"image\": { \"width\": 32, \"height\": 24 } }\n",
             position);
    return sg_test_write(dir, name, text);
}

Test(importance_cli, help_and_usage_errors, .init = setup)
{
    char cmd[8192], err[4096];
    snprintf(cmd, sizeof cmd, "%s --help > /dev/null", program);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 0);
    snprintf(cmd, sizeof cmd, "%s only-one-input.vdb -o x.cache", program);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 2);
    cr_assert_eq(sg_test_count_lines(err), 1, "%s", err);
    snprintf(cmd, sizeof cmd, "%s a b -o c --bogus", program);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 2);
    cr_assert(strstr(err, "--bogus") != NULL, "%s", err);
}

Test(importance_cli, sealed_rooms_build_info_and_scene_litmus, .init = setup)
{
    const char *dir = sg_test_tmpdir();
    char medium[4096], skeleton[4096], cache[4096], vectors[4096], info[4096];
    write_sealed_rooms(dir, medium, skeleton);
    snprintf(cache, sizeof cache, "%s/importance.cache", dir);
    snprintf(vectors, sizeof vectors, "%s/vectors.ply", dir);
    snprintf(info, sizeof info, "%s/info.json", dir);
    char cmd[32768], err[4096];
    snprintf(cmd, sizeof cmd, "%s %s %s -o %s --vectors %s", program, medium, skeleton, cache,
             vectors);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 0, "%s", err);
    cr_assert_eq(sg_test_count_lines(err), 1, "one summary line: %s", err);
    cr_assert(sg_test_exists(vectors));

    /* Without a scene: lights with a place on the skeleton. */
    cJSON *j = info_json(cache, NULL, info);
    cr_assert_eq(json_number(j, "lights_total"), 3);
    cr_assert_eq(json_number(j, "lights_reachable"), 2);
    cr_assert_eq(json_number(j, "nodes"), 12 + 12);
    cr_assert_eq(json_number(j, "components"), 2);
    cr_assert_eq(json_number(j, "medium_voxels"), 13 * 10 * 3 + 12 * 10 * 3);
    cr_assert_eq(json_number(j, "bytes"), file_size(cache));
    cJSON_Delete(j);

    /* With a scene whose camera is in room A: only light 0 reaches it. */
    j = info_json(cache, rooms_scene(dir, "rooms.json", "[5.5, 6.5, 2.5]"), info);
    cr_assert_eq(json_number(j, "lights_total"), 3);
    cr_assert_eq(json_number(j, "lights_reachable"), 1);
    cr_assert(cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(j, "camera_in_medium")));
    cJSON_Delete(j);
    /* Camera in room B: only light 1. */
    j = info_json(cache, rooms_scene(dir, "rooms_b.json", "[25.5, 3.5, 1.5]"), info);
    cr_assert_eq(json_number(j, "lights_reachable"), 1);
    cJSON_Delete(j);
}

Test(importance_cli, bad_inputs_fail_with_one_line_and_no_output, .init = setup)
{
    const char *dir = sg_test_tmpdir();
    char medium[4096], skeleton[4096], cache[4096];
    write_sealed_rooms(dir, medium, skeleton);
    snprintf(cache, sizeof cache, "%s/out.cache", dir);
    char cmd[32768], err[4096];

    snprintf(cmd, sizeof cmd, "%s %s/missing.vdb %s -o %s", program, dir, skeleton, cache);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 1);
    cr_assert_eq(sg_test_count_lines(err), 1, "%s", err);
    cr_assert(strstr(err, "missing.vdb") != NULL, "%s", err);
    cr_assert_not(sg_test_exists(cache));

    /* A truncated skeleton. */
    FILE *f = fopen(skeleton, "r+b");
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fclose(f);
    cr_assert_eq(truncate(skeleton, n - 5), 0);
    snprintf(cmd, sizeof cmd, "%s %s %s -o %s", program, medium, skeleton, cache);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 1);
    cr_assert_eq(sg_test_count_lines(err), 1, "%s", err);
    cr_assert(strstr(err, skeleton) != NULL && strstr(err, "truncated") != NULL, "%s", err);
    cr_assert_not(sg_test_exists(cache));

    /* The skeleton given as the medium and the other way round. */
    snprintf(cmd, sizeof cmd, "%s %s %s -o %s", program, skeleton, medium, cache);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 1);
    cr_assert_eq(sg_test_count_lines(err), 1, "%s", err);
    cr_assert_not(sg_test_exists(cache));

    /* A skeleton made for another medium: a light node naming light 7. */
    SgSkeleton other = {0};
    int a0[3] = {2, 6, 2}, a1[3] = {12, 6, 2};
    uint32_t last = sgt_line(&other, SG_CACHE_NONE, a0, a1);
    other.nodes[last].kind = SG_NODE_LIGHT;
    other.nodes[last].light = 7;
    char other_path[4096];
    snprintf(other_path, sizeof other_path, "%s/other.ply", dir);
    SgError e = {0};
    cr_assert(sg_skeleton_write_ply(&other, other_path, &e), "%s", e.message);
    sg_skeleton_release(&other);
    snprintf(cmd, sizeof cmd, "%s %s %s -o %s", program, medium, other_path, cache);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 1);
    cr_assert_eq(sg_test_count_lines(err), 1, "%s", err);
    cr_assert(strstr(err, other_path) != NULL && strstr(err, "light 7") != NULL, "%s", err);
    cr_assert_not(sg_test_exists(cache));

    /* --info on something that is not a cache, and on a missing file. */
    snprintf(cmd, sizeof cmd, "%s --info %s", program, medium);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 1);
    cr_assert(strstr(err, medium) != NULL && strstr(err, "magic") != NULL, "%s", err);
    snprintf(cmd, sizeof cmd, "%s --info %s/none.cache", program, dir);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 1);
    cr_assert_eq(sg_test_count_lines(err), 1, "%s", err);
}

/* A lattice skeleton for a real medium: a node on every medium voxel of a
 * lattice of pitch `pitch`, joined to its lattice neighbours (26) that it
 * sees, plus a node on each light's seed joined to the lattice nodes it sees
 * nearby. Not a thinning, but a valid graph on the real air. */
static void lattice_skeleton(const SgMedium *m, int pitch, SgSkeleton *s)
{
    const SgGrid *g = &m->grid;
    int lx = (g->nx + pitch - 1) / pitch, ly = (g->ny + pitch - 1) / pitch,
        lz = (g->nz + pitch - 1) / pitch;
    uint32_t *id = malloc((size_t)lx * ly * lz * sizeof *id);
    memset(s, 0, sizeof *s);
    for (int k = 0; k < lz; k++)
        for (int j = 0; j < ly; j++)
            for (int i = 0; i < lx; i++) {
                size_t c = (size_t)i + (size_t)lx * ((size_t)j + (size_t)ly * k);
                int v[3] = {i * pitch + pitch / 2, j * pitch + pitch / 2, k * pitch + pitch / 2};
                id[c] = sg_grid_get(g, v[0], v[1], v[2])
                            ? sgt_node(s, v[0], v[1], v[2], SG_NODE_PLAIN, -1)
                            : SG_CACHE_NONE;
            }
    for (int k = 0; k < lz; k++)
        for (int j = 0; j < ly; j++)
            for (int i = 0; i < lx; i++) {
                uint32_t a = id[(size_t)i + (size_t)lx * ((size_t)j + (size_t)ly * k)];
                if (a == SG_CACHE_NONE)
                    continue;
                for (int dz = 0; dz <= 1; dz++)
                    for (int dy = -1; dy <= 1; dy++)
                        for (int dx = -1; dx <= 1; dx++) {
                            if (dz == 0 && (dy < 0 || (dy == 0 && dx <= 0)))
                                continue; /* each pair once */
                            int ni = i + dx, nj = j + dy, nk = k + dz;
                            if (ni < 0 || nj < 0 || ni >= lx || nj >= ly || nk >= lz)
                                continue;
                            uint32_t b = id[(size_t)ni + (size_t)lx * ((size_t)nj + (size_t)ly * nk)];
                            if (b != SG_CACHE_NONE &&
                                sg_importance_visible(g, s->nodes[a].voxel, s->nodes[b].voxel))
                                sgt_edge(s, a, b);
                        }
            }
    uint32_t lattice = s->node_count;
    for (uint32_t k = 0; k < m->light_count; k++) {
        const int *seed = m->lights[k].seed;
        if (!sg_grid_get(g, seed[0], seed[1], seed[2]))
            continue;
        uint32_t ln = sgt_node(s, seed[0], seed[1], seed[2], SG_NODE_LIGHT, (int)k);
        for (uint32_t n = 0; n < lattice; n++) {
            const int *v = s->nodes[n].voxel;
            if (abs(v[0] - seed[0]) <= 2 * pitch && abs(v[1] - seed[1]) <= 2 * pitch &&
                abs(v[2] - seed[2]) <= 2 * pitch &&
                sg_importance_visible(g, seed, v))
                sgt_edge(s, ln, n);
        }
    }
    /* sgt_node places nodes in unit voxels at the origin: use the grid's
     * world transform instead. */
    for (uint32_t n = 0; n < s->node_count; n++) {
        double p[3];
        const int *v = s->nodes[n].voxel;
        sg_grid_voxel_center(g, v[0], v[1], v[2], p);
        for (int a = 0; a < 3; a++)
            s->nodes[n].position[a] = (float)p[a];
    }
    free(id);
}

Test(importance_cli, corridor_scene_end_to_end, .init = setup)
{
    char voxelize[4096];
    sg_test_program("voxelize", voxelize, sizeof voxelize);
    if (!sg_test_exists(voxelize) || !sg_test_exists("data/corridor/corridor.json"))
        cr_skip_test("bin/voxelize or data/corridor missing");
    const char *dir = sg_test_tmpdir();
    char medium[4096], skeleton[4096], cache[4096], info[4096];
    snprintf(medium, sizeof medium, "%s/medium.vdb", dir);
    snprintf(skeleton, sizeof skeleton, "%s/skeleton.ply", dir);
    snprintf(cache, sizeof cache, "%s/importance.cache", dir);
    snprintf(info, sizeof info, "%s/info.json", dir);
    char cmd[32768], err[4096];
    snprintf(cmd, sizeof cmd, "%s data/corridor/corridor.json -o %s --resolution 64 -q", voxelize,
             medium);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 0, "%s", err);

    SgMedium m;
    SgError e = {0};
    cr_assert(sg_medium_read(&m, medium, &e), "%s", e.message);
    cr_assert_gt(m.light_count, 0);
    SgSkeleton s;
    lattice_skeleton(&m, 3, &s);
    cr_assert(sg_skeleton_write_ply(&s, skeleton, &e), "%s", e.message);

    char vectors[4096];
    snprintf(vectors, sizeof vectors, "%s/vectors.ply", dir);
    snprintf(cmd, sizeof cmd, "%s %s %s -o %s --vectors %s -q", program, medium, skeleton, cache,
             vectors);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 0, "%s", err);
    snprintf(cmd, sizeof cmd, "%s --info %s data/corridor/corridor.json > %s", program, cache,
             info);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 0, "%s", err);
    cJSON *j = read_json(info);
    cr_assert_eq(json_number(j, "lights_total"), m.light_count);
    cr_assert_geq(json_number(j, "lights_reachable"), 1);
    cr_assert_eq(json_number(j, "nodes"), s.node_count);
    cr_assert(cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(j, "geometry_matches")));
    cr_assert(cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(j, "camera_in_medium")));
    cJSON_Delete(j);

    /* Every medium voxel finds a node, and each node's importance point for
     * a reachable light is inside the grid's box (or on the light). */
    SgImportanceCache *c = sg_cache_open(cache, &e);
    cr_assert_not_null(c, "%s", e.message);
    const SgGrid *g = &m.grid;
    for (uint32_t n = 0; n < s.node_count; n++)
        for (uint32_t k = 0; k < m.light_count; k++) {
            double q[3];
            if (!sg_cache_node_importance_point(c, n, k, q))
                continue;
            for (int a = 0; a < 3; a++) {
                double lo = g->origin[a], hi = lo + g->voxel_size * (a == 0 ? g->nx : a == 1 ? g->ny : g->nz);
                cr_assert(q[a] >= lo - 1e-3 && q[a] <= hi + 1e-3, "node %u point %g outside", n, q[a]);
            }
        }
    uint64_t found = 0, medium_voxels = 0;
    for (int k = 0; k < g->nz; k++)
        for (int jy = 0; jy < g->ny; jy++)
            for (int i = 0; i < g->nx; i++) {
                if (!sg_grid_get(g, i, jy, k))
                    continue;
                medium_voxels++;
                double p[3];
                sg_grid_voxel_center(g, i, jy, k, p);
                uint32_t n;
                found += sg_cache_nearest_node(c, p, &n) && n < s.node_count;
            }
    /* The lattice may miss pockets of air smaller than its pitch. */
    cr_assert_geq(found, medium_voxels * 99 / 100, "%lu of %lu", (unsigned long)found,
                  (unsigned long)medium_voxels);
    sg_cache_close(c);
    sg_skeleton_release(&s);
    sg_medium_release(&m);
}
