/* pbrt-v4 scene files: a tokenizer, the graphics state (transform stack,
 * material, area light), and the statements real shared scenes use,
 * mapped onto the scene builder. What pbrt renders but we cannot is named
 * in one scene warning per kind; malformed input is "file:line: cause".
 *
 * Conventions (pbrt-v4): the CTM is post-multiplied by every transform
 * statement; `Transform`/`ConcatTransform` list the matrix column by column
 * (the translation is the last four numbers); at `Camera` the CTM is the
 * camera-from-world transform, camera space has +z forward, +y up and the
 * image's x grows along camera +x; `fov` spans the shorter image axis;
 * `WorldBegin` resets the CTM. Relative file names are resolved against the
 * directory of the main file, as pbrt does.
 *
 * This header is private to common/pbrt/: the parser's state and the
 * functions its files share. The public entry point is pbrt_scene.h.
 * Calls go down the list below, never back up: tokens.c, params.c,
 * spectra.c, textures.c, materials.c, graphics_state.c, shapes.c, and the
 * statement loop in loader.c at the top. */
#ifndef SG_PBRT_PARSER_H
#define SG_PBRT_PARSER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "error.h"
#include "image_average.h"
#include "scene_builder.h"
#include "transform.h"

#define MAX_INCLUDE_DEPTH 32

/* ---- the parser's state ------------------------------------------------- */

typedef struct Source {
    char *text; /* NUL-terminated; quoted strings are unescaped in place */
    size_t size, pos;
    int line;
    char path[4096];
} Source;

typedef struct Token {
    const char *s; /* not NUL-terminated: use len */
    uint32_t len;
    int line;
    bool quoted;
    const Source *source;
} Token;

typedef enum ParamKind { PARAM_NUMBERS, PARAM_STRINGS, PARAM_BOOLS } ParamKind;

typedef struct Param {
    char type[16];
    char name[128];
    ParamKind kind;
    size_t first, count; /* into numbers[], strings[] or bools[] */
    int line;
    const Source *source;
} Param;

typedef struct GraphicsState {
    SgTransform ctm;
    bool reverse_orientation;
    uint32_t material; /* index into Parser.materials */
    bool area_light;
    float radiance[3];
    /* MediumInterface's inside medium, where it absorbs only (media.c):
     * its absorption coefficient; 0: none */
    float inside_sigma_a[3];
} GraphicsState;

typedef struct SavedState {
    GraphicsState state;
    Token begin; /* its AttributeBegin, for unbalanced blocks */
} SavedState;

/* A material as pbrt defines it; turned into a scene material when a
 * shape first uses it (emissive shapes get their own copy). */
typedef struct PbrtMaterial {
    char *name; /* NULL for an anonymous `Material` */
    SgMaterial material;
    bool invisible; /* "interface": the shape only bounds a medium */
    uint32_t scene_id; /* UINT32_MAX until used */
    /* Named by NamedMaterial before its MakeNamedMaterial (pbrt-v4 resolves
     * names after parsing): shapes use it now, the definition fills it in. */
    bool pending;
    Token first_use;
} PbrtMaterial;

/* What a shape adds to its material: an alpha cut-out (its "alpha") and
 * the absorption of the medium inside it (MediumInterface). Zeroed: none. */
typedef struct ShapeAttributes {
    bool cutout;
    float alpha;
    uint32_t alpha_texture;
    float sigma_a[3];
} ShapeAttributes;

/* A scene material made from another for a shape's attributes. */
typedef struct MaterialVariant {
    uint32_t base; /* scene material */
    ShapeAttributes attr;
    uint32_t scene_id;
} MaterialVariant;

/* A MakeNamedMedium: what its absorption is, if it is one we take. */
typedef struct NamedMedium {
    char *name;
    float sigma_a[3];
    bool supported; /* homogeneous and absorbing only */
} NamedMedium;

typedef struct Texture {
    char *name;
    float value[3]; /* average colour (float textures: all three equal) */
    uint32_t scene_texture; /* 1 + index in the scene's textures; 0: a constant, `value` */
} Texture;

typedef struct NamedTransform {
    char *name;
    SgTransform m;
} NamedTransform;

/* A shape of an object definition, in world space at its definition. */
typedef struct Object {
    char *name;
    SgShapeGroup shapes;
} Object;

typedef struct Parser {
    SgSceneBuilder core;
    SgError *err;
    char base_dir[4096];

    Source **sources; /* every file read, kept until the end */
    size_t source_count, source_capacity;
    Source *stack[MAX_INCLUDE_DEPTH];
    int depth;
    Token pending;
    bool has_pending;
    const Source *last_source; /* for "premature end of file" */
    int last_line;

    Param *params;
    size_t param_count, param_capacity;
    double *numbers;
    size_t number_count, number_capacity;
    Token *strings;
    size_t string_count, string_capacity;
    bool *bools;
    size_t bool_count, bool_capacity;

    GraphicsState state;
    SavedState *saved;
    size_t saved_count, saved_capacity;
    bool in_world;

    PbrtMaterial *materials;
    size_t material_count, material_capacity;
    ShapeAttributes shape; /* of the Shape statement being read */
    MaterialVariant *variants;
    size_t variant_count, variant_capacity;
    NamedMedium *media;
    size_t medium_count, medium_capacity;
    Texture *textures;
    size_t texture_count, texture_capacity;
    NamedTransform *coordinate_systems;
    size_t coordinate_system_count, coordinate_system_capacity;
    Object *objects;
    size_t object_count, object_capacity;
    Object *defining; /* inside ObjectBegin .. ObjectEnd */
    Token defining_begin;

    bool has_camera;
    SgTransform camera_from_world;
    double fov;
    int film_width, film_height;


} Parser;

/* ---- tokens.c: errors, warnings, files and the lexer -------------------- */

/* Grows *array to hold needed items of size item. */
bool pbrt_reserve(Parser *p, void **array, size_t *capacity, size_t needed, size_t item);
#define RESERVE(p, array, count, capacity, extra)                                                \
    pbrt_reserve((p), (void **)&(array), &(capacity), (count) + (extra), sizeof *(array))

/* "file:line: cause". */
bool pbrt_fail_at(Parser *p, const Token *t, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
/* One warning per kind: the first place it happened and how many times. */
void pbrt_warn_at(Parser *p, const Token *t, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

bool pbrt_token_is(const Token *t, const char *word);
bool pbrt_string_is(const Token *t, const char *word);
char *pbrt_token_dup(const Token *t);

bool pbrt_push_file(Parser *p, const char *path, const Token *from);
bool pbrt_resolve_path(Parser *p, const Token *at, const Token *name, char *out, size_t size);
bool pbrt_next_token(Parser *p, Token *t);
void pbrt_unget_token(Parser *p, const Token *t);
bool pbrt_need_token(Parser *p, const Token *statement, Token *t);
bool pbrt_token_number(const Token *t, double *out);
bool pbrt_need_number(Parser *p, const Token *statement, double *out);
bool pbrt_need_string(Parser *p, const Token *statement, Token *out);
bool pbrt_need_bracketed_numbers(Parser *p, const Token *statement, int n, double *out);

/* ---- params.c: parameter lists ------------------------------------------ */

bool pbrt_parse_params(Parser *p);
const Param *pbrt_find_param(const Parser *p, const char *name);
Token pbrt_param_token(const Param *param);
bool pbrt_param_float(Parser *p, const char *name, double fallback, double *out);
bool pbrt_param_bool(Parser *p, const char *name, bool fallback, bool *out);
const Token *pbrt_param_string(Parser *p, const char *name);

/* ---- spectra.c: colours and spectra ------------------------------------- */

bool pbrt_param_color(Parser *p, const char *name, const float fallback[3], float out[3],
                      bool *present);
bool pbrt_param_scalar(Parser *p, const char *name, double fallback, double *out);
/* The scene texture a "texture NAME" parameter names (1 + index; 0: the
 * parameter is absent, a constant, or a texture that does not vary). */
uint32_t pbrt_param_texture(Parser *p, const char *name);

/* ---- the statements, by file -------------------------------------------- */

bool pbrt_texture_statement(Parser *p, const Token *statement); /* textures.c */

/* materials.c */
bool pbrt_add_material(Parser *p, const PbrtMaterial *m, uint32_t *index);
bool pbrt_material_statement(Parser *p, const Token *statement);
bool pbrt_make_named_material_statement(Parser *p, const Token *statement);
bool pbrt_named_material_statement(Parser *p, const Token *statement);
bool pbrt_current_scene_material(Parser *p, bool emissive, uint32_t *id);
bool pbrt_area_light_statement(Parser *p, const Token *statement);
bool pbrt_light_source_statement(Parser *p, const Token *statement); /* lights.c */

/* media.c */
bool pbrt_make_named_medium_statement(Parser *p, const Token *statement);
bool pbrt_medium_interface_statement(Parser *p, const Token *statement);

/* graphics_state.c: the transform statements (Translate, Scale, Rotate,
 * LookAt, Transform, ConcatTransform), named coordinate systems, and the
 * attribute blocks that save and restore the graphics state */
bool pbrt_transform_statement(Parser *p, const Token *statement);
bool pbrt_set_coordinate_system(Parser *p, const Token *name, const SgTransform *m);
bool pbrt_coordinate_system_statement(Parser *p, const Token *statement); /* CoordinateSystem, CoordSysTransform */
bool pbrt_push_state(Parser *p, const Token *begin);
/* fails on a block end without its begin; transform_only: TransformEnd */
bool pbrt_pop_state(Parser *p, const Token *t, bool transform_only);

/* shapes.c */
bool pbrt_shape_statement(Parser *p, const Token *statement);
bool pbrt_object_begin(Parser *p, const Token *statement);
bool pbrt_object_end(Parser *p, const Token *statement);
bool pbrt_object_instance(Parser *p, const Token *statement);

#endif
