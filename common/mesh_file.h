/* A mesh file into a scene under construction: PLY through our own reader
 * (ply_mesh.h), every other format through Assimp, with its materials and
 * their diffuse maps (docs/scene-format.md). The scene description
 * that names the file (scene_json.c) decides its materials through
 * SgMeshFileMaterials. */
#ifndef SG_MESH_FILE_H
#define SG_MESH_FILE_H

#include <stdbool.h>
#include <stdint.h>

#include "error.h"
#include "image_average.h"
#include "scene_builder.h"
#include "transform.h"

typedef struct SgMeshFileMaterials SgMeshFileMaterials;
struct SgMeshFileMaterials {
    /* The material of every triangle of the file, by name; NULL: the file's own. */
    const char *name;
    /* Given to every material of the file; NULL: what the file says. */
    const float *emission;
    /* The scene's material for the file's triangles when `name` is set or
     * the file has no material of its own (called once the file is read). */
    bool (*plain)(const SgMeshFileMaterials *rules, const char *file, uint32_t *id, SgError *err);
    /* Optional: changes a material converted from the file (named `label`)
     * before it is added. */
    bool (*adjust)(const SgMeshFileMaterials *rules, const char *label, SgMaterial *m, SgError *err);
    void *context; /* the callbacks' */
};

/* Appends the file's triangles transformed by xf; images holds the texture
 * files read so far (each read once). Fails with "FILE: cause". */
bool sg_mesh_file_load(SgSceneBuilder *builder, SgImageAverages *images, const char *file,
                       const SgTransform *xf, const SgMeshFileMaterials *materials, SgError *err);

#endif
