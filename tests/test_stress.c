/* Stress suite: the whole pipeline (bin/voxelize, skeletonize, importance,
 * render) on strange input, and the renderer's sampling at its limits. In
 * every case: no crash, no NaN or infinity in any output, and where the
 * input cannot be served, one line naming the file and the cause, with no
 * output left behind.
 *
 *   - one scene at scales 1e-4, 1, 1e5 and translated by 1e6: the same mean
 *     radiance within the noise (radiance does not depend on units);
 *   - degenerate, tiny, duplicated and flipped triangles and a cracked wall:
 *     the same image as the clean scene within the noise;
 *   - zero-area lights, a light flush with the ceiling or touching a wall, a
 *     light sealed in a box, a camera in a room no light reaches;
 *   - a medium of one voxel, a corridor one voxel wide, grids and images
 *     larger than the memory available (refused before allocating);
 *   - runs killed mid-write and a full disk leave no file under the target's
 *     name, and a later run removes the dead run's temporary;
 *   - lobe exponents 0 to 1e5, importance points at the shading point, on
 *     its tangent plane, NaN or far away, grazing directions. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "../render/bsdf.h"
#include "../render/renderer.h"
#include "../render/sampling.h"
#include "image_io.h"
#include "support_files.h"
#include "support_render.h"

static bool sanitized(void) { return getenv("SG_SANITIZED") != NULL; }

/* ---- scenes as JSON, built in C --------------------------------------- */

/* A scene under construction: every coordinate goes through
 * p -> scale * p + shift, so that one scene can be built at any unit. */
typedef struct Json {
    SgTestText meshes, lights;
    double scale, shift[3];
    int mesh_count, light_count;
} Json;

static Json json_new(double scale, double shift)
{
    Json j = {.scale = scale, .shift = {shift, shift, shift}};
    return j;
}

static void put_point(SgTestText *t, const Json *j, const double p[3])
{
    sg_test_put(t, "%.17g, %.17g, %.17g", j->scale * p[0] + j->shift[0], j->scale * p[1] + j->shift[1],
        j->scale * p[2] + j->shift[2]);
}

/* One mesh of triangles over its own vertices. */
static void add_mesh(Json *j, const double (*v)[3], int nv, const int *tri, int nt, const char *material)
{
    SgTestText *t = &j->meshes;
    sg_test_put(t, "%s\n    { \"vertices\": [", j->mesh_count++ ? "," : "");
    for (int i = 0; i < nv; i++) {
        sg_test_put(t, i ? ", " : "");
        put_point(t, j, v[i]);
    }
    sg_test_put(t, "], \"triangles\": [");
    for (int i = 0; i < 3 * nt; i++)
        sg_test_put(t, "%s%d", i ? ", " : "", tri[i]);
    sg_test_put(t, "], \"material\": \"%s\" }", material);
}

/* Quads c0 c1 c2 c3 (normal (c1 - c0) x (c2 - c0)) as one mesh. */
static void add_quads(Json *j, const double (*q)[4][3], int n, const char *material)
{
    double (*v)[3] = malloc(sizeof(double[3]) * 4 * (size_t)n);
    int *tri = malloc(sizeof(int) * 6 * (size_t)n);
    for (int i = 0; i < n; i++) {
        memcpy(v + 4 * i, q[i], sizeof(double[4][3]));
        const int t[6] = {4 * i, 4 * i + 1, 4 * i + 2, 4 * i, 4 * i + 2, 4 * i + 3};
        memcpy(tri + 6 * i, t, sizeof t);
    }
    add_mesh(j, (const double(*)[3])v, 4 * n, tri, 2 * n, material);
    free(v);
    free(tri);
}

static void add_light(Json *j, const double q[4][3], double radiance)
{
    SgTestText *t = &j->lights;
    sg_test_put(t, "%s\n    { \"type\": \"quad\", \"corners\": [", j->light_count++ ? "," : "");
    for (int c = 0; c < 4; c++) {
        sg_test_put(t, "%s[", c ? ", " : "");
        put_point(t, j, q[c]);
        sg_test_put(t, "]");
    }
    sg_test_put(t, "], \"radiance\": [%g, %g, %g] }", radiance, radiance, radiance);
}

/* Writes dir/name with the camera at pos looking at `at`; frees j. */
static const char *json_write(Json *j, const char *dir, const char *name, const double pos[3],
                              const double at[3], int width, int height)
{
    SgTestText t = {0};
    sg_test_put(&t, "{ \"meshes\": [%s ],\n", j->meshes.data ? j->meshes.data : "");
    sg_test_put(&t, "  \"materials\": { \"white\": { \"type\": \"diffuse\", \"albedo\": [0.7, 0.7, 0.7] },\n"
            "                 \"grey\": { \"type\": \"diffuse\", \"albedo\": [0.4, 0.4, 0.4] } },\n");
    sg_test_put(&t, "  \"lights\": [%s ],\n", j->lights.data ? j->lights.data : "");
    sg_test_put(&t, "  \"camera\": { \"position\": [");
    put_point(&t, j, pos);
    sg_test_put(&t, "], \"look_at\": [");
    put_point(&t, j, at);
    sg_test_put(&t, "], \"up\": [0, 1, 0], \"fov\": 70 },\n");
    sg_test_put(&t, "  \"image\": { \"width\": %d, \"height\": %d },\n", width, height);
    sg_test_put(&t, "  \"render\": { \"max_depth\": 6 } }\n");
    const char *path = sg_test_write(dir, name, t.data);
    free(t.data);
    free(j->meshes.data);
    free(j->lights.data);
    memset(j, 0, sizeof *j);
    return path;
}

/* The faces of the box [lo, hi], each wound so that its normal points in. */
static void box_inward(const double lo[3], const double hi[3], double q[6][4][3])
{
    for (int axis = 0; axis < 3; axis++)
        for (int side = 0; side < 2; side++) {
            int u = (axis + 1) % 3, v = (axis + 2) % 3;
            /* (u, v) counter-clockwise: normal +axis; clockwise: -axis */
            const int ccw[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
            const int cw[4][2] = {{0, 0}, {0, 1}, {1, 1}, {1, 0}};
            const int (*order)[2] = side ? cw : ccw;
            for (int c = 0; c < 4; c++) {
                double *p = q[2 * axis + side][c];
                p[axis] = side ? hi[axis] : lo[axis];
                p[u] = order[c][0] ? hi[u] : lo[u];
                p[v] = order[c][1] ? hi[v] : lo[v];
            }
        }
}

/* A square light of side `size` centred at c in the plane normal to `axis`,
 * facing sign * axis. */
static void light_square(const double c[3], double size, int axis, int sign, double q[4][3])
{
    int u = (axis + 1) % 3, v = (axis + 2) % 3;
    const int ccw[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    const int cw[4][2] = {{0, 0}, {0, 1}, {1, 1}, {1, 0}};
    const int (*order)[2] = sign > 0 ? ccw : cw;
    for (int k = 0; k < 4; k++) {
        q[k][axis] = c[axis];
        q[k][u] = c[u] + size * (order[k][0] - 0.5);
        q[k][v] = c[v] + size * (order[k][1] - 0.5);
    }
}

/* The six walls of the box [lo, hi] facing inwards (the first `walls` of
 * them: box_inward's order), of one material. */
static void add_box(Json *j, const double lo[3], const double hi[3], int walls, const char *material)
{
    double box[6][4][3];
    box_inward(lo, hi, box);
    add_quads(j, (const double(*)[4][3])box, walls, material);
}

/* A square light (light_square) of that radiance. */
static void add_square_light(Json *j, const double c[3], double size, int axis, int sign, double radiance)
{
    double l[4][3];
    light_square(c, size, axis, sign, l);
    add_light(j, l, radiance);
}

/* The box [lo, hi] of white walls lit by one square light, at unit scale. */
static Json lit_box(const double lo[3], const double hi[3], const double c[3], double size, int axis, int sign,
                    double radiance)
{
    Json j = json_new(1, 0);
    add_box(&j, lo, hi, 6, "white");
    add_square_light(&j, c, size, axis, sign, radiance);
    return j;
}

/* Two rooms [0,2]^3 and [2,4]x[0,2]^2 joined by a door in the wall x = 2
 * (z in [0.7, 1.3], y below 1.2; no door: sealed). The light is on room A's
 * ceiling; the camera in room B sees the door: B is lit only indirectly. */
static Json two_rooms(double scale, double shift, bool door)
{
    Json j = json_new(scale, shift);
    const double lo[3] = {0, 0, 0}, hi[3] = {4, 2, 2};
    add_box(&j, lo, hi, 6, "white");
    if (door) {
        const double wall[3][4][3] = {
            {{2, 0, 0}, {2, 2, 0}, {2, 2, 0.7}, {2, 0, 0.7}},
            {{2, 0, 1.3}, {2, 2, 1.3}, {2, 2, 2}, {2, 0, 2}},
            {{2, 1.2, 0.7}, {2, 2, 0.7}, {2, 2, 1.3}, {2, 1.2, 1.3}},
        };
        add_quads(&j, wall, 3, "grey");
    } else {
        const double wall[1][4][3] = {{{2, 0, 0}, {2, 2, 0}, {2, 2, 2}, {2, 0, 2}}};
        add_quads(&j, wall, 1, "grey");
    }
    return j;
}

static const double room_b_camera[3] = {3.7, 1.0, 1.0}, room_b_target[3] = {2.0, 0.8, 1.0};
static const double ceiling_light_centre[3] = {1.0, 1.98, 1.0};

/* json_write with the camera in room B, looking at the door, 32x24. */
static const char *json_write_room_b(Json *j, const char *dir, const char *name)
{
    return json_write(j, dir, name, room_b_camera, room_b_target, 32, 24);
}

/* The reference scene at a unit and offset. */
static const char *base_scene(const char *dir, const char *name, double scale, double shift)
{
    Json j = two_rooms(scale, shift, true);
    add_square_light(&j, ceiling_light_centre, 0.5, 1, -1, 20);
    return json_write_room_b(&j, dir, name);
}

/* ---- running the programs ----------------------------------------------- */

typedef struct Result {
    int status;           /* 0: every step succeeded */
    char step[16];        /* the step that failed */
    char err[4096];       /* its stderr (or render's, on success) */
    char voxelize_err[4096];
    double mean;          /* mean radiance over pixels and channels */
    bool finite;          /* every pixel finite */
    float *rgb;           /* the image (caller frees) */
    int width, height;
} Result;

static const char *prog(const char *name)
{
    static char bufs[4][4096];
    static int next;
    char *b = bufs[next++ % 4];
    return sg_test_program(name, b, 4096);
}

static int spp_for_tests(void) { return sanitized() ? 8 : 16; }

/* voxelize -> skeletonize -> importance -> render --cache. Outputs go to
 * dir/tag.{vdb,ply,cache,exr}. */
static Result pipeline(const char *dir, const char *scene, const char *tag, int resolution, int spp,
                       int seed, const char *env)
{
    Result r = {0};
    char cmd[16384];
    const char *e = env ? env : "";
    snprintf(cmd, sizeof cmd, "%s %s '%s' -o %s/%s.vdb --resolution %d --threads 2", e, prog("voxelize"),
             scene, dir, tag, resolution);
    r.status = sg_test_run(cmd, r.err, sizeof r.err);
    memcpy(r.voxelize_err, r.err, sizeof r.err);
    if (r.status) {
        strcpy(r.step, "voxelize");
        return r;
    }
    snprintf(cmd, sizeof cmd, "%s %s %s/%s.vdb -o %s/%s.ply --threads 2", e, prog("skeletonize"), dir, tag,
             dir, tag);
    if ((r.status = sg_test_run(cmd, r.err, sizeof r.err))) {
        strcpy(r.step, "skeletonize");
        return r;
    }
    snprintf(cmd, sizeof cmd, "%s %s %s/%s.vdb %s/%s.ply -o %s/%s.cache --threads 2", e, prog("importance"),
             dir, tag, dir, tag, dir, tag);
    if ((r.status = sg_test_run(cmd, r.err, sizeof r.err))) {
        strcpy(r.step, "importance");
        return r;
    }
    snprintf(cmd, sizeof cmd, "%s %s '%s' --cache %s/%s.cache --spp %d --seed %d --threads 2 -o %s/%s.exr",
             e, prog("render"), scene, dir, tag, spp, seed, dir, tag);
    if ((r.status = sg_test_run(cmd, r.err, sizeof r.err))) {
        strcpy(r.step, "render");
        return r;
    }
    char path[4200];
    snprintf(path, sizeof path, "%s/%s.exr", dir, tag);
    SgError err = {0};
    cr_assert(sg_image_read(path, &r.width, &r.height, &r.rgb, &err), "%s", err.message);
    size_t n = (size_t)r.width * r.height * 3;
    double sum = 0;
    r.finite = true;
    for (size_t i = 0; i < n; i++) {
        r.finite = r.finite && isfinite(r.rgb[i]);
        sum += r.rgb[i];
    }
    r.mean = sum / (double)n;
    return r;
}

/* A successful run: every step exit 0, a finite image, and render's own
 * count of non-finite samples at zero. */
static Result pipeline_ok(const char *dir, const char *scene, const char *tag, int resolution, int spp,
                          int seed)
{
    Result r = pipeline(dir, scene, tag, resolution, spp, seed, NULL);
    cr_assert_eq(r.status, 0, "%s: %s failed: %s", tag, r.step, r.err);
    cr_assert(r.finite, "%s: the image holds NaN or infinity", tag);
    cr_assert(strstr(r.err, " 0 NaN/inf") != NULL, "%s: render summary: %s", tag, r.err);
    return r;
}

/* Standard error of an image's mean, from two renders that differ only in
 * the seed: var(a - b) = 2 var(pixel). */
static double mean_std_error(const Result *a, const Result *b)
{
    size_t n = (size_t)a->width * a->height * 3;
    double s2 = 0;
    for (size_t i = 0; i < n; i++) {
        double d = (double)a->rgb[i] - b->rgb[i];
        s2 += d * d;
    }
    return sqrt(s2 / 2.0) / (double)n;
}

/* The reference scene (base_scene, as TAG.json) rendered with seeds 1 and 2
 * (TAG, TAG2): the first render; *se the standard error of its mean; the
 * second render in *second, or freed where second is NULL. */
static Result reference_renders(const char *dir, const char *tag, int res, int spp, double *se, Result *second)
{
    char scene[64], tag2[64];
    snprintf(scene, sizeof scene, "%s.json", tag);
    snprintf(tag2, sizeof tag2, "%s2", tag);
    Result ref = pipeline_ok(dir, base_scene(dir, scene, 1, 0), tag, res, spp, 1);
    Result ref2 = pipeline_ok(dir, base_scene(dir, scene, 1, 0), tag2, res, spp, 2);
    *se = mean_std_error(&ref, &ref2);
    if (second)
        *second = ref2;
    else
        free(ref2.rgb);
    return ref;
}

/* Means of two independent-noise estimates agree within k standard errors. */
static void assert_same_mean(const Result *a, const Result *b, double se, double k, const char *what)
{
    double tol = k * sqrt(2.0) * se;
    cr_log_info("%s: mean %.5f vs %.5f (tolerance %.5f)", what, a->mean, b->mean, tol);
    cr_assert(fabs(a->mean - b->mean) <= tol, "%s: mean %.5f vs %.5f, tolerance %.5f", what, a->mean,
              b->mean, tol);
}

/* A render against its reference (reference_renders) at 5 standard errors;
 * both images are freed. */
static void assert_like_reference(Result *r, Result *ref, double se, const char *what)
{
    assert_same_mean(r, ref, se, 5, what);
    free(r->rgb);
    free(ref->rgb);
}

/* Non-zero status; the error is the last line of stderr, names the file
 * and the cause; any line before it is a warning of the same program. */
static void assert_refused(const Result *r, const char *step, const char *file, const char *cause)
{
    cr_assert_neq(r->status, 0, "expected %s to refuse", step);
    cr_assert_str_eq(r->step, step, "refused by %s, not %s: %s", r->step, step, r->err);
    char prefix[32];
    snprintf(prefix, sizeof prefix, "%s: ", step);
    const char *last = r->err;
    for (const char *line = r->err; *line;) {
        cr_assert(strncmp(line, prefix, strlen(prefix)) == 0, "a line not from %s: %s", step, r->err);
        last = line;
        const char *nl = strchr(line, '\n');
        if (!nl)
            break;
        line = nl + 1;
    }
    cr_assert(strstr(last, file) != NULL, "does not name %s: %s", file, last);
    if (cause)
        cr_assert(strstr(last, cause) != NULL, "does not say '%s': %s", cause, last);
}

static bool exists2(const char *dir, const char *name)
{
    char p[4200];
    snprintf(p, sizeof p, "%s/%s", dir, name);
    return sg_test_exists(p);
}

/* ---- units and placement ------------------------------------------------ */

Test(stress, same_image_at_any_unit_and_far_from_origin, .timeout = 240)
{
    const char *dir = sg_test_tmpdir();
    const int spp = spp_for_tests(), res = 24;
    Result ref2;
    double se;
    Result ref = reference_renders(dir, "unit", res, spp, &se, &ref2);
    cr_assert_gt(ref.mean, 0.0, "the reference scene renders black");
    cr_assert_gt(se, 0.0);
    /* the noise estimate must be a small fraction of the signal, or the test
     * could not tell anything apart */
    cr_assert_lt(se, 0.2 * ref.mean, "standard error %.5f vs mean %.5f", se, ref.mean);
    assert_same_mean(&ref, &ref2, se, 5, "two seeds");

    const struct {
        double scale, shift;
        const char *tag;
    } cases[] = {{1e5, 0, "huge"}, {1e-4, 1e6 * 1e-4, "tiny_far"}, {1e-4, 0, "tiny"}, {1, 1e6, "far"}};
    /* under the sanitizers the two that combine the others (every
     * extreme's code runs in them) */
    size_t count = sanitized() ? 2 : sizeof cases / sizeof cases[0];
    for (size_t c = 0; c < count; c++) {
        char name[64];
        snprintf(name, sizeof name, "%s.json", cases[c].tag);
        Result r = pipeline_ok(dir, base_scene(dir, name, cases[c].scale, cases[c].shift), cases[c].tag,
                               res, spp, 1);
        /* the grid, the skeleton and the image do not depend on the unit */
        cr_assert(strstr(r.voxelize_err, "24x12x12 voxels") != NULL, "%s: %s", cases[c].tag,
                  r.voxelize_err);
        assert_same_mean(&r, &ref, se, 5, cases[c].tag);
        free(r.rgb);
    }
    free(ref.rgb);
    free(ref2.rgb);
}

/* ---- messy geometry ----------------------------------------------------- */

Test(stress, degenerate_duplicated_flipped_and_cracked_geometry, .timeout = 240)
{
    const char *dir = sg_test_tmpdir();
    const int spp = spp_for_tests(), res = 24;
    double se;
    Result ref = reference_renders(dir, "clean", res, spp, &se, NULL);

    Json j = json_new(1, 0);
    /* the outer box with its +z wall split in two along x = 3, the halves
     * 1e-6 apart: a crack far below a voxel */
    const double lo[3] = {0, 0, 0}, hi[3] = {4, 2, 2};
    add_box(&j, lo, hi, 5, "white");
    const double cracked[2][4][3] = {
        {{0, 0, 2}, {0, 2, 2}, {3, 2, 2}, {3, 0, 2}},
        {{3 + 1e-6, 0, 2}, {3 + 1e-6, 2, 2}, {4, 2, 2}, {4, 0, 2}},
    };
    add_quads(&j, cracked, 2, "white");
    /* the partition twice, and once more with the opposite winding */
    for (int copy = 0; copy < 2; copy++) {
        const double wall[3][4][3] = {
            {{2, 0, 0}, {2, 2, 0}, {2, 2, 0.7}, {2, 0, 0.7}},
            {{2, 0, 1.3}, {2, 2, 1.3}, {2, 2, 2}, {2, 0, 2}},
            {{2, 1.2, 0.7}, {2, 2, 0.7}, {2, 2, 1.3}, {2, 1.2, 1.3}},
        };
        add_quads(&j, wall, 3, "grey");
    }
    const double flipped[3][4][3] = {
        {{2, 0, 0}, {2, 0, 0.7}, {2, 2, 0.7}, {2, 2, 0}},
        {{2, 0, 1.3}, {2, 0, 2}, {2, 2, 2}, {2, 2, 1.3}},
        {{2, 1.2, 0.7}, {2, 1.2, 1.3}, {2, 2, 1.3}, {2, 2, 0.7}},
    };
    add_quads(&j, flipped, 3, "grey");
    /* the floor again, flipped */
    const double floor_flipped[1][4][3] = {{{0, 0, 0}, {0, 0, 2}, {4, 0, 2}, {4, 0, 0}}};
    add_quads(&j, floor_flipped, 1, "white");
    /* degenerate triangles: a repeated vertex, collinear points, a point */
    const double deg_v[6][3] = {{1, 1, 1}, {1, 1, 1}, {1.5, 1, 1}, {3, 0.5, 0.5}, {3.2, 0.6, 0.6}, {3.4, 0.7, 0.7}};
    const int deg_t[9] = {0, 1, 2, 3, 4, 5, 0, 0, 0};
    add_mesh(&j, deg_v, 6, deg_t, 3, "white");
    /* tiny triangles floating in both rooms (1e-9 of the scene) */
    const double tiny_v[6][3] = {{1, 1, 1}, {1 + 1e-9, 1, 1}, {1, 1 + 1e-9, 1},
                                 {3, 1, 0.5}, {3, 1 + 2e-9, 0.5}, {3, 1, 0.5 + 2e-9}};
    const int tiny_t[6] = {0, 1, 2, 3, 4, 5};
    add_mesh(&j, tiny_v, 6, tiny_t, 2, "white");
    add_square_light(&j, ceiling_light_centre, 0.5, 1, -1, 20);
    const char *messy = json_write_room_b(&j, dir, "messy.json");
    Result r = pipeline_ok(dir, messy, "messy", res, spp, 1);
    /* the same grid, and the same image up to noise */
    cr_assert(strstr(r.voxelize_err, "24x12x12 voxels") != NULL, "%s", r.voxelize_err);
    assert_like_reference(&r, &ref, se, "messy vs clean");
}

/* ---- lights ------------------------------------------------------------- */

Test(stress, zero_area_lights, .timeout = 240)
{
    const char *dir = sg_test_tmpdir();
    const int spp = spp_for_tests(), res = 24;
    /* the only light has no area: refused, naming the scene */
    const double flat[4][3] = {{1, 1.98, 1}, {1.5, 1.98, 1}, {1.5, 1.98, 1}, {1, 1.98, 1}};
    const double point[4][3] = {{1, 1.98, 1}, {1, 1.98, 1}, {1, 1.98, 1}, {1, 1.98, 1}};
    Json j = two_rooms(1, 0, true);
    add_light(&j, flat, 20);
    add_light(&j, point, 20);
    const char *dark = json_write_room_b(&j, dir, "zero_light.json");
    Result r = pipeline(dir, dark, "zero", res, spp, 1, NULL);
    assert_refused(&r, "voxelize", "zero_light.json", "light");
    cr_assert_not(exists2(dir, "zero.vdb"));
    /* beside a real light they change nothing */
    double se;
    Result ref = reference_renders(dir, "ref", res, spp, &se, NULL);
    j = two_rooms(1, 0, true);
    double l[4][3];
    light_square(ceiling_light_centre, 0.5, 1, -1, l);
    add_light(&j, flat, 20);
    add_light(&j, l, 20);
    add_light(&j, point, 20);
    Result both = pipeline_ok(dir, json_write_room_b(&j, dir, "with_zero.json"),
                              "with_zero", res, spp, 1);
    assert_like_reference(&both, &ref, se, "real light + zero-area lights");
}

Test(stress, light_flush_with_the_ceiling_and_touching_a_wall, .timeout = 240)
{
    const char *dir = sg_test_tmpdir();
    const int spp = spp_for_tests(), res = 24;
    Json j = two_rooms(1, 0, true);
    /* exactly in the ceiling's plane (coplanar, facing down) */
    const double flush_c[3] = {1.0, 2.0, 1.0};
    double flush[4][3];
    light_square(flush_c, 0.5, 1, -1, flush);
    add_light(&j, flush, 20);
    /* vertical, one edge on the wall x = 0, facing +z */
    const double side[4][3] = {{0, 0.5, 1.5}, {0.4, 0.5, 1.5}, {0.4, 0.9, 1.5}, {0, 0.9, 1.5}};
    add_light(&j, side, 20);
    /* in a corner of room B, touching three walls, facing down */
    const double corner[4][3] = {{4, 2, 2}, {3.7, 2, 2}, {3.7, 2, 1.7}, {4, 2, 1.7}};
    add_light(&j, corner, 5);
    const char *scene = json_write_room_b(&j, dir, "touching.json");
    Result r = pipeline_ok(dir, scene, "touching", res, spp, 1);
    cr_assert_gt(r.mean, 0.0);
    cr_assert(strstr(r.voxelize_err, "3 light(s)") != NULL, "%s", r.voxelize_err);
    free(r.rgb);
}

Test(stress, light_sealed_in_a_closed_box, .timeout = 240)
{
    const char *dir = sg_test_tmpdir();
    const int spp = spp_for_tests(), res = 24;
    /* a closed box around the only light, in room A: the air inside the box
     * is the medium; the camera outside sees nothing lit */
    const double lo[3] = {0.6, 0.6, 0.6}, hi[3] = {1.4, 1.4, 1.4};
    double box[6][4][3];
    box_inward(lo, hi, box);
    const double c[3] = {1.0, 1.3, 1.0};
    double inner[4][3];
    light_square(c, 0.2, 1, -1, inner);
    Json j = two_rooms(1, 0, true);
    add_quads(&j, (const double(*)[4][3])box, 6, "grey");
    add_light(&j, inner, 20);
    const char *boxed = json_write_room_b(&j, dir, "boxed.json");
    Result r = pipeline_ok(dir, boxed, "boxed", res, spp, 1);
    cr_assert_eq(r.mean, 0.0, "light escaped a closed box: mean %g", r.mean);
    cr_assert(strstr(r.voxelize_err, "camera") != NULL, "voxelize does not warn: %s", r.voxelize_err);
    free(r.rgb);

    /* a box smaller than a voxel: the grid cannot see inside, voxelize takes
     * the nearest air as the light's (a harmless guess); the image stays
     * exactly black */
    const double tlo[3] = {0.95, 0.95, 0.95}, thi[3] = {1.05, 1.05, 1.05};
    box_inward(tlo, thi, box);
    const double tc[3] = {1.0, 1.02, 1.0};
    light_square(tc, 0.05, 1, -1, inner);
    j = two_rooms(1, 0, true);
    add_quads(&j, (const double(*)[4][3])box, 6, "grey");
    add_light(&j, inner, 20);
    const char *tiny = json_write_room_b(&j, dir, "tiny_box.json");
    r = pipeline_ok(dir, tiny, "tiny_box", res, spp, 1);
    cr_assert_eq(r.mean, 0.0, "light escaped a closed box: mean %g", r.mean);
    free(r.rgb);

    /* beside a free light: the image is lit */
    j = two_rooms(1, 0, true);
    add_quads(&j, (const double(*)[4][3])box, 6, "grey");
    add_light(&j, inner, 20);
    add_square_light(&j, ceiling_light_centre, 0.5, 1, -1, 20);
    const char *one_sealed = json_write_room_b(&j, dir, "one_sealed.json");
    Result ok = pipeline_ok(dir, one_sealed, "one_sealed", res, spp, 1);
    cr_assert_gt(ok.mean, 0.0);
    free(ok.rgb);
}

Test(stress, camera_in_a_room_no_light_reaches, .timeout = 240)
{
    const char *dir = sg_test_tmpdir();
    Json j = two_rooms(1, 0, false);
    add_square_light(&j, ceiling_light_centre, 0.5, 1, -1, 20);
    const char *scene = json_write_room_b(&j, dir, "dark.json");
    Result r = pipeline_ok(dir, scene, "dark", 24, spp_for_tests(), 1);
    /* exactly black: no path from this room reaches the light */
    cr_assert_eq(r.mean, 0.0, "mean %g", r.mean);
    cr_assert(strstr(r.voxelize_err, "camera") != NULL, "voxelize does not warn: %s", r.voxelize_err);
    free(r.rgb);
}

/* ---- grids -------------------------------------------------------------- */

/* A box lit by a unit square light (light_square's axis and sign), seen
 * from pos toward at: at resolution res its medium is `voxels` voxels and
 * the image is not black. */
static void assert_box_medium(const char *name, const double lo[3], const double hi[3], const double light[3],
                              int axis, int sign, double radiance, const double pos[3], const double at[3],
                              int res, int voxels)
{
    const char *dir = sg_test_tmpdir();
    Json j = lit_box(lo, hi, light, 1.0, axis, sign, radiance);
    char file[64], summary[64];
    snprintf(file, sizeof file, "%s.json", name);
    snprintf(summary, sizeof summary, "medium %d voxels", voxels);
    const char *scene = json_write(&j, dir, file, pos, at, 16, 12);
    Result r = pipeline_ok(dir, scene, name, res, spp_for_tests(), 1);
    cr_assert(strstr(r.voxelize_err, summary) != NULL, "%s", r.voxelize_err);
    cr_assert_gt(r.mean, 0.0);
    free(r.rgb);
}

Test(stress, medium_of_one_voxel, .timeout = 240)
{
    /* a 3 x 3 x 3 room at resolution 3: every voxel but the centre one
     * touches a wall */
    const double lo[3] = {0, 0, 0}, hi[3] = {3, 3, 3}, c[3] = {1.5, 2.999, 1.5};
    const double pos[3] = {1.5, 1.5, 1.2}, at[3] = {1.5, 1.0, 3};
    assert_box_medium("one", lo, hi, c, 1, -1, 5, pos, at, 3, 1);
}

Test(stress, corridor_one_voxel_wide, .timeout = 240)
{
    /* [0,20] x [0,3] x [0,3] at resolution 20: the air is 18 x 1 x 1 voxels */
    const double lo[3] = {0, 0, 0}, hi[3] = {20, 3, 3}, c[3] = {0.001, 1.5, 1.5};
    const double pos[3] = {18.5, 1.5, 1.5}, at[3] = {0, 1.5, 1.5};
    assert_box_medium("corridor", lo, hi, c, 0, +1, 50, pos, at, 20, 18);
}

/* Work larger than the memory available is refused before it allocates,
 * with the size in the message (SG_MEMORY_LIMIT_MB plays a small machine;
 * the real limit refuses the same way). */
Test(stress, larger_than_memory_is_refused_cleanly, .timeout = 240)
{
    const char *dir = sg_test_tmpdir();
    const char *scene = base_scene(dir, "big.json", 1, 0);
    char cmd[16384], err[4096];
    /* a 1024 x 512 x 512 grid (256 MB) on a "64 MB machine" */
    snprintf(cmd, sizeof cmd, "SG_MEMORY_LIMIT_MB=64 %s '%s' -o %s/big.vdb --resolution 1024", prog("voxelize"),
             scene, dir);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 1, "%s", err);
    cr_assert_eq(sg_test_count_lines(err), 1, "%s", err);
    cr_assert(strstr(err, "big.json") && strstr(err, "1024x512x512") && strstr(err, "MB of memory"), "%s", err);
    cr_assert_not(exists2(dir, "big.vdb"));
    /* the largest resolution on a cube: 4096^3 bytes, 64 GB; run only where
     * the machine has less, so that it must be refused (before allocating) */
    if ((double)sysconf(_SC_PHYS_PAGES) * sysconf(_SC_PAGESIZE) < 60e9) {
        const double lo[3] = {0, 0, 0}, hi[3] = {2, 2, 2};
        const double c[3] = {1, 1.99, 1}, pos[3] = {1, 1, 0.3}, at[3] = {1, 1, 2};
        Json j = lit_box(lo, hi, c, 0.5, 1, -1, 5);
        const char *cube = json_write(&j, dir, "cube.json", pos, at, 16, 12);
        snprintf(cmd, sizeof cmd, "%s '%s' -o %s/cube.vdb --resolution 4096", prog("voxelize"), cube, dir);
        cr_assert_eq(sg_test_run(cmd, err, sizeof err), 1, "%s", err);
        cr_assert(sg_test_count_lines(err) == 1 && strstr(err, "4096x4096x4096") && strstr(err, "memory"),
                  "%s", err);
        cr_assert_not(exists2(dir, "cube.vdb"));
    }
    /* the later steps on a medium that fits, with a machine too small */
    Result ok = pipeline_ok(dir, scene, "fits", 48, 1, 1);
    free(ok.rgb);
    snprintf(cmd, sizeof cmd, "SG_MEMORY_LIMIT_MB=0.1 %s %s/fits.vdb -o %s/small.ply", prog("skeletonize"), dir, dir);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 1, "%s", err);
    cr_assert(sg_test_count_lines(err) == 1 && strstr(err, "fits.vdb") && strstr(err, "MB of memory"), "%s", err);
    cr_assert_not(exists2(dir, "small.ply"));
    snprintf(cmd, sizeof cmd, "SG_MEMORY_LIMIT_MB=0.1 %s %s/fits.vdb %s/fits.ply -o %s/small.cache",
             prog("importance"), dir, dir, dir);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 1, "%s", err);
    cr_assert(sg_test_count_lines(err) == 1 && strstr(err, "fits.vdb") && strstr(err, "MB of memory"), "%s", err);
    cr_assert_not(exists2(dir, "small.cache"));
    /* an image of 30000 x 30000 pixels on a 1 GB machine */
    snprintf(cmd, sizeof cmd, "SG_MEMORY_LIMIT_MB=1024 %s '%s' --size 30000x30000 --spp 1 -o %s/huge.exr",
             prog("render"), scene, dir);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 1, "%s", err);
    cr_assert(sg_test_count_lines(err) == 1 && strstr(err, "30000x30000") && strstr(err, "MB of memory"), "%s", err);
    cr_assert_not(exists2(dir, "huge.exr"));
}

/* ---- interrupted runs --------------------------------------------------- */

static long file_size(const char *dir, const char *name)
{
    char p[4200];
    snprintf(p, sizeof p, "%s/%s", dir, name);
    struct stat st;
    return stat(p, &st) == 0 ? (long)st.st_size : -1;
}

/* Files in dir whose name starts with prefix. */
static int count_prefixed(const char *dir, const char *prefix)
{
    char cmd[8192];
    snprintf(cmd, sizeof cmd, "ls -A '%s' | grep -c '^%s' > '%s/.count'", dir, prefix, dir);
    (void)!system(cmd);
    char p[4200];
    snprintf(p, sizeof p, "%s/.count", dir);
    FILE *f = fopen(p, "r");
    int n = -1;
    if (f) {
        if (fscanf(f, "%d", &n) != 1)
            n = -1;
        fclose(f);
    }
    remove(p);
    return n;
}

/* Each program, killed by SIGXFSZ after 512 bytes of its output (a kill
 * mid-write), then on a "full disk" (the same limit with SIGXFSZ ignored:
 * writes fail with EFBIG): no file under the target's name, a one-line
 * error for the full disk, the previous output untouched, and the next
 * successful run removes the dead run's temporary. */
Test(stress, killed_or_full_disk_leaves_no_partial_output, .timeout = 240)
{
    const char *dir = sg_test_tmpdir();
    const char *scene = base_scene(dir, "cut.json", 1, 0);
    Result ok = pipeline_ok(dir, scene, "ok", 32, 1, 1);
    free(ok.rgb);
    const struct {
        const char *step, *out, *command;
    } steps[] = {
        {"voxelize", "m.vdb", "%s '%s' -o %s/m.vdb --resolution 32"},
        {"skeletonize", "s.ply", "%s %s/ok.vdb -o %s/s.ply"},
        {"importance", "c.cache", "%s %s/ok.vdb %s/ok.ply -o %s/c.cache"},
        {"render", "i.exr", "%s '%s' --cache %s/ok.cache --spp 1 -o %s/i.exr"},
    };
    for (size_t s = 0; s < sizeof steps / sizeof steps[0]; s++) {
        char run[8192];
        if (s == 0 || s == 3)
            snprintf(run, sizeof run, steps[s].command, prog(steps[s].step), s == 0 ? scene : scene, dir, dir);
        else
            snprintf(run, sizeof run, steps[s].command, prog(steps[s].step), dir, dir, dir);
        char cmd[16384], err[4096];
        /* the complete output must be larger than the limit */
        cr_assert_eq(sg_test_run(run, err, sizeof err), 0, "%s: %s", steps[s].step, err);
        long full = file_size(dir, steps[s].out);
        cr_assert_gt(full, 512, "%s: output of %ld bytes is too small for this test", steps[s].step, full);
        char tmp_prefix[64];
        snprintf(tmp_prefix, sizeof tmp_prefix, "\\.%s\\.tmp\\.", steps[s].out);
        char out_path[4200];
        snprintf(out_path, sizeof out_path, "%s/%s", dir, steps[s].out);
        remove(out_path);

        /* killed mid-write */
        snprintf(cmd, sizeof cmd, "ulimit -f 1; exec %s", run);
        int rc = sg_test_run(cmd, err, sizeof err);
        cr_assert_neq(rc, 0, "%s was not interrupted", steps[s].step);
        cr_assert_not(sg_test_exists(out_path), "%s: a killed run left %s", steps[s].step, steps[s].out);
        /* a temporary may remain (a writer that saw the failure removes it) */
        cr_assert_leq(count_prefixed(dir, tmp_prefix), 1, "%s", steps[s].step);

        /* full disk: writes fail */
        snprintf(cmd, sizeof cmd, "trap '' XFSZ; ulimit -f 1; exec %s", run);
        rc = sg_test_run(cmd, err, sizeof err);
        cr_assert_eq(rc, 1, "%s on a full disk: exit %d: %s", steps[s].step, rc, err);
        cr_assert_not(sg_test_exists(out_path), "%s: a failed write left %s", steps[s].step, steps[s].out);
        char last[4096];
        const char *nl = strrchr(err, '\n');
        const char *start = err;
        for (const char *c = err; nl && c < nl; c++)
            if (*c == '\n')
                start = c + 1;
        snprintf(last, sizeof last, "%.*s", nl ? (int)(nl - start) : (int)strlen(start), start);
        cr_assert(strstr(last, steps[s].out) != NULL, "%s: error does not name the output: %s",
                  steps[s].step, err);

        /* a good run: complete output, stale temporary gone */
        cr_assert_eq(sg_test_run(run, err, sizeof err), 0, "%s: %s", steps[s].step, err);
        cr_assert_eq(file_size(dir, steps[s].out), full, "%s", steps[s].step);
        cr_assert_eq(count_prefixed(dir, tmp_prefix), 0, "%s: a stale temporary survived the next run",
                     steps[s].step);

        /* full disk again: the previous output stays as it was */
        snprintf(cmd, sizeof cmd, "trap '' XFSZ; ulimit -f 1; exec %s", run);
        cr_assert_eq(sg_test_run(cmd, err, sizeof err), 1, "%s", steps[s].step);
        cr_assert_eq(file_size(dir, steps[s].out), full, "%s: the previous output changed", steps[s].step);
    }
}

/* ---- the renderer's sampling at its limits ------------------------------- */

static bool finite3(Vec3 v) { return isfinite(v.x) && isfinite(v.y) && isfinite(v.z); }

static const float exponents[] = {0.0f, 1e-6f, 0.5f, 1.0f, 10.0f, 1e3f, 1e4f, 1e5f};
/* 0, the smallest steps away from 0 and 1, and the largest float below 1 */
static const float edge_u[] = {0.0f, 1e-7f, 0.25f, 0.5f, 0.9999f, 0.99999994f};

static void check_direction(Vec3 w, float pdf, const char *what, float p, float u1, float u2)
{
    cr_assert(finite3(w), "%s p=%g u=(%g,%g): non-finite direction", what, p, u1, u2);
    float len = sqrtf(v3_dot(w, w));
    cr_assert(fabsf(len - 1.0f) < 1e-3f, "%s p=%g u=(%g,%g): |w| = %g", what, p, u1, u2, len);
    cr_assert(isfinite(pdf) && pdf >= 0.0f, "%s p=%g u=(%g,%g): pdf %g", what, p, u1, u2, pdf);
}

Test(stress, lobes_at_extreme_exponents_and_edge_random_numbers)
{
    const Vec3 axes[] = {v3(0, 0, 1), v3(0, 0, -1), v3(1, 0, 0), v3(0, -1, 0),
                         v3_normalize(v3(0.3f, -0.5f, 0.81f)), v3_normalize(v3(1e-7f, 1e-7f, -1))};
    for (size_t a = 0; a < sizeof axes / sizeof axes[0]; a++)
        for (size_t e = 0; e < sizeof exponents / sizeof exponents[0]; e++)
            for (size_t i = 0; i < sizeof edge_u / sizeof edge_u[0]; i++)
                for (size_t k = 0; k < sizeof edge_u / sizeof edge_u[0]; k++) {
                    float p = exponents[e], u1 = edge_u[i], u2 = edge_u[k];
                    Vec3 w = sg_sample_cosine_power(axes[a], p, u1, u2);
                    float pdf = sg_pdf_cosine_power(axes[a], p, w);
                    check_direction(w, pdf, "cosine power", p, u1, u2);
                    cr_assert(v3_dot(w, axes[a]) >= -1e-6f, "cosine power p=%g: sample below its axis", p);
                    /* on the axis the density is (p + 1) / 2 pi, finite */
                    float peak = sg_pdf_cosine_power(axes[a], p, axes[a]);
                    cr_assert(fabsf(peak - (p + 1) / (2 * SG_PI)) <= 1e-4f * (p + 1),
                              "peak pdf %g for p=%g", peak, p);
                }
}

Test(stress, grazing_directions_and_lobes_below_the_surface)
{
    const Vec3 n = v3(0, 1, 0);
    /* guide axes on, just above and just below the tangent plane, and
     * straight into the surface */
    const Vec3 axes[] = {v3(1, 0, 0), v3_normalize(v3(1, 1e-7f, 0)), v3_normalize(v3(1, -1e-7f, 0)),
                         v3(0, -1, 0), v3_normalize(v3(0.6f, 1e-4f, -0.8f))};
    /* outgoing directions: grazing (exactly, and nearly), normal */
    const Vec3 wos[] = {v3(0, 0, 1), v3_normalize(v3(0, 1e-7f, 1)), v3(0, 1, 0),
                        v3_normalize(v3(1, 1e-3f, 1))};
    for (size_t e = 0; e < sizeof exponents / sizeof exponents[0]; e++)
        for (size_t i = 0; i < sizeof edge_u / sizeof edge_u[0]; i++)
            for (size_t k = 0; k < sizeof edge_u / sizeof edge_u[0]; k++) {
                float p = exponents[e], u1 = edge_u[i], u2 = edge_u[k];
                for (size_t a = 0; a < sizeof axes / sizeof axes[0]; a++) {
                    Vec3 w = sg_sample_folded_lobe(axes[a], n, p, u1, u2);
                    float pdf = sg_pdf_folded_lobe(axes[a], n, p, w);
                    check_direction(w, pdf, "folded lobe", p, u1, u2);
                    cr_assert(v3_dot(w, n) >= -1e-6f, "folded lobe p=%g axis %zu: sample below", p, a);
                }
                for (size_t o = 0; o < sizeof wos / sizeof wos[0]; o++)
                    for (int dw = 0; dw <= 2; dw++) {
                        SgGlossyLobe lobe = sg_glossy_lobe(n, wos[o], p, 0.5f * dw);
                        cr_assert(finite3(lobe.r), "glossy lobe: mirror direction not finite");
                        Vec3 w = sg_sample_glossy(&lobe, 0.5f * u1, u1, u2);
                        check_direction(w, sg_pdf_glossy(&lobe, w), "glossy", p, u1, u2);
                        for (size_t a = 0; a < sizeof axes / sizeof axes[0]; a++) {
                            const float alphas[] = {1e-6f, 0.5f, 1.0f};
                            for (int al = 0; al < 3; al++) {
                                Bsdf b = {.lobe = lobe, .kind = BSDF_PHONG};
                                SgFoldedLobe fl = sg_folded_lobe(axes[a], lobe.n, p);
                                Vec3 wm = bsdf_mixture_sample(&b, &fl, alphas[al], u1, u2, 1.0f - u1);
                                float pb, c1, c2;
                                float pm = bsdf_mixture_pdf(&b, &fl, alphas[al], wm, v3_dot(wm, lobe.n), &pb, &c1, &c2);
                                check_direction(wm, pm, "mixture", p, u1, u2);
                            }
                        }
                    }
            }
}

/* ---- the renderer with importance points at their limits ----------------- */

typedef struct Guide {
    int kind;
    double point[3];
} Guide;

/* 0: the query point itself; 1: NaN; 2: infinity; 3: a fixed point. */
static bool odd_guide(void *ctx, const double p[3], uint32_t light, double q[3])
{
    (void)light;
    const Guide *g = ctx;
    switch (g->kind) {
    case 0: memcpy(q, p, sizeof(double[3])); break;
    case 1: q[0] = q[1] = q[2] = NAN; break;
    case 2: q[0] = INFINITY, q[1] = -INFINITY, q[2] = INFINITY; break;
    default: memcpy(q, g->point, sizeof(double[3])); break;
    }
    return true;
}

/* Two rooms in memory (inward walls, door, light in A, camera in B). */
static SgScene *memory_two_rooms(void)
{
    SgScene *s = sgt_scene_new();
    const float white[3] = {0.7f, 0.7f, 0.7f}, emit[3] = {20, 20, 20};
    uint32_t w = sgt_add_material(s, SG_MATERIAL_DIFFUSE, white, NULL);
    uint32_t lm = sgt_add_material(s, SG_MATERIAL_DIFFUSE, NULL, emit);
    const double lo[3] = {0, 0, 0}, hi[3] = {4, 2, 2};
    sgt_add_box_inside(s, lo, hi, w);
    const double wall[3][4][3] = {
        {{2, 0, 0}, {2, 2, 0}, {2, 2, 0.7}, {2, 0, 0.7}},
        {{2, 0, 1.3}, {2, 2, 1.3}, {2, 2, 2}, {2, 0, 2}},
        {{2, 1.2, 0.7}, {2, 2, 0.7}, {2, 2, 1.3}, {2, 1.2, 1.3}},
    };
    for (int i = 0; i < 3; i++)
        sgt_add_quad(s, wall[i], w);
    double l[4][3];
    light_square(ceiling_light_centre, 0.5, 1, -1, l);
    sgt_add_quad(s, (const double(*)[3])l, lm);
    const double up[3] = {0, 1, 0};
    sgt_set_camera(s, room_b_camera, room_b_target, up, 70, 24, 18);
    sgt_finish(s);
    return s;
}

typedef struct Estimate {
    double mean, std_error;
    uint64_t nonfinite;
    bool image_finite;
} Estimate;

/* Mean over every sample, its standard error from their spread. */
static Estimate estimate(const SgScene *s, const SgRenderOptions *o, int spp)
{
    SgError err = {0};
    SgRenderer *r = sg_renderer_create(s, o, &err);
    cr_assert_not_null(r, "%s", err.message);
    double sum = 0, sum2 = 0;
    size_t n = 0, pixels = (size_t)o->width * o->height;
    for (int pass = 0; pass < spp; pass++) {
        sg_renderer_pass(r);
        const float *last = sg_renderer_last_pass(r);
        for (size_t i = 0; i < pixels; i++) {
            double v = (last[3 * i] + last[3 * i + 1] + last[3 * i + 2]) / 3.0;
            sum += v;
            sum2 += v * v;
            n++;
        }
    }
    Estimate e = {.mean = sum / n};
    e.std_error = sqrt(fmax(0.0, sum2 / n - e.mean * e.mean) / (n - 1));
    float *img = malloc(sizeof(float) * 3 * pixels);
    sg_renderer_image(r, img);
    e.image_finite = true;
    for (size_t i = 0; i < 3 * pixels; i++)
        e.image_finite = e.image_finite && isfinite(img[i]);
    free(img);
    e.nonfinite = sgt_stats(r).nonfinite;
    sg_renderer_free(r);
    return e;
}

/* Guided sampling stays unbiased whatever the guide says: the same mean as
 * BSDF sampling within the noise, no NaN, for importance points at the
 * shading point, NaN or infinite, on the floor's plane (exactly grazing on
 * the floor), far away (grazing on every wall parallel to x), and lobe
 * exponents from 0 to 1e5. The paper's (biased) rule: finite. */
Test(stress, renderer_with_odd_importance_points_and_exponents, .timeout = 240)
{
    SgScene *s = memory_two_rooms();
    SgRenderOptions o;
    sg_render_options_default(&o, s);
    o.max_depth = 6;
    o.threads = 2;
    const int spp = sanitized() ? 6 : 24;
    o.seed = 100;
    Estimate ref = estimate(s, &o, spp);
    cr_assert_gt(ref.mean, 0.0);
    cr_assert_eq(ref.nonfinite, 0);

    const Guide guides[] = {{0, {0}},           {1, {0}},         {2, {0}},
                            {3, {3, 0, 1}},     {3, {1e6, 1, 1}}, {3, {2.0, 0.6, 1.0}}};
    const float lobe_exponents[] = {0.0f, 4.0f, 1e4f, 1e5f};
    int seed = 1;
    for (size_t g = 0; g < sizeof guides / sizeof guides[0]; g++)
        for (size_t e = 0; e < sizeof lobe_exponents / sizeof lobe_exponents[0]; e++)
            for (int mode = 0; mode < 2; mode++) {
                /* query at the hit point itself for the first guide */
                o.importance.importance_point = odd_guide;
                o.importance.ctx = (void *)&guides[g];
                o.importance.query_offset = guides[g].kind == 0 ? 0.0 : 0.1;
                o.lobe_exponent = lobe_exponents[e];
                o.sampling = mode ? SG_SAMPLING_SKELETON : SG_SAMPLING_GUIDED;
                o.seed = (uint64_t)seed++;
                Estimate est = estimate(s, &o, mode ? 2 : spp);
                cr_assert_eq(est.nonfinite, 0, "guide %zu exponent %g mode %d: %llu NaN/inf samples", g,
                             lobe_exponents[e], mode, (unsigned long long)est.nonfinite);
                cr_assert(est.image_finite, "guide %zu exponent %g mode %d: image not finite", g,
                          lobe_exponents[e], mode);
                if (mode)
                    continue;
                double se = sqrt(est.std_error * est.std_error + ref.std_error * ref.std_error);
                cr_assert(fabs(est.mean - ref.mean) < 4.5 * se,
                          "guide %zu exponent %g: guided %.5f vs bsdf %.5f (4.5 se = %.5f)", g,
                          lobe_exponents[e], est.mean, ref.mean, 4.5 * se);
            }
    sgt_scene_free(s);
}
