/* skeleton.ply: writer (binary_little_endian) and a defensive reader
 * (ascii and binary_little_endian). The reader loads the whole file, parses
 * the header into a list of elements and properties (common/ply_file.c,
 * shared with the mesh reader), then decodes each element with bounds
 * checks on every read: a malformed or truncated file ends in a one-line
 * error naming the file, never in a read past the end. */
#include "skeleton_graph.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "input_file.h"
#include "output_file.h"
#include "ply_file.h"

/* ---- writer ------------------------------------------------------------ */

static void put_u32(unsigned char *p, uint32_t v)
{
    p[0] = (unsigned char)v;
    p[1] = (unsigned char)(v >> 8);
    p[2] = (unsigned char)(v >> 16);
    p[3] = (unsigned char)(v >> 24);
}

static void put_f32(unsigned char *p, float f)
{
    uint32_t v;
    memcpy(&v, &f, 4);
    put_u32(p, v);
}

static void put_i32(unsigned char *p, int32_t i)
{
    uint32_t v;
    memcpy(&v, &i, 4);
    put_u32(p, v);
}

enum { SG_PLY_VERTEX_BYTES = 37, SG_PLY_EDGE_BYTES = 8 };

bool sg_skeleton_write_ply(const SgSkeleton *skeleton, const char *path, SgError *err)
{
    /* Refuse to write what the reader would refuse to read. */
    for (uint32_t v = 0; v < skeleton->node_count; v++) {
        const SgSkeletonNode *n = &skeleton->nodes[v];
        if (!isfinite(n->position[0]) || !isfinite(n->position[1]) ||
            !isfinite(n->position[2]) || !isfinite(n->radius))
            return sg_fail(err, "%s: node %u has a non-finite position or radius", path, v);
        if (n->kind > SG_NODE_CAMERA)
            return sg_fail(err, "%s: node %u has unknown kind %u", path, v, n->kind);
    }
    for (uint32_t e = 0; e < skeleton->edge_count; e++)
        if (skeleton->edges[e][0] >= skeleton->node_count ||
            skeleton->edges[e][1] >= skeleton->node_count ||
            skeleton->edges[e][0] > INT32_MAX || skeleton->edges[e][1] > INT32_MAX)
            return sg_fail(err, "%s: edge %u refers to a missing node", path, e);

    SgOutputFile out;
    if (!sg_ply_write_begin(&out, path, "skeleton-guided path tracing: curvilinear skeleton graph", err))
        return false;
    fprintf(out.file,
            "element vertex %u\n"
            "property float x\nproperty float y\nproperty float z\n"
            "property int i\nproperty int j\nproperty int k\n"
            "property uchar kind\n"
            "property float radius\n"
            "property int lifespan\n"
            "property int light\n"
            "element edge %u\n"
            "property int vertex1\nproperty int vertex2\n"
            "end_header\n",
            skeleton->node_count, skeleton->edge_count);
    unsigned char rec[SG_PLY_VERTEX_BYTES];
    for (uint32_t v = 0; v < skeleton->node_count; v++) {
        const SgSkeletonNode *n = &skeleton->nodes[v];
        for (int a = 0; a < 3; a++) {
            put_f32(rec + 4 * a, n->position[a]);
            put_i32(rec + 12 + 4 * a, n->voxel[a]);
        }
        rec[24] = n->kind;
        put_f32(rec + 25, n->radius);
        put_i32(rec + 29, n->lifespan);
        put_i32(rec + 33, n->kind == SG_NODE_LIGHT ? n->light : -1);
        fwrite(rec, 1, sizeof rec, out.file);
    }
    for (uint32_t e = 0; e < skeleton->edge_count; e++) {
        put_u32(rec, skeleton->edges[e][0]);
        put_u32(rec + 4, skeleton->edges[e][1]);
        fwrite(rec, 1, SG_PLY_EDGE_BYTES, out.file);
    }
    return sg_output_commit(&out, err);
}

/* ---- reader ------------------------------------------------------------ */

/* Where a known property's value goes. */
typedef enum PlyField {
    F_UNKNOWN = -1,
    F_X, F_Y, F_Z, F_I, F_J, F_K, F_KIND, F_RADIUS, F_LIFESPAN, F_LIGHT, /* vertex */
    F_V1, F_V2,                                                           /* edge */
    F_COUNT
} PlyField;

static const char *const field_names[F_COUNT] = {
    "x", "y", "z", "i", "j", "k", "kind", "radius", "lifespan", "light", "vertex1", "vertex2",
};

typedef struct PlyReader {
    const char *path;
    const unsigned char *data;
    size_t size;
    size_t pos;
    bool ascii;
    SgPlyHeader header;
    /* field[e][p]: where property p of element e goes */
    PlyField field[SG_PLY_MAX_ELEMENTS][SG_PLY_MAX_PROPERTIES];
} PlyReader;

/* The shared header walk, then this reader's policy: ascii or little
 * endian (what the writer writes and MeshLab and Blender read back), and
 * each known field once, as a scalar of its kind of type. */
static bool parse_header(PlyReader *r, SgError *err)
{
    SgPlyHeader *h = &r->header;
    if (!sg_ply_header_parse(h, r->data, r->size, false, r->path, err))
        return false;
    r->ascii = h->format == SG_PLY_ASCII;
    r->pos = h->data_start;
    for (int e = 0; e < h->element_count; e++) {
        const SgPlyElement *current = &h->elements[e];
        int first = -1, last = -1;
        if (strcmp(current->name, "vertex") == 0)
            first = F_X, last = F_LIGHT;
        else if (strcmp(current->name, "edge") == 0)
            first = F_V1, last = F_V2;
        for (int i = 0; i < current->property_count; i++) {
            const SgPlyProperty *p = &current->properties[i];
            const char *name = p->name;
            PlyField field = F_UNKNOWN;
            for (int f = first; f >= 0 && f <= last; f++)
                if (strcmp(name, field_names[f]) == 0)
                    field = (PlyField)f;
            r->field[e][i] = field;
            if (field == F_UNKNOWN)
                continue;
            for (int q = 0; q < i; q++)
                if (r->field[e][q] == field)
                    return sg_fail(err, "%s: property %s.%s given twice", r->path,
                                   current->name, name);
            if (p->count_type != SG_PLY_NONE)
                return sg_fail(err, "%s: property %s.%s must be a scalar, not a list",
                               r->path, current->name, name);
            bool wants_float = field == F_X || field == F_Y || field == F_Z || field == F_RADIUS;
            if (wants_float != sg_ply_type_is_float(p->type))
                return sg_fail(err, "%s: property %s.%s has type %s, expected %s", r->path,
                               current->name, name, sg_ply_type_name(p->type),
                               wants_float ? "float or double" : "an integer type");
        }
    }
    return true;
}

/* Reads one ascii token as a value of type t; 0 = ok, 1 = end of data,
 * 2 = not a valid number of that type. */
static int read_ascii(PlyReader *r, SgPlyType t, double *out)
{
    char token[80];
    SgPlyToken got = sg_ply_read_token(r->data, r->size, &r->pos, token, sizeof token);
    if (got != SG_PLY_TOKEN_OK)
        return got == SG_PLY_TOKEN_END ? 1 : 2;
    char *end;
    errno = 0;
    if (sg_ply_type_is_float(t)) {
        *out = strtod(token, &end);
        if (*end)
            return 2;
        if (t == SG_PLY_F32 && isfinite(*out))
            *out = (float)*out;
        return 0;
    }
    long long v = strtoll(token, &end, 10);
    if (*end || errno)
        return 2;
    long long lo, hi;
    switch (t) {
    case SG_PLY_I8: lo = INT8_MIN, hi = INT8_MAX; break;
    case SG_PLY_U8: lo = 0, hi = UINT8_MAX; break;
    case SG_PLY_I16: lo = INT16_MIN, hi = INT16_MAX; break;
    case SG_PLY_U16: lo = 0, hi = UINT16_MAX; break;
    case SG_PLY_I32: lo = INT32_MIN, hi = INT32_MAX; break;
    default: lo = 0, hi = UINT32_MAX; break;
    }
    if (v < lo || v > hi)
        return 2;
    *out = (double)v;
    return 0;
}

static bool read_value(PlyReader *r, SgPlyType t, double *out, const SgPlyElement *e, uint64_t row,
                       SgError *err)
{
    if (r->ascii) {
        int rc = read_ascii(r, t, out);
        if (rc == 1)
            return sg_fail(err, "%s: truncated (%s %llu of %llu)", r->path, e->name,
                           (unsigned long long)row, (unsigned long long)e->count);
        if (rc == 2)
            return sg_fail(err, "%s: malformed number in %s %llu", r->path, e->name,
                           (unsigned long long)row);
        return true;
    }
    if (!sg_ply_read_binary(r->data, r->size, &r->pos, t, false, out))
        return sg_fail(err, "%s: truncated (%s %llu of %llu)", r->path, e->name,
                       (unsigned long long)row, (unsigned long long)e->count);
    return true;
}

/* Smallest number of bytes one row of e can take: bounds element counts by
 * the file size before anything is allocated. */
static size_t min_row_bytes(const PlyReader *r, const SgPlyElement *e)
{
    size_t bytes = 0;
    for (int p = 0; p < e->property_count; p++) {
        const SgPlyProperty *q = &e->properties[p];
        if (r->ascii)
            bytes += 2; /* a digit and a separator */
        else
            bytes += (size_t)sg_ply_type_size(q->count_type != SG_PLY_NONE ? q->count_type : q->type);
    }
    return bytes;
}

static bool in_int_range(double v) { return v >= INT32_MIN && v <= INT32_MAX; }

/* The vertex and edge elements (once each, with rows the file can hold)
 * and the properties they need. */
static bool find_elements(PlyReader *r, const SgPlyElement **vertex, const SgPlyElement **edge, SgError *err)
{
    const char *path = r->path;
    *vertex = *edge = NULL;
    for (int i = 0; i < r->header.element_count; i++) {
        const SgPlyElement *e = &r->header.elements[i];
        if (strcmp(e->name, "vertex") == 0 || strcmp(e->name, "edge") == 0) {
            const SgPlyElement **slot = e->name[0] == 'v' ? vertex : edge;
            if (*slot)
                return sg_fail(err, "%s: element %s given twice", path, e->name);
            *slot = e;
        }
        size_t row = min_row_bytes(r, e);
        if (row > 0 && e->count > (r->size - r->pos) / row)
            return sg_fail(err, "%s: truncated (element %s declares %llu rows, the file is too "
                           "short)", path, e->name, (unsigned long long)e->count);
        if (row == 0 && e->count > 0 && (e == *vertex || e == *edge))
            return sg_fail(err, "%s: element %s has no properties", path, e->name);
    }
    if (!*vertex)
        return sg_fail(err, "%s: no 'vertex' element", path);
    bool have[F_COUNT] = {false};
    for (int i = 0; i < r->header.element_count; i++)
        for (int p = 0; p < r->header.elements[i].property_count; p++)
            if (r->field[i][p] != F_UNKNOWN)
                have[r->field[i][p]] = true;
    for (int f = F_X; f <= F_LIFESPAN; f++)
        if (!have[f])
            return sg_fail(err, "%s: vertex property '%s' is missing", path, field_names[f]);
    if (*edge && (!have[F_V1] || !have[F_V2]))
        return sg_fail(err, "%s: edge properties 'vertex1' and 'vertex2' are required", path);
    return true;
}

/* Row `row` of element i into v (by field); an unknown list is read past. */
static bool read_row(PlyReader *r, int i, uint64_t row, double v[F_COUNT], SgError *err)
{
    const SgPlyElement *e = &r->header.elements[i];
    for (int p = 0; p < e->property_count; p++) {
        const SgPlyProperty *q = &e->properties[p];
        double value;
        if (q->count_type == SG_PLY_NONE) {
            if (!read_value(r, q->type, &value, e, row, err))
                return false;
            if (r->field[i][p] != F_UNKNOWN)
                v[r->field[i][p]] = value;
            continue;
        }
        /* An unknown list: read its length, skip its items. */
        if (!read_value(r, q->count_type, &value, e, row, err))
            return false;
        if (value < 0)
            return sg_fail(err, "%s: negative list length in %s %llu", r->path, e->name, (unsigned long long)row);
        for (double item = 0; item < value; item++) {
            double ignored;
            if (!read_value(r, q->type, &ignored, e, row, err))
                return false;
        }
    }
    return true;
}

static bool store_node(SgSkeletonNode *n, uint64_t row, const double v[F_COUNT], const char *path, SgError *err)
{
    for (int a = 0; a < 3; a++) {
        if (!isfinite(v[F_X + a]) || fabs(v[F_X + a]) > 3.0e38)
            return sg_fail(err, "%s: vertex %llu has a non-finite position", path, (unsigned long long)row);
        n->position[a] = (float)v[F_X + a];
    }
    if (!isfinite(v[F_RADIUS]) || v[F_RADIUS] < 0 || v[F_RADIUS] > 3.0e38)
        return sg_fail(err, "%s: vertex %llu has a bad radius", path, (unsigned long long)row);
    if (v[F_KIND] < 0 || v[F_KIND] > SG_NODE_CAMERA)
        return sg_fail(err, "%s: vertex %llu has unknown kind %g", path, (unsigned long long)row, v[F_KIND]);
    if (!in_int_range(v[F_I]) || !in_int_range(v[F_J]) || !in_int_range(v[F_K]) ||
        !in_int_range(v[F_LIFESPAN]) || !in_int_range(v[F_LIGHT]) || v[F_LIGHT] < -1)
        return sg_fail(err, "%s: vertex %llu has an out-of-range integer", path, (unsigned long long)row);
    n->voxel[0] = (int)v[F_I];
    n->voxel[1] = (int)v[F_J];
    n->voxel[2] = (int)v[F_K];
    n->kind = (uint8_t)v[F_KIND];
    n->radius = (float)v[F_RADIUS];
    n->lifespan = (int)v[F_LIFESPAN];
    n->light = n->kind == SG_NODE_LIGHT ? (int)v[F_LIGHT] : -1;
    return true;
}

static bool store_edge(uint32_t edge[2], uint64_t row, const double v[F_COUNT], uint64_t vertex_count,
                       const char *path, SgError *err)
{
    for (int a = 0; a < 2; a++)
        if (v[F_V1 + a] < 0 || v[F_V1 + a] >= (double)vertex_count)
            return sg_fail(err, "%s: edge %llu refers to vertex %g, which does not exist (%llu vertices)", path,
                           (unsigned long long)row, v[F_V1 + a], (unsigned long long)vertex_count);
    if (v[F_V1] == v[F_V2])
        return sg_fail(err, "%s: edge %llu joins vertex %g to itself", path, (unsigned long long)row, v[F_V1]);
    edge[0] = (uint32_t)v[F_V1];
    edge[1] = (uint32_t)v[F_V2];
    return true;
}

/* Decode elements in file order. */
static bool decode_elements(PlyReader *r, const SgPlyElement *vertex, const SgPlyElement *edge,
                            SgSkeleton *skeleton, SgError *err)
{
    for (int i = 0; i < r->header.element_count; i++) {
        const SgPlyElement *e = &r->header.elements[i];
        /* Rows without properties hold no data: nothing to decode (and a
         * count of 4 billion must not take a minute to step through). */
        if (e->property_count == 0)
            continue;
        for (uint64_t row = 0; row < e->count; row++) {
            double v[F_COUNT] = {0};
            v[F_LIGHT] = -1;
            if (!read_row(r, i, row, v, err))
                return false;
            if (e == vertex && !store_node(&skeleton->nodes[row], row, v, r->path, err))
                return false;
            if (e == edge && !store_edge(skeleton->edges[row], row, v, vertex->count, r->path, err))
                return false;
        }
    }
    return true;
}

bool sg_skeleton_parse_ply(SgSkeleton *skeleton, const void *data, size_t size,
                           const char *path, SgError *err)
{
    memset(skeleton, 0, sizeof *skeleton);
    PlyReader *r = calloc(1, sizeof *r);
    if (!r)
        return sg_fail(err, "%s: out of memory", path);
    r->path = path;
    r->data = data;
    r->size = size;
    const SgPlyElement *vertex = NULL, *edge = NULL;
    bool ok = parse_header(r, err) && find_elements(r, &vertex, &edge, err);
    if (ok && vertex->count > 0) {
        skeleton->nodes = calloc(vertex->count, sizeof *skeleton->nodes);
        ok = skeleton->nodes || sg_fail(err, "%s: out of memory", path);
    }
    if (ok && edge && edge->count > 0) {
        skeleton->edges = calloc(edge->count, sizeof *skeleton->edges);
        ok = skeleton->edges || sg_fail(err, "%s: out of memory", path);
    }
    ok = ok && decode_elements(r, vertex, edge, skeleton, err);
    if (ok) {
        skeleton->node_count = (uint32_t)vertex->count;
        skeleton->edge_count = edge ? (uint32_t)edge->count : 0;
    } else {
        sg_skeleton_release(skeleton);
    }
    free(r);
    return ok;
}

bool sg_skeleton_read_ply(SgSkeleton *skeleton, const char *path, SgError *err)
{
    memset(skeleton, 0, sizeof *skeleton);
    char *data;
    size_t size;
    bool ok = sg_read_file(path, NULL, SG_LIMIT_SKELETON, &data, &size, err);
    if (ok)
        ok = sg_skeleton_parse_ply(skeleton, (const unsigned char *)data, size, path, err);
    free(data);
    return ok;
}

void sg_skeleton_release(SgSkeleton *skeleton)
{
    free(skeleton->nodes);
    free(skeleton->edges);
    memset(skeleton, 0, sizeof *skeleton);
}
