/* A learned mode's training as a step of its own (render --field-out,
 * --field): a field file round-trips bit for bit, a field read back renders
 * the same image as the renderer that wrote it, and a render refuses a
 * field made for something else, or a broken one, in one line with no
 * output. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../render/guides/openpgl_field.h"
#include "../render/renderer.h"
#include "../render/edge_rays.h"
#include "support_files.h"
#include "support_importance.h"
#include "support_render.h"

/* The furnace with the guided mode's stand-in guide: a learner still
 * learns its regions there, and Open PGL its field. */
static SgtFixedPoint furnace_point = {{0.0, 1.4, 1.9}};

static SgRenderOptions field_options(const SgScene *s, SgSampling mode, int training)
{
    SgRenderOptions o = sgt_options(s, mode);
    o.training_passes = training;
    o.importance.importance_point = sgt_fixed_point_guide;
    o.importance.ctx = &furnace_point;
    return o;
}

/* A renderer of s trained and its field written to the test folder's
 * `name` (its path to path[size]). */
static SgRenderer *trained(const SgScene *s, const SgRenderOptions *o, const char *name, char *path, size_t size)
{
    snprintf(path, size, "%s/%s", sg_test_tmpdir(), name);
    SgError err = {0};
    SgRenderer *r = sg_renderer_create(s, o, &err);
    cr_assert_not_null(r, "%s", err.message);
    cr_assert(sg_renderer_train(r, &err), "%s", err.message);
    cr_assert(sg_renderer_write_field(r, path, &err), "%s", err.message);
    return r;
}

/* Frees what a test of two renderers made. */
static void free_pair(SgRenderer *a, SgRenderer *b, float *ia, float *ib, SgScene *s)
{
    free(ia);
    free(ib);
    sg_renderer_free(a);
    sg_renderer_free(b);
    sgt_scene_free(s);
}

static SgRenderer *renderer(const SgScene *s, const SgRenderOptions *o)
{
    SgError err = {0};
    SgRenderer *r = sg_renderer_create(s, o, &err);
    cr_assert_not_null(r, "%s", err.message);
    return r;
}

static float *render_passes(SgRenderer *r, const SgRenderOptions *o, int passes)
{
    for (int p = 0; p < passes; p++)
        sg_renderer_pass(r);
    float *img = malloc(sizeof *img * 3 * (size_t)o->width * o->height);
    cr_assert_not_null(img);
    sg_renderer_image(r, img);
    return img;
}

static bool skip_without(SgSampling mode)
{
    if (mode == SG_SAMPLING_OPENPGL && !sg_pgl_available()) {
        cr_skip_test("no Open PGL in this build (make openpgl builds it)");
        return true; /* not reached: cr_skip_test ends the test */
    }
    return false;
}

/* Trains, writes the field, freezes and renders; then a second renderer
 * reads the field and renders the same passes: the images are equal bit
 * for bit, and the field written again from the second is the same file. */
static void field_round_trip(SgSampling mode, int training, bool learned_roulette)
{
    if (skip_without(mode))
        return;
    SgScene *s = sgt_furnace_scene();
    SgRenderOptions o = field_options(s, mode, training);
    o.roulette = learned_roulette ? SG_ROULETTE_LEARNED : SG_ROULETTE_ALBEDO;
    const char *dir = sg_test_tmpdir();
    char f1[4200], f2[4200];
    snprintf(f1, sizeof f1, "%s/a.field", dir);
    snprintf(f2, sizeof f2, "%s/b.field", dir);
    SgError err = {0};

    SgRenderer *a = renderer(s, &o);
    cr_assert(sg_renderer_train(a, &err), "%s", err.message);
    cr_assert_eq(sg_renderer_spp(a), training, "the training ran its passes");
    cr_assert(sg_renderer_write_field(a, f1, &err), "%s", err.message);
    sg_renderer_freeze(a);
    cr_assert_eq(sg_renderer_spp(a), 0, "freeze starts the film again");
    float *ia = render_passes(a, &o, 12);

    SgRenderer *b = renderer(s, &o);
    cr_assert(sg_renderer_read_field(b, f1, &err), "%s", err.message);
    cr_assert(sg_renderer_write_field(b, f2, &err), "%s", err.message);
    float *ib = render_passes(b, &o, 12);

    size_t n = 3 * (size_t)o.width * o.height;
    cr_assert_eq(memcmp(ia, ib, n * sizeof *ia), 0, "%s: a field read back renders another image",
                 sg_sampling_name(mode));
    size_t sa, sb;
    uint8_t *da = sgt_read_file(f1, &sa), *db = sgt_read_file(f2, &sb);
    cr_assert(da && db);
    cr_assert(sa == sb && memcmp(da, db, sa) == 0, "%s: the field did not round-trip bit for bit (%zu, %zu bytes)",
              sg_sampling_name(mode), sa, sb);
    /* and it is no constant: the frozen render is the furnace's 1 */
    double mean = 0.0;
    for (size_t i = 0; i < n; i++)
        mean += ia[i];
    mean /= (double)n;
    cr_assert(mean > 0.9 && mean < 1.1, "the frozen field's furnace came out %g, not 1", mean);
    free(da);
    free(db);
    free_pair(a, b, ia, ib, s);
}

/* A field serves any view of its scene: read into a renderer of another
 * camera and image size, its guide renders (the furnace's 1), while the
 * pixels' noise, learned for the first view's pixels, is left out (the
 * learned roulette learns the new pixels; the round trips above take it
 * along for the same view). */
Test(render_field, a_field_serves_another_camera_and_size, .timeout = 120)
{
    SgScene *s = sgt_furnace_scene();
    SgRenderOptions o = field_options(s, SG_SAMPLING_GUIDED, 6);
    char path[4200];
    sg_renderer_free(trained(s, &o, "view.field", path, sizeof path));
    SgError err = {0};

    SgRenderOptions other = o;
    other.width = o.width / 2 + 3;
    other.height = o.height / 2 + 1;
    s->camera.position[0] += 0.3;
    s->camera.look_at[1] -= 0.2;
    SgRenderer *b = renderer(s, &other);
    cr_assert(sg_renderer_read_field(b, path, &err), "another view: %s", err.message);
    float *img = render_passes(b, &other, 8);
    size_t n = 3 * (size_t)other.width * other.height;
    double mean = 0.0;
    for (size_t i = 0; i < n; i++)
        mean += img[i];
    mean /= (double)n;
    cr_log_info("furnace from a field of another view: %.4f", mean);
    cr_assert(mean > 0.9 && mean < 1.1, "the furnace came out %g, not 1", mean);
    free(img);
    sg_renderer_free(b);
    sgt_scene_free(s);
}

Test(render_field, guided_round_trips_bit_for_bit, .timeout = 120) { field_round_trip(SG_SAMPLING_GUIDED, 6, true); }
Test(render_field, guided_with_albedo_roulette_round_trips, .timeout = 120)
{
    field_round_trip(SG_SAMPLING_GUIDED, 4, false);
}
Test(render_field, openpgl_round_trips_bit_for_bit, .timeout = 120) { field_round_trip(SG_SAMPLING_OPENPGL, 6, false); }

/* A room whose back wall holds a light with an edge through a column of
 * pixels: those pixels take extra camera rays (render/edge_rays.h), chosen
 * from the render's own survey and samples, never from the training's: the
 * renderer that trained the field and one that reads it back render the
 * same image, bit for bit. */
static SgScene *room_with_a_lights_edge_in_view(void)
{
    SgScene *s = sgt_scene_new();
    const float grey[3] = {0.5f, 0.5f, 0.5f}, black[3] = {0, 0, 0}, glow[3] = {4, 4, 4};
    uint32_t wall = sgt_add_material(s, SG_MATERIAL_DIFFUSE, grey, NULL);
    uint32_t lamp = sgt_add_material(s, SG_MATERIAL_DIFFUSE, black, glow);
    const double lo[3] = {-2, -2, -2}, hi[3] = {2, 2, 2};
    sgt_add_box_inside(s, lo, hi, wall);
    /* just off the back wall, facing the camera; its left edge through pixel column 7.5 of 16 */
    const double q[4][3] = {{-0.03, -1, -1.99}, {1, -1, -1.99}, {1, 1, -1.99}, {-0.03, 1, -1.99}};
    sgt_add_quad(s, q, lamp);
    const double pos[3] = {0, 0, 1}, at[3] = {0, 0, -2};
    sgt_finish_looking(s, pos, at, 60, 16, 12);
    return s;
}

Test(render_field, a_lights_edge_in_view_renders_the_same_from_a_field_read_back, .timeout = 120)
{
    SgScene *s = room_with_a_lights_edge_in_view();
    SgRenderOptions o = field_options(s, SG_SAMPLING_GUIDED, 6);
    char f1[4200];
    SgRenderer *a = trained(s, &o, "edge.field", f1, sizeof f1);
    SgError err = {0};
    sg_renderer_freeze(a);
    float *ia = render_passes(a, &o, 12);
    double rays = sgt_stats(a).edge_rays_per_sample;
    SgRenderer *b = renderer(s, &o);
    cr_assert(sg_renderer_read_field(b, f1, &err), "%s", err.message);
    float *ib = render_passes(b, &o, 12);
    cr_log_info("light's edge from a field: %.3f extra camera rays a sample", rays);
    cr_assert(rays > (double)EDGE_RAYS_SURVEY / 12.0, "the edge took no extra rays (%g a sample)", rays);
    cr_assert_float_eq(sgt_stats(b).edge_rays_per_sample, rays, 1e-12, "the two renders took other edge rays");
    cr_assert_eq(memcmp(ia, ib, sizeof *ia * 3 * (size_t)o.width * o.height), 0,
                 "a field read back renders another image where a light's edge is in view");
    free_pair(a, b, ia, ib, s);
}

/* The edge rays change what the camera sees directly, never the paths:
 * they draw no random number of the path's, and the learned roulette's
 * pixel noise is the light past the camera ray's own hit. So guided with
 * its learned roulette and splitting traces the same paths with and
 * without them (the same branches, the same rays less the edge rays). */
Test(render_field, the_edge_rays_leave_the_paths_as_they_were, .timeout = 120)
{
    SgScene *s = room_with_a_lights_edge_in_view();
    double branches[2], path_rays[2], edge[2];
    for (int with = 0; with < 2; with++) {
        SgRenderOptions o = field_options(s, SG_SAMPLING_GUIDED, 4);
        o.edge_rays = with ? EDGE_RAYS_MAX : 0;
        SgRenderer *r = renderer(s, &o);
        const int passes = 40; /* splitting from pass 16 */
        free(render_passes(r, &o, passes));
        double samples = (double)o.width * o.height * passes;
        branches[with] = sgt_stats(r).branches_per_path;
        edge[with] = sgt_stats(r).edge_rays_per_sample;
        path_rays[with] = (double)sgt_stats(r).rays - edge[with] * samples;
        sg_renderer_free(r);
    }
    cr_log_info("guided, learned roulette: %.4f / %.4f branches a path, %.0f / %.0f path rays, %.3f edge rays a "
                "sample", branches[0], branches[1], path_rays[0], path_rays[1], edge[1]);
    cr_assert(edge[1] > 0.0 && edge[0] == 0.0);
    cr_assert(branches[0] > 0.0, "no path split: the test shows nothing");
    cr_assert_float_eq(branches[1], branches[0], 1e-12, "the edge rays changed the roulette's splitting");
    cr_assert_float_eq(path_rays[1], path_rays[0], 0.5, "the edge rays changed the paths");
    sgt_scene_free(s);
}

/* A frozen guide learns nothing more: its field after rendering is the
 * field it was given. */
Test(render_field, a_frozen_guide_learns_nothing, .timeout = 120)
{
    if (skip_without(SG_SAMPLING_OPENPGL))
        return;
    SgScene *s = sgt_furnace_scene();
    const char *dir = sg_test_tmpdir();
    char f1[4200], f2[4200];
    snprintf(f1, sizeof f1, "%s/c.field", dir);
    snprintf(f2, sizeof f2, "%s/d.field", dir);
    SgError err = {0};
    SgSampling modes[] = {SG_SAMPLING_GUIDED, SG_SAMPLING_OPENPGL};
    for (int m = 0; m < 2; m++) {
        SgRenderOptions o = field_options(s, modes[m], 4);
        o.roulette = SG_ROULETTE_ALBEDO; /* the pixels' noise would go on counting */
        SgRenderer *a = renderer(s, &o);
        cr_assert(sg_renderer_train(a, &err), "%s", err.message);
        sg_renderer_freeze(a);
        cr_assert(sg_renderer_write_field(a, f1, &err), "%s", err.message);
        free(render_passes(a, &o, 6));
        cr_assert(sg_renderer_write_field(a, f2, &err), "%s", err.message);
        size_t s1, s2;
        uint8_t *d1 = sgt_read_file(f1, &s1), *d2 = sgt_read_file(f2, &s2);
        cr_assert(s1 == s2 && memcmp(d1, d2, s1) == 0, "%s learned while frozen", sg_sampling_name(modes[m]));
        free(d1);
        free(d2);
        sg_renderer_free(a);
    }
    sgt_scene_free(s);
}

Test(render_field, bsdf_has_no_field)
{
    SgScene *s = sgt_furnace_scene();
    SgRenderOptions o = field_options(s, SG_SAMPLING_BSDF, 2);
    SgRenderer *r = renderer(s, &o);
    SgError err = {0};
    cr_assert_not(sg_renderer_train(r, &err));
    cr_assert(strstr(err.message, "learns nothing"), "%s", err.message);
    sg_renderer_free(r);
    sgt_scene_free(s);
}

/* ---- bin/render: the options, and every refusal in one line with no output ---- */

static const char *render_bin(void)
{
    static char buf[4096];
    return sg_test_program("render", buf, sizeof buf);
}

static const char *room(const char *dir, const char *name, double light)
{
    char text[2048];
    snprintf(text, sizeof text,
             "{ \"meshes\": [ { \"vertices\": [0,0,0, 2,0,0, 2,0,2, 0,0,2, 0,2,0, 2,2,0, 2,2,2, 0,2,2],\n"
             "    \"triangles\": [0,1,2, 0,2,3, 4,6,5, 4,7,6, 0,4,5, 0,5,1, 3,2,6, 3,6,7, 0,3,7, 0,7,4, 1,5,6, 1,6,2],\n"
             "    \"material\": \"white\" } ],\n"
             "  \"materials\": { \"white\": { \"type\": \"diffuse\", \"albedo\": [0.6, 0.6, 0.6] } },\n"
             "  \"lights\": [ { \"type\": \"quad\", \"corners\": [[0.8,1.99,0.8],[1.2,1.99,0.8],[1.2,1.99,1.2],"
             "[0.8,1.99,1.2]],\n"
             "                \"radiance\": [%g, %g, %g] } ],\n"
             "  \"camera\": { \"position\": [1, 1, 0.2], \"look_at\": [1, 1, 2], \"up\": [0, 1, 0], \"fov\": 60 },\n"
             "  \"image\": { \"width\": 24, \"height\": 16 } }\n",
             light, light, light);
    return sg_test_write(dir, name, text);
}

/* Runs render with `args`; on refusal: status 1, one line naming `names`, no -o output. */
static void refused(const char *dir, const char *args, const char *names)
{
    char cmd[16384], err[4096], out[4200];
    snprintf(out, sizeof out, "%s/refused.exr", dir);
    snprintf(cmd, sizeof cmd, "%s %s -o %s", render_bin(), args, out);
    int status = sg_test_run(cmd, err, sizeof err);
    cr_assert_neq(status, 0, "accepted: %s", args);
    cr_assert_eq(sg_test_count_lines(err), 1, "%s: %s", args, err);
    cr_assert(strstr(err, names), "'%s' does not name %s: %s", args, names, err);
    cr_assert_not(sg_test_exists(out), "a refused render left its output: %s", args);
}

static void copy_bytes(const char *path, const uint8_t *data, size_t size)
{
    FILE *f = fopen(path, "wb");
    cr_assert_not_null(f);
    cr_assert_eq(fwrite(data, 1, size, f), size);
    fclose(f);
}

Test(render_field, the_program_trains_renders_and_refuses_what_is_not_its_field, .timeout = 120)
{
    if (skip_without(SG_SAMPLING_OPENPGL))
        return;
    const char *dir = sg_test_tmpdir();
    const char *scene = room(dir, "room.json", 10), *other = room(dir, "other.json", 12);
    char cmd[16384], err[4096], field[4200], exr[4200];
    snprintf(field, sizeof field, "%s/room.field", dir);
    snprintf(exr, sizeof exr, "%s/train.exr", dir);
    snprintf(cmd, sizeof cmd, "%s %s --sampling openpgl --field-out %s --training-passes 3 -o %s --threads 2 --quiet",
             render_bin(), scene, field, exr);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 0, "%s", err);
    cr_assert(sg_test_exists(field) && sg_test_exists(exr));
    snprintf(cmd, sizeof cmd, "%s %s --sampling openpgl --field %s --spp 2 -o %s/frozen.exr --quiet", render_bin(),
             scene, field, dir);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 0, "%s", err);

    char args[8192];
    /* made for another scene, other options, another mode (another size
     * is only another view: the field serves it) */
    snprintf(args, sizeof args, "%s --sampling openpgl --field %s --spp 1", other, field);
    refused(dir, args, field);
    snprintf(cmd, sizeof cmd, "%s %s --sampling openpgl --field %s --spp 1 --size 32x16 -o %s/small.exr --quiet",
             render_bin(), scene, field, dir);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 0, "another size: %s", err);
    snprintf(args, sizeof args, "%s --sampling openpgl --field %s --spp 1 --max-depth 3", scene, field);
    refused(dir, args, field);
    snprintf(args, sizeof args, "%s --sampling bsdf --field %s --spp 1", scene, field);
    refused(dir, args, "learns nothing");
    /* missing, foreign, truncated, corrupt */
    snprintf(args, sizeof args, "%s --sampling openpgl --field %s/none.field --spp 1", scene, dir);
    refused(dir, args, "none.field");
    snprintf(args, sizeof args, "%s --sampling openpgl --field %s --spp 1", scene, scene);
    refused(dir, args, "not a field file");
    size_t size;
    uint8_t *data = sgt_read_file(field, &size);
    cr_assert(data && size > 400);
    char broken[4200];
    snprintf(broken, sizeof broken, "%s/broken.field", dir);
    copy_bytes(broken, data, size - 100);
    snprintf(args, sizeof args, "%s --sampling openpgl --field %s --spp 1", scene, broken);
    refused(dir, args, "truncated");
    copy_bytes(broken, data, 200);
    refused(dir, args, "broken.field");
    data[size - 50] ^= 0x40;
    copy_bytes(broken, data, size);
    refused(dir, args, "corrupt");
    data[size - 50] ^= 0x40;
    data[40] ^= 0x01; /* the header (its scene hash) */
    copy_bytes(broken, data, size);
    refused(dir, args, "corrupt");
    free(data);
    /* a training whose field cannot be written leaves no image either */
    snprintf(args, sizeof args, "%s --sampling openpgl --field-out %s/no/such/dir/x.field --training-passes 1", scene,
             dir);
    refused(dir, args, "x.field");
    /* options that do not go together */
    snprintf(args, sizeof args, "%s --sampling openpgl --field-out %s --spp 4", scene, field);
    refused(dir, args, "--field-out");
    snprintf(args, sizeof args, "%s --sampling openpgl --save-field %s --spp 4 --shard 0/2", scene, field);
    refused(dir, args, "--save-field");
    /* with a budget, one run learns, writes the field when it stops, and
     * renders on: the field then serves the next render */
    snprintf(cmd, sizeof cmd,
             "%s %s --sampling openpgl --save-field %s/within.field --training-passes 2 --spp 4 -o %s/within.exr "
             "--threads 2 --quiet",
             render_bin(), scene, dir, dir);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 0, "%s", err);
    snprintf(cmd, sizeof cmd, "%s %s --sampling openpgl --field %s/within.field --spp 1 -o %s/again.exr --quiet",
             render_bin(), scene, dir, dir);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 0, "%s", err);
}

/* The shards of a farm render with one field: merged, they are the one
 * process's image (to float rounding) where nothing else is learned on the
 * clock (albedo roulette; the learned one also counts each shard's own
 * pixels' noise). */
static void shards_from_one_field(SgSampling mode)
{
    if (skip_without(mode))
        return;
    SgScene *s = sgt_furnace_scene();
    SgRenderOptions o = field_options(s, mode, 4);
    o.roulette = SG_ROULETTE_ALBEDO;
    char field[4200];
    snprintf(field, sizeof field, "%s/shards.field", sg_test_tmpdir());
    SgError err = {0};
    SgRenderer *t = renderer(s, &o);
    cr_assert(sg_renderer_train(t, &err) && sg_renderer_write_field(t, field, &err), "%s", err.message);
    sg_renderer_free(t);

    enum { PASSES = 8, SHARDS = 4 };
    size_t n = 3 * (size_t)o.width * o.height;
    SgRenderer *one = renderer(s, &o);
    cr_assert(sg_renderer_read_field(one, field, &err), "%s", err.message);
    float *whole = render_passes(one, &o, PASSES);
    double *merged = calloc(n, sizeof *merged);
    for (int k = 0; k < SHARDS; k++) {
        SgRenderOptions ok = o;
        ok.shard = k;
        ok.shard_count = SHARDS;
        SgRenderer *r = renderer(s, &ok);
        cr_assert(sg_renderer_read_field(r, field, &err), "%s", err.message);
        float *img = render_passes(r, &ok, PASSES / SHARDS);
        for (size_t i = 0; i < n; i++)
            merged[i] += img[i] / SHARDS;
        free(img);
        sg_renderer_free(r);
    }
    double worst = 0.0;
    for (size_t i = 0; i < n; i++) {
        double d = fabs(merged[i] - whole[i]) / fmax(1e-6, fabs(whole[i]));
        worst = fmax(worst, d);
    }
    cr_assert(worst < 1e-5, "%s: %d shards from one field differ from one process by %g (relative)",
              sg_sampling_name(mode), SHARDS, worst);
    free(merged);
    free(whole);
    sg_renderer_free(one);
    sgt_scene_free(s);
}

Test(render_field, guided_shards_from_one_field_are_one_process, .timeout = 120)
{
    shards_from_one_field(SG_SAMPLING_GUIDED);
}
Test(render_field, openpgl_shards_from_one_field_are_one_process, .timeout = 120)
{
    shards_from_one_field(SG_SAMPLING_OPENPGL);
}
