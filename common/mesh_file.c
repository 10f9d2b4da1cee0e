/* Mesh files into a scene under construction: PLY through our own strict
 * reader (ply_mesh.h), every other format through Assimp, whose raw output
 * is checked before its post-processing runs, with its materials (MTL,
 * glTF) and their diffuse maps. See docs/scene-format.md. */
#include "mesh_file.h"

#include <assimp/ObjMaterial.h>
#include <assimp/cimport.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "input_file.h"
#include "ply_mesh.h"
#include "vecmath.h"

/* ---- Assimp's materials ------------------------------------------------- */

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
static bool diffuse_texture(SgSceneBuilder *b, SgImageAverages *images, const struct aiMaterial *mat,
                            const char *file, const char *label, bool *warned_embedded, uint32_t *texture,
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
    bool gltf = sg_has_extension(file, ".gltf") || sg_has_extension(file, ".glb");
    float factor[3];
    memcpy(factor, mean, sizeof factor); /* glTF: the base colour read as Kd */
    SgTexture t = {.kind = SG_TEXTURE_IMAGE, .uscale = 1, .vscale = 1, .scale = 1};
    t.gamma = (float)sg_image_default_gamma(path);
    t.wrap = mode == aiTextureMapMode_Clamp ? SG_WRAP_CLAMP
             : mode == aiTextureMapMode_Decal ? SG_WRAP_BLACK
                                              : SG_WRAP_REPEAT;
    bool first;
    if (sg_image_average(images, path, t.gamma, t.mean, &first)) {
        t.path = path;
    } else {
        t.mean[0] = t.mean[1] = t.mean[2] = 0.5f;
        if (first)
            sg_scene_add_warning(b->scene, "%s: material \"%s\": texture \"%s\" cannot be read: "
                                           "taken as grey 0.5", file, label, path);
    }
    uint32_t id;
    if (!sg_builder_add_texture(b, &t, &id, err))
        return false;
    *texture = id + 1;
    memcpy(mean, t.mean, 3 * sizeof(float));
    if (gltf && (factor[0] != 1 || factor[1] != 1 || factor[2] != 1)) {
        SgTexture scale = {.kind = SG_TEXTURE_SCALE, .uscale = 1, .vscale = 1};
        scale.input[0].texture = *texture;
        memcpy(scale.input[1].value, factor, sizeof factor);
        for (int c = 0; c < 3; c++)
            mean[c] = scale.mean[c] = t.mean[c] * factor[c];
        if (!sg_builder_add_texture(b, &scale, &id, err))
            return false;
        *texture = id + 1;
    }
    return true;
}

/* Maps an Assimp (mostly MTL) material to ours, then lets the scene
 * description adjust it (rules->adjust: JSON "materials" of the same name). */
static bool convert_material(SgSceneBuilder *b, SgImageAverages *images, const struct aiMaterial *mat,
                             const char *file, uint32_t mesh_index, bool *warned_embedded,
                             const SgMeshFileMaterials *rules, SgMaterial *m, SgError *err)
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
    if (!diffuse_texture(b, images, mat, file, label, warned_embedded, &texture, m->diffuse, err))
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
    return !rules->adjust || rules->adjust(rules, label, m, err);
}

/* ---- the files ---------------------------------------------------------- */

static bool load_ply_file(SgSceneBuilder *b, const char *file, const SgTransform *xf,
                          const SgMeshFileMaterials *rules, SgError *err)
{
    SgPlyMesh mesh;
    if (!sg_ply_mesh_read(&mesh, file, err))
        return false;
    uint32_t material;
    bool ok = rules->plain(rules, file, &material, err) &&
              sg_builder_append_mesh(b, file, mesh.positions, mesh.vertex_count,
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

static bool load_assimp_file(SgSceneBuilder *b, SgImageAverages *images, const char *file,
                             const SgTransform *xf, const SgMeshFileMaterials *rules, SgError *err)
{
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
    if (rules->name || as->mNumMaterials == 0)
        ok = rules->plain(rules, file, &override_id, err);
    uint32_t *material_ids = calloc(as->mNumMaterials ? as->mNumMaterials : 1, sizeof(uint32_t));
    if (ok && !material_ids)
        ok = sg_fail(err, "%s: out of memory", file);
    bool warned_embedded = false;
    for (unsigned m = 0; ok && m < as->mNumMaterials && override_id == UINT32_MAX; m++) {
        SgMaterial mat;
        ok = convert_material(b, images, as->mMaterials[m], file, m, &warned_embedded, rules, &mat, err);
        if (ok && rules->emission)
            memcpy(mat.emission, rules->emission, sizeof mat.emission);
        ok = ok && sg_builder_add_material(b, &mat, &material_ids[m], err);
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
        ok = sg_builder_append_mesh(b, file, positions, mesh->mNumVertices, indices,
                                    triangles, xf, material, err) &&
             (!tc || sg_builder_set_uvs(b, first, mesh->mNumVertices, uvs, err));
    }
    free(positions);
    free(indices);
    free(uvs);
    free(material_ids);
    aiReleaseImport(as);
    return ok;
}

bool sg_mesh_file_load(SgSceneBuilder *builder, SgImageAverages *images, const char *file,
                       const SgTransform *xf, const SgMeshFileMaterials *materials, SgError *err)
{
    if (sg_has_extension(file, ".ply"))
        return load_ply_file(builder, file, xf, materials, err);
    return load_assimp_file(builder, images, file, xf, materials, err);
}
