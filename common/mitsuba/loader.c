/* Mitsuba scene files, the loader: the scene element and what stands in
 * it (default, include, path, bsdf, texture, shape, emitter, sensor,
 * integrator), the emitters that are not shapes, the sensor in our camera
 * terms, and the entry point sg_mitsuba_scene_load. */
#include "mitsuba_scene.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "input_file.h"
#include "mitsuba_parser.h"
#include "sunsky.h"
#include "vecmath.h"

/* Mitsuba's max_depth counts the segments of a path from the camera (1:
 * the emitters it sees, 2: direct light), as ours does: the same number.
 * Its -1 (unbounded, the default) becomes our longest, where Russian
 * roulette ends paths first. */
#define MTS_UNBOUNDED_DEPTH 1024

/* ---- emitters that are not shapes --------------------------------------- */

static void linear_column(const SgTransform *m, int c, double out[3])
{
    for (int r = 0; r < 3; r++)
        out[r] = m->m[r][c];
}

static bool unit(MtsParser *p, const XmlNode *at, double v[3], const char *what)
{
    double len = d3_length(v);
    if (!(len > 0 && isfinite(len)))
        return mts_fail(p, at, "%s is zero or not finite", what);
    for (int a = 0; a < 3; a++)
        v[a] /= len;
    return true;
}

static bool check_rgb(MtsParser *p, const XmlNode *at, const float rgb[3], const char *what)
{
    for (int c = 0; c < 3; c++)
        if (!(rgb[c] >= 0 && isfinite(rgb[c])))
            return mts_fail(p, at, "%s must be finite and not negative", what);
    return true;
}

/* Mitsuba's envmap maps (u, v) to (sin v pi sin 2 pi u, cos v pi,
 * -sin v pi cos 2 pi u) in its local frame (y up); our lat-long layout to
 * (sin theta cos phi, sin theta sin phi, cos theta) (z up). The columns
 * below are where our axes land in Mitsuba's frame. */
static const double OURS_TO_MITSUBA[3][3] = {{0, 1, 0}, {0, 0, 1}, {-1, 0, 0}};

/* An environment's frame: the rotation of to_world (*world_from_mitsuba)
 * and, from it, the light's light_to_world. */
static bool environment_frame(MtsParser *p, const XmlNode *e, const SgTransform *to_world,
                              double world_from_mitsuba[3][3], SgLightSource *l)
{
    for (int c = 0; c < 3; c++) {
        double col[3];
        linear_column(to_world, c, col);
        if (!unit(p, e, col, "emitter to_world axis"))
            return false;
        for (int r = 0; r < 3; r++)
            world_from_mitsuba[r][c] = col[r];
    }
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) {
            double s = 0;
            for (int k = 0; k < 3; k++)
                s += world_from_mitsuba[r][k] * OURS_TO_MITSUBA[k][c];
            l->light_to_world[r][c] = s;
        }
    return true;
}

static bool envmap(MtsParser *p, const XmlNode *e, const SgTransform *to_world, SgLightSource *l, char *path,
                   size_t size)
{
    const char *file;
    double scale;
    if (!mts_string(p, e, "filename", NULL, &file) || !mts_float(p, e, "scale", 1, &scale))
        return false;
    if (!file)
        return mts_fail(p, e, "envmap without a \"filename\"");
    if (!(scale >= 0 && isfinite(scale)))
        return mts_fail(p, e, "envmap scale must be finite and not negative");
    mts_resolve(p, e, file, path, size);
    FILE *f = fopen(path, "rb");
    if (!f)
        return mts_fail(p, e, "envmap \"%s\": cannot open it", path);
    fclose(f);
    l->kind = SG_LIGHT_INFINITE;
    l->image_path = path;
    l->layout = SG_ENVIRONMENT_LATLONG;
    l->rgb[0] = l->rgb[1] = l->rgb[2] = (float)scale;
    double world_from_mitsuba[3][3];
    return environment_frame(p, e, to_world, world_from_mitsuba, l);
}

/* The sun's direction in the emitter's frame (Mitsuba's: y up, x east, z
 * north... as its sun plugin places it): sun_direction (world space) where
 * given, else where the sun stands for the place and time asked. */
static bool sun_direction(MtsParser *p, const XmlNode *e, const double world_from_mitsuba[3][3], double local[3])
{
    double world[3];
    bool given;
    static const double up[3] = {0, 1, 0};
    if (!mts_point(p, e, "sun_direction", up, world, &given))
        return false;
    if (given) {
        if (!unit(p, e, world, "sun_direction"))
            return false;
        for (int c = 0; c < 3; c++) /* the inverse of a rotation: its transpose */
            local[c] = world_from_mitsuba[0][c] * world[0] + world_from_mitsuba[1][c] * world[1] +
                       world_from_mitsuba[2][c] * world[2];
        return true;
    }
    long year, month, day;
    double hour, minute, second, timezone, latitude, longitude;
    if (!mts_int(p, e, "year", 2010, &year) || !mts_int(p, e, "month", 7, &month) || !mts_int(p, e, "day", 10, &day) ||
        !mts_float(p, e, "hour", 15, &hour) || !mts_float(p, e, "minute", 0, &minute) ||
        !mts_float(p, e, "second", 0, &second) || !mts_float(p, e, "timezone", 9, &timezone) ||
        !mts_float(p, e, "latitude", 35.6894, &latitude) || !mts_float(p, e, "longitude", 139.6917, &longitude))
        return false;
    if (!(month >= 1 && month <= 12 && day >= 1 && day <= 31 && labs(year) < 100000))
        return mts_fail(p, e, "sun position: want a month 1..12, a day 1..31 and a sensible year");
    double zenith, azimuth;
    sg_sun_position((int)year, (int)month, (int)day, hour, minute, second, timezone, latitude, longitude, &zenith,
                    &azimuth);
    local[0] = sin(azimuth) * sin(zenith);
    local[1] = cos(zenith);
    local[2] = -cos(azimuth) * sin(zenith);
    return true;
}

/* Mitsuba's sky, sun and sunsky: Preetham's sky as an environment
 * image made here (common/sunsky.h), the sun a distant light with its disk;
 * sky_scale, sun_scale, sun_radius_scale (the disk's size, its power kept;
 * 0 a delta), turbidity, resolution, extend. Mitsuba's values are spectral
 * radiance (W m^-2 sr^-1 nm^-1) averaged under the CIE y curve: Preetham's
 * luminance in kcd/m^2 over 683 lm/W times the curve's 106.857 nm / 1000. */
#define KCD_PER_MITSUBA_RADIANCE (683.0 * 106.857 / 1000.0)

static bool sunsky(MtsParser *p, const XmlNode *e, const char *type, const SgTransform *to_world)
{
    bool with_sky = strcmp(type, "sun") != 0, with_sun = strcmp(type, "sky") != 0, extend;
    double turbidity, sky_scale, sun_scale, radius_scale, stretch, local[3], world_from_mitsuba[3][3];
    long resolution;
    SgLightSource sky = {0};
    if (!mts_float(p, e, "turbidity", 3, &turbidity) || !mts_float(p, e, "sky_scale", 1, &sky_scale) ||
        !mts_float(p, e, "sun_scale", 1, &sun_scale) || !mts_float(p, e, "sun_radius_scale", 1, &radius_scale) ||
        !mts_float(p, e, "stretch", 1, &stretch) || !mts_int(p, e, "resolution", 512, &resolution) ||
        !mts_bool(p, e, "extend", false, &extend) || !environment_frame(p, e, to_world, world_from_mitsuba, &sky) ||
        !sun_direction(p, e, world_from_mitsuba, local))
        return false;
    if (!(turbidity >= 1 && turbidity <= 30))
        return mts_fail(p, e, "%s: turbidity must be in [1, 30]", type);
    if (!(sky_scale >= 0 && sun_scale >= 0 && radius_scale >= 0 && isfinite(sky_scale * sun_scale * radius_scale)))
        return mts_fail(p, e, "%s: scales must be finite and not negative", type);
    if (!(resolution >= 4 && resolution <= 8192))
        return mts_fail(p, e, "%s: resolution must be in [4, 8192]", type);
    /* Mitsuba's sky is Hosek and Wilkie's (2012) in 0.5, 0.6 and 3; its
     * fitted coefficients are not at hand (docs/scene-format.md) */
    if (with_sky)
        mts_warn(p, e, "%s: Mitsuba's Hosek-Wilkie sky is taken as Preetham's: its colour and level may differ", type);
    if (stretch != 1)
        mts_warn(p, e, "%s: stretch is ignored", type);
    double theta_sun = acos(fmin(fmax(local[1], -1.0), 1.0));
    if (with_sky) {
        /* the sun in our light space (z up): the transpose of OURS_TO_MITSUBA */
        double ours[3];
        for (int c = 0; c < 3; c++)
            ours[c] = OURS_TO_MITSUBA[0][c] * local[0] + OURS_TO_MITSUBA[1][c] * local[1] +
                      OURS_TO_MITSUBA[2][c] * local[2];
        SgPreethamSky model;
        sg_preetham_init(&model, turbidity, fmin(theta_sun, 0.5 * M_PI));
        sky.kind = SG_LIGHT_INFINITE;
        sky.layout = SG_ENVIRONMENT_LATLONG;
        sky.rgb[0] = sky.rgb[1] = sky.rgb[2] = 1.0f;
        sky.image_width = (int)(2 * resolution);
        sky.image_height = (int)resolution;
        if (!(sky.image_pixels = sg_sky_image(&model, ours, sky.image_width, sky.image_height,
                                              sky_scale / KCD_PER_MITSUBA_RADIANCE, extend, p->err)))
            return false;
        bool ok = sg_builder_add_light_source(&p->core, &sky, p->err);
        free(sky.image_pixels);
        if (!ok)
            return false;
    }
    if (!with_sun)
        return true;
    float radiance[3];
    sg_sun_radiance(turbidity, theta_sun, radiance);
    if (!(radiance[0] + radiance[1] + radiance[2] > 0)) {
        mts_warn(p, e, "%s: the sun is below the horizon: no sun", type);
        return true;
    }
    SgLightSource sun = {0};
    sun.kind = SG_LIGHT_DISTANT;
    double disk = 2 * M_PI * (1 - cos(SG_SUN_ANGULAR_RADIUS)); /* the physical disk's solid angle */
    for (int c = 0; c < 3; c++) {
        sun.rgb[c] = (float)(radiance[c] / KCD_PER_MITSUBA_RADIANCE * disk * sun_scale);
        sun.direction[c] = -(world_from_mitsuba[c][0] * local[0] + world_from_mitsuba[c][1] * local[1] +
                             world_from_mitsuba[c][2] * local[2]);
    }
    sun.angular_radius = fmin(SG_SUN_ANGULAR_RADIUS * radius_scale, 0.5);
    return sg_builder_add_light_source(&p->core, &sun, p->err);
}

static bool emitter(MtsParser *p, XmlNode *e)
{
    if (!mts_substitute(p, e) || !mts_register_id(p, e))
        return false;
    const char *type = sg_xml_attr(e, "type");
    if (!type)
        return mts_fail(p, e, "<emitter> without a type");
    SgLightSource l;
    memset(&l, 0, sizeof l);
    SgTransform to_world;
    bool has_world;
    char path[8192];
    static const float one[3] = {1, 1, 1};
    static const double origin[3] = {0, 0, 0}, forward[3] = {0, 0, 1};
    if (!mts_transform(p, e, "to_world", &to_world, &has_world))
        return false;
    if (!strcmp(type, "point") || !strcmp(type, "spot")) {
        bool spot = !strcmp(type, "spot"), has_position;
        double position[3];
        if (!mts_color(p, e, "intensity", one, l.rgb, NULL, NULL) ||
            !mts_point(p, e, "position", origin, position, &has_position) ||
            !check_rgb(p, e, l.rgb, "intensity"))
            return false;
        l.kind = spot ? SG_LIGHT_SPOT : SG_LIGHT_POINT;
        if (has_position)
            memcpy(l.position, position, sizeof position);
        else
            sg_transform_point(&to_world, origin, l.position);
        if (spot) {
            double cutoff, beam;
            if (!mts_float(p, e, "cutoff_angle", 20, &cutoff) || !mts_float(p, e, "beam_width", cutoff * 0.75, &beam))
                return false;
            if (!(cutoff > 0 && cutoff <= 90 && beam >= 0 && beam <= cutoff))
                return mts_fail(p, e, "spot: want 0 < cutoff_angle <= 90 and 0 <= beam_width <= cutoff_angle");
            linear_column(&to_world, 2, l.direction);
            if (!unit(p, e, l.direction, "spot direction"))
                return false;
            l.cos_cone = cos(cutoff * M_PI / 180);
            l.cos_falloff_start = cos(beam * M_PI / 180);
            mts_warn(p, e, "spot falloff is pbrt's smooth step between beam_width and cutoff_angle, not Mitsuba's "
                           "linear one");
        }
    } else if (!strcmp(type, "directional")) {
        bool has_direction;
        if (!mts_color(p, e, "irradiance", one, l.rgb, NULL, NULL) ||
            !mts_point(p, e, "direction", forward, l.direction, &has_direction) ||
            !check_rgb(p, e, l.rgb, "irradiance"))
            return false;
        if (!has_direction)
            linear_column(&to_world, 2, l.direction);
        if (!unit(p, e, l.direction, "directional direction"))
            return false;
        l.kind = SG_LIGHT_DISTANT;
    } else if (!strcmp(type, "constant")) {
        if (!mts_color(p, e, "radiance", one, l.rgb, NULL, NULL) || !check_rgb(p, e, l.rgb, "radiance"))
            return false;
        l.kind = SG_LIGHT_INFINITE;
        for (int a = 0; a < 3; a++)
            l.light_to_world[a][a] = 1;
    } else if (!strcmp(type, "envmap")) {
        if (!envmap(p, e, &to_world, &l, path, sizeof path))
            return false;
    } else if (!strcmp(type, "sunsky") || !strcmp(type, "sky") || !strcmp(type, "sun")) {
        return sunsky(p, e, type, &to_world);
    } else {
        mts_warn(p, e, "emitter \"%s\" is not supported: left out", type);
        if (!p->unsupported_emitter[0])
            snprintf(p->unsupported_emitter, sizeof p->unsupported_emitter, "%.40s", type);
        return true;
    }
    return sg_builder_add_light_source(&p->core, &l, p->err);
}

/* ---- sensor and integrator ---------------------------------------------- */

/* Mitsuba's focal_length ("50mm"): the horizontal fov of a 36 mm film. */
static bool focal_length_fov(MtsParser *p, const XmlNode *s, double *fov)
{
    const char *text;
    if (!mts_string(p, s, "focal_length", "50mm", &text))
        return false;
    char *end;
    double mm = strtod(text, &end);
    if (end == text || !(mm > 0) || (*end && strcmp(end, "mm")))
        return mts_fail(p, s, "focal_length \"%.40s\" is not a length in mm", text);
    *fov = 2 * atan(18.0 / mm) * 180 / M_PI;
    return true;
}

static bool sensor(MtsParser *p, XmlNode *s)
{
    if (!mts_substitute(p, s) || !mts_register_id(p, s))
        return false;
    if (p->has_sensor) {
        mts_warn(p, s, "more than one sensor: the first is used");
        return true;
    }
    p->has_sensor = true;
    const char *type = sg_xml_attr(s, "type");
    if (!type || (strcmp(type, "perspective") && strcmp(type, "thinlens")))
        mts_warn(p, s, "sensor \"%s\" is taken as a perspective camera", type ? type : "");
    else if (!strcmp(type, "thinlens"))
        mts_warn(p, s, "thinlens depth of field is ignored: a pinhole camera");
    SgScene *scene = p->core.scene;
    const XmlNode *film, *sampler, *fov_node;
    long width = 768, height = 576, spp = 0;
    if (!mts_find_object(p, s, "film", 0, &film) || !mts_find_object(p, s, "sampler", 0, &sampler))
        return false;
    if (film && (!mts_int(p, film, "width", 768, &width) || !mts_int(p, film, "height", 576, &height)))
        return false;
    if (!(width >= 1 && width <= 65536 && height >= 1 && height <= 65536))
        return mts_fail(p, film ? film : s, "film size %ldx%ld is out of range", width, height);
    if (sampler && !mts_int(p, sampler, "sample_count", 0, &spp))
        return false;
    if (spp >= 1 && spp <= (1 << 24))
        scene->render.spp = (int)spp;
    double fov, near_clip;
    const char *axis;
    SgTransform w;
    if (!mts_find(p, s, "fov", &fov_node) || !mts_string(p, s, "fov_axis", "x", &axis) ||
        !mts_float(p, s, "near_clip", 0.01, &near_clip) || !mts_transform(p, s, "to_world", &w, NULL))
        return false;
    if (fov_node ? !mts_float(p, s, "fov", 90, &fov) : !focal_length_fov(p, s, &fov))
        return false;
    if (!(fov > 0 && fov < 180))
        return mts_fail(p, s, "fov %g is not in (0, 180) degrees", fov);
    if (near_clip > 0.01)
        mts_warn(p, s, "near_clip is ignored: the camera sees from its position on");
    /* the vertical fov of ours from the axis Mitsuba's spans */
    double t = tan(fov * M_PI / 360), wd = (double)width, hd = (double)height;
    if (!strcasecmp(axis, "smaller"))
        axis = wd < hd ? "x" : "y";
    else if (!strcasecmp(axis, "larger"))
        axis = wd > hd ? "x" : "y";
    if (!strcasecmp(axis, "x"))
        t *= hd / wd;
    else if (!strcasecmp(axis, "diagonal"))
        t *= hd / sqrt(wd * wd + hd * hd);
    else if (strcasecmp(axis, "y"))
        return mts_fail(p, s, "fov_axis \"%s\" is not x, y, diagonal, smaller or larger", axis);
    scene->camera.fov_deg = 2 * atan(t) * 180 / M_PI;
    scene->camera.width = (int)width;
    scene->camera.height = (int)height;
    /* camera space looks along +z with +y up; Mitsuba's image right is
     * camera -x (its lookat puts "left" in the first column) */
    double pos[3], dir[3], up[3], left[3], right[3];
    static const double origin[3] = {0, 0, 0};
    sg_transform_point(&w, origin, pos);
    linear_column(&w, 0, left);
    linear_column(&w, 1, up);
    linear_column(&w, 2, dir);
    if (!unit(p, s, dir, "the sensor's view direction") || !unit(p, s, up, "the sensor's up"))
        return false;
    d3_cross(dir, up, right);
    if (d3_dot(right, left) > 0)
        mts_warn(p, s, "the sensor's to_world mirrors the image: ours is Mitsuba's mirrored left to right");
    for (int a = 0; a < 3; a++) {
        scene->camera.position[a] = pos[a];
        scene->camera.look_at[a] = pos[a] + dir[a];
        scene->camera.up[a] = up[a];
    }
    scene->has_camera = true;
    return true;
}

/* The max_depth of an integrator, or of the first nested one giving it. */
static bool integrator_depth(MtsParser *p, const XmlNode *n, long *depth, int level)
{
    const XmlNode *given, *nested;
    if (level > 8)
        return mts_fail(p, n, "integrators nested too deeply");
    if (!mts_substitute(p, (XmlNode *)n) || !mts_find(p, n, "max_depth", &given))
        return false;
    if (given)
        return mts_int(p, n, "max_depth", -1, depth);
    if (!mts_find_object(p, n, "integrator", 0, &nested))
        return false;
    return !nested || integrator_depth(p, nested, depth, level + 1);
}

static bool integrator(MtsParser *p, XmlNode *n)
{
    long depth = -1;
    if (!integrator_depth(p, n, &depth, 0))
        return false;
    const char *type = sg_xml_attr(n, "type");
    bool direct = type && (!strcmp(type, "direct") || !strcmp(type, "direct_projective"));
    if (direct && depth < 0)
        depth = 2; /* direct light only: the camera's segment and the light's */
    else if (type && strcmp(type, "path") && strcmp(type, "volpath") && strcmp(type, "volpath_simple") &&
             strcmp(type, "guided_path") && !direct)
        mts_warn(p, n, "integrator \"%s\" is taken for its max_depth only", type);
    if (direct)
        mts_warn(p, n, "integrator \"%s\" is rendered as paths of at most 2 segments (direct light)", type);
    if (depth == 0) {
        mts_warn(p, n, "max_depth 0 (Mitsuba renders black) is taken as 1");
        depth = 1;
    }
    p->core.scene->render.max_depth =
        depth < 0 || depth > MTS_UNBOUNDED_DEPTH ? MTS_UNBOUNDED_DEPTH : (int)depth;
    return true;
}

/* ---- the walk ----------------------------------------------------------- */

static bool scene_children(MtsParser *p, XmlNode *scene);

static bool keep_doc(MtsParser *p, XmlDoc *doc)
{
    if (!MTS_RESERVE(p, p->docs, p->doc_count, p->doc_capacity, 1)) {
        sg_xml_free(doc);
        return false;
    }
    p->docs[p->doc_count++] = doc;
    return true;
}

/* Every file's text goes into the scene's source hash, in the order read. */
static void add_source(void *builder, const char *text, size_t size)
{
    sg_builder_add_source(builder, text, size);
}

/* The version tells the dialect: below 2, Mitsuba 0.x's camelCase. */
static bool read_scene_file(MtsParser *p, const char *path, const XmlNode *from, XmlDoc **out)
{
    SgError local = {0};
    XmlDoc *doc = sg_xml_read(path, add_source, &p->core, &local);
    if (!doc)
        return from ? mts_fail(p, from, "include: %s", local.message) : sg_fail(p->err, "%s", local.message);
    if (!keep_doc(p, doc))
        return false;
    XmlNode *root = doc->root;
    if (!mts_is_tag(root, "scene"))
        return mts_fail(p, root, "the root element is <%s>, not <scene>", root->tag);
    const char *version = sg_xml_attr(root, "version");
    if (!version)
        return mts_fail(p, root, "<scene> has no version (Mitsuba needs one)");
    int major = atoi(version);
    if (major < 0 || major > 3 || !strchr("0123", version[0]))
        return mts_fail(p, root, "scene version \"%.20s\" is not Mitsuba's 0.x to 3.x", version);
    doc->old_dialect = major < 2;
    *out = doc;
    return true;
}

static bool include(MtsParser *p, XmlNode *n)
{
    const char *file = mts_attr(p, n, "filename");
    if (!file)
        return p->err->failed ? false : mts_fail(p, n, "<include> without a filename");
    char path[8192], real[PATH_MAX];
    mts_resolve(p, n, file, path, sizeof path);
    if (!realpath(path, real))
        return mts_fail(p, n, "include \"%s\": cannot open it", path);
    for (int i = 0; i < p->include_depth; i++)
        if (!strcmp(p->include_stack[i], real))
            return mts_fail(p, n, "cyclic include: \"%s\" includes itself", path);
    if (p->include_depth == MTS_MAX_INCLUDE_DEPTH)
        return mts_fail(p, n, "includes nested more than %d deep", MTS_MAX_INCLUDE_DEPTH);
    XmlDoc *doc;
    if (!read_scene_file(p, path, n, &doc))
        return false;
    if (!(p->include_stack[p->include_depth] = strdup(real)))
        return sg_fail(p->err, "%s: out of memory", p->core.path);
    p->include_depth++;
    bool ok = scene_children(p, doc->root);
    free(p->include_stack[--p->include_depth]);
    return ok;
}

static bool define_default(MtsParser *p, XmlNode *n)
{
    const char *name = mts_attr(p, n, "name"), *value = mts_attr(p, n, "value");
    if (!name || !value)
        return p->err->failed ? false : mts_fail(p, n, "<default> needs a name and a value");
    for (size_t i = 0; i < p->default_count; i++)
        if (!strcmp(p->defaults[i].name, name))
            return true; /* the first one stands, as a value given from outside would */
    if (!MTS_RESERVE(p, p->defaults, p->default_count, p->default_capacity, 1))
        return false;
    MtsDefault *d = &p->defaults[p->default_count];
    d->name = strdup(name);
    d->value = strdup(value);
    if (!d->name || !d->value) {
        free(d->name);
        free(d->value);
        return sg_fail(p->err, "%s: out of memory", p->core.path);
    }
    p->default_count++;
    return true;
}

static bool search_path(MtsParser *p, XmlNode *n)
{
    const char *value = mts_attr(p, n, "value");
    if (!value)
        return p->err->failed ? false : mts_fail(p, n, "<path> without a value");
    char dir[8192];
    mts_resolve(p, n, value, dir, sizeof dir);
    if (!MTS_RESERVE(p, p->search_dirs, p->search_dir_count, p->search_dir_capacity, 1))
        return false;
    if (!(p->search_dirs[p->search_dir_count] = strdup(dir)))
        return sg_fail(p->err, "%s: out of memory", p->core.path);
    p->search_dir_count++;
    return true;
}

/* A bsdf or texture defined at the top: known by its id from here on;
 * turned into a material when a shape uses it. */
static bool declaration(MtsParser *p, XmlNode *n)
{
    if (!mts_substitute(p, n) || !mts_register_id(p, n))
        return false;
    if (!sg_xml_attr(n, "id"))
        mts_warn(p, n, "a top-level <%s> without an id is never used (as in Mitsuba: only the ids inside it are "
                       "reached)", n->tag);
    return true;
}

/* The ids of an element and of everything nested in it (a bsdf's id
 * inside a bumpmap is known to the whole scene, as in Mitsuba). */
static bool register_ids(MtsParser *p, XmlNode *n, int depth)
{
    if (depth > 64)
        return mts_fail(p, n, "elements nested too deeply");
    if (!mts_substitute(p, n) || !mts_register_id(p, n))
        return false;
    for (size_t i = 0; i < n->child_count; i++)
        if (!mts_is_tag(n->children[i], "ref") && !register_ids(p, n->children[i], depth + 1))
            return false;
    return true;
}

static bool scene_children(MtsParser *p, XmlNode *scene)
{
    for (size_t i = 0; i < scene->child_count; i++) {
        XmlNode *n = scene->children[i];
        bool ok;
        if (!mts_is_tag(n, "default") && !mts_is_tag(n, "include") && !mts_is_tag(n, "path") &&
            !mts_is_tag(n, "alias") && !register_ids(p, n, 0))
            return false;
        if (mts_is_tag(n, "default"))
            ok = define_default(p, n);
        else if (mts_is_tag(n, "include"))
            ok = include(p, n);
        else if (mts_is_tag(n, "path"))
            ok = search_path(p, n);
        else if (mts_is_tag(n, "shape"))
            ok = mts_shape(p, n);
        else if (mts_is_tag(n, "emitter"))
            ok = emitter(p, n);
        else if (mts_is_tag(n, "sensor") || mts_is_tag(n, "camera"))
            ok = sensor(p, n);
        else if (mts_is_tag(n, "integrator"))
            ok = integrator(p, n);
        else if (mts_is_tag(n, "bsdf") || mts_is_tag(n, "texture") || mts_is_tag(n, "spectrum") ||
                 mts_is_tag(n, "rgb") || mts_is_tag(n, "float"))
            ok = declaration(p, n);
        else if (mts_is_tag(n, "alias")) {
            const char *id = mts_attr(p, n, "id"), *as = mts_attr(p, n, "as");
            const XmlNode *target = id ? mts_lookup_id(p, id) : NULL;
            if (!target)
                ok = p->err->failed ? false : mts_fail(p, n, "alias of an unknown id \"%s\"", id ? id : "");
            else
                ok = !as || (MTS_RESERVE(p, p->ids, p->id_count, p->id_capacity, 1) &&
                             (p->ids[p->id_count++] = (MtsId){as, target}, true));
        } else if (mts_is_tag(n, "medium")) { /* read where a shape holds it; what cannot be, said now */
            float sigma_a[3];
            bool absorbing;
            ok = mts_medium_absorption(p, n, sigma_a, &absorbing);
        } else if (mts_is_tag(n, "phase")) {
            mts_warn(p, n, "phase functions are not supported: left out");
            ok = true;
        } else {
            mts_warn(p, n, "<%s> at the top of a scene is not supported: left out", n->tag);
            ok = true;
        }
        if (!ok)
            return false;
    }
    return true;
}

/* ---- entry point -------------------------------------------------------- */

static void release(MtsParser *p)
{
    for (size_t i = 0; i < p->doc_count; i++)
        sg_xml_free(p->docs[i]);
    free(p->docs);
    for (int i = 0; i < p->include_depth; i++)
        free(p->include_stack[i]);
    for (size_t i = 0; i < p->search_dir_count; i++)
        free(p->search_dirs[i]);
    free(p->search_dirs);
    for (size_t i = 0; i < p->default_count; i++) {
        free(p->defaults[i].name);
        free(p->defaults[i].value);
    }
    free(p->defaults);
    free(p->ids);
    free(p->materials);
    free(p->textures);
    for (size_t i = 0; i < p->group_count; i++)
        sg_shape_group_release(&p->groups[i].shapes);
    free(p->groups);
    sg_builder_release(&p->core);
}

/* Mitsuba's camera when the scene has no sensor: at the origin looking
 * down +z, fov 39.6 degrees across 768 x 576. */
static void default_camera(SgScene *s)
{
    s->camera.width = 768;
    s->camera.height = 576;
    s->camera.position[0] = s->camera.position[1] = s->camera.position[2] = 0;
    s->camera.look_at[0] = s->camera.look_at[1] = 0;
    s->camera.look_at[2] = 1;
    s->camera.up[0] = s->camera.up[2] = 0;
    s->camera.up[1] = 1;
    s->camera.fov_deg = 2 * atan(tan(39.5977 * M_PI / 360) * 576.0 / 768.0) * 180 / M_PI;
    s->has_camera = true;
}

SgScene *sg_mitsuba_scene_load(const char *path, SgError *err)
{
    MtsParser p = {.err = err};
    sg_folder_of(path, p.base_dir, sizeof p.base_dir);
    if (!sg_builder_begin(&p.core, path, err))
        return NULL;
    SgScene *s = p.core.scene;
    s->render.max_depth = MTS_UNBOUNDED_DEPTH; /* Mitsuba's default path integrator: -1 */
    char real[PATH_MAX];
    XmlDoc *doc = NULL;
    bool ok = read_scene_file(&p, path, NULL, &doc);
    if (ok && realpath(path, real)) {
        ok = (p.include_stack[0] = strdup(real)) != NULL;
        if (ok)
            p.include_depth = 1;
        else
            sg_fail(err, "%s: out of memory", path);
    }
    ok = ok && scene_children(&p, doc->root);
    ok = ok && !err->failed;
    if (ok && !p.has_sensor)
        default_camera(s);
    if (ok && s->triangle_count == 0)
        ok = sg_fail(err, "%s: the scene has no triangles%s", path,
                     p.core.dropped_degenerate ? " (all were degenerate)" : "");
    ok = ok && sg_builder_finish(&p.core, err);
    if (ok && s->light_count == 0 && s->light_source_count == 0 && p.unsupported_emitter[0])
        ok = sg_fail(err, "%s: the scene has no light (%s is not supported)", path, p.unsupported_emitter);
    else if (ok && s->light_count == 0 && s->light_source_count == 0)
        ok = sg_fail(err, "%s: the scene has no light (no area, point, spot, directional, constant or envmap emitter)",
                     path);
    release(&p);
    if (!ok) {
        sg_scene_free(s);
        return NULL;
    }
    return s;
}
