/* The PLY format's scalar types, shared by its two readers (meshes,
 * common/ply_mesh.c; skeletons, common/skeleton_graph.c): their names in a
 * header, their sizes, and a binary value decoded to a double. */
#ifndef SG_PLY_TYPES_H
#define SG_PLY_TYPES_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

typedef enum SgPlyType {
    SG_PLY_NONE, SG_PLY_I8, SG_PLY_U8, SG_PLY_I16, SG_PLY_U16, SG_PLY_I32, SG_PLY_U32, SG_PLY_F32, SG_PLY_F64
} SgPlyType;

/* A type's name in a "property" line (both spellings, "uchar" and
 * "uint8"...); SG_PLY_NONE for anything else. */
static inline SgPlyType sg_ply_type_parse(const char *name)
{
    static const struct {
        const char *name;
        SgPlyType type;
    } names[] = {
        {"char", SG_PLY_I8},   {"int8", SG_PLY_I8},     {"uchar", SG_PLY_U8},  {"uint8", SG_PLY_U8},
        {"short", SG_PLY_I16}, {"int16", SG_PLY_I16},   {"ushort", SG_PLY_U16}, {"uint16", SG_PLY_U16},
        {"int", SG_PLY_I32},   {"int32", SG_PLY_I32},   {"uint", SG_PLY_U32},  {"uint32", SG_PLY_U32},
        {"float", SG_PLY_F32}, {"float32", SG_PLY_F32}, {"double", SG_PLY_F64}, {"float64", SG_PLY_F64},
    };
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
        if (!strcmp(name, names[i].name))
            return names[i].type;
    return SG_PLY_NONE;
}

/* Bytes of a binary value (0 for SG_PLY_NONE). */
static inline size_t sg_ply_type_size(SgPlyType t)
{
    static const size_t sizes[] = {0, 1, 1, 2, 2, 4, 4, 4, 8};
    return (unsigned)t < sizeof sizes / sizeof sizes[0] ? sizes[t] : 0;
}

static inline bool sg_ply_type_is_float(SgPlyType t) { return t == SG_PLY_F32 || t == SG_PLY_F64; }

/* A type's first spelling in the table above ("uchar" for SG_PLY_U8), for
 * messages; "none" for SG_PLY_NONE. */
static inline const char *sg_ply_type_name(SgPlyType t)
{
    static const char *const names[] = {"none", "char", "uchar", "short", "ushort", "int", "uint", "float", "double"};
    return (unsigned)t < sizeof names / sizeof names[0] ? names[t] : "none";
}

/* The binary value of type t at p (sg_ply_type_size(t) bytes, little- or
 * big-endian) as a double; false for SG_PLY_NONE. */
static inline bool sg_ply_decode(const unsigned char *p, SgPlyType t, bool big_endian, double *out)
{
    size_t size = sg_ply_type_size(t);
    unsigned char b[8];
    for (size_t i = 0; i < size; i++)
        b[i] = big_endian ? p[size - 1 - i] : p[i];
    switch (t) {
    case SG_PLY_I8: *out = (int8_t)b[0]; break;
    case SG_PLY_U8: *out = b[0]; break;
    case SG_PLY_I16: { int16_t v; memcpy(&v, b, 2); *out = v; break; }
    case SG_PLY_U16: { uint16_t v; memcpy(&v, b, 2); *out = v; break; }
    case SG_PLY_I32: { int32_t v; memcpy(&v, b, 4); *out = v; break; }
    case SG_PLY_U32: { uint32_t v; memcpy(&v, b, 4); *out = v; break; }
    case SG_PLY_F32: { float v; memcpy(&v, b, 4); *out = v; break; }
    case SG_PLY_F64: { double v; memcpy(&v, b, 8); *out = v; break; }
    default: return false;
    }
    return true;
}

#endif
