/* pbrt scene files, the graphics state: the current transform (transform
 * statements, named coordinate systems) and the attribute blocks that save
 * and restore the whole state. Below the shapes and the statement loop,
 * which both open and close blocks. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "pbrt_parser.h"
#include "vecmath.h"

/* ---- transforms --------------------------------------------------------- */

static bool finite_matrix(const SgTransform *m)
{
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            if (!isfinite(m->m[i][j]))
                return false;
    return true;
}

bool pbrt_transform_statement(Parser *p, const Token *t)
{
    SgTransform m;
    sg_transform_identity(&m);
    if (pbrt_token_is(t, "Translate")) {
        double v[3];
        if (!pbrt_need_number(p, t, &v[0]) || !pbrt_need_number(p, t, &v[1]) ||
            !pbrt_need_number(p, t, &v[2]))
            return false;
        for (int a = 0; a < 3; a++)
            m.m[a][3] = v[a];
    } else if (pbrt_token_is(t, "Scale")) {
        double v[3];
        if (!pbrt_need_number(p, t, &v[0]) || !pbrt_need_number(p, t, &v[1]) ||
            !pbrt_need_number(p, t, &v[2]))
            return false;
        for (int a = 0; a < 3; a++)
            m.m[a][a] = v[a];
    } else if (pbrt_token_is(t, "Rotate")) {
        double v[4];
        for (int i = 0; i < 4; i++)
            if (!pbrt_need_number(p, t, &v[i]))
                return false;
        if (!sg_transform_rotation(&m, v[0], v + 1))
            return pbrt_fail_at(p, t, "Rotate: the axis is zero");
    } else if (pbrt_token_is(t, "LookAt")) {
        double v[9];
        for (int i = 0; i < 9; i++)
            if (!pbrt_need_number(p, t, &v[i]))
                return false;
        double pos[3] = {v[0], v[1], v[2]}, dir[3], up[3] = {v[6], v[7], v[8]}, right[3],
               new_up[3];
        d3_sub(v + 3, pos, dir);
        double dl = d3_length(dir), ul = d3_length(up);
        if (!(dl > 0))
            return pbrt_fail_at(p, t, "LookAt: the eye and the target coincide");
        for (int a = 0; a < 3; a++) {
            dir[a] /= dl;
            up[a] = ul > 0 ? up[a] / ul : 0;
        }
        d3_cross(up, dir, right);
        double rl = d3_length(right);
        if (!(rl > 1e-12))
            return pbrt_fail_at(p, t, "LookAt: the up vector is parallel to the view direction");
        for (int a = 0; a < 3; a++)
            right[a] /= rl;
        d3_cross(dir, right, new_up);
        SgTransform world_from_camera;
        sg_transform_identity(&world_from_camera);
        for (int a = 0; a < 3; a++) {
            world_from_camera.m[a][0] = right[a];
            world_from_camera.m[a][1] = new_up[a];
            world_from_camera.m[a][2] = dir[a];
            world_from_camera.m[a][3] = pos[a];
        }
        if (!sg_transform_inverse(&world_from_camera, &m))
            return pbrt_fail_at(p, t, "LookAt: singular view");
    } else { /* Transform, ConcatTransform: 16 numbers, column by column */
        double v[16];
        if (!pbrt_need_bracketed_numbers(p, t, 16, v))
            return false;
        for (int i = 0; i < 4; i++)
            for (int j = 0; j < 4; j++)
                m.m[i][j] = v[4 * j + i];
        if (pbrt_token_is(t, "Transform")) {
            p->state.ctm = m;
            return true;
        }
    }
    if (!finite_matrix(&m))
        return pbrt_fail_at(p, t, "%.*s: non-finite numbers", (int)t->len, t->s);
    sg_transform_multiply(&p->state.ctm, &m, &p->state.ctm);
    return true;
}

static NamedTransform *find_coordinate_system(Parser *p, const Token *name)
{
    for (size_t i = 0; i < p->coordinate_system_count; i++)
        if (pbrt_string_is(name, p->coordinate_systems[i].name))
            return &p->coordinate_systems[i];
    return NULL;
}

bool pbrt_set_coordinate_system(Parser *p, const Token *name, const SgTransform *m)
{
    NamedTransform *n = find_coordinate_system(p, name);
    if (!n) {
        if (!RESERVE(p, p->coordinate_systems, p->coordinate_system_count,
                     p->coordinate_system_capacity, 1))
            return false;
        n = &p->coordinate_systems[p->coordinate_system_count];
        if (!(n->name = pbrt_token_dup(name)))
            return sg_fail(p->err, "%s: out of memory", p->core.path);
        p->coordinate_system_count++;
    }
    n->m = *m;
    return true;
}

bool pbrt_coordinate_system_statement(Parser *p, const Token *t)
{
    Token name;
    if (!pbrt_need_string(p, t, &name))
        return false;
    if (pbrt_token_is(t, "CoordinateSystem"))
        return pbrt_set_coordinate_system(p, &name, &p->state.ctm);
    NamedTransform *n = find_coordinate_system(p, &name);
    if (!n)
        return pbrt_fail_at(p, &name, "CoordSysTransform \"%.*s\": no such coordinate system",
                            (int)name.len, name.s);
    p->state.ctm = n->m;
    return true;
}

/* ---- attribute blocks --------------------------------------------------- */

bool pbrt_push_state(Parser *p, const Token *begin)
{
    if (!RESERVE(p, p->saved, p->saved_count, p->saved_capacity, 1))
        return false;
    p->saved[p->saved_count].state = p->state;
    p->saved[p->saved_count].begin = *begin;
    p->saved_count++;
    return true;
}

bool pbrt_pop_state(Parser *p, const Token *t, bool transform_only)
{
    if (p->saved_count == 0)
        return pbrt_fail_at(p, t, "%.*s without a matching %s", (int)t->len, t->s,
                            transform_only ? "TransformBegin" : "AttributeBegin");
    GraphicsState *s = &p->saved[--p->saved_count].state;
    if (transform_only)
        p->state.ctm = s->ctm;
    else
        p->state = *s;
    return true;
}
