/* Meshes read through Assimp (OBJ + MTL, glTF): their texture coordinates
 * and diffuse maps, a missing or embedded map, and a render of an OBJ
 * texture the right way up. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "image_io.h"
#include "render/renderer.h"
#include "scene_load.h"
#include "support_files.h"
#include "support_render.h"

/* A quad in the z = 0 plane facing +z, its vt the image's corners. */
#define QUAD_OBJ(mtl, material)                                                                   \
    "mtllib " mtl "\n"                                                                            \
    "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n"                                                    \
    "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"                                                            \
    "usemtl " material "\nf 1/1 2/2 3/3 4/4\n"

/* Quadrants of the test image, linear RGB: top left red, top right green,
 * bottom left blue, bottom right grey. Their mean is 0.3 in each channel. */
static const float quadrant_colour[2][2][3] = {
    {{0.8f, 0, 0}, {0, 0.8f, 0}},    /* top row: left, right */
    {{0, 0, 0.8f}, {0.4f, 0.4f, 0.4f}}, /* bottom row */
};

/* Writes the quadrant image as an 8-bit (sRGB) PNG. */
static void write_quadrants_png(const char *path)
{
    enum { W = 16, H = 16 };
    static float rgb[W * H * 3];
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++)
            memcpy(rgb + 3 * (y * W + x), quadrant_colour[y >= H / 2][x >= W / 2], 3 * sizeof(float));
    SgError err = {0};
    cr_assert(sg_image_write_png(path, W, H, rgb, 0, &err), "%s", err.message);
}

static char *join(char *buf, size_t size, const char *dir, const char *name)
{
    snprintf(buf, size, "%s/%s", dir, name);
    return buf;
}

/* DIR/scene.json: the mesh file under a quad light, loaded. */
static SgScene *load_lit_mesh(const char *dir, const char *mesh)
{
    char text[1024];
    snprintf(text, sizeof text,
             "{ \"mesh\": \"%s\", \"lights\": [ { \"type\": \"quad\", "
             "\"corners\": [[0,0,5],[0,1,5],[1,1,5],[1,0,5]], \"radiance\": [1,1,1] } ] }",
             mesh);
    return sgt_load_ok(sg_test_write(dir, "scene.json", text));
}

static const SgMaterial *material_named(const SgScene *s, const char *name)
{
    for (uint32_t i = 0; i < s->material_count; i++)
        if (!strcmp(s->materials[i].name, name))
            return &s->materials[i];
    cr_assert_fail("no material \"%s\"", name);
    return NULL;
}

static bool has_warning(const SgScene *s, const char *a, const char *b)
{
    for (uint32_t i = 0; i < s->warning_count; i++)
        if (strstr(s->warnings[i], a) && (!b || strstr(s->warnings[i], b)))
            return true;
    return false;
}

/* The mesh (models/quad.obj) lives below the JSON file and its texture
 * below the mesh (models/tex/): map_Kd resolves against the mesh's
 * directory, a Windows separator included. The map replaces Kd; a JSON
 * override's albedo replaces the map. */
Test(mesh_textures, obj_uv_and_map_kd_replacing_kd)
{
    const char *dir = sg_test_tmpdir();
    char models[4200], tex[4300], png[4400];
    cr_assert_eq(mkdir(join(models, sizeof models, dir, "models"), 0700), 0);
    cr_assert_eq(mkdir(join(tex, sizeof tex, models, "tex"), 0700), 0);
    write_quadrants_png(join(png, sizeof png, tex, "quad.png"));
    sg_test_write(models, "quad.obj",
                  QUAD_OBJ("quad.mtl", "painted")
                  "v 0 0 1\nv 1 0 1\nv 0 1 1\nusemtl plain\nf 5 6 7\n"
                  "v 0 0 2\nv 1 0 2\nv 0 1 2\nusemtl recoloured\nf 8 9 10\n");
    /* Kd 0.9 beside the map: replaced by it, not multiplied (0.27) */
    sg_test_write(models, "quad.mtl",
                  "newmtl painted\nKd 0.9 0.9 0.9\nmap_Kd tex\\quad.png\n"
                  "newmtl plain\nKd 0.2 0.4 0.6\n"
                  "newmtl recoloured\nKd 0.9 0.9 0.9\nmap_Kd tex/quad.png\n");
    SgScene *s = sgt_load_ok(sg_test_write(dir, "scene.json",
                                       "{ \"mesh\": \"models/quad.obj\",\n"
                                       "  \"materials\": { \"recoloured\": { \"albedo\": [0.1, 0.2, 0.3] } },\n"
                                       "  \"lights\": [ { \"type\": \"quad\", "
                                       "\"corners\": [[0,0,5],[0,1,5],[1,1,5],[1,0,5]], "
                                       "\"radiance\": [1,1,1] } ] }"));
    cr_expect_eq(s->warning_count, 0, "%s", s->warning_count ? s->warnings[0] : "");
    cr_assert_not_null(s->uvs, "the OBJ's vt");
    /* each corner keeps its vt as written (OBJ and our lookups agree:
     * v = 0 is the image's bottom row); the untextured triangle has none */
    int corners = 0;
    for (uint32_t v = 0; v < s->vertex_count; v++) {
        const double *p = s->positions + 3 * (size_t)v;
        const float *uv = s->uvs + 2 * (size_t)v;
        if (p[2] != 0) {
            cr_expect(uv[0] == 0 && uv[1] == 0, "vertex without vt: (%g, %g)", uv[0], uv[1]);
            continue;
        }
        corners++;
        cr_expect_float_eq(uv[0], (p[0] + 1) / 2, 1e-6, "u at (%g, %g)", p[0], p[1]);
        cr_expect_float_eq(uv[1], (p[1] + 1) / 2, 1e-6, "v at (%g, %g)", p[0], p[1]);
    }
    cr_expect_eq(corners, 4);
    const SgMaterial *painted = material_named(s, "painted");
    cr_assert(painted->diffuse_texture > 0 && painted->diffuse_texture <= s->texture_count);
    const SgTexture *t = &s->textures[painted->diffuse_texture - 1];
    cr_expect_eq(t->kind, SG_TEXTURE_IMAGE);
    cr_assert_not_null(t->path);
    cr_expect_str_eq(t->path, png);
    cr_expect_float_eq(t->gamma, -1.0f, 0, "8-bit colour: sRGB");
    cr_expect(t->uscale == 1 && t->vscale == 1 && t->udelta == 0 && t->vdelta == 0);
    cr_expect_eq(t->wrap, SG_WRAP_REPEAT);
    for (int c = 0; c < 3; c++) {
        /* the quadrants' linear mean, up to 8-bit rounding */
        cr_expect(fabsf(t->mean[c] - 0.3f) < 0.004f, "mean %d: %g", c, t->mean[c]);
        cr_expect_float_eq(painted->diffuse[c], t->mean[c], 1e-6, "diffuse is the map's mean");
    }
    const SgMaterial *plain = material_named(s, "plain");
    cr_expect_eq(plain->diffuse_texture, 0);
    cr_expect(plain->diffuse[0] == 0.2f && plain->diffuse[2] == 0.6f);
    /* a JSON material of the same name giving its own albedo drops the map */
    const SgMaterial *recoloured = material_named(s, "recoloured");
    cr_expect_eq(recoloured->diffuse_texture, 0);
    cr_expect(recoloured->diffuse[0] == 0.1f && recoloured->diffuse[2] == 0.3f);
    sg_scene_free(s);
}

/* A map_Kd whose file is missing: one warning naming the mesh and the
 * file, however many materials use it; each is a grey 0.5 texture without
 * a path, as a missing pbrt imagemap is. */
Test(mesh_textures, missing_map_kd_warns_once_and_is_grey)
{
    const char *dir = sg_test_tmpdir();
    char obj[4200];
    sg_test_write(dir, "quad.obj",
                  QUAD_OBJ("quad.mtl", "a") "v 0 0 1\nv 1 0 1\nv 0 1 1\nusemtl b\nf 5 6 7\n");
    sg_test_write(dir, "quad.mtl",
                  "newmtl a\nKd 0.9 0.1 0.1\nmap_Kd nothere.png\n"
                  "newmtl b\nKd 0.1 0.9 0.1\nmap_Kd nothere.png\n");
    join(obj, sizeof obj, dir, "quad.obj");
    SgScene *s = load_lit_mesh(dir, "quad.obj");
    cr_expect_eq(s->warning_count, 1);
    cr_expect(has_warning(s, obj, "nothere.png"), "warning: %s", s->warning_count ? s->warnings[0] : "(none)");
    cr_expect(!strchr(s->warning_count ? s->warnings[0] : "", '\n'), "one line");
    for (int m = 0; m < 2; m++) {
        const SgMaterial *mat = material_named(s, m ? "b" : "a");
        cr_assert(mat->diffuse_texture > 0, "still a texture, so that a comparison can mask it");
        const SgTexture *t = &s->textures[mat->diffuse_texture - 1];
        cr_expect_eq(t->kind, SG_TEXTURE_IMAGE);
        cr_expect_null(t->path);
        for (int c = 0; c < 3; c++) {
            cr_expect_float_eq(t->mean[c], 0.5f, 0);
            cr_expect_float_eq(mat->diffuse[c], 0.5f, 0);
        }
    }
    /* the renderer takes it as its mean: it does not try to open it */
    cr_assert(s->has_camera == false);
    s->has_camera = true;
    s->camera = (SgCamera){.position = {0, 0, 3}, .look_at = {0, 0, 0}, .up = {0, 1, 0}, .fov_deg = 30,
                           .width = 8, .height = 8};
    SgRenderOptions o;
    sg_render_options_default(&o, s);
    o.threads = 1;
    SgError err = {0};
    SgRenderer *r = sg_renderer_create(s, &o, &err);
    cr_expect_not_null(r, "%s", err.message);
    sg_renderer_free(r);
    sg_scene_free(s);
}

/* ---- glTF ---------------------------------------------------------------- */

static void put_floats(FILE *f, const float *v, size_t n)
{
    cr_assert_eq(fwrite(v, sizeof *v, n, f), n);
}

/* A triangle whose glTF uv (origin at the image's top left) is
 * (0, 0) (1, 0.25) (0, 1), with a base colour factor and a texture: an
 * image file, or the PNG's bytes inside the buffer (an embedded image). */
static const char *write_gltf(const char *dir, const char *name, const char *png, bool embedded)
{
    char path[4300];
    long png_size = 0;
    unsigned char *png_bytes = NULL;
    if (embedded) {
        FILE *in = fopen(png, "rb");
        cr_assert(in);
        fseek(in, 0, SEEK_END);
        png_size = ftell(in);
        rewind(in);
        png_bytes = malloc((size_t)png_size);
        cr_assert(png_bytes && fread(png_bytes, 1, (size_t)png_size, in) == (size_t)png_size);
        fclose(in);
    }
    FILE *f = fopen(join(path, sizeof path, dir, "tri.bin"), "wb");
    cr_assert(f);
    const float positions[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0}, uv[6] = {0, 0, 1, 0.25f, 0, 1};
    const unsigned short indices[4] = {0, 1, 2, 0}; /* padded to 4 bytes */
    put_floats(f, positions, 9);
    put_floats(f, uv, 6);
    cr_assert_eq(fwrite(indices, sizeof *indices, 4, f), 4);
    if (embedded)
        cr_assert_eq(fwrite(png_bytes, 1, (size_t)png_size, f), (size_t)png_size);
    fclose(f);
    free(png_bytes);
    char image[512], views[512], text[4096];
    if (embedded) {
        snprintf(image, sizeof image, "{ \"bufferView\": 3, \"mimeType\": \"image/png\" }");
        snprintf(views, sizeof views, ", { \"buffer\": 0, \"byteOffset\": 68, \"byteLength\": %ld }", png_size);
    } else {
        snprintf(image, sizeof image, "{ \"uri\": \"quadrants.png\" }");
        views[0] = 0;
    }
    snprintf(text, sizeof text,
             "{ \"asset\": { \"version\": \"2.0\" }, \"scene\": 0, \"scenes\": [ { \"nodes\": [ 0 ] } ],\n"
             "  \"nodes\": [ { \"mesh\": 0 } ],\n"
             "  \"meshes\": [ { \"primitives\": [ { \"attributes\": { \"POSITION\": 0, \"TEXCOORD_0\": 1 },\n"
             "      \"indices\": 2, \"material\": 0 } ] } ],\n"
             "  \"materials\": [ { \"name\": \"tinted\", \"pbrMetallicRoughness\": {\n"
             "      \"baseColorFactor\": [ 0.5, 1, 1, 1 ], \"baseColorTexture\": { \"index\": 0 },\n"
             "      \"metallicFactor\": 0 } } ],\n"
             "  \"textures\": [ { \"source\": 0 } ], \"images\": [ %s ],\n"
             "  \"buffers\": [ { \"uri\": \"tri.bin\", \"byteLength\": %ld } ],\n"
             "  \"bufferViews\": [ { \"buffer\": 0, \"byteOffset\": 0, \"byteLength\": 36 },\n"
             "      { \"buffer\": 0, \"byteOffset\": 36, \"byteLength\": 24 },\n"
             "      { \"buffer\": 0, \"byteOffset\": 60, \"byteLength\": 6 }%s ],\n"
             "  \"accessors\": [\n"
             "    { \"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": \"VEC3\",\n"
             "      \"min\": [ 0, 0, 0 ], \"max\": [ 1, 1, 0 ] },\n"
             "    { \"bufferView\": 1, \"componentType\": 5126, \"count\": 3, \"type\": \"VEC2\" },\n"
             "    { \"bufferView\": 2, \"componentType\": 5123, \"count\": 3, \"type\": \"SCALAR\" } ] }\n",
             image, 68 + png_size, views);
    return sg_test_write(dir, name, text);
}

/* glTF's base colour factor multiplies its texture (a scale texture over
 * the image); its uv, whose origin is the image's top left, come out of
 * Assimp flipped to ours (v = 1 - v). */
Test(mesh_textures, gltf_base_colour_times_texture)
{
    const char *dir = sg_test_tmpdir();
    char png[4200];
    write_quadrants_png(join(png, sizeof png, dir, "quadrants.png"));
    write_gltf(dir, "tri.gltf", png, false);
    SgScene *s = load_lit_mesh(dir, "tri.gltf");
    cr_expect_eq(s->warning_count, 0, "%s", s->warning_count ? s->warnings[0] : "");
    cr_assert_not_null(s->uvs);
    const float want[3][2] = {{0, 1}, {1, 0.75f}, {0, 0}}; /* at (0,0) (1,0) (0,1) */
    int seen = 0;
    for (uint32_t v = 0; v < s->vertex_count; v++) {
        const double *p = s->positions + 3 * (size_t)v;
        if (p[2] != 0)
            continue; /* the light */
        int k = p[0] == 1 ? 1 : p[1] == 1 ? 2 : 0;
        seen++;
        cr_expect(s->uvs[2 * v] == want[k][0] && s->uvs[2 * v + 1] == want[k][1], "corner %d: (%g, %g)", k,
                  s->uvs[2 * v], s->uvs[2 * v + 1]);
    }
    cr_expect_eq(seen, 3);
    const SgMaterial *m = material_named(s, "tinted");
    cr_assert(m->diffuse_texture > 0);
    const SgTexture *scale = &s->textures[m->diffuse_texture - 1];
    cr_assert_eq(scale->kind, SG_TEXTURE_SCALE);
    cr_assert(scale->input[0].texture > 0 && scale->input[1].texture == 0);
    cr_expect(scale->input[1].value[0] == 0.5f && scale->input[1].value[1] == 1.0f);
    const SgTexture *image = &s->textures[scale->input[0].texture - 1];
    cr_expect_eq(image->kind, SG_TEXTURE_IMAGE);
    cr_expect_str_eq(image->path ? image->path : "(null)", png);
    cr_expect(fabsf(m->diffuse[0] - 0.15f) < 0.003f && fabsf(m->diffuse[1] - 0.3f) < 0.004f, "diffuse %g %g",
              m->diffuse[0], m->diffuse[1]);
    cr_expect_float_eq(scale->mean[0], m->diffuse[0], 1e-6);
    sg_scene_free(s);
}

/* An image inside the glTF's buffer is not read: one warning, and the
 * material keeps its base colour. */
Test(mesh_textures, gltf_embedded_image_warns_and_keeps_the_colour)
{
    const char *dir = sg_test_tmpdir();
    char png[4200], gltf[4200];
    write_quadrants_png(join(png, sizeof png, dir, "quadrants.png"));
    snprintf(gltf, sizeof gltf, "%s", write_gltf(dir, "tri.gltf", png, true));
    SgScene *s = load_lit_mesh(dir, "tri.gltf");
    cr_expect_eq(s->warning_count, 1);
    cr_expect(has_warning(s, gltf, "embedded"), "warning: %s", s->warning_count ? s->warnings[0] : "(none)");
    const SgMaterial *m = material_named(s, "tinted");
    cr_expect_eq(m->diffuse_texture, 0);
    /* (0.5, 1, 1), 1 kept just below by the loader's energy rule */
    cr_expect(m->diffuse[0] == 0.5f && m->diffuse[1] == 0.999f, "diffuse %g %g", m->diffuse[0], m->diffuse[1]);
    sg_scene_free(s);
}

/* ---- render -------------------------------------------------------------- */

/* The quadrant image on the OBJ quad, seen straight on with y up and lit
 * from behind the camera: each quarter of the picture is the colour of the
 * image's same quarter (not mirrored, not upside down). */
Test(mesh_render, obj_texture_the_right_way_up, .timeout = 60)
{
    const char *dir = sg_test_tmpdir();
    char png[4200];
    write_quadrants_png(join(png, sizeof png, dir, "quadrants.png"));
    sg_test_write(dir, "quad.obj", QUAD_OBJ("quad.mtl", "painted"));
    sg_test_write(dir, "quad.mtl", "newmtl painted\nKd 1 1 1\nmap_Kd quadrants.png\n");
    /* the light faces -z: (c1 - c0) x (c2 - c0) */
    SgScene *s = sgt_load_ok(sg_test_write(
        dir, "scene.json",
        "{ \"mesh\": \"quad.obj\",\n"
        "  \"lights\": [ { \"type\": \"quad\", \"corners\": [[-20,-20,4],[-20,20,4],[20,20,4],[20,-20,4]],\n"
        "                \"radiance\": [2, 2, 2] } ],\n"
        "  \"camera\": { \"position\": [0, 0, 3], \"look_at\": [0, 0, 0], \"up\": [0, 1, 0], \"fov\": 30 },\n"
        "  \"image\": { \"width\": 32, \"height\": 32 } }"));
    SgRenderOptions o;
    SgError err = {0};
    float *rgb = sgt_render_default(s, &o, 4, &err);
    cr_assert(rgb, "%s", err.message);
    /* the mean of each quarter, away from the seams (bilinear lookups) */
    for (int qy = 0; qy < 2; qy++)
        for (int qx = 0; qx < 2; qx++) {
            double sum[3] = {0, 0, 0};
            int n = 0;
            for (int y = qy * o.height / 2 + 2; y < (qy + 1) * o.height / 2 - 2; y++)
                for (int x = qx * o.width / 2 + 2; x < (qx + 1) * o.width / 2 - 2; x++, n++)
                    for (int c = 0; c < 3; c++)
                        sum[c] += rgb[3 * ((size_t)y * o.width + x) + c];
            const float *want = quadrant_colour[qy][qx];
            double peak = fmax(sum[0], fmax(sum[1], sum[2])) / n;
            cr_assert_gt(peak, 0.05, "quarter (%d, %d) is dark", qx, qy);
            for (int c = 0; c < 3; c++) {
                /* the image's channel share, up to noise and 8-bit rounding */
                double got = sum[c] / n / peak, expect = want[c] / fmaxf(want[0], fmaxf(want[1], want[2]));
                cr_expect(fabs(got - expect) < 0.05, "quarter (%s, %s) channel %d: %g of its peak, want %g",
                          qx ? "right" : "left", qy ? "bottom" : "top", c, got, expect);
            }
        }
    free(rgb);
    sg_scene_free(s);
}
