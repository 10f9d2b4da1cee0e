/* pbrt-v4 scene files: every statement of the supported subset on small
 * hand-written files, the cameras and lights of the shared staircase and
 * bathroom, malformed input, and a render of the staircase against a
 * committed mean brightness. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "color.h"
#include "image_io.h"
#include "render/renderer.h"
#include "scene_load.h"
#include "support_files.h"
#include "support_render.h"

#define STAIRCASE "../shared/scenes/staircase/staircase.pbrt"
#define BATHROOM "../shared/scenes/bathroom/bathroom.pbrt"

/* A camera and film every hand-written scene starts with (three lines;
 * Scale -1 1 1 makes pbrt's default camera agree with our image's sides). */
#define HEADER                                                                                   \
    "Scale -1 1 1 Film \"rgb\" \"integer xresolution\" [ 64 ] \"integer yresolution\" [ 48 ]\n"               \
    "Camera \"perspective\" \"float fov\" [ 45 ]\n"                                              \
    "WorldBegin\n"

/* One triangle (0,0,0) (1,0,0) (0,1,0): its winding faces +z. */
#define TRIANGLE "Shape \"trianglemesh\" \"point3 P\" [ 0 0 0 1 0 0 0 1 0 ] \"integer indices\" [ 0 1 2 ]\n"

static const char *scene_dir;

/* The folder the tests write their scenes and files in (made on first use). */
static const char *scene_folder(void)
{
    if (!scene_dir)
        scene_dir = sg_test_tmpdir();
    return scene_dir;
}

/* path = scene_folder()/name. */
static char *scene_file(char path[4200], const char *name)
{
    snprintf(path, 4200, "%s/%s", scene_folder(), name);
    return path;
}

/* Writes scene_dir/name; the path stays valid until the next call. */
static const char *write_scene(const char *name, const char *text)
{
    static char path[4200];
    scene_file(path, name);
    FILE *f = fopen(path, "wb");
    cr_assert(f, "cannot write %s", path);
    cr_assert(fputs(text, f) >= 0 && fclose(f) == 0, "cannot write %s", path);
    return path;
}

static SgScene *load_text(const char *text, SgError *err)
{
    memset(err, 0, sizeof *err);
    return sg_scene_load(write_scene("scene.pbrt", text), err);
}

static SgScene *load_ok(const char *text)
{
    SgError err;
    SgScene *s = load_text(text, &err);
    cr_assert(s, "load failed: %s", err.message);
    return s;
}

/* The error of a malformed file: asserts it fails with one line that
 * starts with "FILE:LINE: " and contains what. */
static void expect_error(const char *text, int line, const char *what)
{
    SgError err;
    SgScene *s = load_text(text, &err);
    cr_assert_null(s, "loaded a malformed file (expected line %d: %s)", line, what);
    sg_scene_free(s);
    char prefix[4200];
    snprintf(prefix, sizeof prefix, "%s/scene.pbrt:%d: ", scene_dir, line);
    cr_expect(!strncmp(err.message, prefix, strlen(prefix)), "expected \"%s...\", got \"%s\"",
              prefix, err.message);
    cr_expect(strstr(err.message, what), "expected \"%s\" in \"%s\"", what, err.message);
    cr_expect(!strchr(err.message, '\n'), "message is not one line");
}

/* expect_error for an error on the first statement after HEADER (line 4). */
static void expect_first_statement_error(const char *statements, const char *what)
{
    char text[4096];
    cr_assert_lt(strlen(HEADER) + strlen(statements), sizeof text);
    snprintf(text, sizeof text, "%s%s", HEADER, statements);
    expect_error(text, 4, what);
}

static const double *vertex(const SgScene *s, uint32_t t, int c)
{
    return s->positions + 3 * (size_t)s->indices[3 * (size_t)t + c];
}

static void expect_point(const double *p, double x, double y, double z, const char *what)
{
    cr_expect(fabs(p[0] - x) < 1e-9 && fabs(p[1] - y) < 1e-9 && fabs(p[2] - z) < 1e-9,
              "%s: (%g %g %g), expected (%g %g %g)", what, p[0], p[1], p[2], x, y, z);
}

static bool has_warning(const SgScene *s, const char *what)
{
    for (uint32_t i = 0; i < s->warning_count; i++)
        if (strstr(s->warnings[i], what))
            return true;
    return false;
}

static const SgMaterial *material_of(const SgScene *s, uint32_t t)
{
    return &s->materials[s->triangle_material[t]];
}

/* ---- transforms --------------------------------------------------------- */

/* A scene that should have loaded without a warning, freed. */
static void free_quietly_loaded(SgScene *s)
{
    cr_expect_eq(s->warning_count, 0, "warnings: %u (the first: %s)", s->warning_count,
                 s->warning_count ? s->warnings[0] : "");
    sg_scene_free(s);
}

Test(pbrt_transforms, statements_compose_in_pbrt_order)
{
    /* p' = T * R * S * p: the last statement applies first. */
    SgScene *s = load_ok(HEADER "Translate 1 2 3\nRotate 90 0 0 1\nScale 2 2 2\n" TRIANGLE);
    cr_assert_eq(s->triangle_count, 1);
    expect_point(vertex(s, 0, 0), 1, 2, 3, "origin");
    expect_point(vertex(s, 0, 1), 1, 4, 3, "(1,0,0)"); /* scale 2, x -> y, translate */
    expect_point(vertex(s, 0, 2), -1, 2, 3, "(0,1,0)");
    sg_scene_free(s);
}

Test(pbrt_transforms, transform_and_concat_are_column_major)
{
    /* The translation is the last four numbers. */
    SgScene *s = load_ok(HEADER "Transform [ 1 0 0 0  0 1 0 0  0 0 1 0  5 6 7 1 ]\n"
                                "ConcatTransform [ 0 1 0 0  -1 0 0 0  0 0 1 0  0 0 0 1 ]\n" TRIANGLE);
    /* ConcatTransform: columns (0,1,0) (-1,0,0): x -> y, y -> -x */
    expect_point(vertex(s, 0, 0), 5, 6, 7, "origin");
    expect_point(vertex(s, 0, 1), 5, 7, 7, "(1,0,0)");
    expect_point(vertex(s, 0, 2), 4, 6, 7, "(0,1,0)");
    sg_scene_free(s);
}

Test(pbrt_transforms, attribute_blocks_restore_the_transform)
{
    SgScene *s = load_ok(HEADER "AttributeBegin\n"
                                "  Translate 10 0 0\n"
                                "  AttributeBegin\n"
                                "    Translate 0 20 0\n"
                                "    Scale 3 3 3\n" TRIANGLE /* t0: (10,20,0) + 3p */
                                "  AttributeEnd\n" TRIANGLE  /* t1: (10,0,0) + p */
                                "  TransformBegin\n"
                                "    Translate 0 0 5\n" TRIANGLE /* t2: (10,0,5) + p */
                                "  TransformEnd\n"
                                "  Identity\n" TRIANGLE /* t3: p */
                                "AttributeEnd\n"
                                "Translate 0 0 -1\n" TRIANGLE /* t4: (0,0,-1) + p */);
    cr_assert_eq(s->triangle_count, 5);
    expect_point(vertex(s, 0, 1), 13, 20, 0, "nested block");
    expect_point(vertex(s, 1, 1), 11, 0, 0, "after inner AttributeEnd");
    expect_point(vertex(s, 2, 1), 11, 0, 5, "TransformBegin");
    expect_point(vertex(s, 3, 1), 1, 0, 0, "Identity");
    expect_point(vertex(s, 4, 1), 1, 0, -1, "after outer AttributeEnd");
    sg_scene_free(s);
}

Test(pbrt_transforms, named_coordinate_systems)
{
    SgScene *s = load_ok(HEADER "Translate 4 0 0\nCoordinateSystem \"here\"\nIdentity\n"
                                "CoordSysTransform \"here\"\n" TRIANGLE
                                "CoordSysTransform \"world\"\n" TRIANGLE);
    expect_point(vertex(s, 0, 0), 4, 0, 0, "CoordSysTransform here");
    expect_point(vertex(s, 1, 0), 0, 0, 0, "CoordSysTransform world");
    sg_scene_free(s);
}

Test(pbrt_transforms, instances_apply_their_transform_after_the_definition)
{
    SgScene *s = load_ok(HEADER "ObjectBegin \"tri\"\n"
                                "  Translate 0 0 1\n" TRIANGLE /* defined at z = 1 */
                                "ObjectEnd\n"
                                TRIANGLE /* ObjectEnd restored the transform: z = 0 */
                                "AttributeBegin\n  Translate 10 0 0\n  ObjectInstance \"tri\"\n"
                                "AttributeEnd\n"
                                "AttributeBegin\n  Translate 0 10 0\n  Scale 2 2 2\n"
                                "  ObjectInstance \"tri\"\nAttributeEnd\n");
    cr_assert_eq(s->triangle_count, 3, "the definition itself is not drawn");
    expect_point(vertex(s, 0, 1), 1, 0, 0, "after ObjectEnd");
    expect_point(vertex(s, 1, 1), 11, 0, 1, "instance 1");
    expect_point(vertex(s, 2, 0), 0, 10, 2, "instance 2 origin");
    expect_point(vertex(s, 2, 1), 2, 10, 2, "instance 2 (1,0,0)");
    sg_scene_free(s);
}

/* ---- shapes ------------------------------------------------------------- */

Test(pbrt_shapes, trianglemesh_bilinear_and_plymesh)
{
    /* A binary PLY whose first data byte is 0x0A, as in the bathroom. */
    char ply[4200];
    FILE *f = fopen(scene_file(ply, "quad.ply"), "wb");
    cr_assert(f);
    fputs("ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\n"
          "property float y\nproperty float z\nelement face 1\n"
          "property list uchar int vertex_indices\nend_header\n",
          f);
    float v[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    memcpy(v, (const unsigned char[4]){0x0a, 0, 0, 0}, 4); /* first byte 0x0A: x = 1.4e-44 */
    fwrite(v, sizeof v, 1, f);
    unsigned char n = 4;
    int idx[4] = {0, 1, 2, 3};
    fwrite(&n, 1, 1, f);
    fwrite(idx, sizeof idx, 1, f);
    fclose(f);
    SgScene *s = load_ok(HEADER
                         "Shape \"trianglemesh\" \"point3 P\" [ 0 0 0 1 0 0 0 1 0 ]\n" /* no indices */
                         "Shape \"bilinearmesh\" \"point3 P\" [ 0 0 1 1 0 1 0 1 1 1 1 1 ]\n"
                         "    \"integer indices\" [ 0 1 2 3 ]\n"
                         "Translate 0 0 5\n"
                         "Shape \"plymesh\" \"string filename\" \"quad.ply\"\n");
    cr_assert_eq(s->triangle_count, 1 + 2 + 2);
    double area = 0;
    for (uint32_t t = 1; t < 3; t++) {
        double n3[3];
        sg_scene_triangle_normal(s, t, n3);
        area += 0.5 * sqrt(n3[0] * n3[0] + n3[1] * n3[1] + n3[2] * n3[2]);
    }
    cr_expect(fabs(area - 1) < 1e-12, "bilinear patch area %g", area);
    expect_point(vertex(s, 3, 1), 1, 0, 5, "plymesh vertex 1, translated");
    sg_scene_free(s);
}

Test(pbrt_shapes, unsupported_kinds_warn_once_each)
{
    SgScene *s = load_ok(HEADER TRIANGLE "Shape \"curve\" \"float width\" 1\n"
                                "Shape \"curve\" \"float width\" 2\n"
                                "Shape \"cone\"\n"
                                "LightSource \"goniometric\" \"rgb I\" [ 1 1 1 ]\n"
                                "LightSource \"projection\" \"float scale\" 1\n");
    cr_assert_eq(s->triangle_count, 1);
    int curve = 0;
    for (uint32_t i = 0; i < s->warning_count; i++)
        curve += strstr(s->warnings[i], "\"curve\"") != NULL;
    cr_expect_eq(curve, 1, "one line for both curves");
    cr_expect(has_warning(s, "scene.pbrt:5: Shape \"curve\" is not supported: left out (2 times)"));
    cr_expect(has_warning(s, "Shape \"cone\""));
    cr_expect(has_warning(s, "LightSource \"goniometric\""));
    cr_expect(has_warning(s, "LightSource \"projection\""));
    cr_expect_eq(s->warning_count, 4);
    for (uint32_t i = 0; i < s->warning_count; i++)
        cr_expect(!strchr(s->warnings[i], '\n'));
    sg_scene_free(s);
}

Test(pbrt_shapes, include_and_import_resolve_against_the_main_file)
{
    char path[4200];
    mkdir(scene_file(path, "parts"), 0755);
    write_scene("parts/materials.pbrt",
                "MakeNamedMaterial \"red\" \"string type\" \"diffuse\" \"rgb reflectance\" [ 0.8 0 0 ]\n");
    write_scene("parts/geometry.pbrt", "NamedMaterial \"red\"\nTranslate 0 0 2\n" TRIANGLE);
    SgScene *s = load_ok(HEADER "Include \"parts/materials.pbrt\"\nImport \"parts/geometry.pbrt\"\n"
                                "Shape \"trianglemesh\" \"point3 P\" [ 0 0 0 1 0 0 0 1 0 ]\n");
    cr_assert_eq(s->triangle_count, 2);
    expect_point(vertex(s, 0, 0), 0, 0, 2, "included shape");
    cr_expect_float_eq(material_of(s, 0)->diffuse[0], 0.8f, 1e-6);
    /* The transform and material set in the included file carry on. */
    expect_point(vertex(s, 1, 0), 0, 0, 2, "shape after Include");
    cr_expect_float_eq(material_of(s, 1)->diffuse[0], 0.8f, 1e-6);
    sg_scene_free(s);
}

/* ---- materials ---------------------------------------------------------- */

Test(pbrt_materials, mapped_to_ours)
{
    SgScene *s = load_ok(
        HEADER
        "Texture \"flat\" \"spectrum\" \"constant\" \"rgb value\" [ 0.2 0.4 0.6 ]\n"
        "Texture \"half\" \"spectrum\" \"scale\" \"texture tex\" \"flat\" \"float scale\" 0.5\n"
        "Texture \"photo\" \"spectrum\" \"imagemap\" \"string filename\" \"no-such.png\"\n"
        "MakeNamedMaterial \"wall\" \"string type\" \"diffuse\" \"rgb reflectance\" [ 0.1 0.2 0.3 ]\n"
        "MakeNamedMaterial \"floor\" \"string type\" \"coateddiffuse\" \"bool remaproughness\" false\n"
        "    \"float roughness\" 0.1 \"texture reflectance\" \"half\"\n"
        "MakeNamedMaterial \"gold\" \"string type\" \"conductor\" \"float roughness\" 0\n"
        "    \"spectrum eta\" \"metal-Au-eta\" \"spectrum k\" \"metal-Au-k\"\n"
        "MakeNamedMaterial \"brushed\" \"string type\" \"conductor\" \"bool remaproughness\" false\n"
        "    \"float uroughness\" 0.3 \"float vroughness\" 0.3 \"rgb reflectance\" [ 0.9 0.8 0.7 ]\n"
        "MakeNamedMaterial \"water\" \"string type\" \"dielectric\" \"float eta\" 1.33 \"float roughness\" 0.2\n"
        "MakeNamedMaterial \"poster\" \"string type\" \"diffuse\" \"texture reflectance\" \"photo\"\n"
        "NamedMaterial \"wall\"\n" TRIANGLE "NamedMaterial \"floor\"\n" TRIANGLE
        "NamedMaterial \"gold\"\n" TRIANGLE "NamedMaterial \"brushed\"\n" TRIANGLE
        "NamedMaterial \"water\"\n" TRIANGLE "NamedMaterial \"poster\"\n" TRIANGLE
        "Material \"hair\"\n" TRIANGLE "AttributeBegin\nMaterial \"diffuse\" \"rgb reflectance\" [ 0 1 0 ]\n"
        TRIANGLE "AttributeEnd\n" TRIANGLE);
    cr_assert_eq(s->triangle_count, 9);
    const SgMaterial *m = material_of(s, 0);
    cr_expect_eq(m->type, SG_MATERIAL_DIFFUSE);
    cr_expect_float_eq(m->diffuse[2], 0.3f, 1e-6);
    cr_expect_str_eq(m->name, "wall");

    m = material_of(s, 1); /* a GGX coat of alpha 0.1 over the base */
    cr_expect_eq(m->type, SG_MATERIAL_COATED_DIFFUSE);
    cr_expect_float_eq(m->diffuse[1], 0.2f, 1e-6, "texture scale 0.5 of 0.4");
    cr_expect_eq(m->diffuse_texture, 0, "a scaled constant does not vary");
    cr_expect_float_eq(m->roughness[0], 0.1f, 1e-6);
    cr_expect_float_eq(m->ior, 1.5f, 1e-6);

    m = material_of(s, 2); /* smooth gold: gold's complex index, alpha 0 (the renderer's mirror) */
    cr_expect_eq(m->type, SG_MATERIAL_CONDUCTOR);
    cr_expect_float_eq(m->roughness[0], 0.0f, 1e-9);
    cr_expect(fabsf(m->eta[0] - 0.143f) < 1e-3f && fabsf(m->k[2] - 1.60f) < 1e-2f, "gold eta %g k %g", m->eta[0],
              m->k[2]);

    m = material_of(s, 3); /* a reflectance: pbrt's eta 1 and the k that reflects it */
    cr_expect_eq(m->type, SG_MATERIAL_CONDUCTOR);
    cr_expect_float_eq(m->diffuse[1], 0.8f, 1e-6);
    cr_expect_float_eq(m->roughness[1], 0.3f, 1e-6);
    cr_expect_float_eq(m->eta[1], 1.0f, 1e-6);
    cr_expect_float_eq(m->k[1], 2 * sqrtf(0.8f) / sqrtf(0.2f), 1e-4);

    m = material_of(s, 4); /* rough water: roughness remapped by sqrt */
    cr_expect_eq(m->type, SG_MATERIAL_DIELECTRIC);
    cr_expect_float_eq(m->ior, 1.33f, 1e-6);
    cr_expect_float_eq(m->roughness[0], sqrtf(0.2f), 1e-6);
    cr_expect_float_eq(m->roughness[1], sqrtf(0.2f), 1e-6);

    m = material_of(s, 5);
    cr_expect_float_eq(m->diffuse[0], 0.5f, 1e-6, "image textures: grey");
    cr_assert(m->diffuse_texture > 0 && m->diffuse_texture <= s->texture_count, "a texture, though missing");
    cr_expect_null(s->textures[m->diffuse_texture - 1].path, "its file could not be read");
    cr_expect(has_warning(s, "image textures"));

    m = material_of(s, 6);
    cr_expect_eq(m->type, SG_MATERIAL_DIFFUSE);
    cr_expect(has_warning(s, "Material \"hair\""));
    cr_expect_float_eq(material_of(s, 7)->diffuse[1], 1.0f, 1e-6, "Material in a block");
    cr_expect_float_eq(material_of(s, 8)->diffuse[1], 0.5f, 1e-6, "restored by AttributeEnd");
    sg_scene_free(s);
}

Test(pbrt_materials, diffuse_transmission_reflects_and_transmits)
{
    SgScene *s = load_ok(HEADER "Material \"diffusetransmission\" \"rgb reflectance\" [ 0.2 0.3 0.4 ]\n"
                                "    \"rgb transmittance\" [ 0.5 0.4 0.3 ] \"float scale\" 0.5\n" TRIANGLE
                                "Material \"diffusetransmission\"\n" TRIANGLE);
    const SgMaterial *m = material_of(s, 0);
    cr_expect_eq(m->type, SG_MATERIAL_DIFFUSE_TRANSMISSION);
    cr_expect_float_eq(m->diffuse[1], 0.15f, 1e-6, "reflectance times scale");
    cr_expect_float_eq(m->transmittance[0], 0.25f, 1e-6, "transmittance times scale");
    m = material_of(s, 1); /* pbrt-v4's defaults */
    cr_expect_float_eq(m->diffuse[0], 0.25f, 1e-6);
    cr_expect_float_eq(m->transmittance[2], 0.25f, 1e-6);
    free_quietly_loaded(s);
}

Test(pbrt_shapes, alpha_makes_a_cutout_copy_of_the_material)
{
    SgScene *s = load_ok(HEADER "Texture \"leaf\" \"float\" \"checkerboard\" \"float uscale\" 8\n"
                                "Material \"diffuse\"\n"
                                "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2]"
                                " \"float alpha\" 0\n"
                                "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2]"
                                " \"texture alpha\" \"leaf\"\n" TRIANGLE);
    cr_assert_eq(s->triangle_count, 3);
    const SgMaterial *m = material_of(s, 0);
    cr_expect(m->cutout);
    cr_expect_float_eq(m->alpha, 0.0f, 1e-9);
    cr_expect_eq(m->alpha_texture, 0);
    m = material_of(s, 1);
    cr_expect(m->cutout);
    cr_expect(m->alpha_texture > 0 && m->alpha_texture <= s->texture_count, "the leaf texture");
    cr_expect(!material_of(s, 2)->cutout, "a shape without alpha stays opaque");
    cr_expect_eq(material_of(s, 2)->type, material_of(s, 0)->type);
    free_quietly_loaded(s);
}

Test(pbrt_materials, bump_and_normal_maps_are_shading_normals)
{
    SgScene *s = load_ok(HEADER "Texture \"bumps\" \"float\" \"checkerboard\" \"float uscale\" 8\n"
                                "Material \"diffuse\" \"texture displacement\" \"bumps\"\n" TRIANGLE
                                "Material \"conductor\" \"string normalmap\" \"no-such-normals.png\"\n" TRIANGLE);
    const SgMaterial *m = material_of(s, 0);
    cr_expect(m->bump_texture > 0 && m->bump_texture <= s->texture_count, "displacement: a bump map");
    cr_expect_float_eq(m->bump_scale, 1.0f, 1e-9);
    cr_expect_eq(material_of(s, 1)->normal_texture, 0, "a normal map that cannot be read is left out");
    cr_expect(has_warning(s, "normal maps that cannot be read"));
    cr_expect(!has_warning(s, "displacement"));
    sg_scene_free(s);
}

Test(pbrt_materials, absorbing_medium_inside_a_dielectric)
{
    SgScene *s = load_ok(HEADER "MakeNamedMedium \"tint\" \"string type\" \"homogeneous\"\n"
                                "    \"rgb sigma_a\" [ 0.1 0.2 0.4 ] \"rgb sigma_s\" [ 0 0 0 ] \"float scale\" 2\n"
                                "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n"
                                "AttributeBegin\nMediumInterface \"tint\" \"\"\n"
                                "Material \"dielectric\"\n" TRIANGLE
                                "Material \"diffuse\"\n" TRIANGLE "AttributeEnd\n"
                                "Material \"dielectric\"\n" TRIANGLE
                                "MediumInterface \"fog\"\n" TRIANGLE);
    cr_assert_eq(s->triangle_count, 4);
    const SgMaterial *m = material_of(s, 0);
    cr_expect_eq(m->type, SG_MATERIAL_DIELECTRIC);
    cr_expect(m->sigma_a[0] == 0.2f && m->sigma_a[2] == 0.8f, "sigma_a times scale: %g %g", m->sigma_a[0],
              m->sigma_a[2]);
    cr_expect_eq(material_of(s, 1)->sigma_a[0], 0.0f, "only a dielectric holds a medium");
    cr_expect_eq(material_of(s, 2)->sigma_a[1], 0.0f, "AttributeEnd restores the clear inside");
    cr_expect_eq(material_of(s, 3)->sigma_a[1], 0.0f, "a scattering medium is left out");
    cr_expect(has_warning(s, "scattering media"));
    cr_expect_eq(s->warning_count, 1);
    sg_scene_free(s);
}

Test(pbrt_materials, textures_as_their_average)
{
    SgScene *s = load_ok(
        HEADER "Texture \"quarter\" \"float\" \"constant\" \"float value\" 0.25\n"
               "Texture \"flat\" \"spectrum\" \"constant\" \"rgb value\" [ 0.2 0.4 0.6 ]\n"
               "Texture \"m\" \"spectrum\" \"mix\" \"texture tex1\" \"flat\"\n"
               "    \"rgb tex2\" [ 1 1 1 ] \"texture amount\" \"quarter\"\n"
               "Texture \"c\" \"spectrum\" \"checkerboard\" \"rgb tex1\" [ 1 0 0 ]\n"
               "    \"rgb tex2\" [ 0 0 1 ]\n"
               "Material \"diffuse\" \"texture reflectance\" \"m\"\n" TRIANGLE
               "Material \"coateddiffuse\" \"texture reflectance\" \"c\"\n"
               "    \"texture roughness\" \"quarter\"\n" TRIANGLE);
    const SgMaterial *m = material_of(s, 0);
    cr_expect_float_eq(m->diffuse[0], 0.75f * 0.2f + 0.25f, 1e-6);
    cr_expect_float_eq(m->diffuse[2], 0.75f * 0.6f + 0.25f, 1e-6);
    m = material_of(s, 1);
    cr_expect_float_eq(m->diffuse[0], 0.5f, 1e-6, "checkerboard: mean of the two");
    cr_expect_float_eq(m->diffuse[1], 0.0f, 1e-9);
    cr_assert(m->diffuse_texture > 0, "a checkerboard varies");
    const SgTexture *t = &s->textures[m->diffuse_texture - 1];
    cr_expect_eq(t->kind, SG_TEXTURE_CHECKERBOARD);
    cr_expect(t->input[0].value[0] == 1.0f && t->input[1].value[2] == 1.0f, "its two colours");
    /* remaproughness (default true): alpha = sqrt(0.25) = 0.5 */
    cr_expect_float_eq(m->roughness[0], 0.5f, 1e-6);
    /* the mix of a constant with a constant does not vary */
    cr_expect_eq(material_of(s, 0)->diffuse_texture, 0);
    free_quietly_loaded(s);
}

Test(pbrt_materials, image_textures_as_their_mean_linear_colour)
{
    /* Left half (0.2, 0.4, 0.6), right half (0.6, 0.4, 0.2): mean 0.4. */
    enum { W = 64, H = 32 };
    static float rgb[W * H * 3];
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++)
            for (int c = 0; c < 3; c++)
                rgb[3 * (y * W + x) + c] = x < W / 2 ? 0.2f * (1 + c) : 0.2f * (3 - c);
    char png[4200], exr[4200];
    scene_file(png, "wood.png");
    scene_file(exr, "wood.exr");
    SgError err = {0};
    cr_assert(sg_image_write_png(png, W, H, rgb, 0, &err), "%s", err.message);
    cr_assert(sg_image_write_exr(exr, W, H, rgb, NULL, 0, &err), "%s", err.message);
    SgScene *s = load_ok(
        HEADER "Texture \"a\" \"spectrum\" \"imagemap\" \"string filename\" \"wood.png\"\n"
               "Texture \"b\" \"spectrum\" \"imagemap\" \"string filename\" \"wood.exr\"\n"
               "    \"float scale\" 0.5\n"
               "Texture \"c\" \"spectrum\" \"imagemap\" \"string filename\" \"wood.png\"\n"
               "    \"string encoding\" \"linear\"\n"
               "Texture \"d\" \"spectrum\" \"imagemap\" \"string filename\" \"none.png\"\n"
               "Material \"diffuse\" \"texture reflectance\" \"a\"\n" TRIANGLE
               "Material \"diffuse\" \"texture reflectance\" \"b\"\n" TRIANGLE
               "Material \"diffuse\" \"texture reflectance\" \"c\"\n" TRIANGLE
               "Material \"diffuse\" \"texture reflectance\" \"d\"\n" TRIANGLE);
    for (int c = 0; c < 3; c++) {
        /* the PNG holds sRGB bytes: decoded back to linear, up to 8-bit rounding */
        cr_expect(fabsf(material_of(s, 0)->diffuse[c] - 0.4f) < 0.004f, "png %d: %g", c,
                  material_of(s, 0)->diffuse[c]);
        cr_expect(fabsf(material_of(s, 1)->diffuse[c] - 0.2f) < 1e-4f, "exr %d: %g", c,
                  material_of(s, 1)->diffuse[c]);
        cr_expect_float_eq(material_of(s, 3)->diffuse[c], 0.5f, 1e-6, "missing file: grey");
    }
    /* read as linear, the sRGB bytes are brighter than the colour they encode */
    cr_expect(material_of(s, 2)->diffuse[1] > 0.6f, "%g", material_of(s, 2)->diffuse[1]);
    cr_expect(has_warning(s, "scene.pbrt:9: image textures that cannot be read"));
    cr_expect_eq(s->warning_count, 1);
    sg_scene_free(s);
}

Test(pbrt_materials, pbrt_v3_materials)
{
    SgScene *s = load_ok(
        HEADER "Material \"matte\" \"color Kd\" [ 0.3 0.2 0.1 ]\n" TRIANGLE
               "Material \"plastic\" \"rgb Kd\" [ 0.8 0.8 0.8 ] \"rgb Ks\" [ 0.4 0.4 0.4 ]\n"
               "    \"float roughness\" 0.02 \"bool remaproughness\" \"false\"\n" TRIANGLE
               "Material \"mirror\"\n" TRIANGLE
               "Material \"glass\" \"float index\" 1.7\n" TRIANGLE
               "Material \"metal\" \"float roughness\" 0.001\n" TRIANGLE
               "Material \"substrate\"\n" TRIANGLE);
    cr_assert_eq(s->triangle_count, 6);
    const SgMaterial *m = material_of(s, 0);
    cr_expect(m->type == SG_MATERIAL_DIFFUSE && fabsf(m->diffuse[0] - 0.3f) < 1e-6f);
    m = material_of(s, 1); /* Kd + Ks = 1.2: scaled to 1, keeping the ratio */
    cr_expect_eq(m->type, SG_MATERIAL_GLOSSY);
    cr_expect_float_eq(m->diffuse[0], 0.8f / 1.2f, 1e-6);
    cr_expect_float_eq(m->specular[0], 0.4f / 1.2f, 1e-6);
    cr_expect_float_eq(m->exponent, (float)(2 / 4e-4 - 2), 1e-1);
    m = material_of(s, 2);
    cr_expect(m->type == SG_MATERIAL_MIRROR && fabsf(m->specular[1] - 0.9f) < 1e-6f);
    m = material_of(s, 3);
    cr_expect(m->type == SG_MATERIAL_DIELECTRIC && fabsf(m->ior - 1.7f) < 1e-6f);
    cr_expect_float_eq(m->roughness[0], 0.0f, 1e-9, "no roughness is smooth glass, whatever the v3 remapping");
    m = material_of(s, 4); /* v3 remapping of 0.001: alpha ~ 0.05, a rough copper */
    cr_expect_eq(m->type, SG_MATERIAL_CONDUCTOR);
    cr_expect(m->roughness[0] > 0.03f && m->roughness[0] < 0.08f, "alpha %g", m->roughness[0]);
    cr_expect(m->k[0] > m->k[2], "copper's index");
    m = material_of(s, 5);
    cr_expect(m->type == SG_MATERIAL_GLOSSY && fabsf(m->diffuse[0] - 0.5f) < 1e-6f);
    free_quietly_loaded(s);
}

Test(pbrt_materials, named_before_defined_like_pbrt_v4)
{
    SgScene *s = load_ok(HEADER "NamedMaterial \"late\"\n" TRIANGLE
                                "AreaLightSource \"diffuse\" \"rgb L\" [ 2 2 2 ]\n" TRIANGLE
                                "MakeNamedMaterial \"late\" \"string type\" \"conductor\"\n"
                                "    \"float roughness\" 0 \"rgb reflectance\" [ 0.9 0.9 0.9 ]\n");
    cr_assert_eq(s->triangle_count, 2);
    for (uint32_t t = 0; t < 2; t++) {
        cr_expect_eq(material_of(s, t)->type, SG_MATERIAL_CONDUCTOR, "triangle %u", t);
        cr_expect_float_eq(material_of(s, t)->diffuse[0], 0.9f, 1e-6);
    }
    cr_expect_float_eq(material_of(s, 1)->emission[0], 2.0f, 1e-6, "keeps its emission");
    cr_expect_float_eq(material_of(s, 0)->emission[0], 0.0f, 1e-9);
    sg_scene_free(s);
}

/* ---- area lights -------------------------------------------------------- */

Test(pbrt_lights, radiance_scale_and_emitting_side)
{
    /* light 4: a PLY whose normals (-z) disagree with its winding (+z) */
    write_scene("lamp.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                            "property float y\nproperty float z\nproperty float nx\n"
                            "property float ny\nproperty float nz\nelement face 1\n"
                            "property list uchar int vertex_indices\nend_header\n"
                            "0 0 0 0 0 -1\n1 0 0 0 0 -1\n0 1 0 0 0 -1\n3 0 1 2\n");
    SgScene *s = load_ok(
        HEADER
        "AttributeBegin\n  Translate 20 0 0\n"
        "  AreaLightSource \"diffuse\" \"rgb L\" [ 7 7 7 ]\n"
        "  Shape \"plymesh\" \"string filename\" \"lamp.ply\"\nAttributeEnd\n"
        "AttributeBegin\n" /* light 0: winding faces +z */
        "  AreaLightSource \"diffuse\" \"rgb L\" [ 1 2 3 ] \"float scale\" 2\n" TRIANGLE
        "AttributeEnd\n"
        "AttributeBegin\n" /* light 1: normals say -z, winding says +z: normals win */
        "  Translate 5 0 0\n"
        "  AreaLightSource \"diffuse\" \"rgb L\" [ 4 4 4 ]\n"
        "  Shape \"trianglemesh\" \"point3 P\" [ 0 0 0 1 0 0 0 1 0 ] \"integer indices\" [ 0 1 2 ]\n"
        "      \"normal N\" [ 0 0 -1 0 0 -1 0 0 -1 ]\n"
        "AttributeEnd\n"
        "AttributeBegin\n" /* light 2: ReverseOrientation flips the winding */
        "  Translate 10 0 0\n  ReverseOrientation\n"
        "  AreaLightSource \"diffuse\" \"rgb L\" [ 5 5 5 ]\n" TRIANGLE
        "AttributeEnd\n"
        "AttributeBegin\n" /* light 3: a mirroring transform flips the side too */
        "  Translate 15 0 0\n  Scale 1 1 -1\n"
        "  AreaLightSource \"diffuse\" \"rgb L\" [ 6 6 6 ]\n" TRIANGLE
        "AttributeEnd\n" TRIANGLE /* not emissive: the block ended */);
    cr_assert_eq(s->light_count, 5);
    cr_assert_eq(s->triangle_count, 6);
    cr_expect_eq(s->triangle_light[5], SG_NO_LIGHT);
    double expected_z[5] = {1, -1, -1, -1, -1};
    float expected_r[5] = {2, 4, 5, 6, 7};
    for (uint32_t k = 0; k < 5; k++) {
        const SgLight *l = NULL;
        for (uint32_t i = 0; i < s->light_count; i++)
            if (fabsf(s->lights[i].radiance[0] - expected_r[k]) < 1e-6f)
                l = &s->lights[i];
        cr_assert(l, "light %u", k);
        cr_expect(fabs(l->normal[2] - expected_z[k]) < 1e-12, "light %u normal z %g", k,
                  l->normal[2]);
        cr_expect(fabs(l->area - 0.5) < 1e-12);
    }
    for (uint32_t i = 0; i < s->light_count; i++)
        if (s->lights[i].radiance[0] == 2)
            cr_expect(s->lights[i].radiance[2] == 6, "scale applies to each channel");
    sg_scene_free(s);
}

static double rgb_luminance(const float c[3]) { return sg_luminance(c[0], c[1], c[2]); }

Test(pbrt_lights, blackbody_has_luminance_one_and_two_sided_warns)
{
    SgScene *s = load_ok(HEADER "AttributeBegin\n"
                                "AreaLightSource \"diffuse\" \"blackbody L\" 2700 \"float scale\" 3\n"
                                "    \"bool twosided\" true\n" TRIANGLE "AttributeEnd\n"
                                "Translate 5 0 0\n"
                                "AreaLightSource \"diffuse\" \"blackbody L\" [ 6504 ]\n" TRIANGLE);
    cr_assert_eq(s->light_count, 2);
    cr_expect(has_warning(s, "two-sided"));
    const float *warm = s->lights[0].radiance, *d65 = s->lights[1].radiance;
    if (warm[0] < d65[0]) {
        const float *t = warm;
        warm = d65;
        d65 = t;
    }
    /* pbrt normalizes a blackbody to luminance 1 (times "scale"). */
    cr_expect(fabs(rgb_luminance(warm) - 3) < 1e-4, "luminance %g", rgb_luminance(warm));
    cr_expect(fabs(rgb_luminance(d65) - 1) < 1e-5, "luminance %g", rgb_luminance(d65));
    cr_expect(warm[0] > warm[1] && warm[1] > warm[2], "2700 K is orange: %g %g %g", warm[0],
              warm[1], warm[2]);
    /* 6504 K is close to sRGB's white (D65 is not exactly a blackbody). */
    for (int c = 0; c < 3; c++)
        cr_expect(fabs(d65[c] - 1) < 0.1, "6504 K channel %d: %g", c, d65[c]);
    sg_scene_free(s);
}

Test(pbrt_lights, area_lights_in_instances_are_ignored_like_pbrt)
{
    SgScene *s = load_ok(HEADER "ObjectBegin \"lamp\"\n"
                                "  AreaLightSource \"diffuse\" \"rgb L\" [ 1 1 1 ]\n" TRIANGLE
                                "ObjectEnd\nObjectInstance \"lamp\"\n");
    cr_expect_eq(s->triangle_count, 1);
    cr_expect_eq(s->light_count, 0);
    cr_expect(has_warning(s, "ObjectBegin"));
    sg_scene_free(s);
}

/* ---- camera ------------------------------------------------------------- */

static void expect_vec(const double *v, const double *w, double tol, const char *what)
{
    cr_expect(fabs(v[0] - w[0]) < tol && fabs(v[1] - w[1]) < tol && fabs(v[2] - w[2]) < tol,
              "%s: (%.7g %.7g %.7g), expected (%.7g %.7g %.7g)", what, v[0], v[1], v[2], w[0],
              w[1], w[2]);
}

Test(pbrt_camera, lookat_with_the_usual_mirror)
{
    SgScene *s = load_ok("Scale -1 1 1\nLookAt 1 2 3  1 2 0  0 1 0\n"
                         "Film \"rgb\" \"integer xresolution\" 200 \"integer yresolution\" 100\n"
                         "Camera \"perspective\" \"float fov\" 40\nWorldBegin\n" TRIANGLE);
    cr_assert(s->has_camera);
    expect_vec(s->camera.position, (double[]){1, 2, 3}, 1e-12, "position");
    expect_vec(s->camera.look_at, (double[]){1, 2, 2}, 1e-12, "look_at (unit distance)");
    expect_vec(s->camera.up, (double[]){0, 1, 0}, 1e-12, "up");
    cr_expect_eq(s->camera.width, 200);
    cr_expect_eq(s->camera.height, 100);
    cr_expect(fabs(s->camera.fov_deg - 40) < 1e-9, "landscape: fov is vertical");
    cr_expect_eq(s->warning_count, 0, "no mirror warning with Scale -1 1 1");
    sg_scene_free(s);
}

Test(pbrt_camera, portrait_fov_and_plain_lookat_warns_mirror)
{
    SgScene *s = load_ok("LookAt 0 0 0  0 0 -1  0 1 0\n"
                         "Film \"rgb\" \"integer xresolution\" 100 \"integer yresolution\" 200\n"
                         "Camera \"perspective\" \"float fov\" 40\nWorldBegin\n" TRIANGLE);
    double vertical = 2 * atan(tan(20 * M_PI / 180) * 2) * 180 / M_PI;
    cr_expect(fabs(s->camera.fov_deg - vertical) < 1e-9, "fov %g, expected %g",
              s->camera.fov_deg, vertical);
    cr_expect(has_warning(s, "mirrored"));
    sg_scene_free(s);
}

/* pbrt-v4's maxdepth counts the bounces after the camera ray (its
 * PathIntegrator stops at `depth++ == maxDepth`, before the light sample),
 * our max_depth the segments from the camera: maxdepth 1 (direct light) is
 * our 2. Measured on tests/data/pbrt-lights/room-window.pbrt: pbrt-v4 at
 * maxdepth 1 gives the image mean 0.0845 0.0566 0.0732, ours 0.0845 0.0566
 * 0.0732 at --max-depth 2 and 0.0604 0.0373 0.0521 at 1. */
Test(pbrt_integrator, maxdepth_counts_bounces_ours_segments)
{
    static const struct {
        const char *integrator;
        int max_depth;
    } cases[] = {
        {"", 6}, /* no Integrator: pbrt's volpath, maxdepth 5 */
        {"Integrator \"path\"\n", 6},
        {"Integrator \"volpath\" \"integer maxdepth\" [ 1 ]\n", 2},
        {"Integrator \"path\" \"integer maxdepth\" [ 0 ]\n", 1},
        {"Integrator \"path\" \"integer maxdepth\" [ 12 ]\n", 13},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        char text[1024];
        snprintf(text, sizeof text, "%sCamera \"perspective\"\nWorldBegin\n" TRIANGLE, cases[i].integrator);
        SgScene *s = load_ok(text);
        cr_expect_eq(s->render.max_depth, cases[i].max_depth, "case %zu (%.40s...): max_depth %d, want %d", i,
                     cases[i].integrator, s->render.max_depth, cases[i].max_depth);
        sg_scene_free(s);
    }
}

Test(pbrt_camera, transform_statement_equals_lookat)
{
    /* The world-to-camera matrix of LookAt (with Scale -1 1 1), written out. */
    SgScene *a = load_ok("Scale -1 1 1\nLookAt 3 1 2  0 1 0  0 1 0\nCamera \"perspective\"\n"
                         "WorldBegin\n" TRIANGLE);
    SgCamera ca = a->camera;
    sg_scene_free(a);
    /* camera axes in world: right = up x dir... here dir = (-3,0,-2)/|.|;
     * pbrt's right = normalize(up x dir); Scale -1 negates camera x. */
    double l = sqrt(13), dx = -3 / l, dz = -2 / l;
    double rx = dz, rz = -dx; /* (0,1,0) x (dx,0,dz) = (dz, 0, -dx) */
    char text[2048];
    /* rows of world->camera: -right, up, dir; translation -R p */
    double r0[3] = {-rx, 0, -rz}, r1[3] = {0, 1, 0}, r2[3] = {dx, 0, dz}, p[3] = {3, 1, 2};
    double t0 = -(r0[0] * p[0] + r0[2] * p[2]), t1 = -p[1], t2 = -(r2[0] * p[0] + r2[2] * p[2]);
    snprintf(text, sizeof text,
             "Transform [ %.17g %.17g %.17g 0  %.17g %.17g %.17g 0  %.17g %.17g %.17g 0  "
             "%.17g %.17g %.17g 1 ]\nCamera \"perspective\"\nWorldBegin\n" TRIANGLE,
             r0[0], r1[0], r2[0], r0[1], r1[1], r2[1], r0[2], r1[2], r2[2], t0, t1, t2);
    SgScene *b = load_ok(text);
    expect_vec(b->camera.position, ca.position, 1e-12, "position");
    expect_vec(b->camera.look_at, ca.look_at, 1e-12, "look_at");
    expect_vec(b->camera.up, ca.up, 1e-12, "up");
    cr_expect_eq(b->camera.width, 1280, "pbrt's default film");
    cr_expect_eq(b->camera.height, 720);
    cr_expect(fabs(b->camera.fov_deg - 90) < 1e-12, "pbrt's default fov");
    sg_scene_free(b);
}

/* The numbers of ../shared/scenes/NAME/camera.txt. */
typedef struct ExpectedCamera {
    double position[3], look_at[3], up[3], fov;
    int width, height;
} ExpectedCamera;

static bool read_camera_txt(const char *path, ExpectedCamera *c)
{
    FILE *f = fopen(path, "r");
    if (!f)
        return false;
    char line[512];
    int found = 0;
    while (fgets(line, sizeof line, f)) {
        double *v = NULL;
        if (!strncmp(line, "position", 8))
            v = c->position;
        else if (!strncmp(line, "lookat", 6))
            v = c->look_at;
        else if (!strncmp(line, "up", 2))
            v = c->up;
        if (v && sscanf(strchr(line, ' '), "%lf %lf %lf", &v[0], &v[1], &v[2]) == 3)
            found++;
        if ((!strncmp(line, "fov_deg", 7) || !strncmp(line, "hfov_deg", 8)) &&
            sscanf(strchr(line, ' '), "%lf", &c->fov) == 1)
            found++;
        if (!strncmp(line, "resolution", 10) &&
            sscanf(line + 10, "%d %d", &c->width, &c->height) == 2)
            found++;
    }
    fclose(f);
    return found == 5;
}

static void check_shared_scene(const char *pbrt, const char *camera_txt, const char *json,
                               const double light_normal[3])
{
    if (!sg_test_have_shared_scenes() || !sg_test_exists(pbrt))
        cr_skip_test("%s is absent", pbrt);
    ExpectedCamera want;
    cr_assert(read_camera_txt(camera_txt, &want), "cannot read %s", camera_txt);
    SgError err = {0};
    SgScene *s = sg_scene_load(pbrt, &err);
    cr_assert(s, "%s", err.message);
    cr_expect_eq(s->camera.width, want.width);
    cr_expect_eq(s->camera.height, want.height);
    expect_vec(s->camera.position, want.position, 2e-5, "position");
    expect_vec(s->camera.look_at, want.look_at, 2e-5, "look_at");
    expect_vec(s->camera.up, want.up, 2e-5, "up");
    /* camera.txt gives pbrt's fov (the shorter axis); ours is vertical */
    double aspect = (double)want.width / want.height;
    double vertical = aspect < 1 ? 2 * atan(tan(want.fov * M_PI / 360) / aspect) * 180 / M_PI
                                 : want.fov;
    cr_expect(fabs(s->camera.fov_deg - vertical) < 1e-9, "fov %g, expected %g",
              s->camera.fov_deg, vertical);
    for (uint32_t i = 0; i < s->warning_count; i++)
        cr_expect(!strstr(s->warnings[i], "mirror"), "%s", s->warnings[i]);

    cr_assert_eq(s->light_count, 1);
    cr_expect_float_eq(s->lights[0].radiance[0], 30.0f, 1e-6);
    expect_vec(s->lights[0].normal, light_normal, 1e-5, "light normal");

    /* Same geometry as the hand-made JSON version of the scene. */
    SgScene *j = sg_scene_load(json, &err);
    cr_assert(j, "%s", err.message);
    cr_expect_eq(s->triangle_count, j->triangle_count);
    cr_expect_eq(s->degenerate_dropped, j->degenerate_dropped);
    expect_vec(s->bounds_min, j->bounds_min, 1e-9, "bounds_min");
    expect_vec(s->bounds_max, j->bounds_max, 1e-9, "bounds_max");
    cr_expect(fabs(s->lights[0].area - j->lights[0].area) < 1e-9);
    sg_scene_free(j);

    /* Same file, same scene. */
    SgScene *again = sg_scene_load(pbrt, &err);
    cr_assert(again);
    cr_expect_eq(again->geometry_hash, s->geometry_hash);
    sg_scene_free(again);
    sg_scene_free(s);
}

Test(pbrt_shared, staircase_camera_light_and_geometry)
{
    check_shared_scene(STAIRCASE, "../shared/scenes/staircase/camera.txt",
                       "data/external/staircase.json", (double[]){0, -1, 0});
}

Test(pbrt_shared, bathroom_camera_light_and_geometry)
{
    check_shared_scene(BATHROOM, "../shared/scenes/bathroom/camera.txt",
                       "data/external/bathroom.json", (double[]){1, 0, 0});
}

Test(pbrt_shared, material_mapping_of_the_shared_scenes)
{
    if (!sg_test_have_shared_scenes() || !sg_test_exists(BATHROOM))
        cr_skip_test("shared scenes absent");
    SgError err = {0};
    SgScene *s = sg_scene_load(BATHROOM, &err);
    cr_assert(s, "%s", err.message);
    int mirror = 0, glass = 0, glossy = 0;
    for (uint32_t i = 0; i < s->material_count; i++) {
        const SgMaterial *m = &s->materials[i];
        if (!strcmp(m->name, "Mirror"))
            mirror += m->type == SG_MATERIAL_CONDUCTOR && m->roughness[0] == 0.0f && m->k[1] > 3.0f; /* silver */
        if (!strcmp(m->name, "BulbGlass"))
            glass += m->type == SG_MATERIAL_DIELECTRIC && fabsf(m->ior - 1.5f) < 1e-6f;
        glossy += m->type == SG_MATERIAL_COATED_DIFFUSE;
        glossy += m->type == SG_MATERIAL_CONDUCTOR && m->roughness[0] > 0.0f;
    }
    cr_expect_eq(mirror, 1, "the silver mirror");
    cr_expect_eq(glass, 1);
    cr_expect(glossy > 0);
    sg_scene_free(s);
}

/* ---- malformed input ---------------------------------------------------- */

Test(pbrt_errors, unbalanced_brackets)
{
    expect_error(HEADER "Shape \"trianglemesh\"\n  \"point3 P\" [ 0 0 0 1 0 0 0 1 0\n"
                        "  \"integer indices\" [ 0 1 2 ]\n",
                 5, "'[' is not closed");
    expect_first_statement_error("Shape \"trianglemesh\" \"point3 P\" [ 0 0 0 1 0 0 0 1 0\n"
                                 "Shape \"sphere\"\n", "'[' is not closed");
    expect_first_statement_error("Shape \"trianglemesh\" \"point3 P\" [ 0 0 0 1 0 0 0 1 0 ] ]\n",
                                 "']'");
    expect_first_statement_error("Shape \"trianglemesh\" \"point3 P\" [ 0 0 0 1 0 0 0 1 0",
                                 "never closed");
    expect_first_statement_error("Transform [ 1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1\nWorldBegin\n",
                                 "is not closed");
}

Test(pbrt_errors, unknown_parameter_types_and_statements)
{
    expect_error(HEADER "\n\nShape \"sphere\" \"floot radius\" [ 1 ]\n", 6,
                 "unknown parameter type \"floot\"");
    expect_first_statement_error("Shape \"sphere\" \"radius\" [ 1 ]\n",
                                 "not a parameter declaration");
    expect_first_statement_error("Shapes \"sphere\"\n", "unknown statement \"Shapes\"");
    expect_first_statement_error("Shape \"trianglemesh\" \"point3 P\" [ 0 0 0 1 0 \"x\" 0 1 0 ]\n",
                                 "expected numbers");
    expect_error(HEADER "Translate 1 2\nWorldEnd\n", 5, "expected a number");
    expect_first_statement_error("Shape \"trianglemesh\" \"point3 P\" [ 0 0 0 1 0 nan 0 1 0 ]\n",
                                 "expected a value, found nan");
    expect_first_statement_error("Material \"diffuse\" \"string reflectance\" \"x\n",
                                 "unterminated string");
}

Test(pbrt_errors, missing_files_and_names)
{
    expect_error(HEADER "\nShape \"plymesh\" \"string filename\" \"models/none.ply\"\n", 5,
                 "models/none.ply: cannot open mesh");
    expect_first_statement_error("Include \"none.pbrt\"\n", "none.pbrt: cannot open");
    expect_first_statement_error("Include \"part.pbrt.gz\"\n", "gunzip it first");
    expect_error(HEADER TRIANGLE "NamedMaterial \"nothing\"\n" TRIANGLE, 5,
                 "\"nothing\" is never defined");
    expect_first_statement_error("ObjectInstance \"nothing\"\n", "no such object");
    expect_first_statement_error("Material \"diffuse\" \"texture reflectance\" \"none\"\n",
                                 "no texture named \"none\"");
    /* An error in an included file names that file. */
    write_scene("bad.pbrt", "\nShape \"trianglemesh\" \"point3 P\" [ 0 0 0 ] \"integer indices\" [ 0 1 2 ]\n");
    SgError err;
    cr_assert_null(load_text(HEADER "Include \"bad.pbrt\"\n", &err));
    cr_expect(strstr(err.message, "/bad.pbrt:2: index 1 is out of range"), "%s", err.message);
}

Test(pbrt_errors, unbalanced_blocks)
{
    expect_error(HEADER TRIANGLE "AttributeEnd\n", 5, "AttributeEnd without");
    expect_first_statement_error("AttributeBegin\n" TRIANGLE, "AttributeBegin has no matching");
    expect_first_statement_error("TransformBegin\n" TRIANGLE, "TransformBegin has no matching");
    expect_first_statement_error("ObjectBegin \"a\"\n" TRIANGLE, "ObjectBegin has no matching");
    expect_error(HEADER "ObjectBegin \"a\"\nObjectBegin \"b\"\n", 5, "ObjectBegin inside");
    expect_first_statement_error("ObjectEnd\n", "ObjectEnd without");
}

Test(pbrt_errors, bad_geometry)
{
    expect_first_statement_error("Shape \"trianglemesh\" \"point3 P\" [ 0 0 0 1 0 0 0 1 0 1 1 1 ]\n",
                                 "needs \"integer indices\"");
    expect_first_statement_error("Shape \"trianglemesh\" \"point3 P\" [ 0 0 0 1 0 0 0 1 0 ]\n"
                                 "  \"integer indices\" [ 0 1 3 ]\n", "index 3 is out of range");
    expect_first_statement_error("Shape \"trianglemesh\" \"point3 P\" [ 0 0 0 1 0 0 0 1 ]\n",
                                 "needs \"point3 P\"");
    SgError err;
    cr_assert_null(load_text(HEADER "Shape \"curve\"\n", &err));
    cr_expect(strstr(err.message, "no triangles"), "%s", err.message);
}

/* ---- the programs take .pbrt files -------------------------------------- */

Test(pbrt_programs, voxelize_reads_pbrt_and_prints_warnings)
{
    char prog[4096], cmd[16384], errs[8192];
    sg_test_program("voxelize", prog, sizeof prog);
    if (!sg_test_exists(prog))
        cr_skip_test("bin/voxelize not built");
    const char *scene = write_scene(
        "room.pbrt", HEADER
        "Shape \"trianglemesh\" \"point3 P\" [ 0 0 0 4 0 0 4 0 4 0 0 4  0 4 0 4 4 0 4 4 4 0 4 4 ]\n"
        "  \"integer indices\" [ 0 1 2 0 2 3  4 6 5 4 7 6 ]\n"
        "Shape \"curve\"\n"
        "AttributeBegin\n  AreaLightSource \"diffuse\" \"rgb L\" [ 5 5 5 ]\n"
        "  Shape \"trianglemesh\" \"point3 P\" [ 1 3 1 3 3 1 3 3 3 1 3 3 ]\n"
        "    \"integer indices\" [ 0 1 2 0 2 3 ]\nAttributeEnd\n");
    snprintf(cmd, sizeof cmd, "%s %s -o %s/room.vdb --resolution 16", prog, scene, scene_dir);
    int rc = sg_test_run(cmd, errs, sizeof errs);
    cr_expect_eq(rc, 0, "%s", errs);
    cr_expect(strstr(errs, "voxelize: warning: ") && strstr(errs, "room.pbrt:6: Shape \"curve\""),
              "%s", errs);
    char vdb[4200];
    snprintf(vdb, sizeof vdb, "%s/room.vdb", scene_dir);
    cr_expect(sg_test_exists(vdb));
}

/* ---- render: mean brightness of the staircase ---------------------------- */

/* The committed reference: tests/data/pbrt_staircase_mean.txt. */
Test(pbrt_render, staircase_mean_brightness, .timeout = 120)
{
    char prog[4096];
    sg_test_program("render", prog, sizeof prog);
    if (!sg_test_exists(prog))
        cr_skip_test("bin/render not built");
    if (!sg_test_have_shared_scenes() || !sg_test_exists(STAIRCASE))
        cr_skip_test("shared scenes absent");
    FILE *f = fopen("tests/data/pbrt_staircase_mean.txt", "r");
    cr_assert(f, "tests/data/pbrt_staircase_mean.txt missing");
    char line[256];
    double want[3] = {0, 0, 0}, tolerance = 0;
    int spp = 0, width = 0, height = 0;
    while (fgets(line, sizeof line, f)) {
        sscanf(line, "mean %lf %lf %lf", &want[0], &want[1], &want[2]);
        sscanf(line, "tolerance %lf", &tolerance);
        sscanf(line, "spp %d", &spp);
        sscanf(line, "size %dx%d", &width, &height);
    }
    fclose(f);
    cr_assert(tolerance > 0 && spp > 0 && width > 0 && height > 0, "bad reference file");
    const char *dir = scene_folder();
    char cmd[16384], errs[8192];
    snprintf(cmd, sizeof cmd,
             "%s %s --sampling bsdf --spp %d --size %dx%d --seed 1 -o %s/stairs.exr --quiet",
             prog, STAIRCASE, spp, width, height, dir);
    int rc = sg_test_run(cmd, errs, sizeof errs);
    cr_assert_eq(rc, 0, "%s", errs);
    snprintf(cmd, sizeof cmd, "oiiotool %s/stairs.exr --printstats 2>&1 | grep 'Stats Avg'", dir);
    FILE *stats = popen(cmd, "r");
    cr_assert(stats);
    double got[3] = {-1, -1, -1};
    char *avg = fgets(line, sizeof line, stats) ? strstr(line, "Avg:") : NULL;
    pclose(stats);
    cr_assert(avg && sscanf(avg + 4, "%lf %lf %lf", &got[0], &got[1], &got[2]) == 3,
              "no stats from oiiotool");
    for (int c = 0; c < 3; c++)
        cr_expect(fabs(got[c] - want[c]) <= tolerance * want[c],
                  "channel %d: mean %g, reference %g (tolerance %g%%)", c, got[c], want[c],
                  100 * tolerance);
}

/* ---- render: a texture seen through its uv ------------------------------- */

/* A quad with a 2 x 1 checkerboard of red and blue over its uv, lit from
 * behind the camera: its two halves render in its two colours, each on the
 * side pbrt-v4 puts it. */
Test(pbrt_render, checkerboard_texture_follows_the_uv)
{
    SgScene *s = load_ok(
        HEADER "Texture \"check\" \"spectrum\" \"checkerboard\" \"float uscale\" 2\n"
               "    \"rgb tex1\" [ 0.8 0 0 ] \"rgb tex2\" [ 0 0 0.8 ]\n"
               "Material \"diffuse\" \"texture reflectance\" \"check\"\n"
               "Shape \"trianglemesh\" \"point3 P\" [ -4 -4 5 4 -4 5 4 4 5 -4 4 5 ]\n"
               "    \"point2 uv\" [ 0 0 1 0 1 1 0 1 ] \"integer indices\" [ 0 1 2 0 2 3 ]\n"
               "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [ 5 5 5 ]\n"
               "Shape \"trianglemesh\" \"point3 P\" [ -20 -20 -1 20 -20 -1 20 20 -1 ]\n"
               "    \"integer indices\" [ 0 1 2 ]\nAttributeEnd\n");
    cr_assert_not_null(s->uvs, "the quad's uv");
    SgRenderOptions o;
    SgError err = {0};
    float *rgb = sgt_render_default(s, &o, 4, &err);
    cr_assert(rgb, "%s", err.message);
    /* per column: which colour wins; the columns must split in two runs */
    int red_left = 0, red_right = 0, blue_left = 0, blue_right = 0;
    for (int y = 0; y < o.height; y++)
        for (int x = 0; x < o.width; x++) {
            const float *p = rgb + 3 * ((size_t)y * o.width + x);
            bool left = x < o.width / 2;
            if (p[0] > 4 * p[2] + 1e-3f)
                *(left ? &red_left : &red_right) += 1;
            if (p[2] > 4 * p[0] + 1e-3f)
                *(left ? &blue_left : &blue_right) += 1;
            cr_assert(p[1] < 1e-6f, "no green anywhere (%d, %d): %g", x, y, p[1]);
        }
    int half = o.width * o.height / 2;
    /* pbrt-v4's checkerboard gives tex1 where floor(s) + floor(t) is even:
     * u < 0.5 (uscale 2), the quad's x < 0, is red. The CTM at Camera is
     * camera-from-world, here Scale -1 1 1: world x < 0 is camera x > 0,
     * and raster x grows with camera x (ProjectiveCamera's screen-to-raster
     * keeps x, flips y). So red is on the right, blue on the left. */
    cr_expect(blue_left > half * 9 / 10 && red_right > half * 9 / 10,
              "red %d | %d, blue %d | %d of %d pixels a side (expected blue | red)", red_left, red_right, blue_left,
              blue_right, half);
    free(rgb);
    sg_scene_free(s);
}
