/* Lights that are not surfaces (a sky, a sun, point and spot lights) and
 * pbrt-v4's analytic shapes, against closed forms: a plane under a
 * constant sky (rho L), a white convex object in a white sky (L), the
 * inverse-square law, a spot's falloff, the cosine law of a sun on a
 * tilted plane, a floor under a window in a black room (rho L F with F
 * the rectangle's form factor); the shapes' meshes against their true
 * areas; and the refusals. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <unistd.h>

#include "quadric_mesh.h"
#include "scene_builder.h"
#include "scene_load.h"
#include "../render/environment.h"
#include "../render/renderer.h"
#include "support_files.h"
#include "support_render.h"
#include "vecmath.h"

/* ---- rendering a window of pixels ------------------------------------------ */

typedef SgtSampleMean Estimate;

/* The mean of the image (channel 0) over `passes` passes of `mode`, seed 7,
 * 2 threads, paths up to 16 long. */
static Estimate render_mean(const SgScene *s, SgSampling mode, int passes)
{
    SgRenderOptions o = sgt_options(s, mode);
    o.max_depth = 16;
    SgError err = {0};
    SgRenderer *r = sg_renderer_create(s, &o, &err);
    cr_assert(r, "renderer: %s", err.message);
    Estimate e = sgt_passes_mean(r, passes, (size_t)o.width * o.height);
    sg_renderer_free(r);
    return e;
}

static void expect_near(Estimate e, double want, double rel_floor, const char *what)
{
    double tol = 3.0 * e.std_error + rel_floor * fabs(want);
    cr_expect(fabs(e.mean - want) <= tol, "%s: %.6f, want %.6f (3 sigma %.2g + %.1g)", what, e.mean, want,
              3.0 * e.std_error, rel_floor * fabs(want));
}

/* ---- scenes ------------------------------------------------------------------- */

static const double up_z[3] = {0, 0, 1};

/* A 100 x 100 floor at y = 0 (normal +y) of albedo rho, a narrow camera
 * looking at `at` on it from above. */
static SgScene *floor_scene(float rho, const double at[3])
{
    SgScene *s = sgt_scene_new();
    uint32_t m = sgt_add_material(s, SG_MATERIAL_DIFFUSE, (const float[3]){rho, rho, rho}, NULL);
    const double q[4][3] = {{-50, 0, -50}, {-50, 0, 50}, {50, 0, 50}, {50, 0, -50}};
    sgt_add_quad(s, q, m);
    const double eye[3] = {at[0] + 0.1, 2.0, at[2]};
    sgt_set_camera(s, eye, at, up_z, 0.2, 4, 4);
    return s;
}

static void add_source(SgScene *s, const SgLightSource *l)
{
    s->light_sources = realloc(s->light_sources, (s->light_source_count + 1) * sizeof *s->light_sources);
    s->light_sources[s->light_source_count] = *l;
    if (l->image_path)
        s->light_sources[s->light_source_count].image_path = strdup(l->image_path);
    s->light_source_count++;
}

static SgLightSource constant_sky(float radiance)
{
    SgLightSource l = {.kind = SG_LIGHT_INFINITE, .rgb = {radiance, radiance, radiance}};
    for (int a = 0; a < 3; a++)
        l.light_to_world[a][a] = 1;
    return l;
}

/* ---- the sky --------------------------------------------------------------------- */

Test(render_lights, plane_under_constant_sky_is_rho_L)
{
    SgScene *s = floor_scene(0.5f, (const double[3]){0, 0, 0});
    SgLightSource sky = constant_sky(0.8f);
    add_source(s, &sky);
    sgt_finish(s);
    expect_near(render_mean(s, SG_SAMPLING_BSDF, 256), 0.5 * 0.8, 0.0, "floor under a sky");
    sgt_scene_free(s);
}

Test(render_lights, white_convex_object_in_white_sky_is_L)
{
    SgScene *s = sgt_scene_new();
    uint32_t white = sgt_add_material(s, SG_MATERIAL_DIFFUSE, (const float[3]){1, 1, 1}, NULL);
    SgQuadricMesh mesh;
    SgError err = {0};
    cr_assert(sg_quadric_sphere(1.0, -1.0, 1.0, 2 * M_PI, &mesh, &err));
    for (uint32_t t = 0; t < mesh.triangle_count; t++) { /* as quads of three distinct corners */
        const uint32_t *id = mesh.indices + 3 * (size_t)t;
        double q[4][3];
        for (int c = 0; c < 3; c++)
            memcpy(q[c], mesh.positions + 3 * (size_t)id[c], sizeof q[c]);
        memcpy(q[3], q[2], sizeof q[3]);
        sgt_add_quad(s, q, white);
    }
    sg_quadric_mesh_free(&mesh);
    sgt_set_camera(s, (const double[3]){0, 0, 4}, (const double[3]){0, 0, 0}, (const double[3]){0, 1, 0}, 40, 16,
                   16);
    SgLightSource sky = constant_sky(1.0f);
    add_source(s, &sky);
    sgt_finish(s);
    expect_near(render_mean(s, SG_SAMPLING_BSDF, 64), 1.0, 1e-3, "white furnace sky");
    sgt_scene_free(s);
}

/* The form factor from a point to a parallel rectangle a x b at height c
 * whose corner is straight above it. */
static double corner_form_factor(double a, double b, double c)
{
    double x = a / c, y = b / c, sx = sqrt(1 + x * x), sy = sqrt(1 + y * y);
    return (x / sx * atan(y / sx) + y / sy * atan(x / sy)) / (2 * M_PI);
}

/* A closed black room 4 x 2 x 4 with a 1 x 0.6 opening in its ceiling
 * above the floor's centre, the floor of albedo rho. */
static SgScene *window_room(float rho)
{
    SgScene *s = sgt_scene_new();
    uint32_t floor = sgt_add_material(s, SG_MATERIAL_DIFFUSE, (const float[3]){rho, rho, rho}, NULL);
    uint32_t black = sgt_add_material(s, SG_MATERIAL_DIFFUSE, (const float[3]){0, 0, 0}, NULL);
    const double x0 = -2, x1 = 2, z0 = -2, z1 = 2, h = 2, wx = 0.5, wz = 0.3;
    sgt_add_quad(s, (const double[4][3]){{x0, 0, z0}, {x0, 0, z1}, {x1, 0, z1}, {x1, 0, z0}}, floor);
    /* walls, facing in */
    sgt_add_quad(s, (const double[4][3]){{x0, 0, z0}, {x1, 0, z0}, {x1, h, z0}, {x0, h, z0}}, black);
    sgt_add_quad(s, (const double[4][3]){{x0, 0, z1}, {x0, h, z1}, {x1, h, z1}, {x1, 0, z1}}, black);
    sgt_add_quad(s, (const double[4][3]){{x0, 0, z0}, {x0, h, z0}, {x0, h, z1}, {x0, 0, z1}}, black);
    sgt_add_quad(s, (const double[4][3]){{x1, 0, z0}, {x1, 0, z1}, {x1, h, z1}, {x1, h, z0}}, black);
    /* the ceiling in four pieces round the opening, facing down */
    sgt_add_quad(s, (const double[4][3]){{x0, h, z0}, {x1, h, z0}, {x1, h, -wz}, {x0, h, -wz}}, black);
    sgt_add_quad(s, (const double[4][3]){{x0, h, wz}, {x1, h, wz}, {x1, h, z1}, {x0, h, z1}}, black);
    sgt_add_quad(s, (const double[4][3]){{x0, h, -wz}, {-wx, h, -wz}, {-wx, h, wz}, {x0, h, wz}}, black);
    sgt_add_quad(s, (const double[4][3]){{wx, h, -wz}, {x1, h, -wz}, {x1, h, wz}, {wx, h, wz}}, black);
    sgt_set_camera(s, (const double[3]){0.05, 1.0, 0}, (const double[3]){0, 0, 0}, up_z, 0.2, 4, 4);
    return s;
}

/* The window room under a constant sky of radiance 2 (a portal over the
 * window where `portal`), and the floor's closed form rho L F. */
static SgScene *window_room_under_sky(bool portal, double *closed_form)
{
    SgScene *s = window_room(0.6f);
    SgLightSource sky = constant_sky(2.0f);
    if (portal) {
        const double corners[4][3] = {{-0.5, 2, -0.3}, {0.5, 2, -0.3}, {0.5, 2, 0.3}, {-0.5, 2, 0.3}};
        memcpy(sky.portal, corners, sizeof corners);
        sky.has_portal = true;
    }
    add_source(s, &sky);
    sgt_finish(s);
    *closed_form = 0.6 * 2.0 * 4 * corner_form_factor(0.5, 0.3, 2.0);
    return s;
}

Test(render_lights, floor_under_window_is_rho_L_F)
{
    double want;
    SgScene *s = window_room_under_sky(false, &want);
    expect_near(render_mean(s, SG_SAMPLING_BSDF, 512), want, 0.0, "floor under a window");
    sgt_scene_free(s);
}

/* Open PGL learns from the sky's samples and the rays that leave through
 * the window as from any light: the same closed form. */
Test(render_lights, openpgl_under_window_is_rho_L_F)
{
    const SgSamplingMode *mode = sg_sampling_mode(SG_SAMPLING_OPENPGL);
    SgError why = {0};
    if (mode->available && !mode->available(&why))
        cr_skip_test("%s", why.message);
    double want;
    SgScene *s = window_room_under_sky(false, &want);
    expect_near(render_mean(s, SG_SAMPLING_OPENPGL, 512), want, 0.0, "openpgl under a window");
    sgt_scene_free(s);
}

/* The same through the window drawn as a portal: the same answer, and far
 * less noise than light samples spread over the whole sky. */
Test(render_lights, floor_under_window_through_its_portal)
{
    double want;
    SgScene *s = window_room_under_sky(true, &want);
    Estimate with = render_mean(s, SG_SAMPLING_BSDF, 512);
    expect_near(with, want, 0.0, "floor under a window, through its portal");
    s->light_sources[0].has_portal = false;
    Estimate without = render_mean(s, SG_SAMPLING_BSDF, 512);
    cr_log_info("window: %.6f +- %.2g through the portal, %.6f +- %.2g without", with.mean, with.std_error,
                without.mean, without.std_error);
    cr_expect(with.std_error < 0.5 * without.std_error, "the portal's standard error %g is not half the sky's %g",
              with.std_error, without.std_error);
    sgt_scene_free(s);
}

/* ---- point, spot, sun --------------------------------------------------------------- */

Test(render_lights, point_light_inverse_square)
{
    const double h = 1.5;
    SgScene *s = floor_scene(0.5f, (const double[3]){0, 0, 0});
    SgLightSource l = {.kind = SG_LIGHT_POINT, .rgb = {3, 3, 3}, .position = {0, h, 0}};
    add_source(s, &l);
    sgt_finish(s);
    expect_near(render_mean(s, SG_SAMPLING_BSDF, 16), 0.5 / M_PI * 3.0 / (h * h), 2e-3, "point light");
    sgt_scene_free(s);
}

static double smooth_step(double x, double a, double b)
{
    double t = fmin(fmax((x - a) / (b - a), 0.0), 1.0);
    return t * t * (3 - 2 * t);
}

Test(render_lights, spot_falloff)
{
    const double h = 1.0, cone = 30, delta = 10;
    const double angles[] = {10, 25, 35};
    for (int k = 0; k < 3; k++) {
        double theta = angles[k] * M_PI / 180, r = h * tan(theta);
        SgScene *s = floor_scene(0.5f, (const double[3]){r, 0, 0});
        SgLightSource l = {.kind = SG_LIGHT_SPOT, .rgb = {2, 2, 2}, .position = {0, h, 0}, .direction = {0, -1, 0},
                           .cos_cone = cos(cone * M_PI / 180), .cos_falloff_start = cos((cone - delta) * M_PI / 180)};
        add_source(s, &l);
        sgt_finish(s);
        double d2 = h * h + r * r, c = cos(theta);
        double want = 0.5 / M_PI * 2.0 * smooth_step(c, l.cos_cone, l.cos_falloff_start) * c / d2;
        char what[64];
        snprintf(what, sizeof what, "spot at %g degrees", angles[k]);
        /* at 35 degrees the spot sends nothing: the renderer refuses no scene for it, the image is black */
        Estimate e = render_mean(s, SG_SAMPLING_BSDF, 8);
        if (want == 0.0)
            cr_expect(e.mean == 0.0, "%s: %g, want 0", what, e.mean);
        else
            expect_near(e, want, 2e-3, what);
        sgt_scene_free(s);
    }
}

Test(render_lights, sun_cosine_law_on_tilted_plane)
{
    const double tilt[] = {0, 60, 80};
    for (int k = 0; k < 3; k++) {
        double a = tilt[k] * M_PI / 180;
        SgScene *s = floor_scene(0.5f, (const double[3]){0, 0, 0});
        SgLightSource sun = {.kind = SG_LIGHT_DISTANT, .rgb = {4, 4, 4}, .direction = {sin(a), -cos(a), 0}};
        add_source(s, &sun);
        sgt_finish(s);
        char what[64];
        snprintf(what, sizeof what, "sun %g degrees from the normal", tilt[k]);
        expect_near(render_mean(s, SG_SAMPLING_BSDF, 8), 0.5 / M_PI * 4.0 * cos(a), 1e-4, what);
        sgt_scene_free(s);
    }
}

Test(render_lights, sun_disk_cosine_law_with_mis)
{
    /* a sun of angular radius 5 degrees: reached by light samples and by
     * bounces alike, MIS-weighted; the irradiance keeps the cosine law */
    double a = 50 * M_PI / 180;
    SgScene *s = floor_scene(0.5f, (const double[3]){0, 0, 0});
    SgLightSource sun = {.kind = SG_LIGHT_DISTANT, .rgb = {4, 4, 4}, .direction = {sin(a), -cos(a), 0},
                         .angular_radius = 5 * M_PI / 180};
    add_source(s, &sun);
    sgt_finish(s);
    expect_near(render_mean(s, SG_SAMPLING_BSDF, 256), 0.5 / M_PI * 4.0 * cos(a), 2e-3, "sun disk");
    sgt_scene_free(s);
}

/* ---- the shapes --------------------------------------------------------------------- */

Test(render_lights, quadric_meshes_have_true_area_and_face_out)
{
    SgError err = {0};
    SgQuadricMesh m;
    struct {
        const char *what;
        int shape; /* 0 disk, 1 sphere, 2 cylinder */
        double a, b, c, phi;
    } cases[] = {
        {"disk", 0, 1.5, 0.0, 0.2, 2 * M_PI},   {"annulus", 0, 2.0, 0.5, 0.0, 2 * M_PI},
        {"half disk", 0, 1.0, 0.0, 0.0, M_PI}, {"sphere", 1, 0.7, -0.7, 0.7, 2 * M_PI},
        {"cap", 1, 1.0, 0.3, 1.0, 2 * M_PI},    {"sphere wedge", 1, 2.0, -1.0, 2.0, 1.5},
        {"cylinder", 2, 0.5, -1.0, 2.0, 2 * M_PI}, {"cylinder wedge", 2, 1.0, 0.0, 1.0, 2.0},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        double want;
        if (cases[k].shape == 0) {
            cr_assert(sg_quadric_disk(cases[k].a, cases[k].b, cases[k].c, cases[k].phi, &m, &err));
            want = sg_quadric_disk_area(cases[k].a, cases[k].b, cases[k].phi);
        } else if (cases[k].shape == 1) {
            cr_assert(sg_quadric_sphere(cases[k].a, cases[k].b, cases[k].c, cases[k].phi, &m, &err));
            want = sg_quadric_sphere_area(cases[k].a, cases[k].b, cases[k].c, cases[k].phi);
        } else {
            cr_assert(sg_quadric_cylinder(cases[k].a, cases[k].b, cases[k].c, cases[k].phi, &m, &err));
            want = sg_quadric_cylinder_area(cases[k].a, cases[k].b, cases[k].c, cases[k].phi);
        }
        cr_expect(fabs(sg_quadric_mesh_area(&m) - want) <= 1e-9 * want, "%s: area %.12g, want %.12g", cases[k].what,
                  sg_quadric_mesh_area(&m), want);
        cr_expect(m.triangle_count >= 64, "%s: only %u triangles", cases[k].what, m.triangle_count);
        uint32_t inward = 0;
        for (uint32_t t = 0; t < m.triangle_count; t++) {
            double n[3], out[3];
            sg_quadric_triangle(&m, t, n, out);
            if (cases[k].shape == 0)
                out[0] = out[1] = 0, out[2] = 1;
            else if (cases[k].shape == 2)
                out[2] = 0;
            inward += d3_dot(n, out) <= 0;
        }
        cr_expect(inward == 0, "%s: %u triangles face in", cases[k].what, inward);
        sg_quadric_mesh_free(&m);
    }
}

/* ---- the scene files --------------------------------------------------------------- */

Test(render_lights, json_light_sources)
{
    SgError err = {0};
    SgScene *s = sgt_scene_from_text("sources.json",
                           "{\"lights\": [{\"type\": \"quad\", \"corners\": [[0,2,0],[1,2,0],[1,2,1],[0,2,1]], "
                           "\"radiance\": [1,1,1]},"
                           "{\"type\": \"sky\", \"radiance\": [0.2,0.3,0.4], \"up\": [0,0,2]},"
                           "{\"type\": \"sun\", \"irradiance\": [3,3,3], \"direction\": [0,-2,0], \"angular_radius\": 0.5},"
                           "{\"type\": \"point\", \"intensity\": [1,1,1], \"scale\": 4, \"position\": [0,1,0]},"
                           "{\"type\": \"spot\", \"intensity\": [1,1,1], \"position\": [0,1,0], \"direction\": [0,-1,0], "
                           "\"cone_angle\": 20}]}", &err);
    cr_assert(s, "%s", err.message);
    cr_assert_eq(s->light_source_count, 4);
    cr_expect(s->light_sources[0].kind == SG_LIGHT_INFINITE && s->light_sources[0].rgb[2] == 0.4f);
    cr_expect(fabs(s->light_sources[0].light_to_world[2][2] - 1) < 1e-12, "up is the map's z");
    cr_expect(s->light_sources[1].kind == SG_LIGHT_DISTANT && fabs(s->light_sources[1].direction[1] + 1) < 1e-12);
    cr_expect(fabs(s->light_sources[1].angular_radius - 0.5 * M_PI / 180) < 1e-12);
    cr_expect(s->light_sources[2].rgb[0] == 4.0f);
    cr_expect(fabs(s->light_sources[3].cos_falloff_start - cos(15 * M_PI / 180)) < 1e-12, "default delta 5");
    sg_scene_free(s);
}

Test(render_lights, bad_lights_are_refused_with_the_cause)
{
    struct {
        const char *name, *text, *cause;
    } cases[] = {
        {"negative.pbrt", SGT_PBRT_ROOM "LightSource \"point\" \"rgb I\" [-1 1 1]\n", "negative"},
        {"scale.pbrt", SGT_PBRT_ROOM "LightSource \"distant\" \"float scale\" -2\n", "\"scale\" must be finite"},
        {"both.pbrt", SGT_PBRT_ROOM "LightSource \"infinite\" \"rgb L\" [1 1 1] \"string filename\" \"sky.exr\"\n",
         "not both"},
        {"portal.pbrt", SGT_PBRT_ROOM "LightSource \"infinite\" \"point3 portal\" [0 0 0 1 1 1]\n", "must be 4 points"},
        {"cone.pbrt", SGT_PBRT_ROOM "LightSource \"spot\" \"float coneangle\" 10 \"float conedeltaangle\" 20\n",
         "conedeltaangle"},
        {"radius.pbrt", SGT_PBRT_ROOM "Shape \"sphere\" \"float radius\" -1\n", "\"radius\" must be positive"},
        {"sun.json", "{\"lights\": [{\"type\": \"sun\", \"irradiance\": [1,1,1]}]}", "direction is missing"},
        {"sky.json", "{\"lights\": [{\"type\": \"sky\", \"radiance\": [1,-1,1]}]}", "non-negative"},
        {"kind.json", "{\"lights\": [{\"type\": \"lamp\"}]}", "\"sky\", \"sun\""},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        SgError err = {0};
        SgScene *s = sgt_scene_from_text(cases[k].name, cases[k].text, &err);
        cr_expect(!s, "%s loaded", cases[k].name);
        cr_expect(strstr(err.message, cases[k].cause) && strstr(err.message, cases[k].name), "%s: %s",
                  cases[k].name, err.message);
        sg_scene_free(s);
    }
}

/* The renderer must refuse s (which it frees) with `cause` in its message. */
static void expect_refused(SgScene *s, const char *cause)
{
    sgt_finish(s);
    SgRenderOptions o = sgt_options(s, SG_SAMPLING_BSDF);
    SgError err = {0};
    SgRenderer *r = sg_renderer_create(s, &o, &err);
    cr_expect(!r && strstr(err.message, cause), "want \"%s\": %s", cause, err.message);
    sg_renderer_free(r);
    sgt_scene_free(s);
}

Test(render_lights, renderer_refuses_a_missing_sky_image_and_no_light)
{
    SgScene *s = floor_scene(0.5f, (const double[3]){0, 0, 0});
    SgLightSource sky = constant_sky(1.0f);
    sky.image_path = "/nonexistent/sky.exr";
    add_source(s, &sky);
    expect_refused(s, "/nonexistent/sky.exr");

    /* a portal whose corners lie on a line */
    s = floor_scene(0.5f, (const double[3]){0, 0, 0});
    sky = constant_sky(1.0f);
    const double line[4][3] = {{0, 2, 0}, {1, 2, 0}, {2, 2, 0}, {3, 2, 0}};
    memcpy(sky.portal, line, sizeof line);
    sky.has_portal = true;
    add_source(s, &sky);
    expect_refused(s, "portal is degenerate");

    /* no light at all */
    expect_refused(floor_scene(0.5f, (const double[3]){0, 0, 0}), "no light");

    /* an image neither square nor 2:1 */
    float texels[3 * 3 * 2] = {0};
    Environment e;
    const double turn[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    SgError err = {0};
    cr_expect(!environment_init(&e, texels, 3, 2, SG_ENVIRONMENT_BY_SHAPE, (const float[3]){1, 1, 1}, turn, "odd.exr",
                                &err));
    cr_expect(strstr(err.message, "odd.exr") && strstr(err.message, "3x2"), "%s", err.message);
}

/* The scene's hash (what a cache and a shard are checked against) takes a
 * sky image's bytes, not its path: the scene named from another directory
 * keeps it, the image changed in place changes it, a missing image is
 * refused when the scene loads, naming the image. */
Test(render_lights, a_sky_images_bytes_not_its_path_make_the_scene_hash)
{
    char dir[4096], json[4200], image[4200], cwd[4096];
    snprintf(dir, sizeof dir, "%s", sg_test_tmpdir());
    snprintf(json, sizeof json, "%s/sky.json", dir);
    snprintf(image, sizeof image, "%s/sky.exr", dir);
    cr_assert(getcwd(cwd, sizeof cwd));
    FILE *f = fopen(json, "w");
    cr_assert(f);
    fputs("{\"lights\": [{\"type\": \"quad\", \"corners\": [[0,2,0], [1,2,0], [1,2,1], [0,2,1]], "
          "\"radiance\": [1, 1, 1]}, {\"type\": \"sky\", \"image\": \"sky.exr\"}]}",
          f);
    fclose(f);
    f = fopen(image, "wb");
    cr_assert(f);
    fputs("first bytes", f);
    fclose(f);

    SgError err = {0};
    SgScene *absolute = sg_scene_load(json, &err);
    cr_assert(absolute, "%s", err.message);
    cr_assert_eq(chdir(dir), 0);
    SgScene *relative = sg_scene_load("sky.json", &err);
    cr_assert(relative, "%s", err.message);
    cr_expect_eq(absolute->geometry_hash, relative->geometry_hash, "named from its own directory: %016llx, by its "
                 "absolute path: %016llx", (unsigned long long)relative->geometry_hash,
                 (unsigned long long)absolute->geometry_hash);
    sg_scene_free(relative);

    f = fopen(image, "wb");
    cr_assert(f);
    fputs("other bytes", f);
    fclose(f);
    SgScene *changed = sg_scene_load("sky.json", &err);
    cr_assert(changed, "%s", err.message);
    cr_expect_neq(absolute->geometry_hash, changed->geometry_hash, "the image changed, the hash did not");
    sg_scene_free(changed);
    sg_scene_free(absolute);

    remove(image);
    SgScene *missing = sg_scene_load("sky.json", &err);
    cr_expect_null(missing, "a scene whose sky image is missing loaded");
    cr_expect(strstr(err.message, "sky.json") && strstr(err.message, "sky.exr") && strstr(err.message, "cannot read"),
              "%s", err.message);
    sg_scene_free(missing);
    cr_assert_eq(chdir(cwd), 0);
}
