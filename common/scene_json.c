/* Scene files in JSON (cJSON): materials, transforms, inline meshes, quad
 * lights, camera and settings; mesh files it names go to mesh_file.h. See
 * docs/scene-format.md, "JSON scenes". */
#include "scene_json.h"

#include <cjson/cJSON.h>
#include <glob.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "image_average.h"
#include "input_file.h"
#include "mesh_file.h"
#include "scene_builder.h"
#include "vecmath.h"

typedef struct Builder {
    SgSceneBuilder core;
    SgScene *scene;         /* core.scene */
    const char *json_path;  /* core.path */
    char base_dir[4096];
    const cJSON *material_overrides; /* the "materials" object, or NULL */
} Builder;

/* ---- JSON helpers ------------------------------------------------------- */

/* The first n items of an array (that has them), if all are finite numbers. */
static bool json_finite_numbers(const cJSON *array, int n, double *out)
{
    for (int i = 0; i < n; i++) {
        const cJSON *v = cJSON_GetArrayItem(array, i);
        if (!cJSON_IsNumber(v) || !isfinite(v->valuedouble))
            return false;
        out[i] = v->valuedouble;
    }
    return true;
}

static bool json_vec3(const cJSON *item, double out[3])
{
    return cJSON_IsArray(item) && cJSON_GetArraySize(item) == 3 && json_finite_numbers(item, 3, out);
}

static bool json_color(const cJSON *item, float out[3])
{
    double v[3];
    if (!json_vec3(item, v))
        return false;
    for (int a = 0; a < 3; a++) {
        if (v[a] < 0)
            return false;
        out[a] = (float)v[a];
    }
    return true;
}

/* Optional vec3 member: absent is fine, present must be valid. */
static bool member_vec3(const char *path, const cJSON *obj, const char *owner, const char *name,
                        double out[3], bool *present, SgError *err)
{
    const cJSON *item = cJSON_GetObjectItemCaseSensitive(obj, name);
    if (present)
        *present = item != NULL;
    if (!item)
        return true;
    if (!json_vec3(item, out))
        return sg_fail(err, "%s: %s.%s must be an array of 3 finite numbers", path, owner, name);
    return true;
}

static bool member_color(const char *path, const cJSON *obj, const char *owner, const char *name,
                         float out[3], SgError *err)
{
    const cJSON *item = cJSON_GetObjectItemCaseSensitive(obj, name);
    if (!item)
        return true;
    if (!json_color(item, out))
        return sg_fail(err, "%s: %s.%s must be an array of 3 non-negative numbers", path, owner,
                       name);
    return true;
}

static bool member_number(const char *path, const cJSON *obj, const char *owner, const char *name,
                          double lo, double hi, double *out, SgError *err)
{
    const cJSON *item = cJSON_GetObjectItemCaseSensitive(obj, name);
    if (!item)
        return true;
    if (!cJSON_IsNumber(item) || !isfinite(item->valuedouble) || item->valuedouble < lo ||
        item->valuedouble > hi)
        return sg_fail(err, "%s: %s.%s must be a number in [%g, %g]", path, owner, name, lo, hi);
    *out = item->valuedouble;
    return true;
}

static bool member_int(const char *path, const cJSON *obj, const char *owner, const char *name,
                       int lo, int hi, int *out, SgError *err)
{
    double v = *out;
    if (!member_number(path, obj, owner, name, lo, hi, &v, err))
        return false;
    if (v != floor(v))
        return sg_fail(err, "%s: %s.%s must be a whole number", path, owner, name);
    *out = (int)v;
    return true;
}

/* ---- materials ---------------------------------------------------------- */

static bool apply_material_json(const char *path, const cJSON *obj, const char *name,
                                SgMaterial *m, SgError *err)
{
    if (!cJSON_IsObject(obj))
        return sg_fail(err, "%s: material \"%s\" must be an object", path, name);
    char owner[96];
    snprintf(owner, sizeof owner, "materials.%s", name);
    const cJSON *type = cJSON_GetObjectItemCaseSensitive(obj, "type");
    if (type) {
        const char *t = cJSON_GetStringValue(type);
        if (t && !strcmp(t, "diffuse"))
            m->type = SG_MATERIAL_DIFFUSE;
        else if (t && !strcmp(t, "glossy"))
            m->type = SG_MATERIAL_GLOSSY;
        else if (t && !strcmp(t, "mirror"))
            m->type = SG_MATERIAL_MIRROR;
        else if (t && !strcmp(t, "dielectric"))
            m->type = SG_MATERIAL_DIELECTRIC;
        else if (t && !strcmp(t, "conductor"))
            m->type = SG_MATERIAL_CONDUCTOR;
        else if (t && !strcmp(t, "coateddiffuse"))
            m->type = SG_MATERIAL_COATED_DIFFUSE;
        else
            return sg_fail(err,
                           "%s: %s.type must be diffuse, glossy, mirror, dielectric, conductor or coateddiffuse",
                           path, owner);
    }
    double exponent = m->exponent, ior = m->ior, roughness = m->roughness[0];
    if (!member_color(path, obj, owner, "albedo", m->diffuse, err) ||
        !member_color(path, obj, owner, "specular", m->specular, err) ||
        !member_color(path, obj, owner, "emission", m->emission, err) ||
        !member_number(path, obj, owner, "exponent", 0, 1e7, &exponent, err) ||
        !member_number(path, obj, owner, "ior", 1.0, 10.0, &ior, err) ||
        !member_number(path, obj, owner, "roughness", 0, 1, &roughness, err) ||
        !member_color(path, obj, owner, "eta", m->eta, err) || !member_color(path, obj, owner, "k", m->k, err))
        return false;
    m->exponent = (float)exponent;
    m->ior = (float)ior;
    m->roughness[0] = m->roughness[1] = (float)roughness; /* GGX alpha */
    /* Keep energy conservation: albedos above 1 would make furnaces explode. */
    for (int a = 0; a < 3; a++)
        if (m->diffuse[a] + m->specular[a] > 1.0f && (m->type == SG_MATERIAL_DIFFUSE || m->type == SG_MATERIAL_GLOSSY))
            return sg_fail(err, "%s: %s: albedo + specular exceeds 1 (not energy conserving)",
                           path, owner);
    return true;
}

/* A material named in the JSON "materials" object, looked up by name. */
static bool named_material(Builder *b, const char *name, uint32_t *id, SgError *err)
{
    for (uint32_t i = 0; i < b->scene->material_count; i++)
        if (!strcmp(b->scene->materials[i].name, name)) {
            *id = i;
            return true;
        }
    const cJSON *obj = b->material_overrides
                           ? cJSON_GetObjectItemCaseSensitive(b->material_overrides, name)
                           : NULL;
    if (!obj)
        return sg_fail(err, "%s: material \"%s\" is not defined in \"materials\"", b->json_path,
                       name);
    SgMaterial m;
    sg_material_default(&m, name);
    return apply_material_json(b->json_path, obj, name, &m, err) &&
           sg_builder_add_material(&b->core, &m, id, err);
}

/* ---- transforms --------------------------------------------------------- */

static bool parse_transform(const char *path, const cJSON *obj, const char *owner, SgTransform *t,
                            SgError *err)
{
    sg_transform_identity(t);
    if (!obj)
        return true;
    if (!cJSON_IsObject(obj))
        return sg_fail(err, "%s: %s.transform must be an object", path, owner);
    const cJSON *matrix = cJSON_GetObjectItemCaseSensitive(obj, "matrix");
    if (matrix) {
        if (!cJSON_IsArray(matrix) || cJSON_GetArraySize(matrix) != 16)
            return sg_fail(err, "%s: %s.transform.matrix must hold 16 numbers", path, owner);
        double v[16];
        if (!json_finite_numbers(matrix, 16, v))
            return sg_fail(err, "%s: %s.transform.matrix must hold finite numbers", path, owner);
        if (v[12] != 0 || v[13] != 0 || v[14] != 0 || v[15] != 1)
            return sg_fail(err, "%s: %s.transform.matrix must be affine (last row 0 0 0 1)",
                           path, owner);
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 4; c++)
                t->m[r][c] = v[4 * r + c];
        return true;
    }
    SgTransform s, rot, tr;
    sg_transform_identity(&s);
    sg_transform_identity(&rot);
    sg_transform_identity(&tr);
    const cJSON *scale = cJSON_GetObjectItemCaseSensitive(obj, "scale");
    if (scale) {
        double k[3];
        if (cJSON_IsNumber(scale) && isfinite(scale->valuedouble))
            k[0] = k[1] = k[2] = scale->valuedouble;
        else if (!json_vec3(scale, k))
            return sg_fail(err, "%s: %s.transform.scale must be a number or 3 numbers", path,
                           owner);
        for (int a = 0; a < 3; a++) {
            if (k[a] == 0)
                return sg_fail(err, "%s: %s.transform.scale must not be zero", path, owner);
            s.m[a][a] = k[a];
        }
    }
    const cJSON *rotate = cJSON_GetObjectItemCaseSensitive(obj, "rotate");
    if (rotate) {
        double v[4];
        if (!cJSON_IsArray(rotate) || cJSON_GetArraySize(rotate) != 4)
            return sg_fail(err, "%s: %s.transform.rotate must be [degrees, x, y, z]", path,
                           owner);
        if (!json_finite_numbers(rotate, 4, v))
            return sg_fail(err, "%s: %s.transform.rotate must hold finite numbers", path, owner);
        if (!sg_transform_rotation(&rot, v[0], v + 1))
            return sg_fail(err, "%s: %s.transform.rotate axis is zero", path, owner);
    }
    double translate[3];
    bool has_translate;
    if (!member_vec3(path, obj, owner, "translate", translate, &has_translate, err))
        return false;
    if (has_translate)
        for (int a = 0; a < 3; a++)
            tr.m[a][3] = translate[a];
    SgTransform rs;
    sg_transform_multiply(&rot, &s, &rs);
    sg_transform_multiply(&tr, &rs, t);
    return true;
}

/* ---- geometry ----------------------------------------------------------- */

/* The material of a mesh with none of its own: the override if given. */
static bool plain_material(const SgMeshFileMaterials *rules, const char *file, uint32_t *id, SgError *err)
{
    Builder *b = rules->context;
    const char *material_name = rules->name;
    const float *emission = rules->emission;
    SgMaterial m;
    if (material_name) {
        if (!named_material(b, material_name, id, err))
            return false;
        if (!emission)
            return true;
        m = b->scene->materials[*id];
    } else {
        const char *slash = strrchr(file, '/');
        sg_material_default(&m, slash ? slash + 1 : file);
    }
    if (emission)
        memcpy(m.emission, emission, sizeof m.emission);
    return sg_builder_add_material(&b->core, &m, id, err);
}

/* A material read from a mesh file: the JSON "materials" entry of its name
 * overrides it; an override's own albedo, or a type the texture does not
 * suit, drops the file's texture. */
static bool override_material(const SgMeshFileMaterials *rules, const char *label, SgMaterial *m, SgError *err)
{
    const Builder *b = rules->context;
    const cJSON *override = b->material_overrides
                                ? cJSON_GetObjectItemCaseSensitive(b->material_overrides, label)
                                : NULL;
    if (override && !apply_material_json(b->json_path, override, label, m, err))
        return false;
    if (override && (cJSON_GetObjectItemCaseSensitive(override, "albedo") ||
                     (m->type != SG_MATERIAL_DIFFUSE && m->type != SG_MATERIAL_GLOSSY &&
                      m->type != SG_MATERIAL_COATED_DIFFUSE)))
        m->diffuse_texture = 0;
    return true;
}

static bool load_inline_mesh(Builder *b, const cJSON *mesh, const char *owner,
                             const SgTransform *xf,
                             const char *material_name, const float *emission, SgError *err)
{
    const cJSON *vertices = cJSON_GetObjectItemCaseSensitive(mesh, "vertices");
    const cJSON *triangles = cJSON_GetObjectItemCaseSensitive(mesh, "triangles");
    int nv = cJSON_GetArraySize(vertices), nt = cJSON_GetArraySize(triangles);
    if (!cJSON_IsArray(vertices) || nv % 3 || !cJSON_IsArray(triangles) || nt % 3)
        return sg_fail(err, "%s: %s needs \"vertices\" (x,y,z,...) and \"triangles\" (i,j,k,...)",
                       b->json_path, owner);
    uint32_t material = 0;
    SgMaterial m;
    if (material_name) {
        if (!named_material(b, material_name, &material, err))
            return false;
        m = b->scene->materials[material];
    } else {
        sg_material_default(&m, owner);
    }
    if (emission || !material_name) {
        if (emission)
            memcpy(m.emission, emission, sizeof m.emission);
        if (!sg_builder_add_material(&b->core, &m, &material, err))
            return false;
    }
    SgScene *s = b->scene;
    uint32_t base = s->vertex_count;
    if (!sg_builder_add_vertices(&b->core, (uint32_t)(nv / 3), err) ||
        !sg_builder_add_triangles(&b->core, (uint32_t)(nt / 3), err))
        return false;
    const cJSON *v = vertices->child;
    for (int i = 0; i < nv / 3; i++) {
        double p[3];
        for (int a = 0; a < 3; a++, v = v->next) {
            if (!cJSON_IsNumber(v))
                return sg_fail(err, "%s: %s.vertices must be numbers", b->json_path, owner);
            p[a] = v->valuedouble;
        }
        if (!sg_builder_check_point(&b->core, owner, p, err))
            return false;
        sg_transform_point(xf, p, s->positions + 3 * (size_t)(base + i));
    }
    s->vertex_count += (uint32_t)(nv / 3);
    const cJSON *t = triangles->child;
    for (int i = 0; i < nt / 3; i++) {
        uint32_t idx[3];
        for (int a = 0; a < 3; a++, t = t->next) {
            if (!cJSON_IsNumber(t) || t->valuedouble < 0 || t->valuedouble >= nv / 3 ||
                t->valuedouble != floor(t->valuedouble))
                return sg_fail(err, "%s: %s.triangles has an index out of range", b->json_path,
                               owner);
            idx[a] = base + (uint32_t)t->valuedouble;
        }
        sg_builder_push_triangle(&b->core, idx[0], idx[1], idx[2], material);
    }
    return true;
}

static bool load_meshes(Builder *b, const cJSON *root, SgError *err)
{
    const cJSON *meshes = cJSON_GetObjectItemCaseSensitive(root, "meshes");
    const cJSON *shorthand = cJSON_GetObjectItemCaseSensitive(root, "mesh");
    cJSON *owned = NULL;
    if (shorthand) {
        if (!cJSON_IsString(shorthand))
            return sg_fail(err, "%s: \"mesh\" must be a file name", b->json_path);
        owned = cJSON_CreateArray();
        cJSON *entry = cJSON_CreateObject();
        cJSON_AddStringToObject(entry, "file", shorthand->valuestring);
        cJSON_AddItemToArray(owned, entry);
        if (meshes) {
            cJSON *m;
            cJSON_ArrayForEach(m, meshes) cJSON_AddItemToArray(owned, cJSON_Duplicate(m, 1));
        }
        meshes = owned;
    }
    if (!meshes && !cJSON_GetObjectItemCaseSensitive(root, "lights")) {
        return sg_fail(err, "%s: no geometry: give \"mesh\", \"meshes\" or \"lights\"",
                       b->json_path);
    }
    if (meshes && !cJSON_IsArray(meshes)) {
        cJSON_Delete(owned);
        return sg_fail(err, "%s: \"meshes\" must be an array", b->json_path);
    }
    bool ok = true;
    int index = 0;
    const cJSON *mesh;
    cJSON_ArrayForEach(mesh, meshes)
    {
        char owner[32];
        snprintf(owner, sizeof owner, "meshes[%d]", index++);
        if (!cJSON_IsObject(mesh)) {
            ok = sg_fail(err, "%s: %s must be an object", b->json_path, owner);
            break;
        }
        SgTransform xf;
        float emission[3] = {0, 0, 0};
        const cJSON *em = cJSON_GetObjectItemCaseSensitive(mesh, "emission");
        const cJSON *mat = cJSON_GetObjectItemCaseSensitive(mesh, "material");
        if (mat && !cJSON_IsString(mat)) {
            ok = sg_fail(err, "%s: %s.material must be a material name", b->json_path, owner);
            break;
        }
        if (!parse_transform(b->json_path, cJSON_GetObjectItemCaseSensitive(mesh, "transform"),
                             owner, &xf, err) ||
            !member_color(b->json_path, mesh, owner, "emission", emission, err)) {
            ok = false;
            break;
        }
        const char *material_name = mat ? mat->valuestring : NULL;
        const cJSON *file = cJSON_GetObjectItemCaseSensitive(mesh, "file");
        if (!file) {
            ok = load_inline_mesh(b, mesh, owner, &xf, material_name, em ? emission : NULL, err);
        } else if (!cJSON_IsString(file) || !*file->valuestring) {
            ok = sg_fail(err, "%s: %s.file must be a file name", b->json_path, owner);
        } else {
            char pattern[8192];
            if (file->valuestring[0] == '/')
                snprintf(pattern, sizeof pattern, "%s", file->valuestring);
            else
                snprintf(pattern, sizeof pattern, "%s%s", b->base_dir, file->valuestring);
            glob_t g;
            int rc = glob(pattern, GLOB_NOCHECK, NULL, &g);
            if (rc != 0) {
                ok = sg_fail(err, "%s: %s.file: cannot expand \"%s\"", b->json_path, owner,
                             pattern);
            } else {
                SgMeshFileMaterials rules = {.name = material_name,
                                             .emission = em ? emission : NULL,
                                             .plain = plain_material,
                                             .adjust = override_material,
                                             .context = b};
                for (size_t i = 0; ok && i < g.gl_pathc; i++)
                    ok = sg_mesh_file_load(&b->core, &b->core.images, g.gl_pathv[i], &xf, &rules, err);
                globfree(&g);
            }
        }
        if (!ok)
            break;
    }
    cJSON_Delete(owned);
    return ok;
}

/* A unit vector member (required when `need`); false with the cause. */
static bool member_direction(const char *path, const cJSON *obj, const char *owner, const char *name, bool need,
                             double out[3], SgError *err)
{
    bool present;
    if (!member_vec3(path, obj, owner, name, out, &present, err))
        return false;
    if (!present && need)
        return sg_fail(err, "%s: %s.%s is missing", path, owner, name);
    double len = d3_length(out);
    if (!(len > 0))
        return sg_fail(err, "%s: %s.%s must not be zero", path, owner, name);
    for (int a = 0; a < 3; a++)
        out[a] /= len;
    return true;
}

/* A colour member that must be there, times the optional "scale". */
static bool member_light_colour(const char *path, const cJSON *obj, const char *owner, const char *name,
                                float out[3], SgError *err)
{
    if (!cJSON_GetObjectItemCaseSensitive(obj, name))
        return sg_fail(err, "%s: %s.%s is missing", path, owner, name);
    double scale = 1;
    if (!member_color(path, obj, owner, name, out, err) || !member_number(path, obj, owner, "scale", 0, 1e30, &scale, err))
        return false;
    for (int c = 0; c < 3; c++)
        out[c] = (float)(out[c] * scale);
    return true;
}

/* The sky: "radiance" (times "image" where given), "up" the map's pole. */
static bool sky_light(Builder *b, const cJSON *light, const char *owner, SgLightSource *l, char *image,
                      size_t image_size, SgError *err)
{
    const char *path = b->json_path;
    l->kind = SG_LIGHT_INFINITE;
    l->rgb[0] = l->rgb[1] = l->rgb[2] = 1;
    const cJSON *file = cJSON_GetObjectItemCaseSensitive(light, "image");
    if (file) {
        if (!cJSON_IsString(file) || !file->valuestring[0])
            return sg_fail(err, "%s: %s.image must be a file name", path, owner);
        int n = file->valuestring[0] == '/' ? snprintf(image, image_size, "%s", file->valuestring)
                                            : snprintf(image, image_size, "%s%s", b->base_dir, file->valuestring);
        if (n < 0 || (size_t)n >= image_size)
            return sg_fail(err, "%s: %s.image: file name too long", path, owner);
        l->image_path = image;
        double scale = 1;
        if (!member_color(path, light, owner, "radiance", l->rgb, err) ||
            !member_number(path, light, owner, "scale", 0, 1e30, &scale, err) ||
            !member_number(path, light, owner, "illuminance", 0, 1e30, &l->illuminance, err))
            return false;
        for (int c = 0; c < 3; c++)
            l->rgb[c] = (float)(l->rgb[c] * scale);
        const char *layout = cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(light, "layout"));
        if (layout && !strcmp(layout, "equal-area"))
            l->layout = SG_ENVIRONMENT_EQUAL_AREA;
        else if (layout && !strcmp(layout, "latlong"))
            l->layout = SG_ENVIRONMENT_LATLONG;
        else if (layout)
            return sg_fail(err, "%s: %s.layout must be \"equal-area\" or \"latlong\"", path, owner);
    } else if (!member_light_colour(path, light, owner, "radiance", l->rgb, err)) {
        return false;
    }
    double up[3] = {0, 1, 0}, x[3], y[3];
    if (!member_direction(path, light, owner, "up", false, up, err))
        return false;
    /* the map's x axis: the world axis least along up, made perpendicular */
    int a = fabs(up[0]) <= fabs(up[1]) && fabs(up[0]) <= fabs(up[2]) ? 0 : fabs(up[1]) <= fabs(up[2]) ? 1 : 2;
    double axis[3] = {a == 0, a == 1, a == 2};
    d3_unit_cross(up, axis, y);
    d3_cross(y, up, x);
    for (int r = 0; r < 3; r++) {
        l->light_to_world[r][0] = x[r];
        l->light_to_world[r][1] = y[r];
        l->light_to_world[r][2] = up[r];
    }
    const cJSON *portal = cJSON_GetObjectItemCaseSensitive(light, "portal");
    if (portal) {
        if (!cJSON_IsArray(portal) || cJSON_GetArraySize(portal) != 4)
            return sg_fail(err, "%s: %s.portal must hold 4 points", path, owner);
        for (int k = 0; k < 4; k++)
            if (!json_vec3(cJSON_GetArrayItem(portal, k), l->portal[k]))
                return sg_fail(err, "%s: %s.portal[%d] must be 3 finite numbers", path, owner, k);
        l->has_portal = true;
    }
    return true;
}

/* "sky", "sun", "point" and "spot" (README, "Scene format"). */
static bool light_source(Builder *b, const cJSON *light, const char *owner, const char *type, SgError *err)
{
    const char *path = b->json_path;
    SgLightSource l;
    memset(&l, 0, sizeof l);
    char image[4096];
    if (!strcmp(type, "sky")) {
        if (!sky_light(b, light, owner, &l, image, sizeof image, err))
            return false;
    } else if (!strcmp(type, "sun")) {
        double radius_deg = 0;
        l.kind = SG_LIGHT_DISTANT;
        if (!member_light_colour(path, light, owner, "irradiance", l.rgb, err) ||
            !member_direction(path, light, owner, "direction", true, l.direction, err) ||
            !member_number(path, light, owner, "angular_radius", 0, 90, &radius_deg, err))
            return false;
        l.angular_radius = radius_deg * M_PI / 180;
    } else {
        bool spot = !strcmp(type, "spot");
        l.kind = spot ? SG_LIGHT_SPOT : SG_LIGHT_POINT;
        bool has_position;
        if (!member_light_colour(path, light, owner, "intensity", l.rgb, err) ||
            !member_vec3(path, light, owner, "position", l.position, &has_position, err))
            return false;
        if (!has_position)
            return sg_fail(err, "%s: %s.position is missing", path, owner);
        if (spot) {
            double cone = 30, delta = 5;
            if (!member_direction(path, light, owner, "direction", true, l.direction, err) ||
                !member_number(path, light, owner, "cone_angle", 1e-3, 180, &cone, err) ||
                !member_number(path, light, owner, "cone_delta_angle", 0, cone, &delta, err))
                return false;
            l.cos_cone = cos(cone * M_PI / 180);
            l.cos_falloff_start = cos((cone - delta) * M_PI / 180);
        }
    }
    return sg_builder_add_light_source(&b->core, &l, err);
}

static bool load_lights(Builder *b, const cJSON *root, SgError *err)
{
    const cJSON *lights = cJSON_GetObjectItemCaseSensitive(root, "lights");
    if (!lights)
        return true;
    if (!cJSON_IsArray(lights))
        return sg_fail(err, "%s: \"lights\" must be an array", b->json_path);
    int index = 0;
    const cJSON *light;
    cJSON_ArrayForEach(light, lights)
    {
        char owner[32];
        snprintf(owner, sizeof owner, "lights[%d]", index++);
        const char *type = cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(light, "type"));
        if (type && (!strcmp(type, "sky") || !strcmp(type, "sun") || !strcmp(type, "point") || !strcmp(type, "spot"))) {
            if (!light_source(b, light, owner, type, err))
                return false;
            continue;
        }
        if (!type || strcmp(type, "quad"))
            return sg_fail(err, "%s: %s.type must be \"quad\", \"sky\", \"sun\", \"point\" or \"spot\"",
                           b->json_path, owner);
        const cJSON *corners = cJSON_GetObjectItemCaseSensitive(light, "corners");
        if (!cJSON_IsArray(corners) || cJSON_GetArraySize(corners) != 4)
            return sg_fail(err, "%s: %s.corners must hold 4 points", b->json_path, owner);
        SgMaterial m;
        sg_material_default(&m, owner);
        m.diffuse[0] = m.diffuse[1] = m.diffuse[2] = 0;
        if (!member_color(b->json_path, light, owner, "radiance", m.emission, err))
            return false;
        if (!cJSON_GetObjectItemCaseSensitive(light, "radiance"))
            return sg_fail(err, "%s: %s.radiance is missing", b->json_path, owner);
        uint32_t material;
        if (!sg_builder_add_material(&b->core, &m, &material, err) ||
            !sg_builder_add_vertices(&b->core, 4, err) ||
            !sg_builder_add_triangles(&b->core, 2, err))
            return false;
        SgScene *s = b->scene;
        uint32_t base = s->vertex_count;
        for (int c = 0; c < 4; c++) {
            double p[3];
            if (!json_vec3(cJSON_GetArrayItem(corners, c), p))
                return sg_fail(err, "%s: %s.corners[%d] must be 3 finite numbers", b->json_path,
                               owner, c);
            memcpy(s->positions + 3 * (size_t)(base + c), p, sizeof p);
        }
        s->vertex_count += 4;
        sg_builder_push_triangle(&b->core, base, base + 1, base + 2, material);
        sg_builder_push_triangle(&b->core, base, base + 2, base + 3, material);
    }
    return true;
}

/* ---- camera and settings ------------------------------------------------ */

static bool load_camera(Builder *b, const cJSON *root, SgError *err)
{
    SgScene *s = b->scene;
    const char *path = b->json_path;
    const cJSON *image = cJSON_GetObjectItemCaseSensitive(root, "image");
    s->camera.width = 320;
    s->camera.height = 240;
    if (image) {
        if (!cJSON_IsObject(image))
            return sg_fail(err, "%s: \"image\" must be an object", path);
        if (!member_int(path, image, "image", "width", 1, 65536, &s->camera.width, err) ||
            !member_int(path, image, "image", "height", 1, 65536, &s->camera.height, err))
            return false;
    }
    const cJSON *cam = cJSON_GetObjectItemCaseSensitive(root, "camera");
    if (!cam)
        return true;
    if (!cJSON_IsObject(cam))
        return sg_fail(err, "%s: \"camera\" must be an object", path);
    bool has_pos, has_look, has_up;
    double up[3] = {0, 1, 0};
    if (!member_vec3(path, cam, "camera", "position", s->camera.position, &has_pos, err) ||
        !member_vec3(path, cam, "camera", "look_at", s->camera.look_at, &has_look, err) ||
        !member_vec3(path, cam, "camera", "up", up, &has_up, err))
        return false;
    if (!has_pos || !has_look)
        return sg_fail(err, "%s: camera needs \"position\" and \"look_at\"", path);
    memcpy(s->camera.up, up, sizeof up);
    double fov = 60;
    if (!member_number(path, cam, "camera", "fov", 1e-3, 179.9, &fov, err))
        return false;
    const char *axis = cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(cam, "fov_axis"));
    double aspect = (double)s->camera.width / s->camera.height;
    bool horizontal = false;
    if (axis && !strcmp(axis, "horizontal"))
        horizontal = true;
    else if (axis && !strcmp(axis, "shorter"))
        horizontal = aspect < 1;
    else if (axis && strcmp(axis, "vertical"))
        return sg_fail(err, "%s: camera.fov_axis must be vertical, horizontal or shorter", path);
    if (horizontal)
        fov = 2 * atan(tan(fov * M_PI / 360) / aspect) * 180 / M_PI;
    s->camera.fov_deg = fov;
    double dir[3], side[3];
    d3_sub(s->camera.look_at, s->camera.position, dir);
    d3_cross(dir, up, side);
    if (!(d3_length(dir) > 0))
        return sg_fail(err, "%s: camera position and look_at coincide", path);
    if (!(d3_length(side) > 1e-9 * d3_length(dir) * d3_length(up)))
        return sg_fail(err, "%s: camera up is parallel to the view direction", path);
    s->has_camera = true;
    return true;
}

static bool load_settings(Builder *b, const cJSON *root, SgError *err)
{
    SgScene *s = b->scene;
    const char *path = b->json_path;
    s->render.max_depth = SG_MAX_DEPTH_DEFAULT;
    const cJSON *render = cJSON_GetObjectItemCaseSensitive(root, "render");
    if (render) {
        if (!cJSON_IsObject(render))
            return sg_fail(err, "%s: \"render\" must be an object", path);
        if (!member_int(path, render, "render", "spp", 1, 1 << 24, &s->render.spp, err) ||
            !member_int(path, render, "render", "max_depth", 1, 1024, &s->render.max_depth, err) ||
            !member_number(path, render, "render", "exposure", -64, 64, &s->render.exposure, err))
            return false;
    }
    const cJSON *voxel = cJSON_GetObjectItemCaseSensitive(root, "voxel");
    if (voxel) {
        if (!cJSON_IsObject(voxel))
            return sg_fail(err, "%s: \"voxel\" must be an object", path);
        if (!member_int(path, voxel, "voxel", "resolution", 1, SG_VOXEL_RESOLUTION_MAX, &s->voxel_resolution, err))
            return false;
    }
    return true;
}

/* ---- the file ----------------------------------------------------------- */

/* Line number of a byte offset, for parse errors. */
static int line_of(const char *text, const char *where)
{
    int line = 1;
    for (const char *c = text; c < where && *c; c++)
        line += *c == '\n';
    return line;
}

SgScene *sg_json_scene_load(const char *path, SgError *err)
{
    char *text;
    size_t size;
    if (!sg_read_file(path, NULL, SG_LIMIT_SCENE_TEXT, &text, &size, err))
        return NULL;
    cJSON *root = cJSON_ParseWithOpts(text, NULL, 1);
    if (!root) {
        const char *where = cJSON_GetErrorPtr();
        sg_fail(err, "%s: malformed JSON near line %d", path, where ? line_of(text, where) : 0);
        free(text);
        return NULL;
    }
    if (!cJSON_IsObject(root)) {
        sg_fail(err, "%s: the scene must be a JSON object", path);
        cJSON_Delete(root);
        free(text);
        return NULL;
    }
    Builder b = {.json_path = path};
    bool ok = sg_builder_begin(&b.core, path, err);
    SgScene *s = b.scene = b.core.scene;
    if (ok) {
        sg_builder_add_source(&b.core, text, size);
        sg_folder_of(path, b.base_dir, sizeof b.base_dir);
        b.material_overrides = cJSON_GetObjectItemCaseSensitive(root, "materials");
        if (b.material_overrides && !cJSON_IsObject(b.material_overrides))
            ok = sg_fail(err, "%s: \"materials\" must be an object", path);
        if (ok && b.material_overrides) {
            const cJSON *m;
            cJSON_ArrayForEach(m, b.material_overrides)
            {
                SgMaterial probe;
                sg_material_default(&probe, m->string);
                if (!apply_material_json(path, m, m->string, &probe, err)) {
                    ok = false;
                    break;
                }
            }
        }
    }
    ok = ok && load_camera(&b, root, err) && load_settings(&b, root, err) &&
         load_meshes(&b, root, err) && load_lights(&b, root, err);
    if (ok && s->triangle_count == 0)
        ok = sg_fail(err, "%s: the scene has no triangles%s", path,
                     b.core.dropped_degenerate ? " (all were degenerate)" : "");
    ok = ok && sg_builder_finish(&b.core, err);
    sg_builder_release(&b.core);
    cJSON_Delete(root);
    free(text);
    if (!ok) {
        sg_scene_free(s);
        return NULL;
    }
    return s;
}

