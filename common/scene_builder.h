/* What the scene front ends (JSON: scene_json.c with mesh_file.c, pbrt: pbrt/) share: the
 * flat world-space arrays of an SgScene grown as meshes arrive, degenerate
 * triangles dropped, and the finishing pass that groups emissive triangles
 * into lights and computes the bounds and the geometry hash. */
#ifndef SG_SCENE_BUILDER_H
#define SG_SCENE_BUILDER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "error.h"
#include "scene.h"
#include "transform.h"

typedef struct SgSceneBuilder {
    SgScene *scene;
    const char *path; /* the scene file, for messages */
    uint32_t vertex_capacity, triangle_capacity, material_capacity, texture_capacity, uv_capacity;
    uint32_t dropped_degenerate;
} SgSceneBuilder;

/* Allocates the scene; on failure returns false and b->scene is NULL. */
bool sg_builder_begin(SgSceneBuilder *b, const char *path, SgError *err);

/* Adds a scene file's text to the scene's source_hash. */
void sg_builder_add_source(SgSceneBuilder *b, const char *text, size_t size);

/* Diffuse grey 0.5, ior 1.5, no emission; as a conductor, copper. */
void sg_material_default(SgMaterial *m, const char *name);
bool sg_builder_add_material(SgSceneBuilder *b, const SgMaterial *m, uint32_t *id, SgError *err);

/* Reserve room for count more vertices / triangles (does not add them). */
bool sg_builder_add_vertices(SgSceneBuilder *b, uint32_t count, SgError *err);
bool sg_builder_add_triangles(SgSceneBuilder *b, uint32_t count, SgError *err);
/* Appends one triangle whose vertices are in the vertex array (room
 * reserved); a zero-area triangle is dropped and counted. */
void sg_builder_push_triangle(SgSceneBuilder *b, uint32_t i0, uint32_t i1, uint32_t i2,
                              uint32_t material);
/* Fails with "what has a non-finite vertex coordinate". */
bool sg_builder_check_point(SgSceneBuilder *b, const char *what, const double p[3], SgError *err);
/* Appends a mesh (indices already bounds-checked) transformed by xf with
 * one material; file names it in messages. */
bool sg_builder_append_mesh(SgSceneBuilder *b, const char *file, const double *positions,
                            uint32_t vertex_count, const uint32_t *indices,
                            uint32_t triangle_count, const SgTransform *xf, uint32_t material,
                            SgError *err);

/* Texture coordinates of vertices [first, first + count) (already added);
 * vertices given none keep (0, 0). Non-finite values become 0. */
bool sg_builder_set_uvs(SgSceneBuilder *b, uint32_t first, uint32_t count, const float *uv, SgError *err);
/* Appends a texture (its path copied); *id its index. */
bool sg_builder_add_texture(SgSceneBuilder *b, const SgTexture *t, uint32_t *id, SgError *err);

/* Appends a point, spot, distant or infinite light (its image path copied);
 * fails on a negative or non-finite radiance. */
bool sg_builder_add_light_source(SgSceneBuilder *b, const SgLightSource *light, SgError *err);

/* Groups lights, computes bounds and hash, records the degenerate count.
 * The caller has checked that there are triangles. */
bool sg_builder_finish(SgSceneBuilder *b, SgError *err);

/* Appends one warning line to the scene (kept short; never fails: a
 * warning lost to a full memory is not worth an error). */
void sg_scene_add_warning(SgScene *scene, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

#endif
