/* Mitsuba's .serialized meshes: per mesh a little-endian header (0x041C,
 * version 3 or 4) and a zlib stream of flags, (v4) a name, the vertex and
 * triangle counts, positions, optional normals, texture coordinates and
 * colours, then the triangles' indices; the file ends with each mesh's
 * offset and the mesh count (Mitsuba's documentation of the format). Every
 * count is checked against what the stream can hold before memory is
 * taken, so that a cut or corrupt file is an error, not a crash. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "input_file.h"
#include "mitsuba_parser.h"

enum {
    HAS_NORMALS = 0x0001,
    HAS_TEXCOORDS = 0x0002,
    HAS_COLORS = 0x0008,
    DOUBLE_PRECISION = 0x2000,
};

static uint64_t le(const unsigned char *b, int bytes)
{
    uint64_t v = 0;
    for (int i = bytes; i-- > 0;)
        v = v << 8 | b[i];
    return v;
}

/* Inflates the stream starting at data[0..size) until it ends; *out holds
 * the bytes, cut at `limit` (more is an error). */
static bool inflate_mesh(const char *path, const unsigned char *data, size_t size, size_t limit,
                         unsigned char **out, size_t *out_size, SgError *err)
{
    z_stream z;
    memset(&z, 0, sizeof z);
    if (inflateInit(&z) != Z_OK)
        return sg_fail(err, "%s: zlib cannot start", path);
    size_t cap = size * 4 + 4096, len = 0;
    unsigned char *buf = NULL;
    int rc = Z_OK;
    z.next_in = (unsigned char *)data;
    size_t in_left = size;
    while (rc != Z_STREAM_END) {
        if (cap > limit)
            cap = limit;
        unsigned char *grown = len == cap ? NULL : realloc(buf, cap);
        if (!grown) {
            free(buf);
            inflateEnd(&z);
            return len == cap ? sg_fail(err, "%s: a mesh holds more data than its counts say", path)
                              : sg_fail(err, "%s: out of memory", path);
        }
        buf = grown;
        z.next_out = buf + len;
        z.avail_out = (uInt)((cap - len) > (1u << 30) ? (1u << 30) : (cap - len));
        uInt chunk_in = in_left > (1u << 30) ? (1u << 30) : (uInt)in_left;
        z.avail_in = chunk_in;
        size_t before_out = z.avail_out;
        rc = inflate(&z, Z_NO_FLUSH);
        in_left -= chunk_in - z.avail_in;
        len += before_out - z.avail_out;
        if (rc == Z_STREAM_END)
            break;
        if (rc != Z_OK && rc != Z_BUF_ERROR) {
            free(buf);
            inflateEnd(&z);
            return sg_fail(err, "%s: the compressed mesh data is corrupt (zlib: %s)", path,
                           z.msg ? z.msg : "error");
        }
        if (in_left == 0 && z.avail_out > 0) {
            free(buf);
            inflateEnd(&z);
            return sg_fail(err, "%s: the file is cut short inside a mesh", path);
        }
        if (len == cap)
            cap *= 2;
    }
    inflateEnd(&z);
    *out = buf;
    *out_size = len;
    return true;
}

/* The byte offset where mesh `index` starts. */
static bool mesh_offset(const char *path, const unsigned char *data, size_t size, int version, long index,
                        size_t *offset, SgError *err)
{
    if (index == 0) {
        *offset = 0;
        return true;
    }
    if (size < 8)
        return sg_fail(err, "%s: the file is cut short (no mesh dictionary)", path);
    uint64_t count = le(data + size - 4, 4);
    size_t entry = version == 4 ? 8 : 4;
    if (count == 0 || count > (size - 4) / entry)
        return sg_fail(err, "%s: the mesh dictionary's count %llu is absurd", path, (unsigned long long)count);
    if ((uint64_t)index >= count)
        return sg_fail(err, "%s: shape_index %ld is out of range (%llu meshes)", path, index,
                       (unsigned long long)count);
    size_t at = size - 4 - entry * (size_t)(count - (uint64_t)index);
    *offset = (size_t)le(data + at, (int)entry);
    if (*offset > size - 4)
        return sg_fail(err, "%s: mesh %ld's offset is past the end of the file", path, index);
    return true;
}

static void read_reals(const unsigned char *b, bool dbl, size_t n, double *out)
{
    for (size_t i = 0; i < n; i++) {
        if (dbl) {
            uint64_t v = le(b + 8 * i, 8);
            memcpy(&out[i], &v, 8);
        } else {
            uint32_t v = (uint32_t)le(b + 4 * i, 4);
            float f;
            memcpy(&f, &v, 4);
            out[i] = f;
        }
    }
}

static bool parse_mesh(const char *path, const unsigned char *b, size_t size, int version, SgPlyMesh *mesh,
                       SgError *err)
{
    size_t pos = 4;
    if (size < 4)
        return sg_fail(err, "%s: the mesh data is cut short", path);
    uint32_t flags = (uint32_t)le(b, 4);
    if (version == 4) {
        while (pos < size && b[pos])
            pos++;
        pos++;
    }
    if (pos + 16 > size)
        return sg_fail(err, "%s: the mesh data is cut short", path);
    uint64_t vertices = le(b + pos, 8), triangles = le(b + pos + 8, 8);
    pos += 16;
    bool dbl = flags & DOUBLE_PRECISION;
    size_t real = dbl ? 8 : 4;
    size_t per_vertex = 3 + (flags & HAS_NORMALS ? 3 : 0) + (flags & HAS_TEXCOORDS ? 2 : 0) +
                        (flags & HAS_COLORS ? 3 : 0);
    if (vertices == 0 || triangles == 0 || vertices > UINT32_MAX / 4 || triangles > UINT32_MAX / 4 ||
        vertices * per_vertex * real + triangles * 12 != size - pos)
        return sg_fail(err, "%s: absurd counts (%llu vertices, %llu triangles for %zu bytes)", path,
                       (unsigned long long)vertices, (unsigned long long)triangles, size - pos);
    memset(mesh, 0, sizeof *mesh);
    mesh->vertex_count = (uint32_t)vertices;
    mesh->triangle_count = (uint32_t)triangles;
    mesh->positions = malloc(vertices * 3 * sizeof(double));
    mesh->normals = flags & HAS_NORMALS ? malloc(vertices * 3 * sizeof(double)) : NULL;
    mesh->uvs = flags & HAS_TEXCOORDS ? malloc(vertices * 2 * sizeof(float)) : NULL;
    mesh->indices = malloc(triangles * 3 * sizeof(uint32_t));
    double *uv = flags & HAS_TEXCOORDS ? malloc(vertices * 2 * sizeof(double)) : NULL;
    if (!mesh->positions || !mesh->indices || (flags & HAS_NORMALS && !mesh->normals) ||
        (flags & HAS_TEXCOORDS && (!mesh->uvs || !uv))) {
        free(uv);
        sg_ply_mesh_release(mesh);
        return sg_fail(err, "%s: out of memory", path);
    }
    read_reals(b + pos, dbl, 3 * vertices, mesh->positions);
    pos += 3 * vertices * real;
    if (mesh->normals) {
        read_reals(b + pos, dbl, 3 * vertices, mesh->normals);
        pos += 3 * vertices * real;
    }
    if (uv) {
        read_reals(b + pos, dbl, 2 * vertices, uv);
        for (size_t i = 0; i < 2 * vertices; i++)
            mesh->uvs[i] = (float)uv[i];
        free(uv);
        pos += 2 * vertices * real;
    }
    if (flags & HAS_COLORS)
        pos += 3 * vertices * real;
    for (size_t i = 0; i < 3 * triangles; i++) {
        uint64_t v = le(b + pos + 4 * i, 4);
        if (v >= vertices) {
            sg_ply_mesh_release(mesh);
            return sg_fail(err, "%s: index %llu is out of range (%llu vertices)", path, (unsigned long long)v,
                           (unsigned long long)vertices);
        }
        mesh->indices[i] = (uint32_t)v;
    }
    return true;
}

bool mts_read_serialized(const char *path, long shape_index, SgPlyMesh *mesh, SgError *err)
{
    memset(mesh, 0, sizeof *mesh);
    char *text;
    size_t size;
    if (shape_index < 0)
        return sg_fail(err, "%s: shape_index %ld is negative", path, shape_index);
    if (!sg_read_file(path, "mesh", SG_LIMIT_MESH, &text, &size, err))
        return false;
    const unsigned char *data = (const unsigned char *)text;
    bool ok = true;
    int version = 0;
    size_t offset = 0;
    if (size < 4 || le(data, 2) != 0x041C)
        ok = sg_fail(err, "%s: not a Mitsuba serialized mesh (no 0x041C header)", path);
    if (ok) {
        version = (int)le(data + 2, 2);
        if (version != 3 && version != 4)
            ok = sg_fail(err, "%s: serialized format version %d is not 3 or 4", path, version);
    }
    ok = ok && mesh_offset(path, data, size, version, shape_index, &offset, err);
    if (ok && (offset + 4 > size || le(data + offset, 2) != 0x041C))
        ok = sg_fail(err, "%s: mesh %ld does not start with a header", path, shape_index);
    unsigned char *raw = NULL;
    size_t raw_size = 0;
    ok = ok && inflate_mesh(path, data + offset + 4, size - offset - 4, SG_LIMIT_MESH, &raw, &raw_size, err);
    ok = ok && parse_mesh(path, raw, raw_size, version, mesh, err);
    free(raw);
    free(text);
    return ok;
}
