/* Mitsuba scene files, shapes: obj, ply and serialized meshes, the
 * analytic rectangle, cube, sphere, disk and cylinder as meshes of their
 * true area (quadric_mesh.h), shapegroup and instance; each with its bsdf
 * and area emitter. flip_normals turns the triangles over (the side an
 * area light shines from); face_normals changes nothing here, as the
 * renderer shades with the triangles' own normals. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mesh_file.h"
#include "mitsuba_parser.h"
#include "ply_mesh.h"
#include "quadric_mesh.h"
#include "vecmath.h"

/* The radiance of the shape's area emitter; false without one. */
static bool area_emitter(MtsParser *p, const XmlNode *shape, float radiance[3], bool *emits)
{
    const XmlNode *e;
    *emits = false;
    if (!mts_find_object(p, shape, "emitter", 0, &e))
        return false;
    if (!e)
        return true;
    const char *type = mts_attr(p, e, "type");
    if (!type || strcmp(type, "area")) {
        mts_warn(p, e, "emitters inside shapes other than \"area\" are left out");
        return !p->err->failed;
    }
    static const float one[3] = {1, 1, 1};
    if (!mts_color(p, e, "radiance", one, radiance, NULL, NULL))
        return false;
    for (int c = 0; c < 3; c++)
        if (!(radiance[c] >= 0 && isfinite(radiance[c])))
            return mts_fail(p, e, "area emitter radiance must be finite and not negative");
    *emits = radiance[0] > 0 || radiance[1] > 0 || radiance[2] > 0;
    return true;
}

static void flip_triangle(uint32_t *idx)
{
    uint32_t k = idx[1];
    idx[1] = idx[2];
    idx[2] = k;
}

/* Appends a mesh (object space, placed by xf) with the shape's bsdf and
 * emitter, into the scene or the shapegroup being defined. Emission leaves
 * the side the vertex normals point to where there are normals, else the
 * winding's (flip_normals turns both over), as Mitsuba's area lights. An
 * analytic shape's normal goes through the inverse transpose of to_world,
 * which keeps its side where a mirroring transform turns the winding over:
 * its triangles are turned back. */
static bool emit_mesh(MtsParser *p, const XmlNode *shape, const char *what, const double *positions,
                      uint32_t vertex_count, uint32_t *indices, uint32_t triangle_count, const double *normals,
                      const float *uvs, const SgTransform *xf, bool analytic)
{
    const XmlNode *bsdf;
    float radiance[3];
    bool emits, flip;
    size_t material;
    uint32_t scene_material;
    if (!mts_find_object(p, shape, "bsdf", 0, &bsdf) || !area_emitter(p, shape, radiance, &emits) ||
        !mts_bool(p, shape, "flip_normals", false, &flip) || !mts_material(p, bsdf, &material))
        return false;
    if (p->materials[material].invisible) {
        mts_warn(p, shape, "shapes with the \"null\" bsdf are left out (a medium is taken only inside a dielectric)");
        return true;
    }
    if (emits && p->defining) {
        mts_warn(p, shape, "area emitters inside a shapegroup are ignored");
        emits = false;
    }
    if (!mts_scene_material(p, material, emits ? radiance : NULL, &scene_material) ||
        !mts_interior_material(p, shape, &scene_material))
        return false;
    if (analytic && sg_transform_determinant(xf) < 0)
        flip = !flip;
    for (uint32_t t = 0; t < triangle_count; t++) {
        uint32_t *idx = indices + 3 * (size_t)t;
        bool turn = flip;
        if (normals && emits) {
            double wp[3][3], e1[3], e2[3], n[3], ns[3] = {0, 0, 0}, nw[3];
            for (int c = 0; c < 3; c++) {
                sg_transform_point(xf, positions + 3 * (size_t)idx[c], wp[c]);
                for (int a = 0; a < 3; a++)
                    ns[a] += normals[3 * (size_t)idx[c] + a];
            }
            d3_sub(wp[1], wp[0], e1);
            d3_sub(wp[2], wp[0], e2);
            d3_cross(e1, e2, n);
            sg_transform_normal(xf, ns, nw);
            if (d3_length(nw) > 0)
                turn = (d3_dot(n, nw) < 0) != flip;
        }
        if (turn)
            flip_triangle(idx);
    }
    for (uint32_t v = 0; v < vertex_count; v++)
        if (!sg_builder_check_point(&p->core, what, positions + 3 * (size_t)v, p->err))
            return false;
    if (p->defining)
        return sg_shape_group_add(&p->defining->shapes, p->core.path, positions, vertex_count, indices,
                                  triangle_count, uvs, xf, scene_material, p->err);
    uint32_t first = p->core.scene->vertex_count;
    return sg_builder_append_mesh(&p->core, what, positions, vertex_count, indices, triangle_count, xf,
                                  scene_material, p->err) &&
           (!uvs || sg_builder_set_uvs(&p->core, first, vertex_count, uvs, p->err));
}

/* ---- mesh files --------------------------------------------------------- */

/* Mitsuba looks a bitmap up with v growing down the image from its first
 * row; our textures follow pbrt, whose v grows up from the last row
 * (render/textures.c): a Mitsuba v is our 1 - v. */
static void mitsuba_v_to_ours(float *uvs, uint32_t vertex_count)
{
    for (uint32_t v = 0; uvs && v < vertex_count; v++)
        uvs[2 * (size_t)v + 1] = 1.0f - uvs[2 * (size_t)v + 1];
}

static bool any_material(const SgMeshFileMaterials *rules, const char *file, uint32_t *id, SgError *err)
{
    (void)file;
    SgSceneBuilder *b = rules->context;
    SgMaterial m;
    sg_material_default(&m, "obj");
    return sg_builder_add_material(b, &m, id, err);
}

/* An OBJ file's triangles through the mesh-file loader into a scene of
 * their own, so that they take the shape's bsdf like any other mesh. */
static bool obj(MtsParser *p, XmlNode *shape, const char *path, const SgTransform *xf)
{
    SgSceneBuilder tmp;
    if (!sg_builder_begin(&tmp, path, p->err))
        return false;
    SgMeshFileMaterials rules = {.name = "mitsuba", .plain = any_material, .context = &tmp};
    SgTransform identity;
    sg_transform_identity(&identity);
    SgError local = {0};
    bool ok = sg_mesh_file_load(&tmp, &p->core.images, path, &identity, &rules, &local) ||
              mts_fail(p, shape, "%s", local.message);
    SgScene *s = tmp.scene;
    if (ok && s->triangle_count == 0 && tmp.dropped_degenerate == 0)
        ok = mts_fail(p, shape, "%s: no triangles", path);
    p->core.dropped_degenerate += tmp.dropped_degenerate; /* counted as every other mesh's */
    float *uvs = NULL;
    if (ok && s->uvs) {
        /* Mitsuba turns OBJ's v over (flip_tex_coords, true unless told),
         * which our 1 - v turns back: the file's v as it is */
        bool flip_v;
        ok = mts_bool(p, shape, "flip_tex_coords", true, &flip_v);
        uvs = malloc((size_t)s->vertex_count * 2 * sizeof(float));
        if (ok && !uvs)
            ok = sg_fail(p->err, "%s: out of memory", p->core.path);
        if (ok) {
            memcpy(uvs, s->uvs, (size_t)s->vertex_count * 2 * sizeof(float));
            if (!flip_v)
                mitsuba_v_to_ours(uvs, s->vertex_count);
        }
    }
    ok = ok && (s->triangle_count == 0 || emit_mesh(p, shape, path, s->positions, s->vertex_count, s->indices, s->triangle_count, NULL,
                                                    uvs, xf, false));
    free(uvs);
    sg_scene_free(s);
    sg_builder_release(&tmp);
    return ok;
}

static bool mesh_file(MtsParser *p, XmlNode *shape, const char *type, const SgTransform *xf)
{
    const char *file;
    if (!mts_string(p, shape, "filename", NULL, &file))
        return false;
    if (!file)
        return mts_fail(p, shape, "shape \"%s\" has no \"filename\"", type);
    char path[8192];
    mts_resolve(p, shape, file, path, sizeof path);
    if (!strcmp(type, "obj"))
        return obj(p, shape, path, xf);
    SgError local = {0};
    SgPlyMesh mesh;
    long index = 0;
    if (strcmp(type, "ply") && !mts_int(p, shape, "shape_index", 0, &index))
        return false;
    bool read = !strcmp(type, "ply") ? sg_ply_mesh_read(&mesh, path, &local)
                                     : mts_read_serialized(path, index, &mesh, &local);
    if (!read)
        return mts_fail(p, shape, "%s", local.message);
    mitsuba_v_to_ours(mesh.uvs, mesh.vertex_count);
    bool ok = emit_mesh(p, shape, path, mesh.positions, mesh.vertex_count, mesh.indices, mesh.triangle_count,
                        mesh.normals, mesh.uvs, xf, false);
    sg_ply_mesh_release(&mesh);
    return ok;
}

/* ---- analytic shapes ------------------------------------------------------ */

static bool quadric_shape(MtsParser *p, XmlNode *shape, const char *type, const SgTransform *to_world)
{
    SgQuadricMesh mesh;
    SgTransform xf = *to_world, local;
    sg_transform_identity(&local);
    bool made;
    if (!strcmp(type, "disk")) {
        made = sg_quadric_disk(1, 0, 0, 2 * M_PI, &mesh, p->err);
    } else if (!strcmp(type, "sphere")) {
        double radius, center[3];
        static const double origin[3] = {0, 0, 0};
        if (!mts_float(p, shape, "radius", 1, &radius) || !mts_point(p, shape, "center", origin, center, NULL))
            return false;
        if (!(radius > 0))
            return mts_fail(p, shape, "sphere radius must be positive");
        for (int a = 0; a < 3; a++)
            local.m[a][3] = center[a];
        made = sg_quadric_sphere(radius, -radius, radius, 2 * M_PI, &mesh, p->err);
    } else { /* cylinder: open, from p0 to p1 */
        double radius, p0[3], p1[3], axis[3];
        static const double origin[3] = {0, 0, 0}, top[3] = {0, 0, 1};
        if (!mts_float(p, shape, "radius", 1, &radius) || !mts_point(p, shape, "p0", origin, p0, NULL) ||
            !mts_point(p, shape, "p1", top, p1, NULL))
            return false;
        d3_sub(p1, p0, axis);
        double length = d3_length(axis);
        if (!(radius > 0 && length > 0))
            return mts_fail(p, shape, "cylinder needs a positive radius and p0 != p1");
        /* a frame whose z is the axis */
        double z[3] = {axis[0] / length, axis[1] / length, axis[2] / length}, x[3], y[3];
        double helper[3] = {fabs(z[0]) < 0.9 ? 1 : 0, fabs(z[0]) < 0.9 ? 0 : 1, 0};
        d3_unit_cross(helper, z, x);
        d3_cross(z, x, y);
        for (int a = 0; a < 3; a++) {
            local.m[a][0] = x[a];
            local.m[a][1] = y[a];
            local.m[a][2] = z[a];
            local.m[a][3] = p0[a];
        }
        made = sg_quadric_cylinder(radius, 0, length, 2 * M_PI, &mesh, p->err);
    }
    if (!made)
        return false;
    sg_transform_multiply(to_world, &local, &xf);
    char what[4300];
    snprintf(what, sizeof what, "%s:%d", shape->doc->path, shape->line);
    bool ok = emit_mesh(p, shape, what, mesh.positions, mesh.vertex_count, mesh.indices, mesh.triangle_count, NULL,
                        mesh.uvs, &xf, true);
    sg_quadric_mesh_free(&mesh);
    return ok;
}

static bool rectangle_or_cube(MtsParser *p, XmlNode *shape, bool cube, const SgTransform *xf)
{
    static const double square[4][3] = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
    static const float square_uv[8] = {0, 1, 1, 1, 1, 0, 0, 0}; /* Mitsuba's (x + 1) / 2, (y + 1) / 2, in ours */
    uint32_t square_idx[6] = {0, 1, 2, 0, 2, 3};
    static const double corners[8][3] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                                         {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};
    /* outward: each face wound counter-clockwise seen from outside */
    uint32_t cube_idx[36] = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                             2, 3, 7, 2, 7, 6, 1, 2, 6, 1, 6, 5, 0, 4, 7, 0, 7, 3};
    char what[4300];
    snprintf(what, sizeof what, "%s:%d", shape->doc->path, shape->line);
    if (cube)
        return emit_mesh(p, shape, what, &corners[0][0], 8, cube_idx, 12, NULL, NULL, xf, true);
    return emit_mesh(p, shape, what, &square[0][0], 4, square_idx, 2, NULL, square_uv, xf, true);
}

/* ---- groups ------------------------------------------------------------- */

static bool shapegroup(MtsParser *p, XmlNode *shape)
{
    if (p->defining)
        return mts_fail(p, shape, "a shapegroup inside a shapegroup");
    if (!MTS_RESERVE(p, p->groups, p->group_count, p->group_capacity, 1))
        return false;
    MtsGroup *g = &p->groups[p->group_count++];
    memset(g, 0, sizeof *g);
    g->node = shape;
    p->defining = g;
    bool ok = true;
    for (size_t i = 0; ok && i < shape->child_count; i++)
        if (mts_is_tag(shape->children[i], "shape"))
            ok = mts_shape(p, shape->children[i]);
    p->defining = NULL;
    return ok;
}

static bool instance(MtsParser *p, XmlNode *shape, const SgTransform *xf)
{
    const XmlNode *target;
    if (!mts_find_object(p, shape, "shape", 0, &target))
        return false;
    MtsGroup *g = NULL;
    for (size_t i = 0; target && i < p->group_count; i++)
        if (p->groups[i].node == target)
            g = &p->groups[i];
    if (!g)
        return mts_fail(p, shape, "instance needs a <ref> to a shapegroup");
    if (p->defining)
        return mts_fail(p, shape, "an instance inside a shapegroup");
    return sg_builder_add_group(&p->core, "instance", &g->shapes, xf, p->err);
}

bool mts_shape(MtsParser *p, XmlNode *shape)
{
    if (!mts_substitute(p, shape) || !mts_register_id(p, shape))
        return false;
    const char *type = sg_xml_attr(shape, "type");
    if (!type)
        return mts_fail(p, shape, "<shape> without a type");
    if (!strcmp(type, "shapegroup"))
        return shapegroup(p, shape);
    SgTransform xf;
    if (!mts_transform(p, shape, "to_world", &xf, NULL))
        return false;
    if (fabs(xf.m[3][0]) > 1e-12 || fabs(xf.m[3][1]) > 1e-12 || fabs(xf.m[3][2]) > 1e-12 ||
        fabs(xf.m[3][3] - 1) > 1e-12)
        return mts_fail(p, shape, "to_world is projective: shapes need an affine transform");
    if (!strcmp(type, "instance"))
        return instance(p, shape, &xf);
    if (!strcmp(type, "obj") || !strcmp(type, "ply") || !strcmp(type, "serialized"))
        return mesh_file(p, shape, type, &xf);
    if (!strcmp(type, "rectangle") || !strcmp(type, "cube"))
        return rectangle_or_cube(p, shape, !strcmp(type, "cube"), &xf);
    if (!strcmp(type, "sphere") || !strcmp(type, "disk") || !strcmp(type, "cylinder"))
        return quadric_shape(p, shape, type, &xf);
    mts_warn(p, shape, "shape \"%s\" is not supported: left out", type);
    return true;
}
