/* What the scene readers (JSON: scene_json.c with mesh_file.c, pbrt: pbrt/,
 * Mitsuba: mitsuba/) share: the flat world-space arrays of an SgScene grown
 * as meshes arrive, degenerate triangles dropped, the tally of what they
 * could not honour, and the finishing pass that groups emissive triangles
 * into lights and computes the bounds and the geometry hash. */
#ifndef SG_SCENE_BUILDER_H
#define SG_SCENE_BUILDER_H

#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "error.h"
#include "image_average.h"
#include "scene.h"
#include "transform.h"

/* What a reader could not honour, once per kind: the first place it
 * happened and how many times. */
typedef struct SgBuilderWarning {
    char kind[160];
    char where[4200]; /* file:line of the first occurrence */
    uint32_t count;
} SgBuilderWarning;

/* A reader's material made emissive by an area light: its scene copy
 * with that radiance. */
typedef struct SgBuilderEmissive {
    size_t material; /* the reader's own index of the material */
    float radiance[3];
    uint32_t scene_id;
} SgBuilderEmissive;

typedef struct SgSceneBuilder {
    SgScene *scene;
    const char *path; /* the scene file, for messages */
    uint32_t vertex_capacity, triangle_capacity, material_capacity, texture_capacity, uv_capacity;
    uint32_t dropped_degenerate;
    SgBuilderWarning *warnings;
    size_t warning_count;
    SgBuilderEmissive *emissive;
    size_t emissive_count;
    SgImageAverages images; /* image files read for textures' means, by path */
} SgSceneBuilder;

/* Allocates the scene; on failure returns false and b->scene is NULL. */
bool sg_builder_begin(SgSceneBuilder *b, const char *path, SgError *err);

/* Adds a scene file's text to the scene's source_hash. */
void sg_builder_add_source(SgSceneBuilder *b, const char *text, size_t size);

/* Diffuse grey 0.5, ior 1.5, no emission; as a conductor, copper. */
void sg_material_default(SgMaterial *m, const char *name);
bool sg_builder_add_material(SgSceneBuilder *b, const SgMaterial *m, uint32_t *id, SgError *err);
/* *id: the scene material that is the reader's material number `material`
 * (m) emitting radiance, added on its first use, the same after. */
bool sg_builder_emissive_material(SgSceneBuilder *b, size_t material, const SgMaterial *m,
                                  const float radiance[3], uint32_t *id, SgError *err);

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

/* Meshes kept for instancing (pbrt's ObjectBegin, Mitsuba's shapegroup):
 * copies in the definition's space, placed by each instance's transform. */
typedef struct SgGroupShape {
    double *positions;
    float *uvs; /* 2 per vertex, or NULL */
    uint32_t vertex_count;
    uint32_t *indices;
    uint32_t triangle_count;
    uint32_t material; /* the scene's material */
} SgGroupShape;

typedef struct SgShapeGroup {
    SgGroupShape *shapes;
    size_t shape_count, shape_capacity;
} SgShapeGroup;

/* Keeps a copy of a mesh (indices already bounds-checked), its positions
 * moved by xf, in g; path names the scene in messages. */
bool sg_shape_group_add(SgShapeGroup *g, const char *path, const double *positions, uint32_t vertex_count,
                        const uint32_t *indices, uint32_t triangle_count, const float *uvs,
                        const SgTransform *xf, uint32_t material, SgError *err);
/* Appends every mesh of g moved by xf (an instance); what names it in messages. */
bool sg_builder_add_group(SgSceneBuilder *b, const char *what, const SgShapeGroup *g, const SgTransform *xf,
                          SgError *err);
void sg_shape_group_release(SgShapeGroup *g);

/* Texture coordinates of vertices [first, first + count) (already added);
 * vertices given none keep (0, 0). Non-finite values become 0. */
bool sg_builder_set_uvs(SgSceneBuilder *b, uint32_t first, uint32_t count, const float *uv, SgError *err);
/* Appends a texture (its path copied); *id its index. */
bool sg_builder_add_texture(SgSceneBuilder *b, const SgTexture *t, uint32_t *id, SgError *err);

/* Appends a point, spot, distant or infinite light (its image path copied);
 * fails on a negative or non-finite radiance. */
bool sg_builder_add_light_source(SgSceneBuilder *b, const SgLightSource *light, SgError *err);

/* Groups lights, computes bounds and hash, records the degenerate count,
 * then adds the tallied warnings to the scene ("where: kind (N times)").
 * The caller has checked that there are triangles. */
bool sg_builder_finish(SgSceneBuilder *b, SgError *err);
/* Frees what the builder holds besides the scene (the scene stays the
 * caller's); on every way out of a reader that began one. */
void sg_builder_release(SgSceneBuilder *b);

/* Tallies a warning, its kind printed from fmt, at where (a place
 * "file:line"): the first place of a kind is kept, the next ones counted. Never fails: a
 * warning lost to a full memory is not worth an error. */
void sg_builder_warnv(SgSceneBuilder *b, const char *where, const char *fmt, va_list ap);

/* Appends one warning line to the scene (kept short; never fails: a
 * warning lost to a full memory is not worth an error). */
void sg_scene_add_warning(SgScene *scene, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

#endif
