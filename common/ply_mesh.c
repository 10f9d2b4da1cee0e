#include "ply_mesh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "input_file.h"
#include "ply_file.h"

typedef struct Reader {
    const unsigned char *data;
    size_t size, pos;
    SgPlyFormat format;
} Reader;

/* One value of type t as a double; false at the end of data or on junk. */
static bool read_value(Reader *r, SgPlyType t, double *out)
{
    if (r->format == SG_PLY_ASCII) {
        char token[80];
        if (sg_ply_read_token(r->data, r->size, &r->pos, token, sizeof token) != SG_PLY_TOKEN_OK)
            return false;
        char *end;
        *out = strtod(token, &end);
        return *end == 0;
    }
    return sg_ply_read_binary(r->data, r->size, &r->pos, t, r->format == SG_PLY_BINARY_BE, out);
}

/* Which property of an element is which of the mesh's columns (-1: none). */
typedef struct Columns {
    bool is_vertex, is_face;
    int px, py, pz, pnx, pny, pnz, pu, pv; /* vertex: position, normal, uv */
    int pf;                                /* face: its vertex indices */
} Columns;

static Columns find_columns(const SgPlyElement *el)
{
    Columns k = {!strcmp(el->name, "vertex"), !strcmp(el->name, "face"), -1, -1, -1, -1, -1, -1, -1, -1, -1};
    for (int p = 0; p < el->property_count; p++) {
        const char *n = el->properties[p].name;
        bool list = el->properties[p].count_type != SG_PLY_NONE;
        if (k.is_vertex && !list && !strcmp(n, "x")) k.px = p;
        if (k.is_vertex && !list && !strcmp(n, "y")) k.py = p;
        if (k.is_vertex && !list && !strcmp(n, "z")) k.pz = p;
        if (k.is_vertex && !list && !strcmp(n, "nx")) k.pnx = p;
        if (k.is_vertex && !list && !strcmp(n, "ny")) k.pny = p;
        if (k.is_vertex && !list && !strcmp(n, "nz")) k.pnz = p;
        /* texture coordinates under the names pbrt-v4 reads */
        if (k.is_vertex && !list && (!strcmp(n, "u") || !strcmp(n, "s") || !strcmp(n, "texture_u") ||
                                     !strcmp(n, "texture_s")))
            k.pu = p;
        if (k.is_vertex && !list && (!strcmp(n, "v") || !strcmp(n, "t") || !strcmp(n, "texture_v") ||
                                     !strcmp(n, "texture_t")))
            k.pv = p;
        if (k.is_face && list && (!strcmp(n, "vertex_indices") || !strcmp(n, "vertex_index")))
            k.pf = p;
    }
    return k;
}

/* The vertex arrays for the vertex element: positions, and normals and
 * texture coordinates where it has them. */
static bool alloc_vertices(SgPlyMesh *mesh, const SgPlyElement *el, const Columns *k, size_t file_size,
                           const char *path, SgError *err)
{
    if (k->px < 0 || k->py < 0 || k->pz < 0)
        return sg_fail(err, "%s: PLY vertex element lacks x, y or z", path);
    if (el->count * 3 * sizeof(double) > file_size * 64 + 4096)
        return sg_fail(err, "%s: PLY vertex count %llu does not fit the file", path, (unsigned long long)el->count);
    size_t n = el->count ? el->count : 1;
    mesh->vertex_count = (uint32_t)el->count;
    mesh->positions = malloc(n * 3 * sizeof(double));
    if (!mesh->positions)
        return sg_fail(err, "%s: out of memory", path);
    if (k->pnx >= 0 && k->pny >= 0 && k->pnz >= 0 && !(mesh->normals = malloc(n * 3 * sizeof(double))))
        return sg_fail(err, "%s: out of memory", path);
    if (k->pu >= 0 && k->pv >= 0 && !(mesh->uvs = malloc(n * 2 * sizeof(float))))
        return sg_fail(err, "%s: out of memory", path);
    return true;
}

/* Scalar property p of vertex `row`, stored where it is a column. */
static bool store_vertex_value(SgPlyMesh *mesh, const Columns *k, int p, uint64_t row, double v, const char *path,
                               SgError *err)
{
    if (p == k->px || p == k->py || p == k->pz) {
        if (!isfinite(v))
            return sg_fail(err, "%s: vertex %llu has a non-finite coordinate", path, (unsigned long long)row);
        mesh->positions[3 * row + (p == k->px ? 0 : p == k->py ? 1 : 2)] = v;
    }
    if (mesh->normals && (p == k->pnx || p == k->pny || p == k->pnz))
        mesh->normals[3 * row + (p == k->pnx ? 0 : p == k->pny ? 1 : 2)] = isfinite(v) ? v : 0;
    if (mesh->uvs && (p == k->pu || p == k->pv))
        mesh->uvs[2 * row + (p == k->pv)] = isfinite(v) ? (float)v : 0.0f;
    return true;
}

/* Appends triangle `corners`, growing the index array by doubling. */
static bool add_triangle(SgPlyMesh *mesh, const uint32_t corners[3], uint64_t *capacity, const char *path,
                         SgError *err)
{
    if (mesh->triangle_count == *capacity) {
        *capacity = *capacity ? 2 * *capacity : 1024;
        uint32_t *grown = realloc(mesh->indices, *capacity * 3 * sizeof(uint32_t));
        if (!grown || *capacity > UINT32_MAX)
            return sg_fail(err, "%s: out of memory", path);
        mesh->indices = grown;
    }
    memcpy(mesh->indices + 3 * (size_t)mesh->triangle_count++, corners, 3 * sizeof *corners);
    return true;
}

/* List property p of row `row` of element el; a face's vertex indices
 * become triangles, fanning the polygon: (0, c-1, c) for c >= 2. */
static bool read_list(Reader *r, SgPlyMesh *mesh, const SgPlyElement *el, const Columns *k, int p, uint64_t row,
                      uint64_t *capacity, const char *path, SgError *err)
{
    const SgPlyProperty *prop = &el->properties[p];
    double count, v;
    if (!read_value(r, prop->count_type, &count) || count < 0 || count > 1e6 || count != floor(count))
        return sg_fail(err, "%s: PLY list malformed in %s %llu", path, el->name, (unsigned long long)row);
    uint32_t corners[3] = {0, 0, 0};
    for (uint32_t c = 0; c < (uint32_t)count; c++) {
        if (!read_value(r, prop->type, &v))
            return sg_fail(err, "%s: PLY data truncated or malformed in %s %llu", path, el->name,
                           (unsigned long long)row);
        if (!(k->is_face && p == k->pf))
            continue;
        if (!(v >= 0 && v < mesh->vertex_count) || v != floor(v))
            return sg_fail(err, "%s: face %llu has vertex index %g out of range", path, (unsigned long long)row, v);
        if (c < 2) {
            corners[c] = (uint32_t)v;
            continue;
        }
        corners[2] = (uint32_t)v;
        if (!add_triangle(mesh, corners, capacity, path, err))
            return false;
        corners[1] = corners[2];
    }
    return true;
}

/* Every row of element el: the vertices' columns, the faces' triangles;
 * other properties and elements are read past. */
static bool read_element(Reader *r, SgPlyMesh *mesh, const SgPlyElement *el, uint64_t *capacity, const char *path,
                         SgError *err)
{
    Columns k = find_columns(el);
    if (k.is_vertex && !alloc_vertices(mesh, el, &k, r->size, path, err))
        return false;
    if (k.is_face && k.pf < 0)
        return sg_fail(err, "%s: PLY face element lacks vertex_indices", path);
    for (uint64_t row = 0; row < el->count; row++)
        for (int p = 0; p < el->property_count; p++) {
            const SgPlyProperty *prop = &el->properties[p];
            if (prop->count_type != SG_PLY_NONE) {
                if (!read_list(r, mesh, el, &k, p, row, capacity, path, err))
                    return false;
                continue;
            }
            double v;
            if (!read_value(r, prop->type, &v))
                return sg_fail(err, "%s: PLY data truncated or malformed in %s %llu", path, el->name,
                               (unsigned long long)row);
            if (k.is_vertex && !store_vertex_value(mesh, &k, p, row, v, path, err))
                return false;
        }
    return true;
}

bool sg_ply_mesh_read(SgPlyMesh *mesh, const char *path, SgError *err)
{
    memset(mesh, 0, sizeof *mesh);
    Reader r = {0};
    char *text;
    if (!sg_read_file(path, "mesh", SG_LIMIT_MESH, &text, &r.size, err))
        return false;
    unsigned char *data = (unsigned char *)text;
    r.data = data;
    SgPlyHeader *header = malloc(sizeof *header); /* some 70 kB: not on a thread's stack */
    bool ok = header || sg_fail(err, "%s: out of memory", path);
    ok = ok && sg_ply_header_parse(header, data, r.size, true, path, err);
    if (ok) {
        r.format = header->format;
        r.pos = header->data_start;
    }
    uint64_t triangle_capacity = 0;
    for (int e = 0; ok && e < header->element_count; e++)
        ok = read_element(&r, mesh, &header->elements[e], &triangle_capacity, path, err);
    free(header);
    free(data);
    if (ok && !mesh->positions)
        ok = sg_fail(err, "%s: PLY file has no vertex element", path);
    if (!ok)
        sg_ply_mesh_release(mesh);
    return ok;
}

void sg_ply_mesh_release(SgPlyMesh *mesh)
{
    free(mesh->positions);
    free(mesh->indices);
    free(mesh->normals);
    free(mesh->uvs);
    memset(mesh, 0, sizeof *mesh);
}
