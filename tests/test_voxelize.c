/* Step 1: conservative voxelization, light components, VDB round trip,
 * bad input. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "medium.h"
#include "rng.h"
#include "scene_load.h"
#include "support_files.h"
#include "voxelize/voxelize.h"

/* A scene of the repository's Cornell box written in a temporary folder
 * (so naming the mesh by its absolute path): DIR/NAME holding
 * { "meshes": [ { "file": CORNELL<mesh_members> } ]<scene_members> }. */
static char *write_cornell(const char *dir, const char *name, const char *mesh_members, const char *scene_members)
{
    char json[1024];
    snprintf(json, sizeof json, "{ \"meshes\": [ { \"file\": \"%s\"%s } ]%s }",
             sg_test_source_path("data/cornell-box/CornellBox-Original.obj"), mesh_members, scene_members);
    return sg_test_write(dir, name, json);
}

/* ---- triangle/box overlap against a brute-force reference --------------- */

/* Clips a convex polygon by the half-space s * x[axis] <= bound. */
static int clip(const double in[][3], int n, int axis, double s, double bound, double out[][3])
{
    int m = 0;
    for (int i = 0; i < n; i++) {
        const double *a = in[i], *b = in[(i + 1) % n];
        double da = s * a[axis] - bound, db = s * b[axis] - bound;
        if (da <= 0)
            memcpy(out[m++], a, sizeof(double[3]));
        if ((da < 0 && db > 0) || (da > 0 && db < 0)) {
            double t = da / (da - db);
            for (int k = 0; k < 3; k++)
                out[m][k] = a[k] + t * (b[k] - a[k]);
            m++;
        }
    }
    return m;
}

/* Does the triangle meet the box [-half, half]^3? By clipping it to the box. */
static bool overlap_by_clipping(const double tri[3][3], double half)
{
    double a[16][3], b[16][3];
    memcpy(a, tri, sizeof(double[3][3]));
    int n = 3;
    for (int axis = 0; axis < 3 && n > 0; axis++) {
        n = clip((const double(*)[3])a, n, axis, 1, half, b);
        n = clip((const double(*)[3])b, n, axis, -1, half, a);
    }
    return n > 0;
}

Test(voxelize, triangle_box_overlap_matches_clipping)
{
    SgRng rng;
    sg_rng_seed(&rng, 7, 1);
    const double centre[3] = {0, 0, 0};
    int decided = 0, overlapping = 0;
    for (int trial = 0; trial < 200000; trial++) {
        double tri[3][3];
        /* Mix of scales: slivers, small and large triangles around the box. */
        double scale = trial % 3 == 0 ? 0.3 : trial % 3 == 1 ? 1.5 : 6.0;
        double offset[3];
        for (int k = 0; k < 3; k++)
            offset[k] = 3.0 * (sg_rng_float(&rng) - 0.5);
        for (int v = 0; v < 3; v++)
            for (int k = 0; k < 3; k++)
                tri[v][k] = offset[k] + scale * (sg_rng_float(&rng) - 0.5);
        bool inner = overlap_by_clipping(tri, 0.5 - 1e-7);
        bool outer = overlap_by_clipping(tri, 0.5 + 1e-7);
        if (inner != outer)
            continue; /* touching within rounding: either answer is right */
        decided++;
        overlapping += inner;
        bool sat = sg_triangle_box_overlap(centre, 0.5, tri[0], tri[1], tri[2]);
        cr_assert_eq(sat, inner, "trial %d: SAT says %d, clipping says %d", trial, sat, inner);
    }
    cr_assert_gt(decided, 190000);
    cr_assert_gt(overlapping, 20000, "the sample must exercise both answers");
    cr_assert_lt(overlapping, decided - 20000);
}

Test(voxelize, touching_counts_as_overlap)
{
    const double c[3] = {0.5, 0.5, 0.5};
    /* A triangle lying exactly in the box's face plane x = 1. */
    const double a[3] = {1, 0, 0}, b[3] = {1, 1, 0}, d[3] = {1, 0, 1};
    cr_assert(sg_triangle_box_overlap(c, 0.5, a, b, d));
    /* Only a vertex touches the corner (1,1,1). */
    const double e[3] = {1, 1, 1}, f[3] = {2, 1.5, 1}, g[3] = {1.5, 2, 1.2};
    cr_assert(sg_triangle_box_overlap(c, 0.5, e, f, g));
    const double h[3] = {1.001, 1, 1};
    cr_assert_not(sg_triangle_box_overlap(c, 0.5, h, f, g));
}

/* ---- scenes written as JSON with inline geometry ------------------------- */

typedef struct Rotation {
    double m[3][3];
} Rotation;

static Rotation rotation(double degrees, double x, double y, double z)
{
    double len = sqrt(x * x + y * y + z * z);
    x /= len, y /= len, z /= len;
    double a = degrees * M_PI / 180, c = cos(a), s = sin(a), C = 1 - c;
    Rotation r = {{{x * x * C + c, x * y * C - z * s, x * z * C + y * s},
                   {y * x * C + z * s, y * y * C + c, y * z * C - x * s},
                   {z * x * C - y * s, z * y * C + x * s, z * z * C + c}}};
    return r;
}

static void rotate(const Rotation *r, const double p[3], double out[3])
{
    for (int i = 0; i < 3; i++)
        out[i] = r->m[i][0] * p[0] + r->m[i][1] * p[1] + r->m[i][2] * p[2];
}

/* One mesh entry: quads given as 4 corners each, rotated and scaled. */
static void put_quads(SgTestText *t, const double (*quads)[4][3], int count, const Rotation *r,
                      double scale, const char *extra)
{
    sg_test_put(t, "{ \"vertices\": [");
    for (int q = 0; q < count; q++)
        for (int c = 0; c < 4; c++) {
            double p[3];
            rotate(r, quads[q][c], p);
            sg_test_put(t, "%s%.17g, %.17g, %.17g", q || c ? ", " : "", scale * p[0], scale * p[1],
                scale * p[2]);
        }
    sg_test_put(t, "], \"triangles\": [");
    for (int q = 0; q < count; q++)
        sg_test_put(t, "%s%d, %d, %d, %d, %d, %d", q ? ", " : "", 4 * q, 4 * q + 1, 4 * q + 2, 4 * q,
            4 * q + 2, 4 * q + 3);
    sg_test_put(t, "]%s }", extra);
}

/* The six faces of the box [lo, hi]. */
static void box_quads(const double lo[3], const double hi[3], double quads[6][4][3])
{
    for (int axis = 0; axis < 3; axis++)
        for (int side = 0; side < 2; side++) {
            int u = (axis + 1) % 3, v = (axis + 2) % 3;
            double (*q)[3] = quads[2 * axis + side];
            const int corners[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
            for (int c = 0; c < 4; c++) {
                q[c][axis] = side ? hi[axis] : lo[axis];
                q[c][u] = corners[c][0] ? hi[u] : lo[u];
                q[c][v] = corners[c][1] ? hi[v] : lo[v];
            }
        }
}

/* Small quad light facing +y at height y, centred on (x, z). */
static void light_quad(double x, double y, double z, double size, double q[4][3])
{
    const double corners[4][2] = {{-1, -1}, {-1, 1}, {1, 1}, {1, -1}};
    for (int c = 0; c < 4; c++) {
        q[c][0] = x + 0.5 * size * corners[c][0];
        q[c][1] = y;
        q[c][2] = z + 0.5 * size * corners[c][1];
    }
}

static SgScene *load_scene(const char *path)
{
    SgError err = {0};
    SgScene *s = sg_scene_load(path, &err);
    cr_assert_not_null(s, "scene failed to load: %s", err.message);
    return s;
}

static SgScene *load_text(const char *dir, const char *name, const char *json)
{
    return load_scene(sg_test_write(dir, name, json));
}

static void voxelize_ok(const SgScene *s, int resolution, SgMedium *m, SgVoxelizeStats *st)
{
    SgVoxelizeOptions opt = {.resolution = resolution, .threads = 2};
    SgError err = {0};
    cr_assert(sg_voxelize(s, &opt, m, st, &err), "voxelize failed: %s", err.message);
}

/* A closed room split by a zero-thickness diagonal wall (plane x = y),
 * rotated off the grid axes; the light is in the x > y half. */
static char *split_room_json(const Rotation *r, double scale)
{
    SgTestText t = {0};
    double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1}, walls[6][4][3];
    box_quads(lo, hi, walls);
    double wall[1][4][3] = {{{0, 0, 0}, {1, 1, 0}, {1, 1, 1}, {0, 0, 1}}};
    double light[1][4][3];
    light_quad(0.75, 0.02, 0.5, 0.1, light[0]);
    sg_test_put(&t, "{ \"meshes\": [");
    put_quads(&t, (const double(*)[4][3])walls, 6, r, scale, "");
    sg_test_put(&t, ", ");
    put_quads(&t, (const double(*)[4][3])wall, 1, r, scale, "");
    sg_test_put(&t, ", ");
    put_quads(&t, (const double(*)[4][3])light, 1, r, scale, ", \"emission\": [5, 5, 5]");
    sg_test_put(&t, "] }");
    return t.data;
}

Test(voxelize, thin_wall_does_not_leak)
{
    const char *dir = sg_test_tmpdir();
    const Rotation rotations[] = {rotation(0, 0, 1, 0), rotation(37, 1, 2, 3),
                                  rotation(-71, 0.3, -1, 0.2)};
    const int resolutions[] = {17, 32, 61};
    for (int ri = 0; ri < 3; ri++)
        for (int si = 0; si < 3; si++) {
            char *json = split_room_json(&rotations[ri], 1.0);
            SgScene *s = load_text(dir, "split.json", json);
            free(json);
            SgMedium m;
            SgVoxelizeStats st;
            voxelize_ok(s, resolutions[si], &m, &st);
            /* Side of the wall plane, in the rotated frame. */
            double n0[3] = {M_SQRT1_2, -M_SQRT1_2, 0}, n[3];
            rotate(&rotations[ri], n0, n);
            const SgGrid *g = &m.grid;
            size_t lit = 0;
            for (int k = 0; k < g->nz; k++)
                for (int j = 0; j < g->ny; j++)
                    for (int i = 0; i < g->nx; i++) {
                        if (!sg_grid_get(g, i, j, k))
                            continue;
                        double c[3];
                        sg_grid_voxel_center(g, i, j, k, c);
                        double side = n[0] * c[0] + n[1] * c[1] + n[2] * c[2];
                        cr_assert_gt(side, 0, "leak through the wall at (%d,%d,%d), res %d rot %d",
                                     i, j, k, resolutions[si], ri);
                        lit++;
                    }
            cr_assert_gt(lit, 0);
            cr_assert_geq(st.air_components, 2, "the dark half must be air of its own");
            sg_medium_release(&m);
            sg_scene_free(s);
        }
}

Test(voxelize, sealed_rooms_keep_only_the_lit_one)
{
    const char *dir = sg_test_tmpdir();
    SgTestText t = {0};
    double a_lo[3] = {0, 0, 0}, a_hi[3] = {1, 1, 1}, b_lo[3] = {2, 0, 0}, b_hi[3] = {3, 1, 1};
    double a[6][4][3], b[6][4][3], light[1][4][3];
    box_quads(a_lo, a_hi, a);
    box_quads(b_lo, b_hi, b);
    light_quad(0.5, 0.01, 0.5, 0.2, light[0]);
    Rotation id = rotation(0, 0, 1, 0);
    sg_test_put(&t, "{ \"meshes\": [");
    put_quads(&t, (const double(*)[4][3])a, 6, &id, 1, "");
    sg_test_put(&t, ", ");
    put_quads(&t, (const double(*)[4][3])b, 6, &id, 1, "");
    sg_test_put(&t, ", ");
    put_quads(&t, (const double(*)[4][3])light, 1, &id, 1, ", \"emission\": [1, 1, 1]");
    sg_test_put(&t, "] }");
    SgScene *s = load_text(dir, "rooms.json", t.data);
    free(t.data);
    SgMedium m;
    SgVoxelizeStats st;
    voxelize_ok(s, 60, &m, &st);
    /* Inside A, inside B, and the air between them (inside the bounding box). */
    cr_assert_eq(st.air_components, 3);
    cr_assert_eq(st.medium_components, 1);
    const SgGrid *g = &m.grid;
    size_t count = 0;
    for (int k = 0; k < g->nz; k++)
        for (int j = 0; j < g->ny; j++)
            for (int i = 0; i < g->nx; i++)
                if (sg_grid_get(g, i, j, k)) {
                    double c[3];
                    sg_grid_voxel_center(g, i, j, k, c);
                    cr_assert_lt(c[0], 1.0, "medium voxel outside the lit room");
                    count++;
                }
    cr_assert_eq(count, st.medium_voxels);
    /* Room A is 20^3 voxels minus its one-voxel walls and the light. */
    cr_assert(count > 17 * 17 * 17 && count <= 18 * 18 * 18, "medium of %zu voxels", count);
    sg_medium_release(&m);
    sg_scene_free(s);
}

static void grids_equal(const SgMedium *a, const SgMedium *b, double scale_ratio)
{
    cr_assert_eq(a->grid.nx, b->grid.nx);
    cr_assert_eq(a->grid.ny, b->grid.ny);
    cr_assert_eq(a->grid.nz, b->grid.nz);
    cr_assert_float_eq(a->grid.voxel_size * scale_ratio, b->grid.voxel_size,
                       1e-9 * b->grid.voxel_size);
    size_t n = sg_grid_count(&a->grid), differ = 0;
    for (size_t v = 0; v < n; v++)
        differ += a->grid.voxels[v] != b->grid.voxels[v];
    cr_assert_eq(differ, 0, "%zu voxels differ between scales", differ);
    for (uint32_t k = 0; k < a->light_count; k++)
        for (int c = 0; c < 3; c++)
            cr_assert_eq(a->lights[k].seed[c], b->lights[k].seed[c]);
}

Test(voxelize, same_grid_at_any_unit)
{
    const char *dir = sg_test_tmpdir();
    const double scales[] = {1.0, 1e-3, 1e4};
    SgMedium media[3];
    Rotation r = rotation(23, 1, 1, 0);
    for (int i = 0; i < 3; i++) {
        char *json = split_room_json(&r, scales[i]);
        SgScene *s = load_text(dir, "scaled.json", json);
        free(json);
        SgVoxelizeStats st;
        voxelize_ok(s, 45, &media[i], &st);
        sg_scene_free(s);
    }
    grids_equal(&media[0], &media[1], 1e-3);
    grids_equal(&media[0], &media[2], 1e4);
    for (int i = 0; i < 3; i++)
        sg_medium_release(&media[i]);

    /* A real scene whose walls lie exactly on voxel faces. */
    SgMedium cornell[2];
    for (int i = 0; i < 2; i++) {
        char scale[64];
        snprintf(scale, sizeof scale, ", \"transform\": { \"scale\": %g }", i ? 1e4 : 1e-3);
        SgScene *s = load_scene(write_cornell(dir, "cornell.json", scale, ""));
        SgVoxelizeStats st;
        voxelize_ok(s, 50, &cornell[i], &st);
        sg_scene_free(s);
    }
    grids_equal(&cornell[0], &cornell[1], 1e7);
    sg_medium_release(&cornell[0]);
    sg_medium_release(&cornell[1]);
}

Test(voxelize, medium_round_trips_through_vdb)
{
    const char *dir = sg_test_tmpdir();
    SgError err = {0};
    SgScene *s = sg_scene_load("data/cornell-box/cornell-box.json", &err);
    cr_assert_not_null(s, "%s", err.message);
    SgMedium m, back;
    SgVoxelizeStats st;
    voxelize_ok(s, 40, &m, &st);
    char path[4200];
    snprintf(path, sizeof path, "%s/medium.vdb", dir);
    cr_assert(sg_medium_write(&m, path, &err), "%s", err.message);
    cr_assert(sg_medium_read(&back, path, &err), "%s", err.message);
    grids_equal(&m, &back, 1.0);
    for (int a = 0; a < 3; a++) {
        cr_assert_float_eq(back.grid.origin[a], m.grid.origin[a], 1e-12);
        cr_assert_float_eq(back.camera_position[a], s->camera.position[a], 1e-12);
        cr_assert_float_eq(back.lights[0].position[a], s->lights[0].position[a], 1e-12);
        cr_assert_float_eq(back.lights[0].normal[a], s->lights[0].normal[a], 1e-12);
        cr_assert_float_eq(back.lights[0].radiance[a], s->lights[0].radiance[a], 1e-6);
    }
    cr_assert_eq(back.light_count, 1);
    cr_assert_float_eq(back.lights[0].power, s->lights[0].power, 1e-9);
    cr_assert(back.has_camera);
    cr_assert_eq(back.resolution, 40);
    cr_assert_eq(back.geometry_hash, s->geometry_hash);
    cr_assert_str_eq(back.scene_path, "data/cornell-box/cornell-box.json");
    /* The light's seed is medium, just below the light. */
    const int *seed = back.lights[0].seed;
    cr_assert(sg_grid_get(&back.grid, seed[0], seed[1], seed[2]));

    /* vdb_print, the tool users reach for, reads it. */
    char cmd[8500], out[4096];
    snprintf(cmd, sizeof cmd, "vdb_print -metadata %s", path);
    if (system("command -v vdb_print >/dev/null") == 0) {
        FILE *p = popen(cmd, "r");
        size_t n = fread(out, 1, sizeof out - 1, p);
        out[n] = 0;
        cr_assert_eq(pclose(p), 0);
        cr_assert_not_null(strstr(out, "medium"), "vdb_print output: %s", out);
        cr_assert_not_null(strstr(out, "light_0_seed"), "vdb_print output: %s", out);
    }
    sg_medium_release(&m);
    sg_medium_release(&back);
    sg_scene_free(s);
}

Test(voxelize, scene_grouping_and_hash)
{
    SgError err = {0};
    SgScene *s = sg_scene_load("data/cornell-box/cornell-box.json", &err);
    cr_assert_not_null(s, "%s", err.message);
    cr_assert_eq(s->triangle_count, 36);
    cr_assert_eq(s->light_count, 1, "the light quad is one light, not two triangles");
    cr_assert_eq(s->lights[0].triangle_count, 2);
    cr_assert_float_eq(s->lights[0].normal[1], -1.0, 1e-9);
    cr_assert_float_eq(s->lights[0].area, 0.47 * 0.38, 1e-3);
    cr_assert_float_eq(s->lights[0].radiance[0], 17.0f, 1e-6);
    /* fov_axis horizontal 67.4 at 4:3 is 53.4 degrees vertical. */
    cr_assert_float_eq(s->camera.fov_deg, 2 * atan(tan(67.4 * M_PI / 360) * 0.75) * 180 / M_PI,
                       1e-9);
    /* Moving the camera does not change the geometry's identity. */
    const char *dir = sg_test_tmpdir();
    SgScene *moved = load_scene(write_cornell(
        dir, "moved.json", "", ", \"camera\": { \"position\": [0.3, 1, 1.5], \"look_at\": [0, 1, 0] }"));
    cr_assert_eq(moved->geometry_hash, s->geometry_hash);
    SgScene *shifted =
        load_scene(write_cornell(dir, "shifted.json", ", \"transform\": { \"translate\": [0, 0.001, 0] }", ""));
    cr_assert_neq(shifted->geometry_hash, s->geometry_hash);
    sg_scene_free(s);
    sg_scene_free(moved);
    sg_scene_free(shifted);
}

Test(voxelize, real_scenes_load_with_their_lights)
{
    if (!sg_test_have_shared_scenes())
        cr_skip_test("../shared/scenes is not present");
    SgError err = {0};
    SgScene *s = sg_scene_load("data/external/bathroom.json", &err);
    cr_assert_not_null(s, "%s", err.message);
    /* 855 PLY files, four of which Assimp 5.2 misreads. */
    cr_assert_gt(s->triangle_count, 590000);
    cr_assert_eq(s->light_count, 1);
    cr_assert_float_eq(s->lights[0].normal[0], 1.0, 1e-6);
    sg_scene_free(s);
}

/* ---- the program on bad input ------------------------------------------- */

static void expect_failure(const char *scene, const char *must_contain)
{
    char prog[4096], cmd[16384], err[4096];
    const char *dir = sg_test_tmpdir();
    char out[4200];
    snprintf(out, sizeof out, "%s/out.vdb", dir);
    snprintf(cmd, sizeof cmd, "%s '%s' -o '%s'", sg_test_program("voxelize", prog, sizeof prog),
             scene, out);
    int rc = sg_test_run(cmd, err, sizeof err);
    cr_assert_neq(rc, 0, "voxelize succeeded on %s", scene);
    cr_assert_lt(rc, 128, "voxelize crashed (status %d) on %s: %s", rc, scene, err);
    cr_assert_eq(sg_test_count_lines(err), 1, "want one line, got: %s", err);
    cr_assert_not_null(strstr(err, must_contain), "message lacks \"%s\": %s", must_contain, err);
    cr_assert_not(sg_test_exists(out), "a failed run left %s", out);
    /* No temporary either. */
    char ls[8500], listing[256];
    snprintf(ls, sizeof ls, "ls -A '%s' | wc -l", dir);
    FILE *p = popen(ls, "r");
    cr_assert(fgets(listing, sizeof listing, p));
    pclose(p);
    cr_assert_eq(atoi(listing), 0, "files left in the output directory");
}

/* A scene (DIR/scene_name) whose one mesh file (DIR/mesh_name) holds
 * mesh_text: loading it fails with a message holding `cause`. */
static void expect_mesh_failure(const char *dir, const char *scene_name, const char *mesh_name, const char *mesh_text,
                                const char *cause)
{
    char json[512];
    sg_test_write(dir, mesh_name, mesh_text);
    snprintf(json, sizeof json, "{ \"mesh\": \"%s\" }", mesh_name);
    expect_failure(sg_test_write(dir, scene_name, json), cause);
}

Test(voxelize, bad_input_gives_one_line_and_no_output)
{
    const char *dir = sg_test_tmpdir();
    expect_failure("/nonexistent/scene.json", "/nonexistent/scene.json: cannot open");
    char *p = sg_test_write(dir, "malformed.json", "{ \"mesh\": \"a.obj\",\n  \"camera\": { ]\n}");
    expect_failure(p, "malformed JSON near line 2");
    p = sg_test_write(dir, "missing-mesh.json", "{ \"mesh\": \"nothere.obj\" }");
    expect_failure(p, "nothere.obj: cannot open mesh");
    expect_mesh_failure(dir, "junk.json", "junk.ply",
                        "ply\nformat binary_little_endian 1.0\nelement vertex 3\n"
                        "property float x\nproperty float y\nproperty float z\n"
                        "element face 1\nproperty list uchar int vertex_indices\n"
                        "end_header\n\x01\x02",
                        "junk.ply: PLY data truncated");
    expect_mesh_failure(dir, "junkstl.json", "junk.stl",
                        "solid x\n facet normal 0 0 1\n  outer loop\n   vertex 0 0\n", "junk.stl");
    expect_mesh_failure(dir, "nan.json", "nan.obj",
                        "v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n", "non-finite vertex coordinate");
    expect_mesh_failure(dir, "degenerate.json", "flat.obj",
                        "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n", "all were degenerate");
    expect_mesh_failure(dir, "dark.json", "tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "no light");
    p = sg_test_write(dir, "badcam.json",
                      "{ \"mesh\": \"tri.obj\", \"camera\": { \"position\": [0,0,0] } }");
    expect_failure(p, "camera needs");
    p = sg_test_write(dir, "badres.json",
                      "{ \"mesh\": \"tri.obj\", \"voxel\": { \"resolution\": -3 } }");
    expect_failure(p, "voxel.resolution");
}

Test(voxelize, failure_keeps_the_previous_output)
{
    const char *dir = sg_test_tmpdir();
    char *out = sg_test_write(dir, "medium.vdb", "previous result");
    char *bad = sg_test_write(dir, "bad.json", "{");
    char prog[4096], cmd[16384], err[4096];
    snprintf(cmd, sizeof cmd, "%s '%s' -o '%s'", sg_test_program("voxelize", prog, sizeof prog),
             bad, out);
    cr_assert_neq(sg_test_run(cmd, err, sizeof err), 0);
    FILE *f = fopen(out, "rb");
    char text[64] = {0};
    cr_assert(fread(text, 1, sizeof text - 1, f) > 0);
    fclose(f);
    cr_assert_str_eq(text, "previous result");
}

Test(voxelize, camera_in_a_wall_is_reported)
{
    const char *dir = sg_test_tmpdir();
    /* Camera on the Cornell box's back wall plane. */
    char *scene =
        write_cornell(dir, "wall.json", "", ", \"camera\": { \"position\": [0, 1, -1.02], \"look_at\": [0, 1, 0] }");
    char prog[4096], cmd[16384], err[4096];
    snprintf(cmd, sizeof cmd, "%s '%s' -o '%s/m.vdb' --resolution 32",
             sg_test_program("voxelize", prog, sizeof prog), scene, dir);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 0, "%s", err);
    cr_assert_not_null(strstr(err, "camera is inside a solid voxel"), "stderr: %s", err);
}
