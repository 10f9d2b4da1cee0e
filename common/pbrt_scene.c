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
 * directory of the main file, as pbrt does. */
#include "pbrt_scene.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "color.h"
#include "image_io.h"
#include "input_file.h"
#include "ply_mesh.h"
#include "scene_builder.h"
#include "vecmath.h"

#define MAX_INCLUDE_DEPTH 32

/* ---- tokens ------------------------------------------------------------- */

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
} GraphicsState;

/* A material as pbrt defines it; turned into a scene material when a
 * shape first uses it (emissive shapes get their own copy). */
typedef struct SavedState {
    GraphicsState state;
    Token begin; /* its AttributeBegin, for unbalanced blocks */
} SavedState;

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

typedef struct EmissiveMaterial {
    uint32_t material; /* Parser.materials index */
    float radiance[3];
    uint32_t scene_id;
} EmissiveMaterial;

typedef struct Texture {
    char *name;
    float value[3]; /* average colour (float textures: all three equal) */
} Texture;

typedef struct NamedTransform {
    char *name;
    SgTransform m;
} NamedTransform;

/* A shape of an object definition, in world space at its definition. */
typedef struct ObjectShape {
    double *positions;
    uint32_t vertex_count;
    uint32_t *indices;
    uint32_t triangle_count;
    uint32_t scene_material;
} ObjectShape;

typedef struct Object {
    char *name;
    ObjectShape *shapes;
    size_t shape_count, shape_capacity;
} Object;

typedef struct ImageAverage {
    char *path;
    bool linear; /* the encoding it was averaged with */
    float value[3];
    bool readable;
} ImageAverage;

typedef struct Warning {
    char kind[160];   /* what could not be honoured */
    char where[4200]; /* file:line of the first occurrence */
    uint32_t count;
} Warning;

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
    EmissiveMaterial *emissive;
    size_t emissive_count, emissive_capacity;
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

    Warning *warnings;
    size_t warning_count, warning_capacity;

    ImageAverage *images; /* image files read for textures, by path */
    size_t image_count, image_capacity;
} Parser;

/* Grows *array to hold needed items of size item. */
static bool reserve(Parser *p, void **array, size_t *capacity, size_t needed, size_t item)
{
    if (needed <= *capacity)
        return true;
    size_t cap = *capacity ? *capacity : 16;
    while (cap < needed)
        cap *= 2;
    void *grown = realloc(*array, cap * item);
    if (!grown)
        return sg_fail(p->err, "%s: out of memory", p->core.path);
    *array = grown;
    *capacity = cap;
    return true;
}
#define RESERVE(p, array, count, capacity, extra)                                                \
    reserve((p), (void **)&(array), &(capacity), (count) + (extra), sizeof *(array))

/* "file:line: cause". */
static bool fail_at(Parser *p, const Token *t, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static bool fail_at(Parser *p, const Token *t, const char *fmt, ...)
{
    char cause[900];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(cause, sizeof cause, fmt, ap);
    va_end(ap);
    const Source *src = t && t->source ? t->source : p->last_source;
    int line = t && t->source ? t->line : p->last_line;
    if (src)
        return sg_fail(p->err, "%s:%d: %s", src->path, line, cause);
    return sg_fail(p->err, "%s: %s", p->core.path, cause);
}

/* One warning per kind: the first place it happened and how many times. */
static void warn_at(Parser *p, const Token *t, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static void warn_at(Parser *p, const Token *t, const char *fmt, ...)
{
    char kind[160];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(kind, sizeof kind, fmt, ap);
    va_end(ap);
    for (size_t i = 0; i < p->warning_count; i++)
        if (!strcmp(p->warnings[i].kind, kind)) {
            p->warnings[i].count++;
            return;
        }
    if (!RESERVE(p, p->warnings, p->warning_count, p->warning_capacity, 1))
        return;
    Warning *w = &p->warnings[p->warning_count++];
    snprintf(w->kind, sizeof w->kind, "%s", kind);
    if (t && t->source)
        snprintf(w->where, sizeof w->where, "%s:%d", t->source->path, t->line);
    else
        snprintf(w->where, sizeof w->where, "%s", p->core.path);
    w->count = 1;
}

static bool token_is(const Token *t, const char *word)
{
    size_t n = strlen(word);
    return !t->quoted && t->len == n && !memcmp(t->s, word, n);
}

static bool string_is(const Token *t, const char *word)
{
    size_t n = strlen(word);
    return t->len == n && !memcmp(t->s, word, n);
}

static char *token_dup(const Token *t)
{
    char *s = malloc(t->len + 1);
    if (s) {
        memcpy(s, t->s, t->len);
        s[t->len] = 0;
    }
    return s;
}

/* ---- reading files ------------------------------------------------------ */

static bool push_file(Parser *p, const char *path, const Token *from)
{
    if (p->depth >= MAX_INCLUDE_DEPTH)
        return fail_at(p, from, "Include nested more than %d deep (does a file include itself?)",
                       MAX_INCLUDE_DEPTH);
    size_t n = strlen(path);
    if (n > 3 && !strcmp(path + n - 3, ".gz")) {
        if (from)
            return fail_at(p, from, "%s: compressed files are not read: gunzip it first", path);
        return sg_fail(p->err, "%s: compressed files are not read: gunzip it first", path);
    }
    char *text;
    size_t size;
    SgError read_err = {0};
    if (!sg_read_file(path, NULL, SG_LIMIT_PBRT_TEXT, &text, &size, &read_err)) {
        if (from)
            return fail_at(p, from, "%s", read_err.message);
        return sg_fail(p->err, "%s", read_err.message);
    }
    Source *src = calloc(1, sizeof *src);
    if (!src || !RESERVE(p, p->sources, p->source_count, p->source_capacity, 1)) {
        free(src);
        free(text);
        return sg_fail(p->err, "%s: out of memory", path);
    }
    p->sources[p->source_count++] = src;
    sg_builder_add_source(&p->core, text, size);
    snprintf(src->path, sizeof src->path, "%s", path);
    src->line = 1;
    src->text = text;
    src->size = size;
    if (src->size >= 2 && (((unsigned char)src->text[0] == 0xfe &&
                            (unsigned char)src->text[1] == 0xff) ||
                           ((unsigned char)src->text[0] == 0xff &&
                            (unsigned char)src->text[1] == 0xfe)))
        return sg_fail(p->err, "%s: UTF-16 text is not supported (save it as UTF-8)", path);
    p->stack[p->depth++] = src;
    return true;
}

static bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }

/* Next token of the current file; false at its end (t->s == NULL) or on a
 * lexical error (p->err set). */
static bool lex(Parser *p, Source *src, Token *t)
{
    t->s = NULL;
    for (;;) {
        while (src->pos < src->size && is_space(src->text[src->pos])) {
            if (src->text[src->pos] == '\n')
                src->line++;
            src->pos++;
        }
        if (src->pos >= src->size)
            return false;
        if (src->text[src->pos] != '#')
            break;
        while (src->pos < src->size && src->text[src->pos] != '\n')
            src->pos++;
    }
    char *c = src->text + src->pos;
    t->line = src->line;
    t->source = src;
    t->quoted = false;
    if (*c == '"') {
        char *out = c + 1, *in = c + 1;
        for (;; in++) {
            if (in >= src->text + src->size || *in == '\n') {
                Token at = *t;
                fail_at(p, &at, "unterminated string");
                return false;
            }
            if (*in == '"')
                break;
            if (*in == '\\') {
                in++;
                static const char from[] = "bfnrt\\'\"", to[] = "\b\f\n\r\t\\'\"";
                const char *k = *in ? strchr(from, *in) : NULL;
                if (!k) {
                    Token at = *t;
                    fail_at(p, &at, "unknown escape \\%c in a string", *in ? *in : ' ');
                    return false;
                }
                *out++ = to[k - from];
            } else {
                *out++ = *in;
            }
        }
        t->s = c + 1;
        t->len = (uint32_t)(out - (c + 1));
        t->quoted = true;
        src->pos = (size_t)(in + 1 - src->text);
        return true;
    }
    if (*c == '[' || *c == ']') {
        t->s = c;
        t->len = 1;
        src->pos++;
        return true;
    }
    char *end = c;
    while (end < src->text + src->size && !is_space(*end) && *end != '"' && *end != '[' &&
           *end != ']' && *end != '#')
        end++;
    t->s = c;
    t->len = (uint32_t)(end - c);
    src->pos = (size_t)(end - src->text);
    return true;
}

/* Next token across included files; false at the very end or on error. */
static bool next_token(Parser *p, Token *t)
{
    if (p->has_pending) {
        *t = p->pending;
        p->has_pending = false;
        return true;
    }
    while (p->depth > 0) {
        Source *src = p->stack[p->depth - 1];
        if (lex(p, src, t)) {
            p->last_source = src;
            p->last_line = t->line;
            return true;
        }
        if (p->err->failed)
            return false;
        p->last_source = src;
        p->last_line = src->line;
        p->depth--;
    }
    t->s = NULL;
    return false;
}

static void unget_token(Parser *p, const Token *t)
{
    p->pending = *t;
    p->has_pending = true;
}

/* A token that must be there. */
static bool need_token(Parser *p, const Token *statement, Token *t)
{
    if (next_token(p, t))
        return true;
    if (!p->err->failed)
        fail_at(p, NULL, "premature end of file after %.*s", (int)statement->len,
                statement->s);
    return false;
}

static bool token_number(const Token *t, double *out)
{
    if (t->quoted || t->len == 0 || t->len > 63)
        return false;
    char buf[64];
    memcpy(buf, t->s, t->len);
    buf[t->len] = 0;
    char *end;
    double v = strtod(buf, &end);
    if (*end || !isfinite(v))
        return false;
    *out = v;
    return true;
}

static bool need_number(Parser *p, const Token *statement, double *out)
{
    Token t;
    if (!need_token(p, statement, &t))
        return false;
    if (!token_number(&t, out))
        return fail_at(p, &t, "%.*s: expected a number, found \"%.*s\"", (int)statement->len,
                       statement->s, (int)(t.len > 40 ? 40 : t.len), t.s);
    return true;
}

static bool need_string(Parser *p, const Token *statement, Token *out)
{
    if (!need_token(p, statement, out))
        return false;
    if (!out->quoted)
        return fail_at(p, out, "%.*s: expected a quoted string, found %.*s",
                       (int)statement->len, statement->s, (int)(out->len > 40 ? 40 : out->len),
                       out->s);
    return true;
}

/* "[ n1 ... nN ]" with exactly n numbers. */
static bool need_bracketed_numbers(Parser *p, const Token *statement, int n, double *out)
{
    Token open;
    if (!need_token(p, statement, &open))
        return false;
    bool bracketed = token_is(&open, "[");
    if (!bracketed)
        unget_token(p, &open);
    for (int i = 0; i < n; i++)
        if (!need_number(p, statement, &out[i]))
            return false;
    if (bracketed) {
        Token close;
        if (!need_token(p, statement, &close))
            return false;
        if (!token_is(&close, "]"))
            return fail_at(p, &open, "%.*s: '[' at line %d is not closed by ']' after %d numbers",
                           (int)statement->len, statement->s, open.line, n);
    }
    return true;
}

/* ---- parameter lists ---------------------------------------------------- */

static const char *const known_types[] = {
    "integer", "float", "point2", "vector2", "point3", "vector3", "normal", "normal3", "point",
    "vector", "color", "rgb", "spectrum", "blackbody", "bool", "string", "texture",
};

static bool numeric_type(const char *type)
{
    return strcmp(type, "bool") && strcmp(type, "string") && strcmp(type, "texture") &&
           strcmp(type, "spectrum");
}

static bool add_value(Parser *p, Param *param, const Token *v)
{
    bool is_bool = !v->quoted && (token_is(v, "true") || token_is(v, "false"));
    if (!strcmp(param->type, "bool")) {
        if (!(is_bool || (v->quoted && (string_is(v, "true") || string_is(v, "false")))))
            return fail_at(p, v, "\"bool %s\": expected true or false", param->name);
        if (!RESERVE(p, p->bools, p->bool_count, p->bool_capacity, 1))
            return false;
        if (param->count == 0)
            param->first = p->bool_count;
        p->bools[p->bool_count++] = v->s[0] == 't';
        param->kind = PARAM_BOOLS;
        param->count++;
        return true;
    }
    if (v->quoted) {
        if (numeric_type(param->type))
            return fail_at(p, v, "\"%s %s\": expected numbers, found a string", param->type,
                           param->name);
        if (param->count && param->kind != PARAM_STRINGS)
            return fail_at(p, v, "\"%s %s\": mixes numbers and strings", param->type,
                           param->name);
        if (!RESERVE(p, p->strings, p->string_count, p->string_capacity, 1))
            return false;
        if (param->count == 0)
            param->first = p->string_count;
        p->strings[p->string_count++] = *v;
        param->kind = PARAM_STRINGS;
        param->count++;
        return true;
    }
    double x;
    if (!token_number(v, &x)) {
        if (token_is(v, "["))
            return fail_at(p, v, "\"%s %s\": '[' inside '[ ]'", param->type, param->name);
        return fail_at(p, v, "\"%s %s\": expected a value, found %.*s", param->type, param->name,
                       (int)(v->len > 40 ? 40 : v->len), v->s);
    }
    if (!strcmp(param->type, "string") || !strcmp(param->type, "texture"))
        return fail_at(p, v, "\"%s %s\": expected a quoted string, found a number", param->type,
                       param->name);
    if (param->count && param->kind != PARAM_NUMBERS)
        return fail_at(p, v, "\"%s %s\": mixes numbers and strings", param->type, param->name);
    if (!strcmp(param->type, "integer") && x != floor(x))
        return fail_at(p, v, "\"integer %s\": %.*s is not a whole number", param->name,
                       (int)v->len, v->s);
    if (!RESERVE(p, p->numbers, p->number_count, p->number_capacity, 1))
        return false;
    if (param->count == 0)
        param->first = p->number_count;
    p->numbers[p->number_count++] = x;
    param->kind = PARAM_NUMBERS;
    param->count++;
    return true;
}

/* "type name" with a known type. */
static bool looks_like_declaration(const Token *t)
{
    for (size_t i = 0; i < sizeof known_types / sizeof known_types[0]; i++) {
        size_t n = strlen(known_types[i]);
        if (t->len > n + 1 && !memcmp(t->s, known_types[i], n) && t->s[n] == ' ')
            return true;
    }
    return false;
}

/* Reads "type name" value-or-[values] pairs until the next statement. */
static bool parse_params(Parser *p)
{
    p->param_count = p->number_count = p->string_count = p->bool_count = 0;
    for (;;) {
        Token decl;
        if (!next_token(p, &decl))
            return !p->err->failed;
        if (!decl.quoted) {
            if (token_is(&decl, "["))
                return fail_at(p, &decl, "'[' without a parameter name before it");
            if (token_is(&decl, "]"))
                return fail_at(p, &decl, "']' without a matching '['");
            unget_token(p, &decl);
            return true;
        }
        /* "type name": split at blanks */
        char text[256];
        if (decl.len >= sizeof text)
            return fail_at(p, &decl, "parameter declaration too long");
        memcpy(text, decl.s, decl.len);
        text[decl.len] = 0;
        char type[64], name[128], extra[8];
        int fields = sscanf(text, "%63s %127s %7s", type, name, extra);
        if (fields != 2)
            return fail_at(p, &decl, "\"%s\" is not a parameter declaration (\"type name\")",
                           text);
        if (!strcmp(type, "point"))
            strcpy(type, "point3");
        else if (!strcmp(type, "vector"))
            strcpy(type, "vector3");
        else if (!strcmp(type, "normal"))
            strcpy(type, "normal3");
        else if (!strcmp(type, "color"))
            strcpy(type, "rgb");
        bool known = false;
        for (size_t i = 0; i < sizeof known_types / sizeof known_types[0]; i++)
            known |= !strcmp(type, known_types[i]);
        if (!known)
            return fail_at(p, &decl, "unknown parameter type \"%s\" in \"%s\"", type, text);
        if (!RESERVE(p, p->params, p->param_count, p->param_capacity, 1))
            return false;
        Param *param = &p->params[p->param_count++];
        memset(param, 0, sizeof *param);
        snprintf(param->type, sizeof param->type, "%.15s", type); /* a known type: short */
        snprintf(param->name, sizeof param->name, "%s", name);
        param->line = decl.line;
        param->source = decl.source;
        param->kind = numeric_type(type) ? PARAM_NUMBERS : PARAM_STRINGS;
        Token v;
        if (!need_token(p, &decl, &v))
            return false;
        if (token_is(&v, "[")) {
            Token open = v;
            for (;;) {
                if (!next_token(p, &v)) {
                    if (!p->err->failed)
                        fail_at(p, &open, "'[' is never closed by ']'");
                    return false;
                }
                if (token_is(&v, "]"))
                    break;
                /* A statement name or a parameter declaration: the list ran on. */
                if ((!v.quoted && v.len && v.s[0] >= 'A' && v.s[0] <= 'Z') ||
                    (v.quoted && looks_like_declaration(&v)))
                    return fail_at(p, &open,
                                   "'[' is not closed by ']' before \"%.*s\" (line %d)",
                                   (int)(v.len > 40 ? 40 : v.len), v.s, v.line);
                if (!add_value(p, param, &v))
                    return false;
            }
        } else if (token_is(&v, "]")) {
            return fail_at(p, &v, "']' without a matching '['");
        } else if (!add_value(p, param, &v)) {
            return false;
        }
    }
}

static const Param *find_param(const Parser *p, const char *name)
{
    for (size_t i = p->param_count; i-- > 0;)
        if (!strcmp(p->params[i].name, name))
            return &p->params[i];
    return NULL;
}

static Token param_token(const Param *param)
{
    Token t = {0};
    t.line = param->line;
    t.source = param->source;
    return t;
}

static bool param_float(Parser *p, const char *name, double fallback, double *out)
{
    *out = fallback;
    const Param *param = find_param(p, name);
    if (!param)
        return true;
    Token at = param_token(param);
    if (param->kind != PARAM_NUMBERS || param->count < 1)
        return fail_at(p, &at, "\"%s %s\" must be a number", param->type, name);
    *out = p->numbers[param->first];
    return true;
}

static bool param_bool(Parser *p, const char *name, bool fallback, bool *out)
{
    *out = fallback;
    const Param *param = find_param(p, name);
    if (!param)
        return true;
    Token at = param_token(param);
    if (param->kind != PARAM_BOOLS || param->count < 1)
        return fail_at(p, &at, "\"%s %s\" must be true or false", param->type, name);
    *out = p->bools[param->first];
    return true;
}

/* A string parameter; NULL if absent. */
static const Token *param_string(Parser *p, const char *name)
{
    const Param *param = find_param(p, name);
    if (!param || param->kind != PARAM_STRINGS || param->count < 1)
        return NULL;
    return &p->strings[param->first];
}

/* ---- colours, spectra and textures -------------------------------------- */

static const Texture *find_texture(const Parser *p, const Token *name)
{
    for (size_t i = p->texture_count; i-- > 0;)
        if (string_is(name, p->textures[i].name))
            return &p->textures[i];
    return NULL;
}

/* Complex index of refraction of pbrt's named metal spectra, reduced to
 * red, green and blue (approximate: evaluated near 650, 550 and 450 nm). */
typedef struct NamedMetal {
    const char *name;
    float eta[3], k[3];
} NamedMetal;

static const NamedMetal named_metals[] = {
    {"Ag", {0.155f, 0.117f, 0.138f}, {4.83f, 3.12f, 2.15f}},
    {"Al", {1.66f, 0.880f, 0.521f}, {9.22f, 6.27f, 4.84f}},
    {"Au", {0.143f, 0.375f, 1.44f}, {3.98f, 2.39f, 1.60f}},
    {"Cu", {0.200f, 0.924f, 1.10f}, {3.91f, 2.45f, 2.14f}},
    {"CuZn", {0.444f, 0.527f, 1.09f}, {3.70f, 2.77f, 1.83f}},
    {"MgO", {1.73f, 1.74f, 1.76f}, {0, 0, 0}},
    {"TiO2", {2.58f, 2.74f, 3.03f}, {0, 0, 0}},
};

/* Index of refraction of pbrt's named glasses near 550 nm. */
static const struct {
    const char *name;
    float eta;
} named_glasses[] = {
    {"glass-BK7", 1.5168f}, {"glass-BAF10", 1.6700f}, {"glass-FK51A", 1.4866f},
    {"glass-LASF9", 1.8503f}, {"glass-F5", 1.6034f},  {"glass-F10", 1.6200f},
    {"glass-F11", 1.6200f},  {"glass-SF5", 1.6727f}, {"glass-SF10", 1.7283f},
    {"glass-SF11", 1.7847f},
};

/* One lobe of the CIE 1931 matching functions' analytic fit (Wyman,
 * Sloan and Shirley 2013, "Simple analytic approximations to the CIE XYZ
 * colour matching functions"). */
static double cie_lobe(double lambda, double mu, double sigma_low, double sigma_high)
{
    double t = (lambda - mu) / (lambda < mu ? sigma_low : sigma_high);
    return exp(-0.5 * t * t);
}

/* Linear sRGB of a blackbody at kelvin, scaled to luminance 1 as pbrt
 * normalizes blackbody emitters. */
static void blackbody_rgb(double kelvin, float out[3])
{
    const double h = 6.62606957e-34, c = 299792458.0, kb = 1.3806488e-23;
    double xyz[3] = {0, 0, 0};
    for (double lambda = 360; lambda <= 830; lambda += 1) {
        double l = lambda * 1e-9;
        double planck = 2 * h * c * c / (pow(l, 5) * (exp(h * c / (l * kb * kelvin)) - 1));
        xyz[0] += planck * (1.056 * cie_lobe(lambda, 599.8, 37.9, 31.0) +
                            0.362 * cie_lobe(lambda, 442.0, 16.0, 26.7) -
                            0.065 * cie_lobe(lambda, 501.1, 20.4, 26.2));
        xyz[1] += planck * (0.821 * cie_lobe(lambda, 568.8, 46.9, 40.5) +
                            0.286 * cie_lobe(lambda, 530.9, 16.3, 31.1));
        xyz[2] += planck * (1.217 * cie_lobe(lambda, 437.0, 11.8, 36.0) +
                            0.681 * cie_lobe(lambda, 459.0, 26.0, 13.8));
    }
    double rgb[3] = {3.2406 * xyz[0] - 1.5372 * xyz[1] - 0.4986 * xyz[2],
                     -0.9689 * xyz[0] + 1.8758 * xyz[1] + 0.0415 * xyz[2],
                     0.0557 * xyz[0] - 0.2040 * xyz[1] + 1.0570 * xyz[2]};
    for (int a = 0; a < 3; a++)
        rgb[a] = fmax(rgb[a], 0); /* outside the sRGB gamut: clip */
    double y = sg_luminance(rgb[0], rgb[1], rgb[2]);
    for (int a = 0; a < 3; a++)
        out[a] = y > 0 ? (float)(rgb[a] / y) : 1.0f;
}

/* A spectrum or colour parameter as linear RGB. which: "eta"/"k" for
 * named metal spectra, NULL otherwise. Sets *present. */
static bool param_color(Parser *p, const char *name, const float fallback[3], float out[3],
                        bool *present)
{
    memcpy(out, fallback, 3 * sizeof(float));
    if (present)
        *present = false;
    const Param *param = find_param(p, name);
    if (!param)
        return true;
    if (present)
        *present = true;
    Token at = param_token(param);
    const char *type = param->type;
    if (!strcmp(type, "rgb")) {
        if (param->count != 3)
            return fail_at(p, &at, "\"rgb %s\" needs 3 numbers, not %zu", name, param->count);
        for (int a = 0; a < 3; a++) {
            double v = p->numbers[param->first + a];
            if (v < 0)
                return fail_at(p, &at, "\"rgb %s\" has a negative value", name);
            out[a] = (float)v;
        }
        return true;
    }
    if (!strcmp(type, "float")) {
        if (param->count != 1)
            return fail_at(p, &at, "\"float %s\" needs 1 number", name);
        out[0] = out[1] = out[2] = (float)p->numbers[param->first];
        return true;
    }
    if (!strcmp(type, "texture")) {
        const Texture *tex = find_texture(p, &p->strings[param->first]);
        if (!tex)
            return fail_at(p, &at, "\"texture %s\": no texture named \"%.*s\"", name,
                           (int)p->strings[param->first].len, p->strings[param->first].s);
        memcpy(out, tex->value, 3 * sizeof(float));
        return true;
    }
    if (!strcmp(type, "blackbody")) {
        /* pbrt-v3 wrote [kelvin scale] */
        if (param->count < 1 || param->count > 2 || !(p->numbers[param->first] > 0))
            return fail_at(p, &at, "\"blackbody %s\" needs one temperature in kelvin", name);
        blackbody_rgb(p->numbers[param->first], out);
        double scale = param->count == 2 ? p->numbers[param->first + 1] : 1;
        if (!(scale >= 0))
            return fail_at(p, &at, "\"blackbody %s\": negative scale", name);
        for (int a = 0; a < 3; a++)
            out[a] = (float)(out[a] * scale);
        return true;
    }
    if (!strcmp(type, "spectrum")) {
        if (param->kind == PARAM_NUMBERS) {
            if (param->count < 2 || param->count % 2)
                return fail_at(p, &at, "\"spectrum %s\" needs (wavelength, value) pairs", name);
            double sum = 0;
            for (size_t i = 1; i < param->count; i += 2)
                sum += p->numbers[param->first + i];
            out[0] = out[1] = out[2] = (float)(sum / (double)(param->count / 2));
            warn_at(p, &at, "sampled spectra are taken as grey (their mean value)");
            return true;
        }
        const Token *s = &p->strings[param->first];
        for (size_t i = 0; i < sizeof named_metals / sizeof named_metals[0]; i++) {
            char eta_name[32], k_name[32];
            snprintf(eta_name, sizeof eta_name, "metal-%s-eta", named_metals[i].name);
            snprintf(k_name, sizeof k_name, "metal-%s-k", named_metals[i].name);
            if (string_is(s, eta_name)) {
                memcpy(out, named_metals[i].eta, 3 * sizeof(float));
                return true;
            }
            if (string_is(s, k_name)) {
                memcpy(out, named_metals[i].k, 3 * sizeof(float));
                return true;
            }
        }
        for (size_t i = 0; i < sizeof named_glasses / sizeof named_glasses[0]; i++)
            if (string_is(s, named_glasses[i].name)) {
                out[0] = out[1] = out[2] = named_glasses[i].eta;
                return true;
            }
        if (string_is(s, "stdillum-D65")) { /* the white of sRGB */
            out[0] = out[1] = out[2] = 1;
            return true;
        }
        warn_at(p, &at, "spectrum \"%.*s\" is not known: taken as %s", (int)s->len, s->s,
                strncmp(s->s, "stdillum", 8) ? "the default" : "white");
        if (!strncmp(s->s, "stdillum", 8))
            out[0] = out[1] = out[2] = 1;
        return true;
    }
    return fail_at(p, &at, "\"%s %s\" is not a colour", type, name);
}

/* A float parameter that may also be a (float) texture: its average. */
static bool param_scalar(Parser *p, const char *name, double fallback, double *out)
{
    const float f[3] = {(float)fallback, (float)fallback, (float)fallback};
    float v[3];
    if (!param_color(p, name, f, v, NULL))
        return false;
    *out = find_param(p, name) ? v[0] : fallback;
    return true;
}

static bool resolve_path(Parser *p, const Token *at, const Token *name, char *out, size_t size)
{
    int n = name->len && name->s[0] == '/'
                ? snprintf(out, size, "%.*s", (int)name->len, name->s)
                : snprintf(out, size, "%s%.*s", p->base_dir, (int)name->len, name->s);
    if (n < 0 || (size_t)n >= size)
        return fail_at(p, at, "file name too long");
    return true;
}

static bool has_suffix(const char *s, const char *suffix)
{
    size_t n = strlen(s), k = strlen(suffix);
    if (n < k)
        return false;
    for (size_t i = 0; i < k; i++) {
        char a = s[n - k + i], b = suffix[i];
        if ((a >= 'A' && a <= 'Z' ? a + 32 : a) != b)
            return false;
    }
    return true;
}

/* The mean linear colour of an image file (cached by path). gamma: 0 for
 * linear data, -1 for sRGB, else the exponent. False if it cannot be read. */
static bool image_average(Parser *p, const char *path, double gamma, float out[3])
{
    for (size_t i = 0; i < p->image_count; i++)
        if (!strcmp(p->images[i].path, path) && p->images[i].linear == (gamma == 0)) {
            memcpy(out, p->images[i].value, 3 * sizeof(float));
            return p->images[i].readable;
        }
    int w = 0, h = 0;
    float *rgb = NULL;
    SgError ignored = {0};
    bool readable = sg_image_read(path, &w, &h, &rgb, &ignored);
    double sum[3] = {0, 0, 0};
    if (readable) {
        /* A few hundred thousand pixels give the mean well enough. */
        size_t step = 1 + (size_t)w * (size_t)h / 262144, n = 0;
        for (size_t i = 0; i < (size_t)w * (size_t)h; i += step, n++)
            for (int c = 0; c < 3; c++) {
                double v = rgb[3 * i + c];
                v = !isfinite(v) || v < 0 ? 0 : v;
                sum[c] += gamma == 0 ? v : gamma < 0 ? sg_srgb_to_linear(v) : pow(v, gamma);
            }
        for (int c = 0; c < 3; c++)
            out[c] = (float)(sum[c] / (double)(n ? n : 1));
    }
    free(rgb);
    if (RESERVE(p, p->images, p->image_count, p->image_capacity, 1)) {
        ImageAverage *a = &p->images[p->image_count];
        if ((a->path = strdup(path))) {
            a->linear = gamma == 0;
            a->readable = readable;
            memcpy(a->value, readable ? out : (const float[3]){0, 0, 0}, sizeof a->value);
            p->image_count++;
        }
    }
    return readable;
}

static bool texture_statement(Parser *p, const Token *statement)
{
    Token name, type, klass;
    if (!need_string(p, statement, &name) || !need_string(p, statement, &type) ||
        !need_string(p, statement, &klass) || !parse_params(p))
        return false;
    if (!string_is(&type, "spectrum") && !string_is(&type, "float") &&
        !string_is(&type, "color"))
        return fail_at(p, &type, "Texture \"%.*s\": type must be \"spectrum\" or \"float\"",
                       (int)name.len, name.s);
    static const float grey[3] = {0.5f, 0.5f, 0.5f}, one[3] = {1, 1, 1};
    float value[3];
    memcpy(value, grey, sizeof value);
    if (string_is(&klass, "constant")) {
        if (!param_color(p, "value", one, value, NULL))
            return false;
    } else if (string_is(&klass, "scale")) {
        float tex[3], scale[3];
        if (!param_color(p, "tex", one, tex, NULL) || !param_color(p, "scale", one, scale, NULL))
            return false;
        for (int a = 0; a < 3; a++)
            value[a] = tex[a] * scale[a];
    } else if (string_is(&klass, "mix") || string_is(&klass, "checkerboard")) {
        static const float zero[3] = {0, 0, 0};
        float a[3], b[3];
        double amount = 0.5;
        if (!param_color(p, "tex1", one, a, NULL) || !param_color(p, "tex2", zero, b, NULL) ||
            (string_is(&klass, "mix") && !param_scalar(p, "amount", 0.5, &amount)))
            return false;
        for (int c = 0; c < 3; c++)
            value[c] = (float)((1 - amount) * a[c] + amount * b[c]);
    } else if (string_is(&klass, "imagemap")) {
        const Token *file = param_string(p, "filename");
        const Token *encoding = param_string(p, "encoding");
        float scale[3];
        bool invert;
        if (!param_color(p, "scale", one, scale, NULL) || !param_bool(p, "invert", false, &invert))
            return false;
        if (!file)
            return fail_at(p, statement, "imagemap texture without \"string filename\"");
        char path[8192];
        if (!resolve_path(p, statement, file, path, sizeof path))
            return false;
        /* pbrt's default: 8-bit images hold sRGB, float formats linear values */
        double gamma = has_suffix(path, ".exr") || has_suffix(path, ".pfm") ||
                               has_suffix(path, ".hdr")
                           ? 0
                           : -1;
        if (encoding && string_is(encoding, "linear"))
            gamma = 0;
        else if (encoding && string_is(encoding, "sRGB"))
            gamma = -1;
        else if (encoding && encoding->len > 6 && encoding->len < 40 &&
                 !memcmp(encoding->s, "gamma ", 6)) {
            char number[40];
            snprintf(number, sizeof number, "%.*s", (int)encoding->len - 6, encoding->s + 6);
            gamma = atof(number) > 0 ? atof(number) : -1;
        }
        float average[3];
        if (!image_average(p, path, gamma, average)) {
            memcpy(average, grey, sizeof average);
            warn_at(p, statement, "image textures that cannot be read (missing files) are "
                                  "taken as grey 0.5");
        }
        for (int c = 0; c < 3; c++) {
            value[c] = average[c] * scale[c];
            if (invert)
                value[c] = value[c] < 1 ? 1 - value[c] : 0;
        }
    } else {
        warn_at(p, statement, "Texture \"%.*s\" is not supported: taken as grey 0.5",
                (int)klass.len, klass.s);
    }
    if (!RESERVE(p, p->textures, p->texture_count, p->texture_capacity, 1))
        return false;
    Texture *t = &p->textures[p->texture_count];
    if (!(t->name = token_dup(&name)))
        return sg_fail(p->err, "%s: out of memory", p->core.path);
    memcpy(t->value, value, sizeof value);
    p->texture_count++;
    return true;
}

/* ---- materials ---------------------------------------------------------- */

static void clamp_albedo(Parser *p, const Token *at, float c[3], const char *what)
{
    for (int a = 0; a < 3; a++)
        if (c[a] > 1) {
            warn_at(p, at, "%s above 1 clamped to 1", what);
            c[a] = 1;
        }
}

/* pbrt-v3's roughness remapping (a fit in log roughness). */
static double v3_roughness_to_alpha(double rough)
{
    double x = log(fmax(rough, 1e-3));
    return 1.62142 + 0.819955 * x + 0.1734 * x * x + 0.0171201 * x * x * x +
           0.000640711 * x * x * x * x;
}

/* Microfacet roughness to a Phong exponent (alpha^2 = 2 / (n + 2)).
 * fallback: the material's default roughness; v3: pbrt-v3's remapping. */
static bool roughness_exponent_of(Parser *p, double fallback, bool v3, double *exponent,
                                  double *alpha_out)
{
    double rough, u, v;
    bool remap;
    if (!param_scalar(p, "uroughness", fallback, &u) ||
        !param_scalar(p, "vroughness", fallback, &v) ||
        !param_bool(p, "remaproughness", true, &remap) ||
        !param_scalar(p, "roughness", 0.5 * (u + v), &rough))
        return false;
    if (!(rough >= 0))
        rough = 0;
    double alpha = !remap ? rough : v3 ? v3_roughness_to_alpha(rough) : sqrt(rough);
    *alpha_out = alpha;
    double n = alpha > 0 ? 2 / (alpha * alpha) - 2 : 1e4;
    *exponent = fmin(fmax(n, 1), 1e4);
    return true;
}

static bool roughness_exponent(Parser *p, double *exponent, double *alpha_out)
{
    return roughness_exponent_of(p, 0, false, exponent, alpha_out);
}

/* Smooth-enough conductors become mirrors: a Phong lobe this narrow is a
 * mirror to every practical purpose and cheaper to sample. */
#define MIRROR_ALPHA 0.02

static bool make_material(Parser *p, const Token *at, const Token *type, const char *label,
                          PbrtMaterial *out)
{
    memset(out, 0, sizeof *out);
    out->scene_id = UINT32_MAX;
    SgMaterial *m = &out->material;
    sg_material_default(m, label);
    static const float half[3] = {0.5f, 0.5f, 0.5f};
    const Param *displacement = find_param(p, "displacement");
    if (displacement || find_param(p, "normalmap"))
        warn_at(p, at, "bump and normal maps (\"displacement\", \"normalmap\") are ignored");
    if (string_is(type, "diffuse") || string_is(type, "diffusetransmission") ||
        string_is(type, "subsurface") || string_is(type, "measured") ||
        string_is(type, "hair") || string_is(type, "kdsubsurface") ||
        string_is(type, "fourier") || string_is(type, "disney")) {
        if (!string_is(type, "diffuse"))
            warn_at(p, at, "Material \"%.*s\" is not supported: diffuse instead", (int)type->len,
                    type->s);
        if (!param_color(p, "reflectance", half, m->diffuse, NULL))
            return false;
        clamp_albedo(p, at, m->diffuse, "reflectance");
        m->type = SG_MATERIAL_DIFFUSE;
        return true;
    }
    if (string_is(type, "coateddiffuse")) {
        double exponent, alpha, eta;
        float reflectance[3];
        if (!param_color(p, "reflectance", half, reflectance, NULL) ||
            !roughness_exponent(p, &exponent, &alpha) || !param_scalar(p, "eta", 1.5, &eta))
            return false;
        clamp_albedo(p, at, reflectance, "reflectance");
        if (!(eta >= 1))
            eta = 1.5;
        /* The coat reflects its normal-incidence Fresnel; the base gets the rest. */
        double f0 = (eta - 1) * (eta - 1) / ((eta + 1) * (eta + 1));
        m->type = SG_MATERIAL_GLOSSY;
        for (int a = 0; a < 3; a++) {
            m->diffuse[a] = (float)(reflectance[a] * (1 - f0));
            m->specular[a] = (float)f0;
        }
        m->exponent = (float)exponent;
        return true;
    }
    if (string_is(type, "conductor") || string_is(type, "coatedconductor") ||
        string_is(type, "metal")) {
        if (string_is(type, "coatedconductor"))
            warn_at(p, at, "Material \"coatedconductor\" is approximated by its conductor");
        float eta[3], k[3], reflectance[3];
        bool has_reflectance;
        const NamedMetal *cu = &named_metals[3];
        bool coated = string_is(type, "coatedconductor"), v3 = string_is(type, "metal");
        if (!param_color(p, coated ? "conductor.eta" : "eta", cu->eta, eta, NULL) ||
            !param_color(p, coated ? "conductor.k" : "k", cu->k, k, NULL) ||
            !param_color(p, "reflectance", half, reflectance, &has_reflectance))
            return false;
        for (int a = 0; a < 3; a++) {
            double n = eta[a], kk = k[a];
            double f0 = ((n - 1) * (n - 1) + kk * kk) / ((n + 1) * (n + 1) + kk * kk);
            m->specular[a] = has_reflectance ? fminf(reflectance[a], 1) : (float)f0;
            m->diffuse[a] = 0;
        }
        double exponent, alpha;
        if (!roughness_exponent_of(p, v3 ? 0.01 : 0, v3, &exponent, &alpha))
            return false;
        m->type = alpha < MIRROR_ALPHA ? SG_MATERIAL_MIRROR : SG_MATERIAL_GLOSSY;
        m->exponent = (float)exponent;
        return true;
    }
    /* pbrt-v3 materials: Bitterli's collection first came in v3 syntax. */
    if (string_is(type, "matte") || string_is(type, "translucent")) {
        if (string_is(type, "translucent"))
            warn_at(p, at, "Material \"translucent\" is taken as diffuse (its Kd)");
        if (!param_color(p, "Kd", half, m->diffuse, NULL))
            return false;
        clamp_albedo(p, at, m->diffuse, "Kd");
        m->type = SG_MATERIAL_DIFFUSE;
        return true;
    }
    if (string_is(type, "plastic") || string_is(type, "substrate") || string_is(type, "uber")) {
        bool substrate = string_is(type, "substrate");
        float d = substrate ? 0.5f : 0.25f;
        const float kd[3] = {d, d, d};
        double exponent, alpha, opacity;
        if (!param_color(p, "Kd", kd, m->diffuse, NULL) ||
            !param_color(p, "Ks", kd, m->specular, NULL) ||
            !roughness_exponent_of(p, 0.1, true, &exponent, &alpha) ||
            !param_scalar(p, "opacity", 1, &opacity))
            return false;
        if (opacity < 1 || find_param(p, "Kr") || find_param(p, "Kt"))
            warn_at(p, at, "uber opacity, Kr and Kt are ignored");
        for (int a = 0; a < 3; a++) { /* keep energy: scale the pair down */
            float sum = m->diffuse[a] + m->specular[a];
            if (sum > 1) {
                m->diffuse[a] /= sum;
                m->specular[a] /= sum;
            }
        }
        m->type = SG_MATERIAL_GLOSSY;
        m->exponent = (float)exponent;
        return true;
    }
    if (string_is(type, "mirror")) {
        const float kr[3] = {0.9f, 0.9f, 0.9f};
        if (!param_color(p, "Kr", kr, m->specular, NULL))
            return false;
        clamp_albedo(p, at, m->specular, "Kr");
        m->diffuse[0] = m->diffuse[1] = m->diffuse[2] = 0;
        m->type = SG_MATERIAL_MIRROR;
        return true;
    }
    if (string_is(type, "glass")) {
        double ior;
        if (!param_scalar(p, "index", 1.5, &ior) ||
            (find_param(p, "eta") && !param_scalar(p, "eta", 1.5, &ior)))
            return false;
        if (ior > 0 && ior < 1)
            ior = 1 / ior;
        if (!(ior >= 1 && ior <= 10))
            return fail_at(p, at, "glass index %g is out of range", ior);
        m->type = SG_MATERIAL_DIELECTRIC;
        m->ior = (float)ior;
        m->diffuse[0] = m->diffuse[1] = m->diffuse[2] = 0;
        return true;
    }
    if (string_is(type, "dielectric") || string_is(type, "thindielectric")) {
        if (string_is(type, "thindielectric"))
            warn_at(p, at, "Material \"thindielectric\" is taken as a solid dielectric");
        float eta[3];
        if (!param_color(p, "eta", (const float[3]){1.5f, 1.5f, 1.5f}, eta, NULL))
            return false;
        double ior = eta[1];
        if (ior > 0 && ior < 1)
            ior = 1 / ior;
        if (!(ior >= 1 && ior <= 10))
            return fail_at(p, at, "dielectric eta %g is out of range", (double)eta[1]);
        double exponent, alpha;
        if (!roughness_exponent(p, &exponent, &alpha))
            return false;
        if (alpha > 0)
            warn_at(p, at, "rough dielectrics are taken as smooth");
        m->type = SG_MATERIAL_DIELECTRIC;
        m->ior = (float)ior;
        m->diffuse[0] = m->diffuse[1] = m->diffuse[2] = 0;
        return true;
    }
    if (string_is(type, "interface") || string_is(type, "") || string_is(type, "none")) {
        out->invisible = true;
        return true;
    }
    if (string_is(type, "mix")) {
        const Param *names = find_param(p, "materials");
        double amount;
        if (!param_scalar(p, "amount", 0.5, &amount))
            return false;
        warn_at(p, at, "Material \"mix\" is replaced by the material with the larger weight");
        if (names && names->kind == PARAM_STRINGS && names->count == 2) {
            const Token *pick = &p->strings[names->first + (amount > 0.5 ? 1 : 0)];
            for (size_t i = p->material_count; i-- > 0;)
                if (p->materials[i].name && string_is(pick, p->materials[i].name)) {
                    *out = p->materials[i];
                    out->name = NULL;
                    out->scene_id = UINT32_MAX;
                    out->pending = false;
                    snprintf(out->material.name, sizeof out->material.name, "%s", label);
                    return true;
                }
        }
        return true;
    }
    warn_at(p, at, "Material \"%.*s\" is not supported: grey diffuse instead", (int)type->len,
            type->s);
    return true;
}

static bool add_pbrt_material(Parser *p, const PbrtMaterial *m, uint32_t *index)
{
    if (!RESERVE(p, p->materials, p->material_count, p->material_capacity, 1))
        return false;
    p->materials[p->material_count] = *m;
    *index = (uint32_t)p->material_count++;
    return true;
}

static bool material_statement(Parser *p, const Token *statement)
{
    Token type;
    if (!need_string(p, statement, &type) || !parse_params(p))
        return false;
    char label[64];
    snprintf(label, sizeof label, "%.*s@%d", (int)(type.len > 40 ? 40 : type.len), type.s,
             statement->line);
    PbrtMaterial m;
    return make_material(p, statement, &type, label, &m) &&
           add_pbrt_material(p, &m, &p->state.material);
}

static bool make_named_material_statement(Parser *p, const Token *statement)
{
    Token name;
    if (!need_string(p, statement, &name) || !parse_params(p))
        return false;
    const Token *type = param_string(p, "type");
    if (!type)
        return fail_at(p, statement, "MakeNamedMaterial \"%.*s\" has no \"string type\"",
                       (int)name.len, name.s);
    char label[64];
    snprintf(label, sizeof label, "%.*s", (int)(name.len > 63 ? 63 : name.len), name.s);
    PbrtMaterial m;
    uint32_t index;
    if (!make_material(p, statement, type, label, &m))
        return false;
    for (size_t i = p->material_count; i-- > 0;) {
        PbrtMaterial *old = &p->materials[i];
        if (!old->name || !string_is(&name, old->name))
            continue;
        if (!old->pending) {
            warn_at(p, statement, "MakeNamedMaterial redefines a name: later uses get the new one");
            break;
        }
        /* Fill in the forward reference, and what shapes already got. */
        old->material = m.material;
        old->invisible = m.invisible;
        old->pending = false;
        SgScene *scene = p->core.scene;
        if (old->scene_id != UINT32_MAX)
            scene->materials[old->scene_id] = m.material;
        for (size_t k = 0; k < p->emissive_count; k++)
            if (p->emissive[k].material == i) {
                SgMaterial *e = &scene->materials[p->emissive[k].scene_id];
                float emission[3];
                memcpy(emission, e->emission, sizeof emission);
                *e = m.material;
                memcpy(e->emission, emission, sizeof emission);
            }
        return true;
    }
    if (!(m.name = token_dup(&name)))
        return sg_fail(p->err, "%s: out of memory", p->core.path);
    if (!add_pbrt_material(p, &m, &index)) {
        free(m.name);
        return false;
    }
    return true;
}

static bool named_material_statement(Parser *p, const Token *statement)
{
    Token name;
    if (!need_string(p, statement, &name))
        return false;
    for (size_t i = p->material_count; i-- > 0;)
        if (p->materials[i].name && string_is(&name, p->materials[i].name)) {
            p->state.material = (uint32_t)i;
            return true;
        }
    PbrtMaterial m;
    memset(&m, 0, sizeof m);
    char label[64];
    snprintf(label, sizeof label, "%.*s", (int)(name.len > 63 ? 63 : name.len), name.s);
    sg_material_default(&m.material, label);
    m.scene_id = UINT32_MAX;
    m.pending = true;
    m.first_use = name;
    if (!(m.name = token_dup(&name)))
        return sg_fail(p->err, "%s: out of memory", p->core.path);
    if (!add_pbrt_material(p, &m, &p->state.material)) {
        free(m.name);
        return false;
    }
    return true;
}

/* The scene material of the current state (emissive copies cached). */
static bool current_scene_material(Parser *p, bool emissive, uint32_t *id)
{
    PbrtMaterial *m = &p->materials[p->state.material];
    if (!emissive) {
        if (m->scene_id == UINT32_MAX &&
            !sg_builder_add_material(&p->core, &m->material, &m->scene_id, p->err))
            return false;
        *id = m->scene_id;
        return true;
    }
    const float *L = p->state.radiance;
    for (size_t i = 0; i < p->emissive_count; i++) {
        EmissiveMaterial *e = &p->emissive[i];
        if (e->material == p->state.material && !memcmp(e->radiance, L, sizeof e->radiance)) {
            *id = e->scene_id;
            return true;
        }
    }
    SgMaterial copy = m->material;
    memcpy(copy.emission, L, sizeof copy.emission);
    if (!RESERVE(p, p->emissive, p->emissive_count, p->emissive_capacity, 1) ||
        !sg_builder_add_material(&p->core, &copy, id, p->err))
        return false;
    EmissiveMaterial *e = &p->emissive[p->emissive_count++];
    e->material = p->state.material;
    memcpy(e->radiance, L, sizeof e->radiance);
    e->scene_id = *id;
    return true;
}

static bool area_light_statement(Parser *p, const Token *statement)
{
    Token type;
    if (!need_string(p, statement, &type) || !parse_params(p))
        return false;
    if (!string_is(&type, "diffuse")) {
        warn_at(p, statement, "AreaLightSource \"%.*s\" is not supported: shapes not emissive",
                (int)type.len, type.s);
        p->state.area_light = false;
        return true;
    }
    float L[3];
    double scale;
    bool two_sided;
    if (!param_color(p, "L", (const float[3]){1, 1, 1}, L, NULL) ||
        !param_float(p, "scale", 1, &scale) || !param_bool(p, "twosided", false, &two_sided))
        return false;
    if (!(scale >= 0))
        return fail_at(p, statement, "AreaLightSource: \"scale\" must not be negative");
    if (two_sided)
        warn_at(p, statement, "two-sided area lights emit on their front side only");
    if (find_param(p, "power"))
        warn_at(p, statement, "area light \"power\" is ignored (\"L\" and \"scale\" are used)");
    if (find_param(p, "filename"))
        warn_at(p, statement, "image area lights are taken as uniform");
    for (int a = 0; a < 3; a++)
        L[a] = (float)(L[a] * scale);
    memcpy(p->state.radiance, L, sizeof L);
    p->state.area_light = L[0] > 0 || L[1] > 0 || L[2] > 0;
    return true;
}

/* ---- transforms --------------------------------------------------------- */

static bool finite_matrix(const SgTransform *m)
{
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            if (!isfinite(m->m[i][j]))
                return false;
    return true;
}

/* The CTM as an affine transform for shapes. */
static bool shape_transform(Parser *p, const Token *at, SgTransform *xf)
{
    const double(*m)[4] = p->state.ctm.m;
    double w = m[3][3];
    if (fabs(m[3][0]) > 1e-12 || fabs(m[3][1]) > 1e-12 || fabs(m[3][2]) > 1e-12 ||
        !(fabs(w) > 1e-300))
        return fail_at(p, at, "the current transform is projective: shapes need an affine one");
    sg_transform_identity(xf);
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 4; c++)
            xf->m[r][c] = m[r][c] / w;
    return true;
}

static bool transform_statement(Parser *p, const Token *t)
{
    SgTransform m;
    sg_transform_identity(&m);
    if (token_is(t, "Translate")) {
        double v[3];
        if (!need_number(p, t, &v[0]) || !need_number(p, t, &v[1]) || !need_number(p, t, &v[2]))
            return false;
        for (int a = 0; a < 3; a++)
            m.m[a][3] = v[a];
    } else if (token_is(t, "Scale")) {
        double v[3];
        if (!need_number(p, t, &v[0]) || !need_number(p, t, &v[1]) || !need_number(p, t, &v[2]))
            return false;
        for (int a = 0; a < 3; a++)
            m.m[a][a] = v[a];
    } else if (token_is(t, "Rotate")) {
        double v[4];
        for (int i = 0; i < 4; i++)
            if (!need_number(p, t, &v[i]))
                return false;
        if (!sg_transform_rotation(&m, v[0], v + 1))
            return fail_at(p, t, "Rotate: the axis is zero");
    } else if (token_is(t, "LookAt")) {
        double v[9];
        for (int i = 0; i < 9; i++)
            if (!need_number(p, t, &v[i]))
                return false;
        double pos[3] = {v[0], v[1], v[2]}, dir[3], up[3] = {v[6], v[7], v[8]}, right[3],
               new_up[3];
        d3_sub(v + 3, pos, dir);
        double dl = d3_length(dir), ul = d3_length(up);
        if (!(dl > 0))
            return fail_at(p, t, "LookAt: the eye and the target coincide");
        for (int a = 0; a < 3; a++) {
            dir[a] /= dl;
            up[a] = ul > 0 ? up[a] / ul : 0;
        }
        d3_cross(up, dir, right);
        double rl = d3_length(right);
        if (!(rl > 1e-12))
            return fail_at(p, t, "LookAt: the up vector is parallel to the view direction");
        for (int a = 0; a < 3; a++)
            right[a] /= rl;
        d3_cross(dir, right, new_up);
        SgTransform world_from_camera;
        sg_transform_identity(&world_from_camera);
        for (int a = 0; a < 3; a++) {
            world_from_camera.m[a][0] = right[a];
            world_from_camera.m[a][1] = new_up[a];
            world_from_camera.m[a][2] = dir[a];
            world_from_camera.m[a][3] = pos[a];
        }
        if (!sg_transform_inverse(&world_from_camera, &m))
            return fail_at(p, t, "LookAt: singular view");
    } else { /* Transform, ConcatTransform: 16 numbers, column by column */
        double v[16];
        if (!need_bracketed_numbers(p, t, 16, v))
            return false;
        for (int i = 0; i < 4; i++)
            for (int j = 0; j < 4; j++)
                m.m[i][j] = v[4 * j + i];
        if (token_is(t, "Transform")) {
            p->state.ctm = m;
            return true;
        }
    }
    if (!finite_matrix(&m))
        return fail_at(p, t, "%.*s: non-finite numbers", (int)t->len, t->s);
    sg_transform_multiply(&p->state.ctm, &m, &p->state.ctm);
    return true;
}

static NamedTransform *find_coordinate_system(Parser *p, const Token *name)
{
    for (size_t i = 0; i < p->coordinate_system_count; i++)
        if (string_is(name, p->coordinate_systems[i].name))
            return &p->coordinate_systems[i];
    return NULL;
}

static bool set_coordinate_system(Parser *p, const Token *name, const SgTransform *m)
{
    NamedTransform *n = find_coordinate_system(p, name);
    if (!n) {
        if (!RESERVE(p, p->coordinate_systems, p->coordinate_system_count,
                     p->coordinate_system_capacity, 1))
            return false;
        n = &p->coordinate_systems[p->coordinate_system_count];
        if (!(n->name = token_dup(name)))
            return sg_fail(p->err, "%s: out of memory", p->core.path);
        p->coordinate_system_count++;
    }
    n->m = *m;
    return true;
}

/* ---- attribute blocks --------------------------------------------------- */

static bool push_state(Parser *p, const Token *begin)
{
    if (!RESERVE(p, p->saved, p->saved_count, p->saved_capacity, 1))
        return false;
    p->saved[p->saved_count].state = p->state;
    p->saved[p->saved_count].begin = *begin;
    p->saved_count++;
    return true;
}

static bool pop_state(Parser *p, const Token *t, bool transform_only)
{
    if (p->saved_count == 0)
        return fail_at(p, t, "%.*s without a matching %s", (int)t->len, t->s,
                       transform_only ? "TransformBegin" : "AttributeBegin");
    GraphicsState *s = &p->saved[--p->saved_count].state;
    if (transform_only)
        p->state.ctm = s->ctm;
    else
        p->state = *s;
    return true;
}

/* ---- shapes ------------------------------------------------------------- */

/* Appends a mesh (object-space positions) with the current state. normals
 * (object space, per vertex) decide which side emits, as in pbrt; without
 * them the winding does, flipped by ReverseOrientation and by a mirroring
 * transform. */
static bool emit_mesh(Parser *p, const Token *at, const char *what, const double *positions,
                      uint32_t vertex_count, uint32_t *indices, uint32_t triangle_count,
                      const double *normals)
{
    if (p->materials[p->state.material].invisible) {
        warn_at(p, at, "shapes with the \"interface\" material are left out (media are not "
                       "supported)");
        return true;
    }
    SgTransform xf;
    if (!shape_transform(p, at, &xf))
        return false;
    bool emissive = p->state.area_light;
    if (emissive && p->defining) {
        warn_at(p, at, "area lights inside ObjectBegin are ignored (as pbrt does)");
        emissive = false;
    }
    uint32_t material;
    if (!current_scene_material(p, emissive, &material))
        return false;
    if (emissive) {
        double det = sg_transform_determinant(&xf);
        bool flip_all = p->state.reverse_orientation != (det < 0);
        for (uint32_t t = 0; t < triangle_count; t++) {
            uint32_t *idx = indices + 3 * (size_t)t;
            bool flip = flip_all;
            if (normals) {
                double wp[3][3], e1[3], e2[3], n[3], ns[3] = {0, 0, 0}, nw[3];
                for (int c = 0; c < 3; c++) {
                    sg_transform_point(&xf, positions + 3 * (size_t)idx[c], wp[c]);
                    for (int a = 0; a < 3; a++)
                        ns[a] += normals[3 * (size_t)idx[c] + a];
                }
                d3_sub(wp[1], wp[0], e1);
                d3_sub(wp[2], wp[0], e2);
                d3_cross(e1, e2, n);
                sg_transform_normal(&xf, ns, nw);
                if (d3_length(nw) > 0) /* else: the winding decides */
                    flip = d3_dot(n, nw) < 0;
            }
            if (flip) {
                uint32_t k = idx[1];
                idx[1] = idx[2];
                idx[2] = k;
            }
        }
    }
    if (p->defining) {
        Object *o = p->defining;
        if (!RESERVE(p, o->shapes, o->shape_count, o->shape_capacity, 1))
            return false;
        ObjectShape *s = &o->shapes[o->shape_count];
        memset(s, 0, sizeof *s);
        s->positions = malloc((vertex_count ? vertex_count : 1) * 3 * sizeof(double));
        s->indices = malloc((triangle_count ? triangle_count : 1) * 3 * sizeof(uint32_t));
        if (!s->positions || !s->indices) {
            free(s->positions);
            free(s->indices);
            return sg_fail(p->err, "%s: out of memory", p->core.path);
        }
        o->shape_count++;
        for (uint32_t v = 0; v < vertex_count; v++) {
            if (!sg_builder_check_point(&p->core, what, positions + 3 * (size_t)v, p->err))
                return false;
            sg_transform_point(&xf, positions + 3 * (size_t)v, s->positions + 3 * (size_t)v);
        }
        memcpy(s->indices, indices, triangle_count * 3 * sizeof(uint32_t));
        s->vertex_count = vertex_count;
        s->triangle_count = triangle_count;
        s->scene_material = material;
        return true;
    }
    return sg_builder_append_mesh(&p->core, what, positions, vertex_count, indices,
                                  triangle_count, &xf, material, p->err);
}


static bool plymesh(Parser *p, const Token *statement)
{
    const Token *file = param_string(p, "filename");
    if (!file)
        return fail_at(p, statement, "Shape \"plymesh\" has no \"string filename\"");
    char path[8192];
    if (!resolve_path(p, statement, file, path, sizeof path))
        return false;
    if (find_param(p, "displacement"))
        warn_at(p, statement, "plymesh displacement is ignored");
    SgPlyMesh mesh;
    SgError local = {0};
    if (!sg_ply_mesh_read(&mesh, path, &local))
        return fail_at(p, statement, "%s", local.message);
    bool ok = emit_mesh(p, statement, path, mesh.positions, mesh.vertex_count, mesh.indices,
                        mesh.triangle_count, mesh.normals);
    sg_ply_mesh_release(&mesh);
    return ok;
}

/* trianglemesh, bilinearmesh and loopsubdiv (its control mesh). */
static bool inline_mesh(Parser *p, const Token *statement, const Token *type)
{
    const Param *P = find_param(p, "P");
    if (!P || P->kind != PARAM_NUMBERS || P->count == 0 || P->count % 3)
        return fail_at(p, statement, "Shape \"%.*s\" needs \"point3 P\" (x y z ...)",
                       (int)type->len, type->s);
    if (strcmp(P->type, "point3"))
        return fail_at(p, statement, "\"P\" must be \"point3\", not \"%s\"", P->type);
    size_t vertex_count = P->count / 3;
    if (vertex_count > UINT32_MAX / 4)
        return fail_at(p, statement, "too many vertices");
    const Param *I = find_param(p, "indices");
    bool bilinear = string_is(type, "bilinearmesh");
    size_t per_face = bilinear ? 4 : 3;
    size_t index_count;
    if (I) {
        if (I->kind != PARAM_NUMBERS || strcmp(I->type, "integer"))
            return fail_at(p, statement, "\"indices\" must be \"integer\"");
        index_count = I->count;
    } else if (vertex_count == per_face) {
        index_count = per_face;
    } else {
        return fail_at(p, statement, "Shape \"%.*s\" needs \"integer indices\"", (int)type->len,
                       type->s);
    }
    if (index_count == 0 || index_count % per_face)
        return fail_at(p, statement, "\"indices\" must hold a multiple of %zu values", per_face);
    if (string_is(type, "loopsubdiv"))
        warn_at(p, statement, "loopsubdiv shapes are used without subdivision (control mesh)");
    size_t faces = index_count / per_face;
    size_t triangle_count = bilinear ? 2 * faces : faces;
    uint32_t *indices = malloc(triangle_count * 3 * sizeof(uint32_t));
    double *normals = NULL;
    if (!indices)
        return sg_fail(p->err, "%s: out of memory", p->core.path);
    uint32_t corner[4];
    size_t t = 0;
    for (size_t f = 0; f < faces; f++) {
        for (size_t c = 0; c < per_face; c++) {
            double v = I ? p->numbers[I->first + f * per_face + c] : (double)c;
            if (!(v >= 0 && v < (double)vertex_count)) {
                free(indices);
                return fail_at(p, statement, "index %g is out of range (%zu vertices)", v,
                               vertex_count);
            }
            corner[c] = (uint32_t)v;
        }
        if (bilinear) { /* p00 p10 p01 p11 */
            uint32_t tri[6] = {corner[0], corner[1], corner[3], corner[0], corner[3], corner[2]};
            memcpy(indices + 3 * t, tri, sizeof tri);
            t += 2;
        } else {
            memcpy(indices + 3 * t, corner, 3 * sizeof(uint32_t));
            t++;
        }
    }
    const Param *N = find_param(p, "N");
    if (N && N->kind == PARAM_NUMBERS && N->count == P->count && !bilinear)
        normals = p->numbers + N->first;
    if (find_param(p, "alpha"))
        warn_at(p, statement, "alpha cut-outs are ignored (the shapes are opaque)");
    char what[4300];
    snprintf(what, sizeof what, "%s:%d", statement->source->path, statement->line);
    bool ok = emit_mesh(p, statement, what, p->numbers + P->first, (uint32_t)vertex_count,
                        indices, (uint32_t)triangle_count, normals);
    free(indices);
    return ok;
}

static bool shape_statement(Parser *p, const Token *statement)
{
    Token type;
    if (!need_string(p, statement, &type) || !parse_params(p))
        return false;
    if (!p->in_world)
        warn_at(p, statement, "shapes before WorldBegin are used as if after it");
    if (string_is(&type, "plymesh")) {
        if (find_param(p, "alpha"))
            warn_at(p, statement, "alpha cut-outs are ignored (the shapes are opaque)");
        return plymesh(p, statement);
    }
    if (string_is(&type, "trianglemesh") || string_is(&type, "bilinearmesh") ||
        string_is(&type, "loopsubdiv"))
        return inline_mesh(p, statement, &type);
    warn_at(p, statement, "Shape \"%.*s\" is not supported: left out", (int)type.len, type.s);
    return true;
}

/* ---- object instancing -------------------------------------------------- */

static Object *find_object(Parser *p, const Token *name)
{
    for (size_t i = 0; i < p->object_count; i++)
        if (string_is(name, p->objects[i].name))
            return &p->objects[i];
    return NULL;
}

static bool object_begin(Parser *p, const Token *statement)
{
    Token name;
    if (!need_string(p, statement, &name))
        return false;
    if (p->defining)
        return fail_at(p, statement, "ObjectBegin inside ObjectBegin (line %d)",
                       p->defining_begin.line);
    if (find_object(p, &name))
        return fail_at(p, &name, "object \"%.*s\" is defined twice", (int)name.len, name.s);
    if (!push_state(p, statement) ||
        !RESERVE(p, p->objects, p->object_count, p->object_capacity, 1))
        return false;
    Object *o = &p->objects[p->object_count];
    memset(o, 0, sizeof *o);
    if (!(o->name = token_dup(&name)))
        return sg_fail(p->err, "%s: out of memory", p->core.path);
    p->object_count++;
    p->defining = o;
    p->defining_begin = *statement;
    return true;
}

static bool object_end(Parser *p, const Token *statement)
{
    if (!p->defining)
        return fail_at(p, statement, "ObjectEnd without ObjectBegin");
    p->defining = NULL;
    return pop_state(p, statement, false);
}

static bool object_instance(Parser *p, const Token *statement)
{
    Token name;
    if (!need_string(p, statement, &name))
        return false;
    if (p->defining)
        return fail_at(p, statement, "ObjectInstance inside ObjectBegin (line %d)",
                       p->defining_begin.line);
    Object *o = find_object(p, &name);
    if (!o)
        return fail_at(p, &name, "ObjectInstance \"%.*s\": no such object", (int)name.len, name.s);
    SgTransform xf;
    if (!shape_transform(p, statement, &xf))
        return false;
    for (size_t i = 0; i < o->shape_count; i++) {
        const ObjectShape *s = &o->shapes[i];
        if (!sg_builder_append_mesh(&p->core, o->name, s->positions, s->vertex_count,
                                    s->indices, s->triangle_count, &xf, s->scene_material,
                                    p->err))
            return false;
    }
    return true;
}

/* ---- camera, film and the rest ------------------------------------------ */

static bool camera_statement(Parser *p, const Token *statement)
{
    Token type;
    if (!need_string(p, statement, &type) || !parse_params(p))
        return false;
    if (p->in_world)
        return fail_at(p, statement, "Camera after WorldBegin");
    if (!string_is(&type, "perspective"))
        warn_at(p, statement, "Camera \"%.*s\" is taken as a perspective camera", (int)type.len,
                type.s);
    double fov, lens, aspect;
    if (!param_float(p, "fov", 90, &fov) || !param_float(p, "lensradius", 0, &lens) ||
        !param_float(p, "frameaspectratio", 0, &aspect))
        return false;
    if (!(fov > 0 && fov < 180))
        return fail_at(p, statement, "Camera: fov %g is not in (0, 180) degrees", fov);
    if (lens > 0)
        warn_at(p, statement, "depth of field (lensradius) is ignored: pinhole camera");
    if (find_param(p, "screenwindow") || find_param(p, "frameaspectratio"))
        warn_at(p, statement, "Camera screenwindow/frameaspectratio are ignored");
    p->camera_from_world = p->state.ctm;
    SgTransform world_from_camera;
    if (!sg_transform_inverse(&p->camera_from_world, &world_from_camera))
        return fail_at(p, statement, "Camera: the camera transform is singular");
    p->has_camera = true;
    p->fov = fov;
    Token camera_name = {.s = "camera", .len = 6, .quoted = true};
    return set_coordinate_system(p, &camera_name, &world_from_camera);
}

static bool film_statement(Parser *p, const Token *statement)
{
    Token type;
    if (!need_string(p, statement, &type) || !parse_params(p))
        return false;
    double w, h;
    if (!param_float(p, "xresolution", 1280, &w) || !param_float(p, "yresolution", 720, &h))
        return false;
    if (!(w >= 1 && w <= 65536 && h >= 1 && h <= 65536))
        return fail_at(p, statement, "Film resolution %gx%g is out of range", w, h);
    p->film_width = (int)w;
    p->film_height = (int)h;
    if (find_param(p, "cropwindow") || find_param(p, "pixelbounds"))
        warn_at(p, statement, "Film cropwindow/pixelbounds are ignored: the whole image");
    return true;
}

/* A statement with a name and parameters we read but do not use. */
static bool skip_named_statement(Parser *p, const Token *statement)
{
    Token name;
    return need_string(p, statement, &name) && parse_params(p);
}

static bool include_statement(Parser *p, const Token *statement)
{
    Token name;
    if (!need_string(p, statement, &name))
        return false;
    char path[8192];
    if (!resolve_path(p, statement, &name, path, sizeof path))
        return false;
    return push_file(p, path, statement);
}

static bool statement(Parser *p, const Token *t)
{
    if (t->quoted)
        return fail_at(p, t, "expected a statement, found the string \"%.*s\"",
                       (int)(t->len > 40 ? 40 : t->len), t->s);
    if (token_is(t, "[") || token_is(t, "]"))
        return fail_at(p, t, "'%c' outside a parameter list", t->s[0]);
    if (token_is(t, "AttributeBegin") || token_is(t, "TransformBegin"))
        return push_state(p, t);
    if (token_is(t, "AttributeEnd"))
        return pop_state(p, t, false);
    if (token_is(t, "TransformEnd"))
        return pop_state(p, t, true);
    if (token_is(t, "Translate") || token_is(t, "Scale") || token_is(t, "Rotate") ||
        token_is(t, "LookAt") || token_is(t, "Transform") || token_is(t, "ConcatTransform"))
        return transform_statement(p, t);
    if (token_is(t, "Identity")) {
        sg_transform_identity(&p->state.ctm);
        return true;
    }
    if (token_is(t, "CoordinateSystem") || token_is(t, "CoordSysTransform")) {
        Token name;
        if (!need_string(p, t, &name))
            return false;
        if (token_is(t, "CoordinateSystem"))
            return set_coordinate_system(p, &name, &p->state.ctm);
        NamedTransform *n = find_coordinate_system(p, &name);
        if (!n)
            return fail_at(p, &name, "CoordSysTransform \"%.*s\": no such coordinate system",
                           (int)name.len, name.s);
        p->state.ctm = n->m;
        return true;
    }
    if (token_is(t, "ReverseOrientation")) {
        p->state.reverse_orientation = !p->state.reverse_orientation;
        return true;
    }
    if (token_is(t, "WorldBegin")) {
        if (p->in_world)
            return fail_at(p, t, "WorldBegin twice");
        p->in_world = true;
        sg_transform_identity(&p->state.ctm);
        Token world = {.s = "world", .len = 5, .quoted = true};
        return set_coordinate_system(p, &world, &p->state.ctm);
    }
    if (token_is(t, "WorldEnd")) /* pbrt-v3 */
        return true;
    if (token_is(t, "Camera"))
        return camera_statement(p, t);
    if (token_is(t, "Film"))
        return film_statement(p, t);
    if (token_is(t, "Sampler") || token_is(t, "Integrator")) {
        Token name;
        if (!need_string(p, t, &name) || !parse_params(p))
            return false;
        double v;
        if (token_is(t, "Sampler") && find_param(p, "pixelsamples")) {
            if (!param_float(p, "pixelsamples", 16, &v))
                return false;
            if (v >= 1 && v <= (1 << 24))
                p->core.scene->render.spp = (int)v;
        }
        if (token_is(t, "Integrator")) {
            if (!param_float(p, "maxdepth", 5, &v))
                return false;
            if (v >= 1 && v <= 1024)
                p->core.scene->render.max_depth = (int)v;
        }
        return true;
    }
    if (token_is(t, "PixelFilter") || token_is(t, "Accelerator"))
        return skip_named_statement(p, t);
    if (token_is(t, "ColorSpace")) {
        Token name;
        if (!need_string(p, t, &name))
            return false;
        if (!string_is(&name, "srgb"))
            warn_at(p, t, "ColorSpace \"%.*s\" is ignored: colours are taken as sRGB",
                    (int)name.len, name.s);
        return true;
    }
    if (token_is(t, "Option")) {
        Token name, value;
        return need_string(p, t, &name) && need_token(p, t, &value);
    }
    if (token_is(t, "Shape"))
        return shape_statement(p, t);
    if (token_is(t, "Material"))
        return material_statement(p, t);
    if (token_is(t, "MakeNamedMaterial"))
        return make_named_material_statement(p, t);
    if (token_is(t, "NamedMaterial"))
        return named_material_statement(p, t);
    if (token_is(t, "Texture"))
        return texture_statement(p, t);
    if (token_is(t, "AreaLightSource"))
        return area_light_statement(p, t);
    if (token_is(t, "LightSource")) {
        Token type;
        if (!need_string(p, t, &type) || !parse_params(p))
            return false;
        warn_at(p, t, "LightSource \"%.*s\" is not supported (only area lights): left out",
                (int)type.len, type.s);
        return true;
    }
    if (token_is(t, "MakeNamedMedium")) {
        if (!skip_named_statement(p, t))
            return false;
        warn_at(p, t, "participating media are not supported: left out");
        return true;
    }
    if (token_is(t, "MediumInterface")) {
        Token inside, outside;
        if (!need_string(p, t, &inside))
            return false;
        if (next_token(p, &outside) && !outside.quoted)
            unget_token(p, &outside);
        return !p->err->failed;
    }
    if (token_is(t, "Attribute")) {
        if (!skip_named_statement(p, t))
            return false;
        warn_at(p, t, "Attribute statements are ignored");
        return true;
    }
    if (token_is(t, "ActiveTransform")) {
        Token which;
        if (!need_token(p, t, &which))
            return false;
        if (!token_is(&which, "All") && !token_is(&which, "StartTime") &&
            !token_is(&which, "EndTime"))
            return fail_at(p, &which, "ActiveTransform takes All, StartTime or EndTime");
        warn_at(p, t, "motion (ActiveTransform) is ignored: every transform applies");
        return true;
    }
    if (token_is(t, "TransformTimes")) {
        double a, b;
        return need_number(p, t, &a) && need_number(p, t, &b);
    }
    if (token_is(t, "ObjectBegin"))
        return object_begin(p, t);
    if (token_is(t, "ObjectEnd"))
        return object_end(p, t);
    if (token_is(t, "ObjectInstance"))
        return object_instance(p, t);
    if (token_is(t, "Include") || token_is(t, "Import"))
        return include_statement(p, t);
    return fail_at(p, t, "unknown statement \"%.*s\"", (int)(t->len > 40 ? 40 : t->len), t->s);
}

/* ---- the camera in our terms -------------------------------------------- */

static bool finish_camera(Parser *p)
{
    SgScene *s = p->core.scene;
    s->camera.width = p->film_width;
    s->camera.height = p->film_height;
    SgTransform w;
    if (!p->has_camera) { /* pbrt's default: at the origin looking down +z */
        sg_transform_identity(&p->camera_from_world);
        p->fov = 90;
    }
    if (!sg_transform_inverse(&p->camera_from_world, &w))
        return sg_fail(p->err, "%s: the camera transform is singular", p->core.path);
    double pos[4], dir[3], up[3], right[3];
    for (int r = 0; r < 4; r++)
        pos[r] = w.m[r][3];
    if (!(fabs(pos[3]) > 1e-300))
        return sg_fail(p->err, "%s: the camera transform is projective", p->core.path);
    for (int a = 0; a < 3; a++) {
        pos[a] /= pos[3];
        right[a] = w.m[a][0];
        up[a] = w.m[a][1];
        dir[a] = w.m[a][2];
    }
    double dl = d3_length(dir), ul = d3_length(up);
    if (!(dl > 0 && ul > 0))
        return sg_fail(p->err, "%s: the camera transform is degenerate", p->core.path);
    for (int a = 0; a < 3; a++) {
        s->camera.position[a] = pos[a];
        s->camera.look_at[a] = pos[a] + dir[a] / dl;
        s->camera.up[a] = up[a] / ul;
    }
    /* Our image's right is view x up; pbrt's is camera +x. */
    double ours[3];
    d3_cross(dir, up, ours);
    if (d3_dot(ours, right) < 0) {
        Token none = {0};
        warn_at(p, &none, "the camera transform does not mirror the image as pbrt's screen "
                          "mapping expects (no \"Scale -1 1 1\"): our image is pbrt's mirrored "
                          "left to right");
    }
    /* pbrt's fov spans the shorter image axis; ours is vertical. */
    double aspect = (double)s->camera.width / s->camera.height;
    double fov = p->fov;
    if (aspect < 1)
        fov = 2 * atan(tan(fov * M_PI / 360) / aspect) * 180 / M_PI;
    s->camera.fov_deg = fov;
    s->has_camera = true;
    return true;
}

/* ---- entry point -------------------------------------------------------- */

static void parser_release(Parser *p)
{
    for (size_t i = 0; i < p->source_count; i++) {
        free(p->sources[i]->text);
        free(p->sources[i]);
    }
    free(p->sources);
    free(p->params);
    free(p->numbers);
    free(p->strings);
    free(p->bools);
    free(p->saved);
    for (size_t i = 0; i < p->material_count; i++)
        free(p->materials[i].name);
    free(p->materials);
    free(p->emissive);
    for (size_t i = 0; i < p->texture_count; i++)
        free(p->textures[i].name);
    free(p->textures);
    for (size_t i = 0; i < p->coordinate_system_count; i++)
        free(p->coordinate_systems[i].name);
    free(p->coordinate_systems);
    for (size_t i = 0; i < p->object_count; i++) {
        for (size_t k = 0; k < p->objects[i].shape_count; k++) {
            free(p->objects[i].shapes[k].positions);
            free(p->objects[i].shapes[k].indices);
        }
        free(p->objects[i].shapes);
        free(p->objects[i].name);
    }
    free(p->objects);
    free(p->warnings);
    for (size_t i = 0; i < p->image_count; i++)
        free(p->images[i].path);
    free(p->images);
}

SgScene *sg_pbrt_scene_load(const char *path, SgError *err)
{
    Parser p;
    memset(&p, 0, sizeof p);
    p.err = err;
    if (!sg_builder_begin(&p.core, path, err))
        return NULL;
    SgScene *s = p.core.scene;
    const char *slash = strrchr(path, '/');
    snprintf(p.base_dir, sizeof p.base_dir, "%.*s", slash ? (int)(slash - path + 1) : 0, path);
    p.film_width = 1280; /* pbrt's defaults */
    p.film_height = 720;
    s->render.max_depth = 5;
    sg_transform_identity(&p.state.ctm);
    PbrtMaterial fallback; /* pbrt's default: diffuse 0.5 */
    memset(&fallback, 0, sizeof fallback);
    sg_material_default(&fallback.material, "default");
    fallback.scene_id = UINT32_MAX;
    bool ok = add_pbrt_material(&p, &fallback, &p.state.material) && push_file(&p, path, NULL);
    Token t;
    while (ok && next_token(&p, &t))
        ok = statement(&p, &t);
    ok = ok && !err->failed;
    if (ok && p.defining)
        ok = fail_at(&p, &p.defining_begin, "ObjectBegin has no matching ObjectEnd");
    if (ok && p.saved_count) {
        const Token *begin = &p.saved[p.saved_count - 1].begin;
        ok = fail_at(&p, begin, "%.*s has no matching %s", (int)begin->len, begin->s,
                     token_is(begin, "TransformBegin") ? "TransformEnd" : "AttributeEnd");
    }
    for (size_t i = 0; ok && i < p.material_count; i++)
        if (p.materials[i].pending)
            ok = fail_at(&p, &p.materials[i].first_use, "NamedMaterial \"%s\" is never defined",
                         p.materials[i].name);
    ok = ok && finish_camera(&p);
    if (ok && s->triangle_count == 0)
        ok = sg_fail(err, "%s: the scene has no triangles%s", path,
                     p.core.dropped_degenerate ? " (all were degenerate)" : "");
    ok = ok && sg_builder_finish(&p.core, err);
    if (ok)
        for (size_t i = 0; i < p.warning_count; i++) {
            const Warning *w = &p.warnings[i];
            if (w->count > 1)
                sg_scene_add_warning(s, "%s: %s (%u times)", w->where, w->kind, w->count);
            else
                sg_scene_add_warning(s, "%s: %s", w->where, w->kind);
        }
    parser_release(&p);
    if (!ok) {
        sg_scene_free(s);
        return NULL;
    }
    return s;
}
