/* pbrt scene files, LightSource: point, spot, distant and infinite lights
 * with pbrt-v4's parameters ("I"/"L", "scale", "power", "illuminance",
 * "from"/"to", "coneangle"/"conedeltaangle", "filename", "portal"), placed
 * by the current transform ("portal" excepted: its points are in world
 * space, as pbrt-v4 reads them). An RGB colour counts as pbrt-v4 counts it: its
 * values are the radiance (or intensity) before "scale" and "power". */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "pbrt_parser.h"
#include "vecmath.h"

static void ctm_vector(const Parser *p, const double v[3], double out[3])
{
    const double(*m)[4] = p->state.ctm.m;
    for (int r = 0; r < 3; r++)
        out[r] = m[r][0] * v[0] + m[r][1] * v[1] + m[r][2] * v[2];
}

/* A 3-number parameter (point3, vector3, ...), or the fallback. */
static bool param_triple(Parser *p, const Token *statement, const char *name, const double fallback[3],
                         double out[3])
{
    const Param *param = pbrt_find_param(p, name);
    memcpy(out, fallback, 3 * sizeof(double));
    if (!param)
        return true;
    if (param->kind != PARAM_NUMBERS || param->count != 3)
        return pbrt_fail_at(p, statement, "LightSource: \"%s\" must be 3 numbers", name);
    for (int a = 0; a < 3; a++)
        if (!isfinite(out[a] = p->numbers[param->first + a]))
            return pbrt_fail_at(p, statement, "LightSource: \"%s\" is not finite", name);
    return true;
}

/* "from" and "to" through the current transform: the position and the
 * unit direction the light travels. */
static bool from_to(Parser *p, const Token *statement, double position[3], double direction[3])
{
    double from[3], to[3], d[3];
    if (!param_triple(p, statement, "from", (const double[3]){0, 0, 0}, from) ||
        !param_triple(p, statement, "to", (const double[3]){0, 0, 1}, to))
        return false;
    sg_transform_point(&p->state.ctm, from, position);
    d3_sub(to, from, d);
    ctm_vector(p, d, direction);
    double len = d3_length(direction);
    if (!(len > 0 && isfinite(len)))
        return pbrt_fail_at(p, statement, "LightSource: \"from\" and \"to\" must differ");
    for (int a = 0; a < 3; a++)
        direction[a] /= len;
    return true;
}

/* The colour `name` times "scale" (and a positive `per_unit` factor). */
static bool light_colour(Parser *p, const Token *statement, const char *name, float rgb[3], double *scale)
{
    if (!pbrt_param_color(p, name, (const float[3]){1, 1, 1}, rgb, NULL) || !pbrt_param_float(p, "scale", 1, scale))
        return false;
    if (!(*scale >= 0 && isfinite(*scale)))
        return pbrt_fail_at(p, statement, "LightSource: \"scale\" must be finite and not negative");
    for (int c = 0; c < 3; c++)
        if (!(rgb[c] >= 0 && isfinite(rgb[c])))
            return pbrt_fail_at(p, statement, "LightSource: \"%s\" must be finite and not negative", name);
    return true;
}

static bool positive_or_absent(Parser *p, const Token *statement, const char *name, double *value)
{
    if (!pbrt_param_float(p, name, -1, value))
        return false;
    if (pbrt_find_param(p, name) && !(*value > 0 && isfinite(*value)))
        return pbrt_fail_at(p, statement, "LightSource: \"%s\" must be positive", name);
    return true;
}

static void scale_rgb(float rgb[3], double k)
{
    for (int c = 0; c < 3; c++)
        rgb[c] = (float)(rgb[c] * k);
}

static bool infinite_light(Parser *p, const Token *statement, SgLightSource *l, char *path, size_t path_size)
{
    double scale, illuminance;
    if (!light_colour(p, statement, "L", l->rgb, &scale) ||
        !positive_or_absent(p, statement, "illuminance", &illuminance))
        return false;
    const Token *file = pbrt_param_string(p, "filename");
    if (file && pbrt_find_param(p, "L"))
        return pbrt_fail_at(p, statement, "LightSource \"infinite\": give \"L\" or \"filename\", not both");
    if (file) {
        if (!pbrt_resolve_path(p, statement, file, path, path_size))
            return false;
        l->image_path = path; /* copied by sg_builder_add_light_source */
        l->rgb[0] = l->rgb[1] = l->rgb[2] = 1.0f;
    }
    scale_rgb(l->rgb, scale);
    /* the illuminance of an upward plane: pi L for a constant sky; for an
     * image the renderer knows it once it has read it */
    l->illuminance = illuminance > 0 ? illuminance : 0.0;
    if (illuminance > 0 && !file)
        scale_rgb(l->rgb, illuminance / M_PI);
    /* light space is the current transform's rotation */
    for (int c = 0; c < 3; c++) {
        double axis[3] = {c == 0, c == 1, c == 2}, w[3];
        ctm_vector(p, axis, w);
        double len = d3_length(w);
        if (!(len > 0))
            return pbrt_fail_at(p, statement, "LightSource \"infinite\": the current transform is singular");
        for (int r = 0; r < 3; r++)
            l->light_to_world[r][c] = w[r] / len;
    }
    const Param *portal = pbrt_find_param(p, "portal");
    if (portal) {
        if (portal->kind != PARAM_NUMBERS || portal->count != 12)
            return pbrt_fail_at(p, statement, "LightSource \"infinite\": \"portal\" must be 4 points");
        for (int k = 0; k < 4; k++) {
            double q[3];
            for (int a = 0; a < 3; a++)
                q[a] = p->numbers[portal->first + 3 * k + a];
            if (!(isfinite(q[0]) && isfinite(q[1]) && isfinite(q[2])))
                return pbrt_fail_at(p, statement, "LightSource \"infinite\": \"portal\" is not finite");
            /* in world space, whatever the current transform: pbrt-v4
             * takes the points through its camera transform alone (its
             * lights.cpp, RenderFromWorld), not the light's */
            memcpy(l->portal[k], q, sizeof q);
        }
        l->has_portal = true;
    }
    return true;
}

bool pbrt_light_source_statement(Parser *p, const Token *statement)
{
    Token type;
    if (!pbrt_need_string(p, statement, &type) || !pbrt_parse_params(p))
        return false;
    SgLightSource l;
    memset(&l, 0, sizeof l);
    char image_path[4096];
    double scale, power;
    if (pbrt_string_is(&type, "point") || pbrt_string_is(&type, "spot")) {
        bool spot = pbrt_string_is(&type, "spot");
        l.kind = spot ? SG_LIGHT_SPOT : SG_LIGHT_POINT;
        if (!light_colour(p, statement, "I", l.rgb, &scale) || !positive_or_absent(p, statement, "power", &power) ||
            !from_to(p, statement, l.position, l.direction))
            return false;
        double k = 4.0 * M_PI; /* what intensity 1 sends in all */
        if (spot) {
            double cone, delta;
            if (!pbrt_param_float(p, "coneangle", 30, &cone) || !pbrt_param_float(p, "conedeltaangle", 5, &delta))
                return false;
            if (!(cone > 0 && cone <= 180 && delta >= 0 && delta <= cone))
                return pbrt_fail_at(p, statement, "LightSource \"spot\": want 0 < coneangle <= 180 and "
                                                  "0 <= conedeltaangle <= coneangle");
            l.cos_cone = cos(cone * M_PI / 180);
            l.cos_falloff_start = cos((cone - delta) * M_PI / 180);
            k = 2.0 * M_PI * ((1.0 - l.cos_falloff_start) + (l.cos_falloff_start - l.cos_cone) / 2.0);
        }
        scale_rgb(l.rgb, power > 0 ? scale * power / k : scale);
    } else if (pbrt_string_is(&type, "distant")) {
        double illuminance;
        l.kind = SG_LIGHT_DISTANT;
        if (!light_colour(p, statement, "L", l.rgb, &scale) ||
            !positive_or_absent(p, statement, "illuminance", &illuminance) ||
            !from_to(p, statement, l.position, l.direction))
            return false;
        scale_rgb(l.rgb, illuminance > 0 ? scale * illuminance : scale);
    } else if (pbrt_string_is(&type, "infinite")) {
        l.kind = SG_LIGHT_INFINITE;
        if (!infinite_light(p, statement, &l, image_path, sizeof image_path))
            return false;
    } else {
        pbrt_warn_at(p, statement, "LightSource \"%.*s\" is not supported: left out", (int)type.len, type.s);
        return true;
    }
    if (p->defining) {
        pbrt_warn_at(p, statement, "lights inside ObjectBegin are ignored (as pbrt does)");
        return true;
    }
    return sg_builder_add_light_source(&p->core, &l, p->err);
}
