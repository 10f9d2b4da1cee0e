/* pbrt scene files, the loader: camera and film, the statement loop that
 * hands each statement down to the file that reads it, the camera in our
 * terms, and the entry point sg_pbrt_scene_load. The conventions it follows
 * are in pbrt_parser.h. */
#include "pbrt_scene.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "input_file.h"
#include "pbrt_parser.h"
#include "vecmath.h"

/* ---- camera, film and the rest ------------------------------------------ */

static bool camera_statement(Parser *p, const Token *statement)
{
    Token type;
    if (!pbrt_need_string(p, statement, &type) || !pbrt_parse_params(p))
        return false;
    if (p->in_world)
        return pbrt_fail_at(p, statement, "Camera after WorldBegin");
    if (!pbrt_string_is(&type, "perspective"))
        pbrt_warn_at(p, statement, "Camera \"%.*s\" is taken as a perspective camera",
                     (int)type.len, type.s);
    double fov, lens, aspect;
    if (!pbrt_param_float(p, "fov", 90, &fov) || !pbrt_param_float(p, "lensradius", 0, &lens) ||
        !pbrt_param_float(p, "frameaspectratio", 0, &aspect))
        return false;
    if (!(fov > 0 && fov < 180))
        return pbrt_fail_at(p, statement, "Camera: fov %g is not in (0, 180) degrees", fov);
    if (lens > 0)
        pbrt_warn_at(p, statement, "depth of field (lensradius) is ignored: pinhole camera");
    if (pbrt_find_param(p, "screenwindow") || pbrt_find_param(p, "frameaspectratio"))
        pbrt_warn_at(p, statement, "Camera screenwindow/frameaspectratio are ignored");
    p->camera_from_world = p->state.ctm;
    SgTransform world_from_camera;
    if (!sg_transform_inverse(&p->camera_from_world, &world_from_camera))
        return pbrt_fail_at(p, statement, "Camera: the camera transform is singular");
    p->has_camera = true;
    p->fov = fov;
    Token camera_name = {.s = "camera", .len = 6, .quoted = true};
    return pbrt_set_coordinate_system(p, &camera_name, &world_from_camera);
}

static bool film_statement(Parser *p, const Token *statement)
{
    Token type;
    if (!pbrt_need_string(p, statement, &type) || !pbrt_parse_params(p))
        return false;
    double w, h;
    if (!pbrt_param_float(p, "xresolution", 1280, &w) ||
        !pbrt_param_float(p, "yresolution", 720, &h))
        return false;
    if (!(w >= 1 && w <= 65536 && h >= 1 && h <= 65536))
        return pbrt_fail_at(p, statement, "Film resolution %gx%g is out of range", w, h);
    p->film_width = (int)w;
    p->film_height = (int)h;
    if (pbrt_find_param(p, "cropwindow") || pbrt_find_param(p, "pixelbounds"))
        pbrt_warn_at(p, statement, "Film cropwindow/pixelbounds are ignored: the whole image");
    return true;
}

/* A statement with a name and parameters we read but do not use. */
static bool skip_named_statement(Parser *p, const Token *statement)
{
    Token name;
    return pbrt_need_string(p, statement, &name) && pbrt_parse_params(p);
}

static bool include_statement(Parser *p, const Token *statement)
{
    Token name;
    if (!pbrt_need_string(p, statement, &name))
        return false;
    char path[8192];
    if (!pbrt_resolve_path(p, statement, &name, path, sizeof path))
        return false;
    return pbrt_push_file(p, path, statement);
}

/* ---- statements with no file of their own -------------------------------- */

static bool attribute_end_statement(Parser *p, const Token *t) { return pbrt_pop_state(p, t, false); }

static bool transform_end_statement(Parser *p, const Token *t) { return pbrt_pop_state(p, t, true); }

static bool identity_statement(Parser *p, const Token *t)
{
    (void)t;
    sg_transform_identity(&p->state.ctm);
    return true;
}

static bool reverse_orientation_statement(Parser *p, const Token *t)
{
    (void)t;
    p->state.reverse_orientation = !p->state.reverse_orientation;
    return true;
}

static bool world_begin_statement(Parser *p, const Token *t)
{
    if (p->in_world)
        return pbrt_fail_at(p, t, "WorldBegin twice");
    p->in_world = true;
    sg_transform_identity(&p->state.ctm);
    Token world = {.s = "world", .len = 5, .quoted = true};
    return pbrt_set_coordinate_system(p, &world, &p->state.ctm);
}

/* pbrt-v3's WorldEnd: nothing to do */
static bool world_end_statement(Parser *p, const Token *t)
{
    (void)p, (void)t;
    return true;
}

/* Sampler and Integrator: of theirs, only the samples per pixel and the
 * path depth */
static bool sampler_integrator_statement(Parser *p, const Token *t)
{
    Token name;
    if (!pbrt_need_string(p, t, &name) || !pbrt_parse_params(p))
        return false;
    double v;
    if (pbrt_token_is(t, "Sampler") && pbrt_find_param(p, "pixelsamples")) {
        if (!pbrt_param_float(p, "pixelsamples", 16, &v))
            return false;
        if (v >= 1 && v <= (1 << 24))
            p->core.scene->render.spp = (int)v;
    }
    /* pbrt-v4's maxdepth counts bounces after the camera ray (0: only
     * what the camera sees); ours counts segments, one more */
    if (pbrt_token_is(t, "Integrator")) {
        if (!pbrt_param_float(p, "maxdepth", 5, &v))
            return false;
        if (v >= 0 && v <= 1024)
            p->core.scene->render.max_depth = (int)v + 1;
    }
    return true;
}

static bool color_space_statement(Parser *p, const Token *t)
{
    Token name;
    if (!pbrt_need_string(p, t, &name))
        return false;
    if (!pbrt_string_is(&name, "srgb"))
        pbrt_warn_at(p, t, "ColorSpace \"%.*s\" is ignored: colours are taken as sRGB", (int)name.len, name.s);
    return true;
}

static bool option_statement(Parser *p, const Token *t)
{
    Token name, value;
    return pbrt_need_string(p, t, &name) && pbrt_need_token(p, t, &value);
}

/* A statement read past, with a warning that it is left out. */
static bool skip_with_warning(Parser *p, const Token *t, const char *warning)
{
    if (!skip_named_statement(p, t))
        return false;
    pbrt_warn_at(p, t, "%s", warning);
    return true;
}

static bool attribute_statement(Parser *p, const Token *t)
{
    return skip_with_warning(p, t, "Attribute statements are ignored");
}

static bool active_transform_statement(Parser *p, const Token *t)
{
    Token which;
    if (!pbrt_need_token(p, t, &which))
        return false;
    if (!pbrt_token_is(&which, "All") && !pbrt_token_is(&which, "StartTime") && !pbrt_token_is(&which, "EndTime"))
        return pbrt_fail_at(p, &which, "ActiveTransform takes All, StartTime or EndTime");
    pbrt_warn_at(p, t, "motion (ActiveTransform) is ignored: every transform applies");
    return true;
}

static bool transform_times_statement(Parser *p, const Token *t)
{
    double a, b;
    return pbrt_need_number(p, t, &a) && pbrt_need_number(p, t, &b);
}

/* Every statement's keyword and what reads it. */
static const struct {
    const char *keyword;
    bool (*read)(Parser *p, const Token *t);
} statements[] = {
    {"AttributeBegin", pbrt_push_state},
    {"TransformBegin", pbrt_push_state},
    {"AttributeEnd", attribute_end_statement},
    {"TransformEnd", transform_end_statement},
    {"Translate", pbrt_transform_statement},
    {"Scale", pbrt_transform_statement},
    {"Rotate", pbrt_transform_statement},
    {"LookAt", pbrt_transform_statement},
    {"Transform", pbrt_transform_statement},
    {"ConcatTransform", pbrt_transform_statement},
    {"Identity", identity_statement},
    {"CoordinateSystem", pbrt_coordinate_system_statement},
    {"CoordSysTransform", pbrt_coordinate_system_statement},
    {"ReverseOrientation", reverse_orientation_statement},
    {"WorldBegin", world_begin_statement},
    {"WorldEnd", world_end_statement},
    {"Camera", camera_statement},
    {"Film", film_statement},
    {"Sampler", sampler_integrator_statement},
    {"Integrator", sampler_integrator_statement},
    {"PixelFilter", skip_named_statement},
    {"Accelerator", skip_named_statement},
    {"ColorSpace", color_space_statement},
    {"Option", option_statement},
    {"Shape", pbrt_shape_statement},
    {"Material", pbrt_material_statement},
    {"MakeNamedMaterial", pbrt_make_named_material_statement},
    {"NamedMaterial", pbrt_named_material_statement},
    {"Texture", pbrt_texture_statement},
    {"AreaLightSource", pbrt_area_light_statement},
    {"LightSource", pbrt_light_source_statement},
    {"MakeNamedMedium", pbrt_make_named_medium_statement},
    {"MediumInterface", pbrt_medium_interface_statement},
    {"Attribute", attribute_statement},
    {"ActiveTransform", active_transform_statement},
    {"TransformTimes", transform_times_statement},
    {"ObjectBegin", pbrt_object_begin},
    {"ObjectEnd", pbrt_object_end},
    {"ObjectInstance", pbrt_object_instance},
    {"Include", include_statement},
    {"Import", include_statement},
};

static bool statement(Parser *p, const Token *t)
{
    if (t->quoted)
        return pbrt_fail_at(p, t, "expected a statement, found the string \"%.*s\"",
                            (int)(t->len > 40 ? 40 : t->len), t->s);
    if (pbrt_token_is(t, "[") || pbrt_token_is(t, "]"))
        return pbrt_fail_at(p, t, "'%c' outside a parameter list", t->s[0]);
    for (size_t i = 0; i < sizeof statements / sizeof statements[0]; i++)
        if (pbrt_token_is(t, statements[i].keyword))
            return statements[i].read(p, t);
    return pbrt_fail_at(p, t, "unknown statement \"%.*s\"", (int)(t->len > 40 ? 40 : t->len), t->s);
}

/* ---- the camera in our terms -------------------------------------------- */

static bool finish_camera(Parser *p)
{
    SgScene *s = p->core.scene;
    s->camera.width = p->film_width;
    s->camera.height = p->film_height;
    SgTransform w;
    if (!p->has_camera) { /* pbrt's default: at the origin looking down +z */
        sg_transform_identity(&p->camera_from_world);
        p->fov = 90;
    }
    if (!sg_transform_inverse(&p->camera_from_world, &w))
        return sg_fail(p->err, "%s: the camera transform is singular", p->core.path);
    double pos[4], dir[3], up[3], right[3];
    for (int r = 0; r < 4; r++)
        pos[r] = w.m[r][3];
    if (!(fabs(pos[3]) > 1e-300))
        return sg_fail(p->err, "%s: the camera transform is projective", p->core.path);
    for (int a = 0; a < 3; a++) {
        pos[a] /= pos[3];
        right[a] = w.m[a][0];
        up[a] = w.m[a][1];
        dir[a] = w.m[a][2];
    }
    double dl = d3_length(dir), ul = d3_length(up);
    if (!(dl > 0 && ul > 0))
        return sg_fail(p->err, "%s: the camera transform is degenerate", p->core.path);
    for (int a = 0; a < 3; a++) {
        s->camera.position[a] = pos[a];
        s->camera.look_at[a] = pos[a] + dir[a] / dl;
        s->camera.up[a] = up[a] / ul;
    }
    /* Our image's right is view x up; pbrt's is camera +x. */
    double ours[3];
    d3_cross(dir, up, ours);
    if (d3_dot(ours, right) < 0) {
        Token none = {0};
        pbrt_warn_at(p, &none, "the camera transform does not mirror the image as pbrt's screen "
                          "mapping expects (no \"Scale -1 1 1\"): our image is pbrt's mirrored "
                          "left to right");
    }
    /* pbrt's fov spans the shorter image axis; ours is vertical. */
    double aspect = (double)s->camera.width / s->camera.height;
    double fov = p->fov;
    if (aspect < 1)
        fov = 2 * atan(tan(fov * M_PI / 360) / aspect) * 180 / M_PI;
    s->camera.fov_deg = fov;
    s->has_camera = true;
    return true;
}

/* ---- entry point -------------------------------------------------------- */

static void parser_release(Parser *p)
{
    for (size_t i = 0; i < p->source_count; i++) {
        free(p->sources[i]->text);
        free(p->sources[i]);
    }
    free(p->sources);
    free(p->params);
    free(p->numbers);
    free(p->strings);
    free(p->bools);
    free(p->saved);
    for (size_t i = 0; i < p->material_count; i++)
        free(p->materials[i].name);
    free(p->materials);
    free(p->variants);
    for (size_t i = 0; i < p->medium_count; i++)
        free(p->media[i].name);
    free(p->media);
    for (size_t i = 0; i < p->texture_count; i++)
        free(p->textures[i].name);
    free(p->textures);
    for (size_t i = 0; i < p->coordinate_system_count; i++)
        free(p->coordinate_systems[i].name);
    free(p->coordinate_systems);
    for (size_t i = 0; i < p->object_count; i++) {
        sg_shape_group_release(&p->objects[i].shapes);
        free(p->objects[i].name);
    }
    free(p->objects);
    sg_builder_release(&p->core);
}

SgScene *sg_pbrt_scene_load(const char *path, SgError *err)
{
    Parser p;
    memset(&p, 0, sizeof p);
    p.err = err;
    if (!sg_builder_begin(&p.core, path, err))
        return NULL;
    SgScene *s = p.core.scene;
    sg_folder_of(path, p.base_dir, sizeof p.base_dir);
    p.film_width = 1280; /* pbrt's defaults */
    p.film_height = 720;
    s->render.max_depth = 5 + 1; /* pbrt's default maxdepth, 5 bounces */
    sg_transform_identity(&p.state.ctm);
    PbrtMaterial fallback; /* pbrt's default: diffuse 0.5 */
    memset(&fallback, 0, sizeof fallback);
    sg_material_default(&fallback.material, "default");
    fallback.scene_id = UINT32_MAX;
    bool ok = pbrt_add_material(&p, &fallback, &p.state.material) && pbrt_push_file(&p, path, NULL);
    Token t;
    while (ok && pbrt_next_token(&p, &t))
        ok = statement(&p, &t);
    ok = ok && !err->failed;
    if (ok && p.defining)
        ok = pbrt_fail_at(&p, &p.defining_begin, "ObjectBegin has no matching ObjectEnd");
    if (ok && p.saved_count) {
        const Token *begin = &p.saved[p.saved_count - 1].begin;
        ok = pbrt_fail_at(&p, begin, "%.*s has no matching %s", (int)begin->len, begin->s,
                          pbrt_token_is(begin, "TransformBegin") ? "TransformEnd" : "AttributeEnd");
    }
    for (size_t i = 0; ok && i < p.material_count; i++)
        if (p.materials[i].pending)
            ok = pbrt_fail_at(&p, &p.materials[i].first_use,
                              "NamedMaterial \"%s\" is never defined", p.materials[i].name);
    ok = ok && finish_camera(&p);
    if (ok && s->triangle_count == 0)
        ok = sg_fail(err, "%s: the scene has no triangles%s", path,
                     p.core.dropped_degenerate ? " (all were degenerate)" : "");
    ok = ok && sg_builder_finish(&p.core, err);
    parser_release(&p);
    if (!ok) {
        sg_scene_free(s);
        return NULL;
    }
    return s;
}
