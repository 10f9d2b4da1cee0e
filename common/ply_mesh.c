#include "ply_mesh.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "input_file.h"
#include "ply_types.h"

enum Format { ASCII, BINARY_LE, BINARY_BE };

typedef struct Property {
    char name[64];
    SgPlyType type;
    SgPlyType count_type; /* SG_PLY_NONE unless a list */
} Property;

typedef struct Element {
    char name[64];
    uint64_t count;
    int property_count;
    Property properties[32];
} Element;

typedef struct Reader {
    const unsigned char *data;
    size_t size, pos;
    enum Format format;
    const char *path;
} Reader;

/* One value of type t as a double; false at the end of data or on junk. */
static bool read_value(Reader *r, SgPlyType t, double *out)
{
    if (r->format == ASCII) {
        while (r->pos < r->size && (r->data[r->pos] == ' ' || r->data[r->pos] == '\t' ||
                                    r->data[r->pos] == '\n' || r->data[r->pos] == '\r'))
            r->pos++;
        if (r->pos >= r->size)
            return false;
        char token[64];
        size_t n = 0;
        while (r->pos < r->size && n + 1 < sizeof token && r->data[r->pos] > ' ')
            token[n++] = (char)r->data[r->pos++];
        token[n] = 0;
        char *end;
        *out = strtod(token, &end);
        return *end == 0 && n > 0;
    }
    size_t size = sg_ply_type_size(t);
    if (r->size - r->pos < size)
        return false;
    bool ok = sg_ply_decode(r->data + r->pos, t, r->format == BINARY_BE, out);
    r->pos += size;
    return ok;
}


static bool parse_header(Reader *r, Element *elements, int *element_count, SgError *err)
{
    const char *text = (const char *)r->data;
    if (r->size < 4 || strncmp(text, "ply", 3) || (text[3] != '\n' && text[3] != '\r'))
        return sg_fail(err, "%s: not a PLY file", r->path);
    const char *end = NULL;
    for (size_t i = 0; i + 10 <= r->size; i++)
        if (!memcmp(r->data + i, "end_header", 10)) {
            end = text + i;
            break;
        }
    if (!end)
        return sg_fail(err, "%s: PLY header has no end_header", r->path);
    /* Data start right after the end_header line's newline, whatever the
     * next byte is. */
    size_t data_start = (size_t)(end - text) + 10;
    if (data_start < r->size && r->data[data_start] == '\r')
        data_start++;
    if (data_start >= r->size || r->data[data_start] != '\n')
        return sg_fail(err, "%s: PLY header line end_header is not terminated", r->path);
    data_start++;

    bool has_format = false;
    *element_count = 0;
    const char *line = text + 4;
    int line_no = 1;
    while (line < end) {
        line_no++;
        const char *nl = memchr(line, '\n', (size_t)(end - line));
        size_t len = nl ? (size_t)(nl - line) : (size_t)(end - line);
        char buf[256];
        if (len >= sizeof buf)
            return sg_fail(err, "%s: PLY header line %d too long", r->path, line_no);
        memcpy(buf, line, len);
        buf[len] = 0;
        line = nl ? nl + 1 : end;
        char w[4][64] = {{0}};
        int n = sscanf(buf, "%63s %63s %63s %63s", w[0], w[1], w[2], w[3]);
        if (n <= 0 || !strcmp(w[0], "comment") || !strcmp(w[0], "obj_info"))
            continue;
        if (!strcmp(w[0], "format")) {
            if (!strcmp(w[1], "ascii"))
                r->format = ASCII;
            else if (!strcmp(w[1], "binary_little_endian"))
                r->format = BINARY_LE;
            else if (!strcmp(w[1], "binary_big_endian"))
                r->format = BINARY_BE;
            else
                return sg_fail(err, "%s: unknown PLY format \"%s\"", r->path, w[1]);
            has_format = true;
        } else if (!strcmp(w[0], "element") && n == 3) {
            if (*element_count == 16)
                return sg_fail(err, "%s: too many PLY elements", r->path);
            Element *e = &elements[(*element_count)++];
            memset(e, 0, sizeof *e);
            snprintf(e->name, sizeof e->name, "%s", w[1]);
            char *endp;
            unsigned long long c = strtoull(w[2], &endp, 10);
            if (*endp || c > UINT32_MAX)
                return sg_fail(err, "%s: bad PLY element count on line %d", r->path, line_no);
            e->count = c;
        } else if (!strcmp(w[0], "property") && *element_count > 0) {
            Element *e = &elements[*element_count - 1];
            if (e->property_count == 32)
                return sg_fail(err, "%s: too many PLY properties", r->path);
            Property *p = &e->properties[e->property_count++];
            memset(p, 0, sizeof *p);
            if (!strcmp(w[1], "list") && n == 4) {
                char name[64];
                if (sscanf(buf, "%*s %*s %*s %*s %63s", name) != 1)
                    return sg_fail(err, "%s: bad PLY list property on line %d", r->path, line_no);
                p->count_type = sg_ply_type_parse(w[2]);
                p->type = sg_ply_type_parse(w[3]);
                snprintf(p->name, sizeof p->name, "%s", name);
                if (p->count_type == SG_PLY_NONE || p->count_type == SG_PLY_F32 || p->count_type == SG_PLY_F64)
                    p->type = SG_PLY_NONE;
            } else if (n == 3) {
                p->type = sg_ply_type_parse(w[1]);
                snprintf(p->name, sizeof p->name, "%s", w[2]);
            }
            if (p->type == SG_PLY_NONE)
                return sg_fail(err, "%s: unknown PLY property type on line %d", r->path, line_no);
        } else {
            return sg_fail(err, "%s: unexpected PLY header line %d", r->path, line_no);
        }
    }
    if (!has_format)
        return sg_fail(err, "%s: PLY header has no format line", r->path);
    r->pos = data_start;
    return true;
}

bool sg_ply_mesh_read(SgPlyMesh *mesh, const char *path, SgError *err)
{
    memset(mesh, 0, sizeof *mesh);
    Reader r = {.path = path};
    char *text;
    if (!sg_read_file(path, "mesh", SG_LIMIT_MESH, &text, &r.size, err))
        return false;
    unsigned char *data = (unsigned char *)text;
    r.data = data;
    Element elements[16];
    int element_count = 0;
    bool ok = parse_header(&r, elements, &element_count, err);
    uint64_t triangle_capacity = 0;
    for (int e = 0; ok && e < element_count; e++) {
        Element *el = &elements[e];
        bool is_vertex = !strcmp(el->name, "vertex"), is_face = !strcmp(el->name, "face");
        int px = -1, py = -1, pz = -1, pf = -1, pnx = -1, pny = -1, pnz = -1;
        for (int p = 0; p < el->property_count; p++) {
            const char *n = el->properties[p].name;
            bool list = el->properties[p].count_type != SG_PLY_NONE;
            if (is_vertex && !list && !strcmp(n, "x")) px = p;
            if (is_vertex && !list && !strcmp(n, "y")) py = p;
            if (is_vertex && !list && !strcmp(n, "z")) pz = p;
            if (is_vertex && !list && !strcmp(n, "nx")) pnx = p;
            if (is_vertex && !list && !strcmp(n, "ny")) pny = p;
            if (is_vertex && !list && !strcmp(n, "nz")) pnz = p;
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
        }
        if (is_face && pf < 0) {
            ok = sg_fail(err, "%s: PLY face element lacks vertex_indices", path);
            break;
        }
        for (uint64_t row = 0; ok && row < el->count; row++) {
            for (int p = 0; ok && p < el->property_count; p++) {
                const Property *prop = &el->properties[p];
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
    memset(mesh, 0, sizeof *mesh);
}
