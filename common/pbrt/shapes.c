/* pbrt scene files, shapes: meshes (plymesh, inline triangle and bilinear
 * meshes) placed with the current state, and object instancing. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "pbrt_parser.h"
#include "ply_mesh.h"
#include "quadric_mesh.h"
#include "vecmath.h"

/* ---- shapes ------------------------------------------------------------- */

/* The CTM as an affine transform for shapes. */
static bool shape_transform(Parser *p, const Token *at, SgTransform *xf)
{
    const double(*m)[4] = p->state.ctm.m;
    double w = m[3][3];
    if (fabs(m[3][0]) > 1e-12 || fabs(m[3][1]) > 1e-12 || fabs(m[3][2]) > 1e-12 ||
        !(fabs(w) > 1e-300))
        return pbrt_fail_at(p, at,
                            "the current transform is projective: shapes need an affine one");
    sg_transform_identity(xf);
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 4; c++)
            xf->m[r][c] = m[r][c] / w;
    return true;
}

/* Appends a mesh (object-space positions) with the current state. normals
 * (object space, per vertex) decide which side emits, as in pbrt; without
 * them the winding does, flipped by ReverseOrientation and by a mirroring
 * transform. */
static bool emit_mesh(Parser *p, const Token *at, const char *what, const double *positions,
                      uint32_t vertex_count, uint32_t *indices, uint32_t triangle_count,
                      const double *normals, const float *uvs)
{
    if (p->materials[p->state.material].invisible) {
        pbrt_warn_at(p, at, "shapes with the \"interface\" material are left out (a medium is "
                       "taken only inside a dielectric)");
        return true;
    }
    SgTransform xf;
    if (!shape_transform(p, at, &xf))
        return false;
    bool emissive = p->state.area_light;
    if (emissive && p->defining) {
        pbrt_warn_at(p, at, "area lights inside ObjectBegin are ignored (as pbrt does)");
        emissive = false;
    }
    uint32_t material;
    if (!pbrt_current_scene_material(p, emissive, &material))
        return false;
    if (emissive) {
        double det = sg_transform_determinant(&xf);
        bool flip_all = p->state.reverse_orientation != (det < 0);
        for (uint32_t t = 0; t < triangle_count; t++) {
            uint32_t *idx = indices + 3 * (size_t)t;
            bool flip = flip_all;
            if (normals) {
                double wp[3][3], e1[3], e2[3], n[3], ns[3] = {0, 0, 0}, nw[3];
                for (int c = 0; c < 3; c++) {
                    sg_transform_point(&xf, positions + 3 * (size_t)idx[c], wp[c]);
                    for (int a = 0; a < 3; a++)
                        ns[a] += normals[3 * (size_t)idx[c] + a];
                }
                d3_sub(wp[1], wp[0], e1);
                d3_sub(wp[2], wp[0], e2);
                d3_cross(e1, e2, n);
                sg_transform_normal(&xf, ns, nw);
                if (d3_length(nw) > 0) /* else: the winding decides */
                    flip = d3_dot(n, nw) < 0;
            }
            if (flip) {
                uint32_t k = idx[1];
                idx[1] = idx[2];
                idx[2] = k;
            }
        }
    }
    if (p->defining) {
        for (uint32_t v = 0; v < vertex_count; v++)
            if (!sg_builder_check_point(&p->core, what, positions + 3 * (size_t)v, p->err))
                return false;
        return sg_shape_group_add(&p->defining->shapes, p->core.path, positions, vertex_count, indices,
                                  triangle_count, uvs, &xf, material, p->err);
    }
    uint32_t first = p->core.scene->vertex_count;
    return sg_builder_append_mesh(&p->core, what, positions, vertex_count, indices,
                                  triangle_count, &xf, material, p->err) &&
           (!uvs || sg_builder_set_uvs(&p->core, first, vertex_count, uvs, p->err));
}


static bool plymesh(Parser *p, const Token *statement)
{
    const Token *file = pbrt_param_string(p, "filename");
    if (!file)
        return pbrt_fail_at(p, statement, "Shape \"plymesh\" has no \"string filename\"");
    char path[8192];
    if (!pbrt_resolve_path(p, statement, file, path, sizeof path))
        return false;
    if (pbrt_find_param(p, "displacement"))
        pbrt_warn_at(p, statement, "plymesh displacement is ignored");
    SgPlyMesh mesh;
    SgError local = {0};
    if (!sg_ply_mesh_read(&mesh, path, &local))
        return pbrt_fail_at(p, statement, "%s", local.message);
    bool ok = emit_mesh(p, statement, path, mesh.positions, mesh.vertex_count, mesh.indices,
                        mesh.triangle_count, mesh.normals, mesh.uvs);
    sg_ply_mesh_release(&mesh);
    return ok;
}

/* trianglemesh, bilinearmesh and loopsubdiv (its control mesh). */
static bool inline_mesh(Parser *p, const Token *statement, const Token *type)
{
    const Param *P = pbrt_find_param(p, "P");
    if (!P || P->kind != PARAM_NUMBERS || P->count == 0 || P->count % 3)
        return pbrt_fail_at(p, statement, "Shape \"%.*s\" needs \"point3 P\" (x y z ...)",
                            (int)type->len, type->s);
    if (strcmp(P->type, "point3"))
        return pbrt_fail_at(p, statement, "\"P\" must be \"point3\", not \"%s\"", P->type);
    size_t vertex_count = P->count / 3;
    if (vertex_count > UINT32_MAX / 4)
        return pbrt_fail_at(p, statement, "too many vertices");
    const Param *I = pbrt_find_param(p, "indices");
    bool bilinear = pbrt_string_is(type, "bilinearmesh");
    size_t per_face = bilinear ? 4 : 3;
    size_t index_count;
    if (I) {
        if (I->kind != PARAM_NUMBERS || strcmp(I->type, "integer"))
            return pbrt_fail_at(p, statement, "\"indices\" must be \"integer\"");
        index_count = I->count;
    } else if (vertex_count == per_face) {
        index_count = per_face;
    } else {
        return pbrt_fail_at(p, statement, "Shape \"%.*s\" needs \"integer indices\"",
                            (int)type->len, type->s);
    }
    if (index_count == 0 || index_count % per_face)
        return pbrt_fail_at(p, statement, "\"indices\" must hold a multiple of %zu values",
                            per_face);
    if (pbrt_string_is(type, "loopsubdiv"))
        pbrt_warn_at(p, statement, "loopsubdiv shapes are used without subdivision (control mesh)");
    size_t faces = index_count / per_face;
    size_t triangle_count = bilinear ? 2 * faces : faces;
    uint32_t *indices = malloc(triangle_count * 3 * sizeof(uint32_t));
    double *normals = NULL;
    if (!indices)
        return sg_fail(p->err, "%s: out of memory", p->core.path);
    uint32_t corner[4];
    size_t t = 0;
    for (size_t f = 0; f < faces; f++) {
        for (size_t c = 0; c < per_face; c++) {
            double v = I ? p->numbers[I->first + f * per_face + c] : (double)c;
            if (!(v >= 0 && v < (double)vertex_count)) {
                free(indices);
                return pbrt_fail_at(p, statement, "index %g is out of range (%zu vertices)", v,
                                    vertex_count);
            }
            corner[c] = (uint32_t)v;
        }
        if (bilinear) { /* p00 p10 p01 p11 */
            uint32_t tri[6] = {corner[0], corner[1], corner[3], corner[0], corner[3], corner[2]};
            memcpy(indices + 3 * t, tri, sizeof tri);
            t += 2;
        } else {
            memcpy(indices + 3 * t, corner, 3 * sizeof(uint32_t));
            t++;
        }
    }
    const Param *N = pbrt_find_param(p, "N");
    if (N && N->kind == PARAM_NUMBERS && N->count == P->count && !bilinear)
        normals = p->numbers + N->first;
    char what[4300];
    snprintf(what, sizeof what, "%s:%d", statement->source->path, statement->line);
    /* texture coordinates: pbrt-v4's "point2 uv" (pbrt-v3 also wrote "float uv" or "st") */
    const Param *UV = pbrt_find_param(p, "uv");
    if (!UV)
        UV = pbrt_find_param(p, "st");
    float *uvs = NULL;
    if (UV && UV->kind == PARAM_NUMBERS && UV->count == 2 * vertex_count) {
        if (!(uvs = malloc(2 * vertex_count * sizeof(float)))) {
            free(indices);
            return sg_fail(p->err, "%s: out of memory", p->core.path);
        }
        for (size_t i = 0; i < 2 * vertex_count; i++)
            uvs[i] = (float)p->numbers[UV->first + i];
    } else if (UV) {
        pbrt_warn_at(p, statement, "texture coordinates that are not 2 numbers per vertex are ignored");
    }
    bool ok = emit_mesh(p, statement, what, p->numbers + P->first, (uint32_t)vertex_count,
                        indices, (uint32_t)triangle_count, normals, uvs);
    free(uvs);
    free(indices);
    return ok;
}

/* disk, sphere and cylinder with pbrt-v4's parameters and defaults, as
 * meshes of their true area (quadric_mesh.h). */
static bool quadric(Parser *p, const Token *statement, const Token *type)
{
    double radius, phi_max;
    if (!pbrt_param_float(p, "radius", 1, &radius) || !pbrt_param_float(p, "phimax", 360, &phi_max))
        return false;
    if (!(radius > 0 && isfinite(radius)))
        return pbrt_fail_at(p, statement, "Shape \"%.*s\": \"radius\" must be positive", (int)type->len, type->s);
    if (!(phi_max > 0 && phi_max <= 360))
        return pbrt_fail_at(p, statement, "Shape \"%.*s\": \"phimax\" must be in (0, 360]", (int)type->len,
                            type->s);
    phi_max *= M_PI / 180;
    SgQuadricMesh mesh;
    bool made;
    if (pbrt_string_is(type, "disk")) {
        double height, inner;
        if (!pbrt_param_float(p, "height", 0, &height) || !pbrt_param_float(p, "innerradius", 0, &inner))
            return false;
        if (!(inner >= 0 && inner < radius && isfinite(height)))
            return pbrt_fail_at(p, statement, "Shape \"disk\": want 0 <= \"innerradius\" < \"radius\"");
        made = sg_quadric_disk(radius, inner, height, phi_max, &mesh, p->err);
    } else {
        bool sphere = pbrt_string_is(type, "sphere");
        double z_min, z_max;
        if (!pbrt_param_float(p, "zmin", sphere ? -radius : -1, &z_min) ||
            !pbrt_param_float(p, "zmax", sphere ? radius : 1, &z_max))
            return false;
        if (!(isfinite(z_min) && isfinite(z_max) && z_min != z_max) ||
            (sphere && !(fmin(z_min, z_max) < radius && fmax(z_min, z_max) > -radius)))
            return pbrt_fail_at(p, statement, "Shape \"%.*s\": \"zmin\" and \"zmax\" leave nothing",
                                (int)type->len, type->s);
        made = sphere ? sg_quadric_sphere(radius, z_min, z_max, phi_max, &mesh, p->err)
                      : sg_quadric_cylinder(radius, z_min, z_max, phi_max, &mesh, p->err);
    }
    if (!made)
        return false;
    char what[4300];
    snprintf(what, sizeof what, "%s:%d", statement->source->path, statement->line);
    bool ok = emit_mesh(p, statement, what, mesh.positions, mesh.vertex_count, mesh.indices, mesh.triangle_count,
                        NULL, mesh.uvs);
    sg_quadric_mesh_free(&mesh);
    return ok;
}

/* What the shape adds to its material (ShapeAttributes): pbrt-v4's
 * "alpha", a constant or a float texture (a cut-out where below 0.5), and
 * the absorption of its MediumInterface's inside (dielectrics only). */
static bool shape_attributes(Parser *p)
{
    memset(&p->shape, 0, sizeof p->shape);
    double alpha;
    if (!pbrt_param_scalar(p, "alpha", 1, &alpha))
        return false;
    uint32_t texture = pbrt_param_texture(p, "alpha");
    if (texture || alpha < 1) {
        p->shape.cutout = true;
        p->shape.alpha = texture ? 1.0f : (float)fmax(alpha, 0);
        p->shape.alpha_texture = texture;
    }
    memcpy(p->shape.sigma_a, p->state.inside_sigma_a, sizeof p->shape.sigma_a);
    return true;
}

bool pbrt_shape_statement(Parser *p, const Token *statement)
{
    Token type;
    if (!pbrt_need_string(p, statement, &type) || !pbrt_parse_params(p) || !shape_attributes(p))
        return false;
    if (!p->in_world)
        pbrt_warn_at(p, statement, "shapes before WorldBegin are used as if after it");
    if (pbrt_string_is(&type, "plymesh")) {
        return plymesh(p, statement);
    }
    if (pbrt_string_is(&type, "trianglemesh") || pbrt_string_is(&type, "bilinearmesh") ||
        pbrt_string_is(&type, "loopsubdiv"))
        return inline_mesh(p, statement, &type);
    if (pbrt_string_is(&type, "disk") || pbrt_string_is(&type, "sphere") || pbrt_string_is(&type, "cylinder"))
        return quadric(p, statement, &type);
    pbrt_warn_at(p, statement, "Shape \"%.*s\" is not supported: left out", (int)type.len, type.s);
    return true;
}

/* ---- object instancing -------------------------------------------------- */

static Object *find_object(Parser *p, const Token *name)
{
    for (size_t i = 0; i < p->object_count; i++)
        if (pbrt_string_is(name, p->objects[i].name))
            return &p->objects[i];
    return NULL;
}

/* The object a statement names (ObjectBegin, ObjectInstance), which may
 * not stand inside an object's definition. */
static bool object_statement_name(Parser *p, const Token *statement, Token *name)
{
    if (!pbrt_need_string(p, statement, name))
        return false;
    if (p->defining)
        return pbrt_fail_at(p, statement, "%.*s inside ObjectBegin (line %d)", (int)statement->len, statement->s,
                            p->defining_begin.line);
    return true;
}

bool pbrt_object_begin(Parser *p, const Token *statement)
{
    Token name;
    if (!object_statement_name(p, statement, &name))
        return false;
    if (find_object(p, &name))
        return pbrt_fail_at(p, &name, "object \"%.*s\" is defined twice", (int)name.len, name.s);
    if (!pbrt_push_state(p, statement) ||
        !RESERVE(p, p->objects, p->object_count, p->object_capacity, 1))
        return false;
    Object *o = &p->objects[p->object_count];
    memset(o, 0, sizeof *o);
    if (!(o->name = pbrt_token_dup(&name)))
        return sg_fail(p->err, "%s: out of memory", p->core.path);
    p->object_count++;
    p->defining = o;
    p->defining_begin = *statement;
    return true;
}

bool pbrt_object_end(Parser *p, const Token *statement)
{
    if (!p->defining)
        return pbrt_fail_at(p, statement, "ObjectEnd without ObjectBegin");
    p->defining = NULL;
    return pbrt_pop_state(p, statement, false);
}

bool pbrt_object_instance(Parser *p, const Token *statement)
{
    Token name;
    if (!object_statement_name(p, statement, &name))
        return false;
    Object *o = find_object(p, &name);
    if (!o)
        return pbrt_fail_at(p, &name, "ObjectInstance \"%.*s\": no such object", (int)name.len,
                            name.s);
    SgTransform xf;
    if (!shape_transform(p, statement, &xf))
        return false;
    return sg_builder_add_group(&p->core, o->name, &o->shapes, &xf, p->err);
}
