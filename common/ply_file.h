/* What the two PLY readers (meshes, common/ply_mesh.c; skeletons,
 * common/skeleton_graph.c) share: the header walk into elements and
 * properties, and reading one value of the data in binary or ascii. What a
 * reader accepts beyond that (the skeleton's formats, fields and types) is
 * its own policy, checked on the parsed header. */
#ifndef SG_PLY_FILE_H
#define SG_PLY_FILE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "error.h"
#include "output_file.h"
#include "ply_types.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Fixed limits keep the header one allocation; real files use 2 or 3
 * elements of at most a dozen properties. */
enum { SG_PLY_MAX_ELEMENTS = 16, SG_PLY_MAX_PROPERTIES = 64, SG_PLY_NAME_CAP = 64 };

typedef enum SgPlyFormat { SG_PLY_ASCII, SG_PLY_BINARY_LE, SG_PLY_BINARY_BE } SgPlyFormat;

typedef struct SgPlyProperty {
    char name[SG_PLY_NAME_CAP];
    SgPlyType type;       /* scalar type, or the item type of a list */
    SgPlyType count_type; /* SG_PLY_NONE for a scalar; an integer type for a list */
} SgPlyProperty;

typedef struct SgPlyElement {
    char name[SG_PLY_NAME_CAP];
    uint64_t count; /* at most UINT32_MAX */
    int property_count;
    SgPlyProperty properties[SG_PLY_MAX_PROPERTIES];
} SgPlyElement;

typedef struct SgPlyHeader {
    SgPlyFormat format;
    size_t data_start; /* the byte after the end_header line's '\n' */
    int element_count;
    SgPlyElement elements[SG_PLY_MAX_ELEMENTS];
} SgPlyHeader;

/* Parses the header of the `size` bytes at `data` (not NUL-terminated;
 * never read past size); `path` names them in one-line errors. The header
 * is a "ply" line, "format FORMAT 1.0", "element NAME COUNT", "property
 * TYPE NAME" and "property list COUNT_TYPE TYPE NAME" lines (words after
 * these are ignored, names cut at SG_PLY_NAME_CAP - 1 characters), comment
 * and obj_info lines, and "end_header". FORMAT is ascii or
 * binary_little_endian, or binary_big_endian where the reader takes it
 * (big_endian: a reader's policy, like its size limit). */
bool sg_ply_header_parse(SgPlyHeader *header, const void *data, size_t size, bool big_endian,
                         const char *path, SgError *err);

/* Opens `path` for writing (committed or aborted by the caller, as
 * output_file.h says) and writes the first lines of a binary little-endian
 * PLY header, with one comment line; the caller writes the elements,
 * end_header and the data. */
bool sg_ply_write_begin(SgOutputFile *out, const char *path, const char *comment, SgError *err);

/* One binary value of type t at data[*pos] as a double, *pos moved past
 * it; false when the data end first. Inline: meshes read millions. */
static inline bool sg_ply_read_binary(const unsigned char *data, size_t size, size_t *pos, SgPlyType t,
                                      bool big_endian, double *out)
{
    size_t n = sg_ply_type_size(t);
    if (size - *pos < n)
        return false;
    bool ok = sg_ply_decode(data + *pos, t, big_endian, out);
    *pos += n;
    return ok;
}

typedef enum SgPlyToken { SG_PLY_TOKEN_OK, SG_PLY_TOKEN_END, SG_PLY_TOKEN_BAD } SgPlyToken;

/* The next ascii value's text at data[*pos] (after spaces, tabs and line
 * ends) into token, NUL-terminated, *pos moved past it: END when only
 * blanks are left, BAD when it is longer than cap - 1 or starts with
 * another control byte (a NUL must not end a number early). */
SgPlyToken sg_ply_read_token(const unsigned char *data, size_t size, size_t *pos, char *token, size_t cap);

#ifdef __cplusplus
}
#endif
#endif
