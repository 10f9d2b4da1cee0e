/* Mitsuba scene files: the reader's state and the functions its files
 * share. The public entry point is mitsuba_scene.h.
 *
 * The file is read whole into an XML tree (xml_tree.h) and walked in
 * document order, as Mitsuba does: an `id` is known from its element on,
 * a `<ref>` to anything not seen yet is an error. Property names are
 * compared in Mitsuba 3's snake_case; a file whose scene version is below 2
 * has its camelCase names (toWorld, intIOR, sampleCount) converted first,
 * as Mitsuba 3 upgrades old files. `$name` in an attribute is replaced by
 * the value of the `<default name=...>` seen before it.
 *
 * Calls go down the list, never back up: props.c (properties, colours,
 * spectra, transforms), serialized.c, materials.c (bsdfs, textures),
 * shapes.c, and loader.c (the walk, emitters, sensor, entry point). */
#ifndef SG_MITSUBA_PARSER_H
#define SG_MITSUBA_PARSER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "error.h"
#include "image_average.h"
#include "ply_mesh.h"
#include "scene_builder.h"
#include "transform.h"
#include "xml_tree.h"

#define MTS_MAX_INCLUDE_DEPTH 32

typedef struct MtsDefault {
    char *name, *value;
} MtsDefault;

typedef struct MtsId {
    const char *id; /* the element's own attribute */
    const XmlNode *node;
} MtsId;

/* A bsdf turned into a scene material (once per element). */
typedef struct MtsMaterial {
    const XmlNode *node; /* NULL: the default diffuse */
    SgMaterial material;
    bool invisible; /* "null": the shape only bounds a medium */
    uint32_t scene_id; /* UINT32_MAX until a shape uses it */
} MtsMaterial;

typedef struct MtsTexture {
    const XmlNode *node;
    uint32_t scene_texture; /* 1 + index; 0: a constant */
    float mean[3];
} MtsTexture;

/* A shape of a shapegroup, in the group's space. */
typedef struct MtsGroup {
    const XmlNode *node;
    SgShapeGroup shapes;
} MtsGroup;

typedef struct MtsParser {
    SgSceneBuilder core;
    SgError *err;
    char base_dir[4096];

    XmlDoc **docs; /* every file read, kept until the end */
    size_t doc_count, doc_capacity;
    char *include_stack[MTS_MAX_INCLUDE_DEPTH]; /* real paths, for cycles */
    int include_depth;
    char **search_dirs; /* from <path value=...> */
    size_t search_dir_count, search_dir_capacity;

    MtsDefault *defaults;
    size_t default_count, default_capacity;
    MtsId *ids;
    size_t id_count, id_capacity;
    MtsMaterial *materials;
    size_t material_count, material_capacity;
    MtsTexture *textures;
    size_t texture_count, texture_capacity;
    MtsGroup *groups;
    size_t group_count, group_capacity;
    MtsGroup *defining; /* inside a shapegroup */

    bool has_sensor;
    char unsupported_emitter[64]; /* the first emitter type left out, for "no light" */
} MtsParser;

/* ---- props.c ------------------------------------------------------------ */

bool mts_reserve(MtsParser *p, void **array, size_t *capacity, size_t needed, size_t item);
#define MTS_RESERVE(p, array, count, capacity, extra)                                            \
    mts_reserve((p), (void **)&(array), &(capacity), (count) + (extra), sizeof *(array))

/* "file:line: cause"; returns false. */
bool mts_fail(MtsParser *p, const XmlNode *at, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
/* One warning per kind: the first place and how many times. */
void mts_warn(MtsParser *p, const XmlNode *at, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

/* Replaces "$name" in n's attribute values (once). */
bool mts_substitute(MtsParser *p, XmlNode *n);
/* An attribute of n after substitution (NULL: absent or failed: check p->err). */
const char *mts_attr(MtsParser *p, const XmlNode *n, const char *name);
/* The element an id names (NULL: unknown). */
const XmlNode *mts_lookup_id(const MtsParser *p, const char *id);
bool mts_register_id(MtsParser *p, const XmlNode *n);
/* A child's "name" in snake_case (old files converted); "" if none. */
void mts_child_name(MtsParser *p, const XmlNode *child, char *out, size_t size);
/* The child of obj named `name` (a property, a nested object, or what a
 * <ref name=...> names); *out NULL if absent. False on an error. */
bool mts_find(MtsParser *p, const XmlNode *obj, const char *name, const XmlNode **out);
/* Nested objects by tag (bsdf, texture, emitter, ...), refs resolved:
 * the index-th one, *out NULL when there are fewer. */
bool mts_find_object(MtsParser *p, const XmlNode *obj, const char *tag, size_t index, const XmlNode **out);
bool mts_is_tag(const XmlNode *n, const char *tag);

bool mts_float(MtsParser *p, const XmlNode *obj, const char *name, double fallback, double *out);
bool mts_int(MtsParser *p, const XmlNode *obj, const char *name, long fallback, long *out);
bool mts_bool(MtsParser *p, const XmlNode *obj, const char *name, bool fallback, bool *out);
/* The string property, or fallback (may be NULL). */
bool mts_string(MtsParser *p, const XmlNode *obj, const char *name, const char *fallback, const char **out);
bool mts_point(MtsParser *p, const XmlNode *obj, const char *name, const double fallback[3], double out[3],
               bool *present);
/* A transform property (identity when absent). */
bool mts_transform(MtsParser *p, const XmlNode *obj, const char *name, SgTransform *out, bool *present);
/* Numbers of a list attribute ("1, 2, 3" or "1 2 3"): how many were read. */
bool mts_numbers(MtsParser *p, const XmlNode *at, const char *text, double *out, size_t max, size_t *count);
/* A colour element (rgb, srgb, spectrum, float, blackbody) as linear RGB. */
bool mts_color_of(MtsParser *p, const XmlNode *n, float out[3]);
/* A spectrum's "value": one number, or "wavelength:value, ..." pairs. */
bool mts_spectrum_text(MtsParser *p, const XmlNode *at, const char *text, float out[3]);
/* Resolves a file name of the scene: absolute, the file's directory, the
 * main file's, then <path> directories; the first that exists. */
void mts_resolve(MtsParser *p, const XmlNode *at, const char *name, char *out, size_t size);

/* ---- serialized.c ------------------------------------------------------- */

/* Mesh shape_index of a .serialized file, into the mesh a PLY file reads
 * to (sg_ply_mesh_release frees it); errors are "path: cause". */
bool mts_read_serialized(const char *path, long shape_index, SgPlyMesh *mesh, SgError *err);

/* ---- materials.c -------------------------------------------------------- */

/* A colour or texture property: *texture is 1 + the scene texture where
 * one varies it (NULL: textures are taken as their mean). */
bool mts_color(MtsParser *p, const XmlNode *obj, const char *name, const float fallback[3], float out[3],
               uint32_t *texture, bool *present);
/* The material of a bsdf element (NULL: Mitsuba's default diffuse). */
bool mts_material(MtsParser *p, const XmlNode *bsdf, size_t *index);
/* Its scene id; with emission, a copy that emits radiance. */
bool mts_scene_material(MtsParser *p, size_t index, const float *radiance, uint32_t *id);
/* A medium element's absorption where it is homogeneous and absorbs only
 * (*absorbing); otherwise one warning of its kind. */
bool mts_medium_absorption(MtsParser *p, const XmlNode *medium, float sigma_a[3], bool *absorbing);
/* The shape's scene material *id given the absorbing medium inside it
 * ("interior"), where it is a dielectric: a copy with its sigma_a. */
bool mts_interior_material(MtsParser *p, const XmlNode *shape, uint32_t *id);

/* ---- shapes.c ----------------------------------------------------------- */

bool mts_shape(MtsParser *p, XmlNode *shape);

#endif
