/* Mitsuba scene files: the same small scene in Mitsuba 3's and 0.6's
 * dialects loads to the same scene; each shape's area; transforms, camera,
 * bsdfs, emitters and integrator on hand-written files; what cannot be
 * read warns once per kind; bad input fails with one line and no scene;
 * and the programs run on a .xml scene. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "color.h"
#include "scene.h"
#include "sunsky.h"
#include "scene_load.h"
#include "support_files.h"
#include "support_render.h"

#define BOX_V3 "tests/data/mitsuba/box_v3.xml"
#define BOX_V06 "tests/data/mitsuba/box_v06.xml"

/* What every hand-written scene needs to load: a point light. */
#define LIGHT "<emitter type=\"point\"><point name=\"position\" x=\"0\" y=\"5\" z=\"0\"/></emitter>\n"

static char dir[4096];

/* The test's temporary folder (copied: the helpers' strings are reused). */
static const char *folder(void)
{
    if (!dir[0])
        snprintf(dir, sizeof dir, "%s", sg_test_tmpdir());
    return dir;
}

/* A scene file of the given body in dialect version, in the temporary folder. */
static const char *write_xml(const char *name, const char *version, const char *body)
{
    size_t size = strlen(body) + 256;
    char *text = malloc(size);
    cr_assert(text);
    snprintf(text, size, "<?xml version=\"1.0\"?>\n<scene version=\"%s\">\n%s</scene>\n", version, body);
    char *path = sg_test_write(folder(), name, text);
    free(text);
    return path;
}

static SgScene *load_body(const char *version, const char *body)
{
    return sgt_load_ok(write_xml("scene.xml", version, body));
}

static double total_area(const SgScene *s)
{
    double area = 0;
    for (uint32_t t = 0; t < s->triangle_count; t++) {
        double n[3];
        sg_scene_triangle_normal(s, t, n);
        area += 0.5 * sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    }
    return area;
}

static bool has_warning(const SgScene *s, const char *what)
{
    for (uint32_t i = 0; i < s->warning_count; i++)
        if (strstr(s->warnings[i], what))
            return true;
    return false;
}

/* ---- both dialects ------------------------------------------------------ */

Test(mitsuba_dialects, v3_and_v06_files_load_to_the_same_scene)
{
    SgScene *a = sgt_load_ok(sg_test_source_path(BOX_V3));
    SgScene *b = sgt_load_ok(sg_test_source_path(BOX_V06));
    cr_expect_eq(a->triangle_count, b->triangle_count);
    cr_assert_eq(a->vertex_count, b->vertex_count);
    for (size_t i = 0; i < 3 * (size_t)a->vertex_count; i++)
        cr_assert(fabs(a->positions[i] - b->positions[i]) < 1e-12, "vertex coordinate %zu differs", i);
    cr_expect(!memcmp(&a->camera, &b->camera, sizeof a->camera), "cameras differ");
    cr_expect_eq(a->render.max_depth, 5);
    cr_expect_eq(b->render.max_depth, 5);
    cr_expect_eq(a->render.spp, 8);
    cr_expect_eq(b->render.spp, 8);
    cr_expect_eq(a->light_count, 1);
    cr_expect_eq(b->light_count, 1);
    cr_expect_eq(a->light_source_count, 1);
    cr_expect_eq(b->light_source_count, 1);
    cr_assert_eq(a->material_count, b->material_count);
    for (uint32_t m = 0; m < a->material_count; m++) {
        const SgMaterial *x = &a->materials[m], *y = &b->materials[m];
        cr_expect_eq(x->type, y->type, "material %u", m);
        for (int c = 0; c < 3; c++) {
            cr_expect(fabsf(x->diffuse[c] - y->diffuse[c]) < 1e-6f, "material %s diffuse", x->name);
            cr_expect_eq(x->emission[c], y->emission[c]);
            cr_expect_eq(x->eta[c], y->eta[c]);
            cr_expect_eq(x->k[c], y->k[c]);
        }
        cr_expect_eq(x->ior, y->ior);
        cr_expect_eq(x->roughness[0], y->roughness[0]);
    }
    cr_expect_eq(a->geometry_hash, b->geometry_hash);
    sg_scene_free(a);
    sg_scene_free(b);
}

/* The box: its camera, lights and materials as the file says. */
Test(mitsuba_dialects, box_scene_maps_as_written)
{
    SgScene *s = sgt_load_ok(sg_test_source_path(BOX_V3));
    cr_expect_eq(s->camera.width, 64);
    cr_expect_eq(s->camera.height, 48);
    double want_fov = 2 * atan(tan(20 * M_PI / 180) * 48.0 / 64.0) * 180 / M_PI;
    cr_expect(fabs(s->camera.fov_deg - want_fov) < 1e-9, "fov %g, want %g", s->camera.fov_deg, want_fov);
    cr_expect(fabs(s->camera.position[2] - 4) < 1e-12 && fabs(s->camera.look_at[2] - 3) < 1e-12);
    cr_assert_eq(s->light_count, 1);
    cr_expect(fabs(s->lights[0].area - 0.25) < 1e-12, "light area %g", s->lights[0].area);
    cr_expect(fabs(s->lights[0].normal[1] + 1) < 1e-12, "the light faces down");
    cr_expect(fabs(s->lights[0].position[1] - 1.9) < 1e-12);
    cr_expect_eq(s->lights[0].radiance[0], 10.0f);
    const char *names[] = {"white", "red", "gold", "plastic", "glass"};
    const SgMaterialType types[] = {SG_MATERIAL_DIFFUSE, SG_MATERIAL_DIFFUSE, SG_MATERIAL_CONDUCTOR,
                                    SG_MATERIAL_COATED_DIFFUSE, SG_MATERIAL_DIELECTRIC};
    for (int i = 0; i < 5; i++) {
        bool found = false;
        for (uint32_t m = 0; m < s->material_count; m++)
            if (!strcmp(s->materials[m].name, names[i])) {
                found = true;
                cr_expect_eq(s->materials[m].type, types[i], "%s", names[i]);
            }
        cr_expect(found, "no material %s", names[i]);
    }
    for (uint32_t m = 0; m < s->material_count; m++) {
        const SgMaterial *q = &s->materials[m];
        if (!strcmp(q->name, "glass"))
            cr_expect(fabsf(q->ior - 1.5046f / 1.000277f) < 1e-5f, "bk7 over air: %g", q->ior);
        if (!strcmp(q->name, "plastic"))
            cr_expect(fabsf(q->roughness[0] - 0.2f) < 1e-6f && fabsf(q->diffuse[2] - 0.6f) < 1e-6f);
        if (!strcmp(q->name, "gold"))
            cr_expect(fabsf(q->eta[0] - 0.143f) < 1e-6f && fabsf(q->k[0] - 3.98f) < 1e-6f);
    }
    cr_expect_eq(s->warning_count, 0, "%s", s->warning_count ? s->warnings[0] : "");
    sg_scene_free(s);
}

/* An included file speaks its own dialect; "$name" reaches into include
 * names; an alias names the same element. */
Test(mitsuba_dialects, includes_keep_their_own_dialect)
{
    write_xml("old_part.xml", "0.6.0",
              "<shape type=\"rectangle\"><transform name=\"toWorld\"><translate x=\"5\"/></transform>"
              "<ref id=\"other\"/></shape>\n");
    SgScene *s = load_body("3.0.0", "<default name=\"part\" value=\"old_part\"/>\n"
                                    "<bsdf type=\"diffuse\" id=\"grey\"/>\n<alias id=\"grey\" as=\"other\"/>\n"
                                    "<include filename=\"$part.xml\"/>\n" LIGHT);
    cr_expect_eq(s->triangle_count, 2);
    cr_expect(fabs(s->bounds_min[0] - 4) < 1e-12, "toWorld read in the 0.6 file: %g", s->bounds_min[0]);
    sg_scene_free(s);
}

/* ---- shapes ------------------------------------------------------------- */

static double area_of(const char *shape)
{
    char body[4096];
    snprintf(body, sizeof body, "%s%s", shape, LIGHT);
    SgScene *s = load_body("3.0.0", body);
    double a = total_area(s);
    sg_scene_free(s);
    return a;
}

Test(mitsuba_shapes, each_shape_has_its_area)
{
    cr_expect(fabs(area_of("<shape type=\"rectangle\"/>") - 4) < 1e-12);
    cr_expect(fabs(area_of("<shape type=\"cube\"/>") - 24) < 1e-12);
    cr_expect(fabs(area_of("<shape type=\"rectangle\"><transform name=\"to_world\"><scale x=\"3\" y=\"0.5\"/>"
                           "</transform></shape>") - 6) < 1e-12);
    double sphere = area_of("<shape type=\"sphere\"><float name=\"radius\" value=\"2\"/></shape>");
    cr_expect(fabs(sphere - 16 * M_PI) < 1e-6 * 16 * M_PI, "sphere %g", sphere);
    double disk = area_of("<shape type=\"disk\"/>");
    cr_expect(fabs(disk - M_PI) < 1e-6, "disk %g", disk);
    double cylinder = area_of("<shape type=\"cylinder\"><float name=\"radius\" value=\"0.5\"/>"
                              "<point name=\"p0\" x=\"1\" y=\"1\" z=\"1\"/><point name=\"p1\" x=\"1\" y=\"4\" z=\"1\"/>"
                              "</shape>");
    cr_expect(fabs(cylinder - 2 * M_PI * 0.5 * 3) < 1e-6, "cylinder %g", cylinder);
}

Test(mitsuba_shapes, sphere_center_and_cylinder_axis)
{
    SgScene *s = load_body("3.0.0", "<shape type=\"sphere\"><point name=\"center\" x=\"5\" y=\"0\" z=\"0\"/>"
                                    "<float name=\"radius\" value=\"0.5\"/></shape>" LIGHT);
    /* the mesh is a little larger than the sphere: its area is the sphere's */
    cr_expect(fabs(s->bounds_min[0] - 4.5) < 1e-3 && fabs(s->bounds_max[0] - 5.5) < 1e-3);
    sg_scene_free(s);
    s = load_body("3.0.0", "<shape type=\"cylinder\"><point name=\"p0\" x=\"0\" y=\"0\" z=\"0\"/>"
                           "<point name=\"p1\" x=\"0\" y=\"2\" z=\"0\"/></shape>" LIGHT);
    cr_expect(fabs(s->bounds_min[1]) < 1e-9 && fabs(s->bounds_max[1] - 2) < 1e-9, "along y");
    cr_expect(fabs(s->bounds_max[0] - 1) < 1e-3 && fabs(s->bounds_max[2] - 1) < 1e-3, "radius 1");
    sg_scene_free(s);
}

Test(mitsuba_shapes, ply_serialized_and_obj_meshes)
{
    char body[8192];
    snprintf(body, sizeof body, "<shape type=\"ply\"><string name=\"filename\" value=\"%s\"/></shape>" LIGHT,
             sg_test_source_path("tests/data/mitsuba/quad.ply"));
    SgScene *s = load_body("3.0.0", body);
    cr_expect_eq(s->vertex_count, 4);
    cr_expect_eq(s->triangle_count, 2);
    cr_expect(fabs(total_area(s) - 2) < 1e-9);
    cr_assert_not_null(s->uvs);
    /* Mitsuba's v grows down the image, ours (pbrt's) up: the file's 0 is our 1 */
    cr_expect(s->uvs[1] == 1.0f && s->uvs[5] == 0.0f, "v %g %g", s->uvs[1], s->uvs[5]);
    sg_scene_free(s);
    for (int index = 0; index < 2; index++) {
        snprintf(body, sizeof body,
                 "<shape type=\"serialized\"><string name=\"filename\" value=\"%s\"/>"
                 "<integer name=\"shape_index\" value=\"%d\"/></shape>" LIGHT,
                 sg_test_source_path("tests/data/mitsuba/meshes.serialized"), index);
        s = load_body("3.0.0", body);
        cr_expect_eq(s->triangle_count, index ? 2u : 1u, "mesh %d", index);
        cr_expect(fabs(total_area(s) - (index ? 0.16 : 0.5)) < 1e-6, "mesh %d area %g", index, total_area(s));
        if (index)
            cr_expect_not_null(s->uvs, "the second mesh has uvs");
        sg_scene_free(s);
    }
    sg_test_write(folder(), "tri.obj", "v 0 0 0\nv 2 0 0\nv 0 2 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n");
    s = load_body("3.0.0", "<shape type=\"obj\"><string name=\"filename\" value=\"tri.obj\"/>"
                           "<boolean name=\"face_normals\" value=\"true\"/></shape>" LIGHT);
    cr_expect_eq(s->triangle_count, 1);
    cr_expect(fabs(total_area(s) - 2) < 1e-9);
    cr_assert_not_null(s->uvs);
    cr_expect(s->uvs[5] == 1.0f, "OBJ's v as it is (Mitsuba's flip undone by ours): %g", s->uvs[5]);
    sg_scene_free(s);
}

Test(mitsuba_shapes, shapegroup_instances)
{
    SgScene *s = load_body("3.0.0", "<shape type=\"shapegroup\" id=\"g\"><shape type=\"rectangle\"/></shape>\n"
                                    "<shape type=\"instance\"><ref id=\"g\"/></shape>\n"
                                    "<shape type=\"instance\"><ref id=\"g\"/><transform name=\"to_world\">"
                                    "<translate x=\"10\"/></transform></shape>\n" LIGHT);
    cr_expect_eq(s->triangle_count, 4, "two instances of two triangles");
    cr_expect(fabs(s->bounds_max[0] - 11) < 1e-12 && fabs(s->bounds_min[0] + 1) < 1e-12);
    sg_scene_free(s);
}

Test(mitsuba_shapes, flip_normals_turns_an_area_light_over)
{
    const char *light = "<shape type=\"rectangle\"><boolean name=\"flip_normals\" value=\"%s\"/>"
                        "<emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/></emitter></shape>\n";
    for (int flip = 0; flip < 2; flip++) {
        char body[1024];
        snprintf(body, sizeof body, light, flip ? "true" : "false");
        SgScene *s = load_body("3.0.0", body);
        cr_assert_eq(s->light_count, 1);
        cr_expect(fabs(s->lights[0].normal[2] - (flip ? -1 : 1)) < 1e-12, "flip %d: normal z %g", flip,
                  s->lights[0].normal[2]);
        sg_scene_free(s);
    }
}

/* A mirroring to_world turns a rectangle's winding over but not its normal
 * (Mitsuba takes it through the inverse transpose): the light still faces +z. */
Test(mitsuba_shapes, mirrored_analytic_light_keeps_its_side)
{
    SgScene *s = load_body("3.0.0", "<shape type=\"rectangle\"><transform name=\"to_world\"><scale x=\"-2\"/>"
                                    "</transform><emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/>"
                                    "</emitter></shape>\n");
    cr_assert_eq(s->light_count, 1);
    cr_expect(fabs(s->lights[0].normal[2] - 1) < 1e-12, "normal z %g", s->lights[0].normal[2]);
    cr_expect(fabs(s->lights[0].area - 8) < 1e-12);
    sg_scene_free(s);
}

/* ---- transforms ----------------------------------------------------------- */

static void expect_point(const double *p, double x, double y, double z)
{
    cr_expect(fabs(p[0] - x) < 1e-9 && fabs(p[1] - y) < 1e-9 && fabs(p[2] - z) < 1e-9,
              "(%g %g %g), expected (%g %g %g)", p[0], p[1], p[2], x, y, z);
}

/* The rectangle's first corner (-1, -1, 0) through each kind of step, in order. */
Test(mitsuba_transforms, steps_apply_in_order)
{
    struct {
        const char *steps;
        double x, y, z;
    } cases[] = {
        {"<translate x=\"1\" y=\"2\" z=\"3\"/>", 0, 1, 3},
        {"<scale x=\"2\" y=\"3\"/>", -2, -3, 0},
        {"<rotate z=\"1\" angle=\"90\"/>", 1, -1, 0},
        {"<scale value=\"2\"/><translate x=\"5\"/>", 3, -2, 0},
        {"<translate x=\"5\"/><scale value=\"2\"/>", 8, -2, 0},
        {"<matrix value=\"1 0 0 7  0 1 0 0  0 0 1 0  0 0 0 1\"/>", 6, -1, 0},
        {"<lookat origin=\"0, 0, 5\" target=\"0, 0, 6\" up=\"0, 1, 0\"/>", -1, -1, 5},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        char body[1024];
        snprintf(body, sizeof body,
                 "<shape type=\"rectangle\"><transform name=\"to_world\">%s</transform></shape>" LIGHT,
                 cases[i].steps);
        SgScene *s = load_body("3.0.0", body);
        expect_point(s->positions, cases[i].x, cases[i].y, cases[i].z);
        sg_scene_free(s);
    }
}

/* ---- sensor and integrator ---------------------------------------------- */

static double vertical_fov(const char *axis, int w, int h)
{
    char body[1024];
    snprintf(body, sizeof body,
             "<sensor type=\"perspective\"><float name=\"fov\" value=\"60\"/>"
             "<string name=\"fov_axis\" value=\"%s\"/><film type=\"hdrfilm\"><integer name=\"width\" value=\"%d\"/>"
             "<integer name=\"height\" value=\"%d\"/></film></sensor><shape type=\"cube\"/>" LIGHT,
             axis, w, h);
    SgScene *s = load_body("3.0.0", body);
    double fov = s->camera.fov_deg;
    sg_scene_free(s);
    return fov;
}

static double vfov_of(double t) { return 2 * atan(t) * 180 / M_PI; }

Test(mitsuba_sensor, fov_axis_rules)
{
    double t = tan(30 * M_PI / 180);
    cr_expect(fabs(vertical_fov("y", 64, 48) - 60) < 1e-9);
    cr_expect(fabs(vertical_fov("x", 64, 48) - vfov_of(t * 48 / 64)) < 1e-9);
    cr_expect(fabs(vertical_fov("diagonal", 64, 48) - vfov_of(t * 48 / 80)) < 1e-9);
    cr_expect(fabs(vertical_fov("smaller", 64, 48) - 60) < 1e-9);
    cr_expect(fabs(vertical_fov("larger", 64, 48) - vfov_of(t * 48 / 64)) < 1e-9);
    cr_expect(fabs(vertical_fov("smaller", 48, 64) - vfov_of(t * 64 / 48)) < 1e-9, "portrait: x is smaller");
}

Test(mitsuba_sensor, max_depth_rule)
{
    const char *cases[] = {"<integrator type=\"path\"><integer name=\"max_depth\" value=\"3\"/></integrator>",
                           "<integrator type=\"path\"><integer name=\"max_depth\" value=\"-1\"/></integrator>",
                           "<integrator type=\"aov\"><integrator type=\"path\"><integer name=\"max_depth\" "
                           "value=\"7\"/></integrator></integrator>",
                           "", "<integrator type=\"direct\"/>"};
    int want[] = {3, 1024, 7, 1024, 2};
    for (int i = 0; i < 5; i++) {
        char body[1024];
        snprintf(body, sizeof body, "%s<shape type=\"cube\"/>" LIGHT, cases[i]);
        SgScene *s = load_body("3.0.0", body);
        cr_expect_eq(s->render.max_depth, want[i], "case %d: %d", i, s->render.max_depth);
        sg_scene_free(s);
    }
    SgScene *s = load_body("0.6.0", "<integrator type=\"path\"><integer name=\"maxDepth\" value=\"4\"/></integrator>"
                                    "<shape type=\"cube\"/>" LIGHT);
    cr_expect_eq(s->render.max_depth, 4);
    sg_scene_free(s);
}

/* ---- bsdfs and textures ------------------------------------------------- */

static SgMaterial material_of(const char *bsdf, SgScene **keep)
{
    char body[4096];
    snprintf(body, sizeof body, "<shape type=\"cube\">%s</shape>" LIGHT, bsdf);
    SgScene *s = load_body("3.0.0", body);
    cr_assert_eq(s->material_count, 1);
    SgMaterial m = s->materials[0];
    if (keep)
        *keep = s;
    else
        sg_scene_free(s);
    return m;
}

Test(mitsuba_media, absorbing_interior_of_a_dielectric)
{
    /* Mitsuba 3: sigma_t and albedo 0; nested, and by reference */
    SgScene *s = load_body("3.0.0",
                           "<medium type=\"homogeneous\" id=\"ink\"><rgb name=\"sigma_t\" value=\"0.5 1 2\"/>"
                           "<float name=\"albedo\" value=\"0\"/><float name=\"scale\" value=\"2\"/></medium>"
                           "<shape type=\"cube\"><bsdf type=\"dielectric\"/><ref name=\"interior\" id=\"ink\"/></shape>"
                           "<shape type=\"sphere\"><bsdf type=\"diffuse\"/>"
                           "<medium type=\"homogeneous\" name=\"interior\"><float name=\"albedo\" value=\"0\"/>"
                           "</medium></shape>" LIGHT);
    const SgMaterial *m = &s->materials[s->triangle_material[0]];
    cr_expect_eq(m->type, SG_MATERIAL_DIELECTRIC);
    cr_expect(m->sigma_a[0] == 1.0f && m->sigma_a[2] == 4.0f, "sigma_t (1 - albedo) scale: %g %g", m->sigma_a[0],
              m->sigma_a[2]);
    cr_expect(has_warning(s, "not a dielectric"));
    cr_expect(!has_warning(s, "scattering"));
    sg_scene_free(s);
    /* Mitsuba 0.6: sigmaA and sigmaS; a scattering one keeps its warning */
    s = load_body("0.6.0", "<shape type=\"cube\"><bsdf type=\"dielectric\"/>"
                           "<medium type=\"homogeneous\" name=\"interior\"><rgb name=\"sigmaA\" value=\"0.3\"/>"
                           "<rgb name=\"sigmaS\" value=\"0\"/></medium></shape>"
                           "<shape type=\"sphere\"><bsdf type=\"dielectric\"/>"
                           "<medium type=\"homogeneous\" name=\"interior\"/></shape>" LIGHT);
    cr_expect_float_eq(s->materials[s->triangle_material[0]].sigma_a[1], 0.3f, 1e-6);
    cr_expect_eq(s->materials[s->triangle_material[s->triangle_count - 1]].sigma_a[1], 0.0f);
    cr_expect(has_warning(s, "scattering media"));
    sg_scene_free(s);
}

/* Mitsuba 0.6's sunsky: a sky image made at load time and a sun disk. */
Test(mitsuba_emitters, sunsky_is_a_sky_image_and_a_sun)
{
    SgScene *s = load_body("0.6.0",
                           "<shape type=\"cube\"/><emitter type=\"sunsky\">"
                           "<vector name=\"sunDirection\" x=\"0\" y=\"0.8\" z=\"0.6\"/>"
                           "<float name=\"turbidity\" value=\"4\"/><integer name=\"resolution\" value=\"64\"/>"
                           "<float name=\"sunScale\" value=\"0.5\"/><float name=\"sunRadiusScale\" value=\"2\"/>"
                           "</emitter>\n");
    cr_assert_eq(s->light_source_count, 2);
    const SgLightSource *sky = &s->light_sources[0], *sun = &s->light_sources[1];
    cr_expect_eq(sky->kind, SG_LIGHT_INFINITE);
    cr_assert_not_null(sky->image_pixels);
    cr_expect(sky->image_width == 128 && sky->image_height == 64);
    /* the top row looks at the zenith: Preetham's zenith luminance there, in
     * Mitsuba's units (kcd/m^2 over 683 lm/W x 106.857 nm / 1000) */
    double zenith = sg_preetham_zenith_luminance(4.0, acos(0.8)) / (683.0 * 106.857 / 1000.0), y = 0;
    for (int i = 0; i < sky->image_width; i++) {
        const float *px = sky->image_pixels + 3 * i;
        y += sg_luminance(px[0], px[1], px[2]) / sky->image_width;
    }
    cr_expect(fabs(y - zenith) < 0.03 * zenith, "zenith row luminance %g, Preetham's %g", y, zenith);
    const float *below = sky->image_pixels + 3 * (size_t)sky->image_width * (sky->image_height - 1);
    cr_expect(below[0] == 0 && below[1] == 0 && below[2] == 0, "black below the horizon");
    cr_expect_eq(sun->kind, SG_LIGHT_DISTANT);
    expect_point(sun->direction, 0, -0.8, -0.6); /* the way its light travels */
    cr_expect(fabs(sun->angular_radius - 2 * SG_SUN_ANGULAR_RADIUS) < 1e-9);
    cr_expect(sun->rgb[0] > sun->rgb[2] && sun->rgb[2] > 0, "the sun through air is reddened: %g %g", sun->rgb[0],
              sun->rgb[2]);
    cr_expect_eq(s->warning_count, 1, "one warning: the sky's model");
    cr_expect(has_warning(s, "Hosek-Wilkie sky is taken as Preetham's"));
    sg_scene_free(s);
}

Test(mitsuba_bsdfs, conductors)
{
    SgMaterial m = material_of("<bsdf type=\"conductor\"><string name=\"material\" value=\"none\"/></bsdf>", NULL);
    cr_expect_eq(m.type, SG_MATERIAL_MIRROR);
    m = material_of("<bsdf type=\"roughconductor\"><float name=\"alpha\" value=\"0.3\"/></bsdf>", NULL);
    cr_expect_eq(m.type, SG_MATERIAL_CONDUCTOR);
    cr_expect(fabsf(m.eta[1] - 0.924f) < 1e-6f, "copper by default");
    cr_expect(fabsf(m.roughness[0] - 0.3f) < 1e-6f);
    SgScene *rough;
    m = material_of("<bsdf type=\"roughconductor\"><texture type=\"checkerboard\" name=\"alpha\"/></bsdf>", &rough);
    cr_expect(fabsf(m.roughness[0] - 0.3f) < 1e-6f, "a textured alpha is its mean: %g", m.roughness[0]);
    cr_expect(has_warning(rough, "taken as its mean"));
    sg_scene_free(rough);
    m = material_of("<bsdf type=\"conductor\"><rgb name=\"eta\" value=\"0.2 0.3 0.4\"/>"
                    "<rgb name=\"k\" value=\"3 4 5\"/></bsdf>", NULL);
    cr_expect(m.eta[2] == 0.4f && m.k[0] == 3.0f, "explicit eta and k");
    /* a tint keeps the tinted reflectance at normal incidence: eta 1 and its k */
    SgScene *s;
    m = material_of("<bsdf type=\"conductor\"><rgb name=\"eta\" value=\"2\"/><rgb name=\"k\" value=\"0\"/>"
                    "<rgb name=\"specular_reflectance\" value=\"0.5\"/></bsdf>", &s);
    cr_expect(fabsf(m.diffuse[0] - 0.5f / 9) < 1e-6f, "0.5 of ((2-1)/(2+1))^2: %g", m.diffuse[0]);
    cr_expect(m.eta[0] == 1.0f && fabsf(m.k[0] - sg_conductor_k_of_reflectance(0.5f / 9)) < 1e-6f);
    cr_expect(has_warning(s, "specular_reflectance"));
    sg_scene_free(s);
}

Test(mitsuba_bsdfs, wrappers_and_blends)
{
    SgScene *s;
    SgMaterial m = material_of("<bsdf type=\"blendbsdf\"><float name=\"weight\" value=\"0.25\"/>"
                               "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.8\"/></bsdf>"
                               "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.4\"/></bsdf></bsdf>", NULL);
    cr_expect(fabsf(m.diffuse[0] - 0.7f) < 1e-6f, "0.75 0.8 + 0.25 0.4: %g", m.diffuse[0]);
    m = material_of("<bsdf type=\"mask\"><float name=\"opacity\" value=\"0.5\"/><bsdf type=\"dielectric\"/></bsdf>", &s);
    cr_expect_eq(m.type, SG_MATERIAL_DIELECTRIC);
    cr_expect(m.cutout && m.alpha == 0.5f && !m.alpha_texture, "mask: a cut-out of its opacity");
    cr_expect(!has_warning(s, "mask"), "mask is read, no warning");
    sg_scene_free(s);
    m = material_of("<bsdf type=\"mask\"><texture name=\"opacity\" type=\"checkerboard\"/>"
                    "<bsdf type=\"diffuse\"/></bsdf>", NULL);
    cr_expect(m.cutout && m.alpha_texture > 0, "a textured opacity cuts where below 0.5");
    m = material_of("<bsdf type=\"bumpmap\"><texture type=\"checkerboard\"/><bsdf type=\"thindielectric\"/></bsdf>",
                    &s);
    cr_expect_eq(m.type, SG_MATERIAL_DIELECTRIC);
    cr_expect(m.bump_texture > 0 && m.bump_scale == 1.0f, "bumpmap: a bump texture");
    cr_expect(!has_warning(s, "bumpmap") && has_warning(s, "thindielectric"));
    sg_scene_free(s);
    m = material_of("<bsdf type=\"difftrans\"><rgb name=\"transmittance\" value=\"0.7\"/></bsdf>", NULL);
    cr_expect(m.type == SG_MATERIAL_DIFFUSE_TRANSMISSION && m.transmittance[1] == 0.7f && m.diffuse[1] == 0,
              "difftrans: a diffuse transmitter");
    m = material_of("<bsdf type=\"normalmap\"><texture type=\"checkerboard\" name=\"normalmap\"/>"
                    "<bsdf type=\"diffuse\"/></bsdf>", NULL);
    cr_expect(m.normal_texture > 0 && !m.bump_texture, "normalmap: a normal texture");
}

Test(mitsuba_bsdfs, colours_and_spectra)
{
    SgMaterial m = material_of("<bsdf type=\"diffuse\"><spectrum name=\"reflectance\" "
                               "value=\"400:0.5, 500:0.5, 600:0.5, 700:0.5\"/></bsdf>", NULL);
    for (int c = 0; c < 3; c++)
        cr_expect(fabsf(m.diffuse[c] - 0.5f) < 2e-2f, "a flat spectrum is grey: %g", m.diffuse[c]);
    m = material_of("<bsdf type=\"diffuse\"><spectrum name=\"reflectance\" value=\"600:0.9, 700:0.9\"/></bsdf>", NULL);
    cr_expect(m.diffuse[0] > 2 * m.diffuse[2], "a long-wave spectrum is red: %g %g %g", m.diffuse[0], m.diffuse[1],
              m.diffuse[2]);
    m = material_of("<bsdf type=\"diffuse\"><srgb name=\"reflectance\" value=\"#808080\"/></bsdf>", NULL);
    cr_expect(fabsf(m.diffuse[0] - 0.2158605f) < 1e-5f, "sRGB 128 is linear 0.216: %g", m.diffuse[0]);
}

Test(mitsuba_bsdfs, textures)
{
    SgScene *s;
    SgMaterial m = material_of("<bsdf type=\"diffuse\"><texture type=\"checkerboard\" name=\"reflectance\">"
                               "<rgb name=\"color0\" value=\"1 0 0\"/><rgb name=\"color1\" value=\"0 0 1\"/>"
                               "</texture></bsdf>", &s);
    cr_assert_neq(m.diffuse_texture, 0);
    const SgTexture *t = &s->textures[m.diffuse_texture - 1];
    cr_expect_eq(t->kind, SG_TEXTURE_CHECKERBOARD);
    cr_expect_eq(t->uscale, 2.0f, "Mitsuba's squares are half a unit");
    cr_expect_eq(t->input[0].value[0], 1.0f);
    cr_expect_eq(t->input[1].value[2], 1.0f);
    sg_scene_free(s);
    m = material_of("<bsdf type=\"diffuse\"><texture type=\"scale\" name=\"reflectance\">"
                    "<float name=\"scale\" value=\"0.5\"/><texture type=\"checkerboard\"/></texture></bsdf>", &s);
    cr_assert_eq(s->texture_count, 2, "the checkerboard, then its scale");
    cr_expect_eq(m.diffuse_texture, 2);
    cr_expect_eq(s->textures[1].kind, SG_TEXTURE_SCALE);
    cr_expect_eq(s->textures[1].input[0].texture, 1);
    cr_expect(fabsf(m.diffuse[0] - 0.15f) < 1e-6f, "half the checkerboard's mean 0.3: %g", m.diffuse[0]);
    sg_scene_free(s);
    m = material_of("<bsdf type=\"diffuse\"><texture type=\"bitmap\" name=\"reflectance\">"
                    "<string name=\"filename\" value=\"missing.png\"/></texture></bsdf>", &s);
    cr_expect_neq(m.diffuse_texture, 0);
    cr_expect(has_warning(s, "cannot be read"));
    sg_scene_free(s);
}

/* ---- emitters ----------------------------------------------------------- */

Test(mitsuba_emitters, point_spot_directional_constant_envmap)
{
    sg_test_write(folder(), "sky.exr", "not read by the loader");
    SgScene *s = load_body(
        "3.0.0",
        "<shape type=\"cube\"/>\n"
        "<emitter type=\"point\"><point name=\"position\" x=\"1\" y=\"2\" z=\"3\"/>"
        "<rgb name=\"intensity\" value=\"5\"/></emitter>\n"
        "<emitter type=\"spot\"><transform name=\"to_world\"><lookat origin=\"0,4,0\" target=\"0,0,0\" up=\"0,0,1\"/>"
        "</transform><float name=\"cutoff_angle\" value=\"30\"/></emitter>\n"
        "<emitter type=\"directional\"><vector name=\"direction\" x=\"0\" y=\"-2\" z=\"0\"/>"
        "<rgb name=\"irradiance\" value=\"3\"/></emitter>\n"
        "<emitter type=\"constant\"><rgb name=\"radiance\" value=\"0.5\"/></emitter>\n"
        "<emitter type=\"envmap\"><string name=\"filename\" value=\"sky.exr\"/><float name=\"scale\" value=\"2\"/>"
        "</emitter>\n");
    cr_assert_eq(s->light_source_count, 5);
    const SgLightSource *l = s->light_sources;
    cr_expect_eq(l[0].kind, SG_LIGHT_POINT);
    expect_point(l[0].position, 1, 2, 3);
    cr_expect_eq(l[0].rgb[0], 5.0f);
    cr_expect_eq(l[1].kind, SG_LIGHT_SPOT);
    expect_point(l[1].position, 0, 4, 0);
    expect_point(l[1].direction, 0, -1, 0);
    cr_expect(fabs(l[1].cos_cone - cos(M_PI / 6)) < 1e-12);
    cr_expect(fabs(l[1].cos_falloff_start - cos(22.5 * M_PI / 180)) < 1e-12, "beam_width 3/4 of the cutoff");
    cr_expect_eq(l[2].kind, SG_LIGHT_DISTANT);
    expect_point(l[2].direction, 0, -1, 0);
    cr_expect_eq(l[3].kind, SG_LIGHT_INFINITE);
    cr_expect_null(l[3].image_path);
    cr_expect_eq(l[4].kind, SG_LIGHT_INFINITE);
    cr_expect_eq(l[4].layout, SG_ENVIRONMENT_LATLONG);
    cr_expect_eq(l[4].rgb[1], 2.0f);
    /* Mitsuba's envmap is y up: our light space's z is world +y, and its
     * azimuth 0 (u = 0) is Mitsuba's -z */
    double z[3] = {l[4].light_to_world[0][2], l[4].light_to_world[1][2], l[4].light_to_world[2][2]};
    double x[3] = {l[4].light_to_world[0][0], l[4].light_to_world[1][0], l[4].light_to_world[2][0]};
    expect_point(z, 0, 1, 0);
    expect_point(x, 0, 0, -1);
    sg_scene_free(s);
}

/* ---- warnings ----------------------------------------------------------- */

Test(mitsuba_warnings, one_per_kind_with_file_and_line)
{
    const char *path = write_xml("warn.xml", "3.0.0",
                                 "<shape type=\"hair\"/>\n<shape type=\"hair\"/>\n<shape type=\"cube\"/>\n"
                                 "<medium type=\"homogeneous\"/>\n" LIGHT);
    SgScene *s = sgt_load_ok(path);
    cr_expect_eq(s->warning_count, 2);
    char want[4300];
    snprintf(want, sizeof want, "%s:3: shape \"hair\" is not supported: left out (2 times)", path);
    cr_expect(has_warning(s, want), "got: %s", s->warning_count ? s->warnings[0] : "none");
    cr_expect(has_warning(s, "scattering media"), "a scattering medium still warns");
    sg_scene_free(s);
}

/* ---- bad input ---------------------------------------------------------- */

/* Loading fails with one line that names the file (and what). */
static void expect_error_at(const char *path, const char *file, const char *what)
{
    SgError err = {0};
    SgScene *s = sg_scene_load(path, &err);
    cr_expect_null(s, "loaded %s (expected: %s)", path, what);
    sg_scene_free(s);
    cr_expect(strstr(err.message, file), "\"%s\" not in \"%s\"", file, err.message);
    cr_expect(strstr(err.message, what), "\"%s\" not in \"%s\"", what, err.message);
    cr_expect(!strchr(err.message, '\n'), "message is not one line");
}

static void expect_error(const char *body, const char *what)
{
    const char *path = write_xml("bad.xml", "3.0.0", body);
    expect_error_at(path, path, what);
}

Test(mitsuba_errors, meaningless_scenes)
{
    expect_error("<shape type=\"cube\"/>\n", "no light");
    expect_error("<shape type=\"cube\"/><emitter type=\"projector\"/>\n", "no light (projector is not supported)");
    expect_error("<shape type=\"cube\"><ref id=\"nothing\"/></shape>" LIGHT, "unknown id \"nothing\"");
    expect_error("<shape type=\"ply\"><string name=\"filename\" value=\"absent.ply\"/></shape>" LIGHT, "absent.ply");
    expect_error("<shape type=\"obj\"><string name=\"filename\" value=\"absent.obj\"/></shape>" LIGHT, "absent.obj");
    expect_error("<shape type=\"cube\"><float name=\"x\" value=\"$undefined\"/></shape>" LIGHT, "$undefined");
    expect_error(LIGHT, "no triangles");
    expect_error("<shape type=\"cube\"><transform name=\"to_world\"><rotate angle=\"3\"/></transform></shape>" LIGHT,
                 "non-zero axis");
}

Test(mitsuba_errors, truncated_xml_and_bad_versions)
{
    const char *path = sg_test_write(folder(), "cut.xml", "<scene version=\"3.0.0\">\n<shape type=\"cube\">\n");
    expect_error_at(path, "cut.xml:3", "XML");
    path = sg_test_write(folder(), "old.xml", "<scene version=\"7.0\"><shape type=\"cube\"/></scene>");
    expect_error_at(path, "old.xml:1", "version");
    path = sg_test_write(folder(), "root.xml", "<mesh/>");
    expect_error_at(path, "root.xml:1", "not <scene>");
}

Test(mitsuba_errors, cyclic_include)
{
    write_xml("a.xml", "3.0.0", "<include filename=\"b.xml\"/>\n");
    const char *b = write_xml("b.xml", "3.0.0", "<shape type=\"cube\"/>\n<include filename=\"a.xml\"/>\n");
    char a[4300];
    snprintf(a, sizeof a, "%s/a.xml", folder());
    expect_error_at(a, b, "cyclic include");
}

static void write_bytes(const char *name, const unsigned char *data, size_t size)
{
    char path[4300];
    snprintf(path, sizeof path, "%s/%s", folder(), name);
    FILE *f = fopen(path, "wb");
    cr_assert(f, "cannot write %s", path);
    cr_assert(fwrite(data, 1, size, f) == size && fclose(f) == 0, "cannot write %s (%zu bytes)", path, size);
}

Test(mitsuba_errors, serialized_cut_short_or_absurd)
{
    FILE *f = fopen(sg_test_source_path("tests/data/mitsuba/meshes.serialized"), "rb");
    cr_assert(f);
    unsigned char data[4096];
    size_t size = fread(data, 1, sizeof data, f);
    fclose(f);
    cr_assert_gt(size, 40);
    write_bytes("cut.serialized", data, 30);
    expect_error("<shape type=\"serialized\"><string name=\"filename\" value=\"cut.serialized\"/></shape>" LIGHT,
                 "cut short");
    expect_error("<shape type=\"serialized\"><string name=\"filename\" value=\"cut.serialized\"/>"
                 "<integer name=\"shape_index\" value=\"1\"/></shape>" LIGHT,
                 "cut.serialized");
    /* a hand-made mesh claiming 2^40 vertices: zlib of the raw header */
    unsigned char absurd[64] = {0x1C, 0x04, 0x04, 0x00};
    unsigned char raw[22] = {0x00, 0x10, 0, 0, 'x', 0, 0, 0, 0, 0, 0, 1, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0};
    unsigned long packed = sizeof absurd - 4;
    extern int compress(unsigned char *, unsigned long *, const unsigned char *, unsigned long);
    cr_assert_eq(compress(absurd + 4, &packed, raw, sizeof raw), 0);
    write_bytes("absurd.serialized", absurd, 4 + packed);
    expect_error("<shape type=\"serialized\"><string name=\"filename\" value=\"absurd.serialized\"/></shape>" LIGHT,
                 "absurd counts");
    expect_error("<shape type=\"serialized\"><string name=\"filename\" value=\"absurd.serialized\"/>"
                 "<integer name=\"shape_index\" value=\"3\"/></shape>" LIGHT,
                 "absurd");
}

/* Every cut of a scene file and of a serialized mesh either loads or fails
 * with one line: never a crash, never a scene with a message. */
Test(mitsuba_errors, every_truncation_fails_cleanly, .timeout = 60)
{
    const char *inputs[] = {BOX_V06, "tests/data/mitsuba/meshes.serialized"};
    const char *companions[] = {"quad.ply", "meshes.serialized", "light_v06.xml"};
    for (int i = 0; i < 3; i++) { /* what the box names, beside its cut copies */
        char from[4300];
        snprintf(from, sizeof from, "tests/data/mitsuba/%s", companions[i]);
        FILE *f = fopen(sg_test_source_path(from), "rb");
        cr_assert(f);
        unsigned char data[8192];
        size_t size = fread(data, 1, sizeof data, f);
        fclose(f);
        write_bytes(companions[i], data, size);
    }
    for (int which = 0; which < 2; which++) {
        FILE *f = fopen(sg_test_source_path(inputs[which]), "rb");
        cr_assert(f);
        unsigned char data[8192];
        size_t size = fread(data, 1, sizeof data, f);
        fclose(f);
        cr_assert(size > 0 && size < sizeof data);
        for (size_t cut = 0; cut < size; cut += which ? 1 : 23) {
            const char *path;
            if (which) {
                write_bytes("cut.serialized", data, cut);
                path = write_xml("cut_mesh.xml", "3.0.0",
                                 "<shape type=\"serialized\"><string name=\"filename\" value=\"cut.serialized\"/>"
                                 "<integer name=\"shape_index\" value=\"1\"/></shape>" LIGHT);
            } else {
                write_bytes("cut_box.xml", data, cut);
                static char box[4300];
                snprintf(box, sizeof box, "%s/cut_box.xml", folder());
                path = box;
            }
            SgError err = {0};
            SgScene *s = sg_scene_load(path, &err);
            if (s)
                cr_expect(!err.failed, "a scene and an error at cut %zu", cut);
            else
                cr_expect(err.failed && err.message[0] && !strchr(err.message, '\n'), "cut %zu: \"%s\"", cut,
                          err.message);
            sg_scene_free(s);
        }
    }
}

/* ---- the programs take .xml files --------------------------------------- */

Test(mitsuba_programs, voxelize_and_render_a_mitsuba_scene, .timeout = 120)
{
    char voxelize[4096], render[4096], cmd[16384], errs[8192];
    sg_test_program("voxelize", voxelize, sizeof voxelize);
    sg_test_program("render", render, sizeof render);
    if (!sg_test_exists(voxelize) || !sg_test_exists(render))
        cr_skip_test("programs not built");
    const char *scene = sg_test_source_path(BOX_V3);
    snprintf(cmd, sizeof cmd, "%s %s -o %s/box.vdb --resolution 16", voxelize, scene, folder());
    cr_expect_eq(sg_test_run(cmd, errs, sizeof errs), 0, "%s", errs);
    snprintf(cmd, sizeof cmd, "%s/box.vdb", folder());
    cr_expect(sg_test_exists(cmd));
    snprintf(cmd, sizeof cmd, "%s %s --spp 4 --size 32x24 --seed 1 -o %s/box.exr --quiet", render, scene, folder());
    cr_expect_eq(sg_test_run(cmd, errs, sizeof errs), 0, "%s", errs);
    snprintf(cmd, sizeof cmd, "oiiotool %s/box.exr --printstats 2>&1 | grep 'Stats Avg'", folder());
    FILE *stats = popen(cmd, "r");
    cr_assert(stats);
    char line[512];
    double mean[3] = {0, 0, 0};
    char *avg = fgets(line, sizeof line, stats) ? strstr(line, "Avg:") : NULL;
    pclose(stats);
    cr_assert(avg && sscanf(avg + 4, "%lf %lf %lf", &mean[0], &mean[1], &mean[2]) == 3, "no stats");
    cr_expect(mean[0] > 0.01 && mean[0] < 10, "the lit box renders: mean %g", mean[0]);
}
