/* Scene loading: the JSON description (cJSON) and its meshes (Assimp);
 * a .pbrt file goes to pbrt/. Both fill the flat world-space arrays
 * through scene_builder.h. See README.md, "Scene format". */
#include "scene.h"

#include <assimp/ObjMaterial.h>
#include <assimp/cimport.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <cjson/cJSON.h>
#include <errno.h>
#include <glob.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "image_average.h"
#include "input_file.h"
#include "pbrt_scene.h"
#include "ply_mesh.h"
#include "scene_builder.h"
#include "vecmath.h"

typedef struct Builder {
    SgSceneBuilder core;
    SgScene *scene;         /* core.scene */
    const char *json_path;  /* core.path */
    char base_dir[4096];
    const cJSON *material_overrides; /* the "materials" object, or NULL */
    SgImageAverages images;          /* texture files read, by path */
} Builder;

static bool has_extension(const char *file, const char *ext)
{
    size_t n = strlen(file), e = strlen(ext);
    return n > e && !strcasecmp(file + n - e, ext);
}

/* ---- JSON helpers ------------------------------------------------------- */

static bool json_vec3(const cJSON *item, double out[3])
{
    if (!cJSON_IsArray(item) || cJSON_GetArraySize(item) != 3)
        return false;
    for (int a = 0; a < 3; a++) {
        const cJSON *v = cJSON_GetArrayItem(item, a);
        if (!cJSON_IsNumber(v) || !isfinite(v->valuedouble))
            return false;
        out[a] = v->valuedouble;
    }
    return true;
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

static void read_color(const struct aiMaterial *mat, const char *key, unsigned type,
                       unsigned index, float out[3])
{
    struct aiColor4D c;
    if (aiGetMaterialColor(mat, key, type, index, &c) == AI_SUCCESS) {
        out[0] = isfinite(c.r) && c.r > 0 ? c.r : 0;
        out[1] = isfinite(c.g) && c.g > 0 ? c.g : 0;
        out[2] = isfinite(c.b) && c.b > 0 ? c.b : 0;
    }
}

/* The diffuse map of an Assimp material: MTL map_Kd, glTF base colour. */
static bool diffuse_map_path(const struct aiMaterial *mat, struct aiString *path,
                             enum aiTextureMapMode *mode)
{
    static const enum aiTextureType types[] = {aiTextureType_DIFFUSE, aiTextureType_BASE_COLOR};
    for (size_t i = 0; i < sizeof types / sizeof *types; i++) {
        enum aiTextureMapMode modes[2] = {aiTextureMapMode_Wrap, aiTextureMapMode_Wrap};
        if (aiGetMaterialTexture(mat, types[i], 0, path, NULL, NULL, NULL, NULL, modes, NULL) ==
                AI_SUCCESS &&
            path->length) {
            *mode = modes[0];
            return true;
        }
    }
    return false;
}

/* A material's diffuse map as a scene texture: *texture its 1 + index (0:
 * none); mean holds the material's Kd (glTF: base colour) and becomes the
 * texture's mean when there is one.
 *
 * Semantics: an MTL map_Kd replaces Kd, as in pbrt and Blender, not Kd x
 * map as the MTL specification says: exporters such as 3ds Max's (the
 * Dabrovic Sponza's MTL) write beside each map a Kd near the map's own
 * mean (0.53 to 0.83 there), so the product would darken such scenes a
 * second time. glTF's base colour factor multiplies its texture, as its
 * specification says (a scale texture when the factor is not white).
 *
 * A file that cannot be read is a grey 0.5 texture without a path, as in
 * the pbrt loader: a comparison can tell it, the render is grey there.
 * Embedded textures (glTF "*N") are not supported: the colour stays. */
static bool diffuse_texture(Builder *b, const struct aiMaterial *mat, const char *file,
                            const char *label, bool *warned_embedded, uint32_t *texture,
                            float mean[3], SgError *err)
{
    *texture = 0;
    struct aiString name;
    enum aiTextureMapMode mode;
    if (!diffuse_map_path(mat, &name, &mode))
        return true;
    if (name.data[0] == '*') {
        if (!*warned_embedded)
            sg_scene_add_warning(b->scene, "%s: embedded textures are not supported: its materials "
                                           "keep their colour", file);
        *warned_embedded = true;
        return true;
    }
    char path[8192];
    const char *slash = strrchr(file, '/');
    if (name.data[0] == '/')
        snprintf(path, sizeof path, "%s", name.data);
    else
        snprintf(path, sizeof path, "%.*s%s", slash ? (int)(slash - file + 1) : 0, file, name.data);
    /* Windows exporters write "textures\wall.png" */
    for (char *c = path; *c; c++)
        if (*c == '\\')
            *c = '/';
    bool gltf = has_extension(file, ".gltf") || has_extension(file, ".glb");
    float factor[3];
    memcpy(factor, mean, sizeof factor); /* glTF: the base colour read as Kd */
    SgTexture t = {.kind = SG_TEXTURE_IMAGE, .uscale = 1, .vscale = 1, .scale = 1};
    t.gamma = (float)sg_image_default_gamma(path);
    t.wrap = mode == aiTextureMapMode_Clamp ? SG_WRAP_CLAMP
             : mode == aiTextureMapMode_Decal ? SG_WRAP_BLACK
                                              : SG_WRAP_REPEAT;
    bool first;
    if (sg_image_average(&b->images, path, t.gamma, t.mean, &first)) {
        t.path = path;
    } else {
        t.mean[0] = t.mean[1] = t.mean[2] = 0.5f;
        if (first)
            sg_scene_add_warning(b->scene, "%s: material \"%s\": texture \"%s\" cannot be read: "
                                           "taken as grey 0.5", file, label, path);
    }
    uint32_t id;
    if (!sg_builder_add_texture(&b->core, &t, &id, err))
        return false;
    *texture = id + 1;
    memcpy(mean, t.mean, 3 * sizeof(float));
    if (gltf && (factor[0] != 1 || factor[1] != 1 || factor[2] != 1)) {
        SgTexture scale = {.kind = SG_TEXTURE_SCALE, .uscale = 1, .vscale = 1};
        scale.input[0].texture = *texture;
        memcpy(scale.input[1].value, factor, sizeof factor);
        for (int c = 0; c < 3; c++)
            mean[c] = scale.mean[c] = t.mean[c] * factor[c];
        if (!sg_builder_add_texture(&b->core, &scale, &id, err))
            return false;
        *texture = id + 1;
    }
    return true;
}

/* Maps an Assimp (mostly MTL) material to ours; JSON "materials" entries of
 * the same name override it. */
static bool convert_material(Builder *b, const struct aiMaterial *mat, const char *file,
                             uint32_t mesh_index, bool *warned_embedded, SgMaterial *m,
                             SgError *err)
{
    struct aiString name;
    char label[64];
    if (aiGetMaterialString(mat, AI_MATKEY_NAME, &name) == AI_SUCCESS && name.length)
        snprintf(label, sizeof label, "%.63s", name.data);
    else
        snprintf(label, sizeof label, "mesh%u", mesh_index);
    sg_material_default(m, label);
    m->diffuse[0] = m->diffuse[1] = m->diffuse[2] = 0;
    read_color(mat, AI_MATKEY_COLOR_DIFFUSE, m->diffuse);
    read_color(mat, AI_MATKEY_COLOR_SPECULAR, m->specular);
    read_color(mat, AI_MATKEY_COLOR_EMISSIVE, m->emission);
    /* the map's mean stands for Kd in what follows (the type, the energy) */
    uint32_t texture;
    if (!diffuse_texture(b, mat, file, label, warned_embedded, &texture, m->diffuse, err))
        return false;
    float shininess = 0, ior = 1.5f, opacity = 1;
    int illum = 2;
    unsigned one = 1;
    aiGetMaterialFloatArray(mat, AI_MATKEY_SHININESS, &shininess, &one);
    one = 1;
    aiGetMaterialFloatArray(mat, AI_MATKEY_REFRACTI, &ior, &one);
    one = 1;
    aiGetMaterialFloatArray(mat, AI_MATKEY_OPACITY, &opacity, &one);
    one = 1;
    aiGetMaterialIntegerArray(mat, AI_MATKEY_OBJ_ILLUM, &illum, &one);
    if (!isfinite(shininess) || shininess < 0)
        shininess = 0;
    if (!isfinite(ior) || ior < 1)
        ior = 1.5f;
    m->exponent = shininess;
    m->ior = ior;
    float ks = v3_max_component(v3(m->specular[0], m->specular[1], m->specular[2]));
    float kd = v3_max_component(v3(m->diffuse[0], m->diffuse[1], m->diffuse[2]));
    if ((illum == 4 || illum == 6 || illum == 7 || opacity < 1) && ior > 1.0f)
        m->type = SG_MATERIAL_DIELECTRIC;
    else if (illum == 3 || (ks > 0 && kd == 0 && shininess >= 1000))
        m->type = SG_MATERIAL_MIRROR;
    else if (ks > 0 && illum != 1)
        m->type = SG_MATERIAL_GLOSSY;
    else
        m->type = SG_MATERIAL_DIFFUSE;
    if (m->type == SG_MATERIAL_DIFFUSE)
        memset(m->specular, 0, sizeof m->specular);
    /* Scale down what would create energy. */
    for (int a = 0; a < 3; a++) {
        float sum = m->diffuse[a] + (m->type == SG_MATERIAL_GLOSSY ? m->specular[a] : 0);
        if (sum > 0.999f) {
            float k = 0.999f / sum;
            m->diffuse[a] *= k;
            m->specular[a] *= k;
        }
    }
    /* a texture varies the albedo of diffuse and glossy materials only */
    if (m->type == SG_MATERIAL_DIFFUSE || m->type == SG_MATERIAL_GLOSSY)
        m->diffuse_texture = texture;
    const cJSON *override = b->material_overrides
                                ? cJSON_GetObjectItemCaseSensitive(b->material_overrides, label)
                                : NULL;
    if (override && !apply_material_json(b->json_path, override, label, m, err))
        return false;
    /* an override's own albedo, or a type the texture does not suit, wins */
    if (override && (cJSON_GetObjectItemCaseSensitive(override, "albedo") ||
                     (m->type != SG_MATERIAL_DIFFUSE && m->type != SG_MATERIAL_GLOSSY &&
                      m->type != SG_MATERIAL_COATED_DIFFUSE)))
        m->diffuse_texture = 0;
    return true;
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
        for (int i = 0; i < 16; i++) {
            const cJSON *x = cJSON_GetArrayItem(matrix, i);
            if (!cJSON_IsNumber(x) || !isfinite(x->valuedouble))
                return sg_fail(err, "%s: %s.transform.matrix must hold finite numbers", path,
                               owner);
            v[i] = x->valuedouble;
        }
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
        for (int i = 0; i < 4; i++) {
            const cJSON *x = cJSON_GetArrayItem(rotate, i);
            if (!cJSON_IsNumber(x) || !isfinite(x->valuedouble))
                return sg_fail(err, "%s: %s.transform.rotate must hold finite numbers", path,
                               owner);
            v[i] = x->valuedouble;
        }
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
static bool plain_material(Builder *b, const char *file, const char *material_name,
                           const float *emission, uint32_t *id, SgError *err)
{
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

static bool load_ply_file(Builder *b, const char *file, const SgTransform *xf,
                          const char *material_name, const float *emission, SgError *err)
{
    SgPlyMesh mesh;
    if (!sg_ply_mesh_read(&mesh, file, err))
        return false;
    uint32_t material;
    bool ok = plain_material(b, file, material_name, emission, &material, err) &&
              sg_builder_append_mesh(&b->core, file, mesh.positions, mesh.vertex_count,
                                     mesh.indices, mesh.triangle_count, xf, material, err);
    sg_ply_mesh_release(&mesh);
    return ok;
}

/* Assimp's post-processing trusts the importer's indices and coordinates;
 * a bad file can make it fault or hide a NaN. Check them first: NULL if
 * sane, else what is wrong. */
static const char *assimp_scene_problem(const struct aiScene *as)
{
    for (unsigned mi = 0; mi < as->mNumMeshes; mi++) {
        const struct aiMesh *mesh = as->mMeshes[mi];
        if (!mesh || (mesh->mNumVertices && !mesh->mVertices))
            return "malformed mesh (no vertex data)";
        for (unsigned v = 0; v < mesh->mNumVertices; v++)
            if (!isfinite(mesh->mVertices[v].x) || !isfinite(mesh->mVertices[v].y) ||
                !isfinite(mesh->mVertices[v].z))
                return "a vertex has a non-finite vertex coordinate";
        for (unsigned f = 0; f < mesh->mNumFaces; f++) {
            const struct aiFace *face = &mesh->mFaces[f];
            if (face->mNumIndices && !face->mIndices)
                return "malformed mesh (face without indices)";
            for (unsigned i = 0; i < face->mNumIndices; i++)
                if (face->mIndices[i] >= mesh->mNumVertices)
                    return "malformed mesh (face index out of range)";
        }
    }
    return NULL;
}

static bool load_mesh_file(Builder *b, const char *file, const SgTransform *xf,
                           const char *material_name, const float *emission, SgError *err)
{
    if (has_extension(file, ".ply"))
        return load_ply_file(b, file, xf, material_name, emission, err);
    const struct aiScene *as = aiImportFile(file, 0);
    if (!as) {
        const char *why = aiGetErrorString();
        FILE *probe = fopen(file, "rb");
        if (!probe)
            return sg_fail(err, "%s: cannot open mesh: %s", file, strerror(errno));
        fclose(probe);
        return sg_fail(err, "%s: cannot read mesh: %s", file, why && *why ? why : "unknown format");
    }
    const char *problem = assimp_scene_problem(as);
    if (problem) {
        aiReleaseImport(as);
        return sg_fail(err, "%s: %s", file, problem);
    }
    as = aiApplyPostProcessing(as, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                       aiProcess_PreTransformVertices | aiProcess_SortByPType);
    if (!as)
        return sg_fail(err, "%s: cannot process mesh: %s", file, aiGetErrorString());
    bool ok = true;
    uint32_t override_id = UINT32_MAX;
    if (material_name || as->mNumMaterials == 0)
        ok = plain_material(b, file, material_name, emission, &override_id, err);
    uint32_t *material_ids = calloc(as->mNumMaterials ? as->mNumMaterials : 1, sizeof(uint32_t));
    if (ok && !material_ids)
        ok = sg_fail(err, "%s: out of memory", file);
    bool warned_embedded = false;
    for (unsigned m = 0; ok && m < as->mNumMaterials && override_id == UINT32_MAX; m++) {
        SgMaterial mat;
        ok = convert_material(b, as->mMaterials[m], file, m, &warned_embedded, &mat, err);
        if (ok && emission)
            memcpy(mat.emission, emission, sizeof mat.emission);
        ok = ok && sg_builder_add_material(&b->core, &mat, &material_ids[m], err);
    }
    double *positions = NULL;
    uint32_t *indices = NULL;
    float *uvs = NULL;
    for (unsigned mi = 0; ok && mi < as->mNumMeshes; mi++) {
        const struct aiMesh *mesh = as->mMeshes[mi];
        if (!(mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE))
            continue;
        double *p = realloc(positions, (mesh->mNumVertices + 1) * 3 * sizeof(double));
        uint32_t *ix = realloc(indices, (mesh->mNumFaces + 1) * 3 * sizeof(uint32_t));
        const struct aiVector3D *tc = mesh->mTextureCoords[0];
        float *uv = tc ? realloc(uvs, (mesh->mNumVertices + 1) * 2 * sizeof(float)) : uvs;
        if (p)
            positions = p;
        if (ix)
            indices = ix;
        if (uv)
            uvs = uv;
        if (!p || !ix || (tc && !uv)) {
            ok = sg_fail(err, "%s: out of memory", file);
            break;
        }
        for (unsigned v = 0; v < mesh->mNumVertices; v++) {
            positions[3 * v + 0] = mesh->mVertices[v].x;
            positions[3 * v + 1] = mesh->mVertices[v].y;
            positions[3 * v + 2] = mesh->mVertices[v].z;
        }
        uint32_t triangles = 0;
        for (unsigned f = 0; f < mesh->mNumFaces; f++) {
            const struct aiFace *face = &mesh->mFaces[f];
            if (face->mNumIndices != 3)
                continue;
            memcpy(indices + 3 * (size_t)triangles++, face->mIndices, 3 * sizeof(uint32_t));
        }
        uint32_t material = override_id != UINT32_MAX ? override_id
                            : mesh->mMaterialIndex < as->mNumMaterials
                                ? material_ids[mesh->mMaterialIndex]
                                : material_ids[0];
        /* Assimp gives every format's uv with v up from the image's
         * bottom row (it flips glTF's), as pbrt's and so the renderer's
         * lookups expect: no flip here */
        for (unsigned v = 0; tc && v < mesh->mNumVertices; v++) {
            uvs[2 * v + 0] = tc[v].x;
            uvs[2 * v + 1] = tc[v].y;
        }
        uint32_t first = b->scene->vertex_count;
        ok = sg_builder_append_mesh(&b->core, file, positions, mesh->mNumVertices, indices,
                                    triangles, xf, material, err) &&
             (!tc || sg_builder_set_uvs(&b->core, first, mesh->mNumVertices, uvs, err));
    }
    free(positions);
    free(indices);
    free(uvs);
    free(material_ids);
    aiReleaseImport(as);
    return ok;
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
                for (size_t i = 0; ok && i < g.gl_pathc; i++)
                    ok = load_mesh_file(b, g.gl_pathv[i], &xf, material_name,
                                        em ? emission : NULL, err);
                globfree(&g);
            }
        }
        if (!ok)
            break;
    }
    cJSON_Delete(owned);
    return ok;
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
        if (!type || strcmp(type, "quad"))
            return sg_fail(err, "%s: %s.type must be \"quad\"", b->json_path, owner);
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

/* ---- lights from emissive triangles ------------------------------------- */

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
    s->render.max_depth = 8;
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
        if (!member_int(path, voxel, "voxel", "resolution", 1, 4096, &s->voxel_resolution, err))
            return false;
    }
    return true;
}

/* ---- finishing ---------------------------------------------------------- */


/* Line number of a byte offset, for parse errors. */
static int line_of(const char *text, const char *where)
{
    int line = 1;
    for (const char *c = text; c < where && *c; c++)
        line += *c == '\n';
    return line;
}

static SgScene *load_json_scene(const char *path, SgError *err)
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
        const char *slash = strrchr(path, '/');
        snprintf(b.base_dir, sizeof b.base_dir, "%.*s", slash ? (int)(slash - path + 1) : 0, path);
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
    sg_image_averages_free(&b.images);
    cJSON_Delete(root);
    free(text);
    if (!ok) {
        sg_scene_free(s);
        return NULL;
    }
    return s;
}

SgScene *sg_scene_load(const char *path, SgError *err)
{
    if (has_extension(path, ".pbrt") || has_extension(path, ".pbrt.gz"))
        return sg_pbrt_scene_load(path, err);
    return load_json_scene(path, err);
}
