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
    for (int e = 0; ok && e < header->element_count; e++) {
        const SgPlyElement *el = &header->elements[e];
        bool is_vertex = !strcmp(el->name, "vertex"), is_face = !strcmp(el->name, "face");
        int px = -1, py = -1, pz = -1, pf = -1, pnx = -1, pny = -1, pnz = -1, pu = -1, pv = -1;
        for (int p = 0; p < el->property_count; p++) {
            const char *n = el->properties[p].name;
            bool list = el->properties[p].count_type != SG_PLY_NONE;
            if (is_vertex && !list && !strcmp(n, "x")) px = p;
            if (is_vertex && !list && !strcmp(n, "y")) py = p;
            if (is_vertex && !list && !strcmp(n, "z")) pz = p;
            if (is_vertex && !list && !strcmp(n, "nx")) pnx = p;
            if (is_vertex && !list && !strcmp(n, "ny")) pny = p;
            if (is_vertex && !list && !strcmp(n, "nz")) pnz = p;
            /* texture coordinates under the names pbrt-v4 reads */
            if (is_vertex && !list && (!strcmp(n, "u") || !strcmp(n, "s") || !strcmp(n, "texture_u") ||
                                       !strcmp(n, "texture_s")))
                pu = p;
            if (is_vertex && !list && (!strcmp(n, "v") || !strcmp(n, "t") || !strcmp(n, "texture_v") ||
                                       !strcmp(n, "texture_t")))
                pv = p;
            if (is_face && list && (!strcmp(n, "vertex_indices") || !strcmp(n, "vertex_index")))
                pf = p;
        }
        if (is_vertex) {
            if (px < 0 || py < 0 || pz < 0) {
                ok = sg_fail(err, "%s: PLY vertex element lacks x, y or z", path);
                break;
            }
            if (el->count * 3 * sizeof(double) > r.size * 64 + 4096) {
                ok = sg_fail(err, "%s: PLY vertex count %llu does not fit the file", path,
                             (unsigned long long)el->count);
                break;
            }
            mesh->vertex_count = (uint32_t)el->count;
            mesh->positions = malloc((el->count ? el->count : 1) * 3 * sizeof(double));
            if (!mesh->positions) {
                ok = sg_fail(err, "%s: out of memory", path);
                break;
            }
            if (pnx >= 0 && pny >= 0 && pnz >= 0) {
                mesh->normals = malloc((el->count ? el->count : 1) * 3 * sizeof(double));
                if (!mesh->normals) {
                    ok = sg_fail(err, "%s: out of memory", path);
                    break;
                }
            }
            if (pu >= 0 && pv >= 0) {
                mesh->uvs = malloc((el->count ? el->count : 1) * 2 * sizeof(float));
                if (!mesh->uvs) {
                    ok = sg_fail(err, "%s: out of memory", path);
                    break;
                }
            }
        }
        if (is_face && pf < 0) {
            ok = sg_fail(err, "%s: PLY face element lacks vertex_indices", path);
            break;
        }
        for (uint64_t row = 0; ok && row < el->count; row++) {
            for (int p = 0; ok && p < el->property_count; p++) {
                const SgPlyProperty *prop = &el->properties[p];
                double v;
                if (prop->count_type == SG_PLY_NONE) {
                    if (!read_value(&r, prop->type, &v)) {
                        ok = sg_fail(err, "%s: PLY data truncated or malformed in %s %llu", path,
                                     el->name, (unsigned long long)row);
                        break;
                    }
                    if (is_vertex && (p == px || p == py || p == pz)) {
                        if (!isfinite(v)) {
                            ok = sg_fail(err, "%s: vertex %llu has a non-finite coordinate",
                                         path, (unsigned long long)row);
                            break;
                        }
                        mesh->positions[3 * row + (p == px ? 0 : p == py ? 1 : 2)] = v;
                    }
                    if (is_vertex && mesh->normals && (p == pnx || p == pny || p == pnz))
                        mesh->normals[3 * row + (p == pnx ? 0 : p == pny ? 1 : 2)] =
                            isfinite(v) ? v : 0;
                    if (is_vertex && mesh->uvs && (p == pu || p == pv))
                        mesh->uvs[2 * row + (p == pv)] = isfinite(v) ? (float)v : 0.0f;
                    continue;
                }
                double count;
                if (!read_value(&r, prop->count_type, &count) || count < 0 || count > 1e6 ||
                    count != floor(count)) {
                    ok = sg_fail(err, "%s: PLY list malformed in %s %llu", path, el->name,
                                 (unsigned long long)row);
                    break;
                }
                uint32_t corners[3] = {0, 0, 0};
                for (uint32_t c = 0; c < (uint32_t)count; c++) {
                    if (!read_value(&r, prop->type, &v)) {
                        ok = sg_fail(err, "%s: PLY data truncated or malformed in %s %llu", path,
                                     el->name, (unsigned long long)row);
                        break;
                    }
                    if (!(is_face && p == pf))
                        continue;
                    if (!(v >= 0 && v < mesh->vertex_count) || v != floor(v)) {
                        ok = sg_fail(err, "%s: face %llu has vertex index %g out of range", path,
                                     (unsigned long long)row, v);
                        break;
                    }
                    /* Fan the polygon: (0, c-1, c) for c >= 2. */
                    if (c < 2) {
                        corners[c] = (uint32_t)v;
                        continue;
                    }
                    corners[2] = (uint32_t)v;
                    if (mesh->triangle_count == triangle_capacity) {
                        triangle_capacity = triangle_capacity ? 2 * triangle_capacity : 1024;
                        uint32_t *grown =
                            realloc(mesh->indices, triangle_capacity * 3 * sizeof(uint32_t));
                        if (!grown || triangle_capacity > UINT32_MAX) {
                            ok = sg_fail(err, "%s: out of memory", path);
                            break;
                        }
                        mesh->indices = grown;
                    }
                    memcpy(mesh->indices + 3 * (size_t)mesh->triangle_count++, corners,
                           sizeof corners);
                    corners[1] = corners[2];
                }
            }
        }
    }
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
