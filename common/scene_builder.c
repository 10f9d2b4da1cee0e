/* The scene builder shared by the JSON and pbrt front ends: growable flat
 * arrays, degenerate triangles dropped, lights grouped from emissive
 * triangles, bounds and geometry hash. */
#include "scene_builder.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "color.h"
#include "hash.h"
#include "union_find.h"
#include "vecmath.h"

static bool grow(void **array, uint32_t *capacity, uint32_t needed, size_t item,
                 SgError *err, const char *path)
{
    if (needed <= *capacity)
        return true;
    uint64_t cap = *capacity ? *capacity : 1024;
    while (cap < needed)
        cap *= 2;
    if (cap > UINT32_MAX)
        return sg_fail(err, "%s: scene too large (more than 4 billion elements)", path);
    void *p = realloc(*array, (size_t)cap * item);
    if (!p)
        return sg_fail(err, "%s: out of memory", path);
    *array = p;
    *capacity = (uint32_t)cap;
    return true;
}

bool sg_builder_add_vertices(SgSceneBuilder *b, uint32_t count, SgError *err)
{
    SgScene *s = b->scene;
    if ((uint64_t)s->vertex_count + count > UINT32_MAX)
        return sg_fail(err, "%s: too many vertices", b->path);
    return grow((void **)&s->positions, &b->vertex_capacity, s->vertex_count + count,
                3 * sizeof(double), err, b->path);
}

/* The uv array covers at least `needed` vertices; new entries are (0, 0). */
static bool reserve_uvs(SgSceneBuilder *b, uint32_t needed, SgError *err)
{
    uint32_t old = b->uv_capacity;
    if (!grow((void **)&b->scene->uvs, &b->uv_capacity, needed, 2 * sizeof(float), err, b->path))
        return false;
    if (b->uv_capacity > old)
        memset(b->scene->uvs + 2 * (size_t)old, 0, 2 * sizeof(float) * (b->uv_capacity - old));
    return true;
}

bool sg_builder_set_uvs(SgSceneBuilder *b, uint32_t first, uint32_t count, const float *uv, SgError *err)
{
    if ((uint64_t)first + count > b->scene->vertex_count)
        return sg_fail(err, "%s: texture coordinates for vertices the scene does not have", b->path);
    if (!reserve_uvs(b, first + count, err))
        return false;
    for (size_t i = 0; i < 2 * (size_t)count; i++) /* a NaN would poison the texture lookups */
        b->scene->uvs[2 * (size_t)first + i] = isfinite(uv[i]) ? uv[i] : 0.0f;
    return true;
}

bool sg_builder_add_texture(SgSceneBuilder *b, const SgTexture *t, uint32_t *id, SgError *err)
{
    SgScene *s = b->scene;
    if (!grow((void **)&s->textures, &b->texture_capacity, s->texture_count + 1, sizeof(SgTexture), err, b->path))
        return false;
    SgTexture *dst = &s->textures[s->texture_count];
    *dst = *t;
    if (t->path && !(dst->path = strdup(t->path)))
        return sg_fail(err, "%s: out of memory", b->path);
    *id = s->texture_count++;
    return true;
}

bool sg_builder_add_triangles(SgSceneBuilder *b, uint32_t count, SgError *err)
{
    SgScene *s = b->scene;
    if ((uint64_t)s->triangle_count + count > UINT32_MAX)
        return sg_fail(err, "%s: too many triangles", b->path);
    uint32_t cap = b->triangle_capacity;
    if (!grow((void **)&s->indices, &cap, s->triangle_count + count, 3 * sizeof(uint32_t), err,
              b->path))
        return false;
    uint32_t cap2 = b->triangle_capacity;
    if (!grow((void **)&s->triangle_material, &cap2, s->triangle_count + count,
              sizeof(uint32_t), err, b->path))
        return false;
    b->triangle_capacity = cap;
    return true;
}

void sg_material_default(SgMaterial *m, const char *name)
{
    memset(m, 0, sizeof *m);
    snprintf(m->name, sizeof m->name, "%.63s", name);
    m->type = SG_MATERIAL_DIFFUSE;
    m->diffuse[0] = m->diffuse[1] = m->diffuse[2] = 0.5f;
    m->exponent = 1;
    m->ior = 1.5f;
    /* a conductor's index unless told: copper's, pbrt's default */
    const float copper_eta[3] = {0.200f, 0.924f, 1.10f}, copper_k[3] = {3.91f, 2.45f, 2.14f};
    memcpy(m->eta, copper_eta, sizeof copper_eta);
    memcpy(m->k, copper_k, sizeof copper_k);
}

bool sg_builder_add_material(SgSceneBuilder *b, const SgMaterial *m, uint32_t *id, SgError *err)
{
    SgScene *s = b->scene;
    if (!grow((void **)&s->materials, &b->material_capacity, s->material_count + 1,
              sizeof(SgMaterial), err, b->path))
        return false;
    s->materials[s->material_count] = *m;
    *id = s->material_count++;
    return true;
}

bool sg_builder_emissive_material(SgSceneBuilder *b, size_t material, const SgMaterial *m,
                                  const float radiance[3], uint32_t *id, SgError *err)
{
    for (size_t i = 0; i < b->emissive_count; i++) {
        const SgBuilderEmissive *e = &b->emissive[i];
        if (e->material == material && !memcmp(e->radiance, radiance, sizeof e->radiance)) {
            *id = e->scene_id;
            return true;
        }
    }
    SgBuilderEmissive *grown = realloc(b->emissive, (b->emissive_count + 1) * sizeof *grown);
    if (!grown)
        return sg_fail(err, "%s: out of memory", b->path);
    b->emissive = grown;
    SgMaterial copy = *m;
    memcpy(copy.emission, radiance, sizeof copy.emission);
    if (!sg_builder_add_material(b, &copy, id, err))
        return false;
    SgBuilderEmissive *e = &b->emissive[b->emissive_count++];
    e->material = material;
    memcpy(e->radiance, radiance, sizeof e->radiance);
    e->scene_id = *id;
    return true;
}

static bool is_degenerate(const double *a, const double *b, const double *c)
{
    double e1[3], e2[3], e3[3], n[3];
    d3_sub(b, a, e1);
    d3_sub(c, a, e2);
    d3_sub(c, b, e3);
    d3_cross(e1, e2, n);
    double longest = fmax(d3_dot(e1, e1), fmax(d3_dot(e2, e2), d3_dot(e3, e3)));
    /* Relative test: independent of the scene's unit. */
    return !(d3_length(n) > 1e-12 * longest);
}

/* Appends one triangle whose vertices are already in the vertex array. */
void sg_builder_push_triangle(SgSceneBuilder *b, uint32_t i0, uint32_t i1, uint32_t i2,
                              uint32_t material)
{
    SgScene *s = b->scene;
    const double *p = s->positions;
    if (is_degenerate(p + 3 * i0, p + 3 * i1, p + 3 * i2)) {
        b->dropped_degenerate++;
        return;
    }
    uint32_t t = s->triangle_count++;
    s->indices[3 * t + 0] = i0;
    s->indices[3 * t + 1] = i1;
    s->indices[3 * t + 2] = i2;
    s->triangle_material[t] = material;
}

bool sg_builder_check_point(SgSceneBuilder *b, const char *what, const double p[3], SgError *err)
{
    for (int a = 0; a < 3; a++)
        if (!isfinite(p[a]))
            return sg_fail(err, "%s: %s has a non-finite vertex coordinate", b->path, what);
    return true;
}

/* Appends a mesh given as flat positions and triangle indices (already
 * bounds-checked) with one material. */
bool sg_builder_append_mesh(SgSceneBuilder *b, const char *file, const double *positions,
                        uint32_t vertex_count, const uint32_t *indices, uint32_t triangle_count,
                        const SgTransform *xf, uint32_t material, SgError *err)
{
    SgScene *s = b->scene;
    uint32_t base = s->vertex_count;
    if (!sg_builder_add_vertices(b, vertex_count, err) ||
        !sg_builder_add_triangles(b, triangle_count, err))
        return false;
    for (uint32_t v = 0; v < vertex_count; v++) {
        if (!sg_builder_check_point(b, file, positions + 3 * (size_t)v, err))
            return false;
        sg_transform_point(xf, positions + 3 * (size_t)v, s->positions + 3 * (size_t)(base + v));
    }
    s->vertex_count += vertex_count;
    for (uint32_t t = 0; t < triangle_count; t++)
        sg_builder_push_triangle(b, base + indices[3 * (size_t)t],
                                 base + indices[3 * (size_t)t + 1],
                                 base + indices[3 * (size_t)t + 2], material);
    return true;
}

typedef struct LightKey {
    uint32_t root, material, triangle;
} LightKey;

static int compare_light_keys(const void *pa, const void *pb)
{
    const LightKey *a = pa, *b = pb;
    if (a->root != b->root)
        return a->root < b->root ? -1 : 1;
    if (a->material != b->material)
        return a->material < b->material ? -1 : 1;
    return (a->triangle > b->triangle) - (a->triangle < b->triangle);
}

/* Emissive triangles of one material that share vertices form one light. */
static bool group_lights(SgSceneBuilder *b, SgError *err)
{
    SgScene *s = b->scene;
    s->triangle_light = malloc((s->triangle_count ? s->triangle_count : 1) * sizeof(uint32_t));
    uint32_t *parent = malloc((s->vertex_count ? s->vertex_count : 1) * sizeof(uint32_t));
    if (!s->triangle_light || !parent) {
        free(parent);
        return sg_fail(err, "%s: out of memory", b->path);
    }
    for (uint32_t v = 0; v < s->vertex_count; v++)
        parent[v] = v;
    uint32_t emissive = 0;
    for (uint32_t t = 0; t < s->triangle_count; t++) {
        s->triangle_light[t] = SG_NO_LIGHT;
        const float *e = s->materials[s->triangle_material[t]].emission;
        if (!(e[0] > 0 || e[1] > 0 || e[2] > 0))
            continue;
        emissive++;
        const uint32_t *idx = s->indices + 3 * (size_t)t;
        for (int c = 1; c < 3; c++)
            sg_set_union(parent, idx[0], idx[c]);
    }
    /* Sort emissive triangles by (component, material, id) so that lights
     * come out in a deterministic order. */
    LightKey *keys = malloc((emissive ? emissive : 1) * sizeof *keys);
    if (!keys) {
        free(parent);
        return sg_fail(err, "%s: out of memory", b->path);
    }
    uint32_t n = 0;
    for (uint32_t t = 0; t < s->triangle_count; t++) {
        const float *e = s->materials[s->triangle_material[t]].emission;
        if (e[0] > 0 || e[1] > 0 || e[2] > 0)
            keys[n++] = (LightKey){sg_set_find(parent, s->indices[3 * (size_t)t]),
                                   s->triangle_material[t], t};
    }
    qsort(keys, n, sizeof *keys, compare_light_keys);
    s->light_triangles = malloc((n ? n : 1) * sizeof(uint32_t));
    s->lights = calloc(n ? n : 1, sizeof(SgLight));
    if (!s->light_triangles || !s->lights) {
        free(parent);
        free(keys);
        return sg_fail(err, "%s: out of memory", b->path);
    }
    uint32_t light = UINT32_MAX, prev_root = UINT32_MAX, prev_material = UINT32_MAX;
    for (uint32_t i = 0; i < n; i++) {
        uint32_t root = keys[i].root, t = keys[i].triangle, material = keys[i].material;
        if (root != prev_root || material != prev_material) {
            light = s->light_count++;
            s->lights[light].first_triangle = i;
            prev_root = root;
            prev_material = material;
        }
        s->light_triangles[i] = t;
        s->triangle_light[t] = light;
        SgLight *l = &s->lights[light];
        l->triangle_count++;
        double nrm[3];
        sg_scene_triangle_normal(s, t, nrm);
        double area = 0.5 * d3_length(nrm);
        const double *p = s->positions;
        const uint32_t *idx = s->indices + 3 * (size_t)t;
        for (int a = 0; a < 3; a++) {
            double c = (p[3 * idx[0] + a] + p[3 * idx[1] + a] + p[3 * idx[2] + a]) / 3;
            l->position[a] += area * c;
            l->normal[a] += 0.5 * nrm[a];
        }
        l->area += area;
        memcpy(l->radiance, s->materials[material].emission, sizeof l->radiance);
    }
    for (uint32_t k = 0; k < s->light_count; k++) {
        SgLight *l = &s->lights[k];
        double len = d3_length(l->normal);
        for (int a = 0; a < 3; a++) {
            l->position[a] /= l->area;
            l->normal[a] = len > 0 ? l->normal[a] / len : 0;
        }
        double lum = sg_luminance(l->radiance[0], l->radiance[1], l->radiance[2]);
        l->power = M_PI * l->area * lum;
    }
    free(parent);
    free(keys);
    return true;
}

/* An image's bytes into the hash, not its path: the same scene named from
 * another directory (or by an absolute path) keeps its hash, and an image
 * changed in place changes it. */
static bool hash_file(uint64_t *h, const char *scene_path, const char *file, SgError *err)
{
    FILE *f = fopen(file, "rb");
    if (!f)
        return sg_fail(err, "%s: cannot read the sky image %s: %s", scene_path, file, strerror(errno));
    unsigned char buf[65536];
    size_t n;
    while ((n = fread(buf, 1, sizeof buf, f)) > 0)
        *h = sg_hash_bytes(*h, buf, n);
    bool ok = !ferror(f);
    fclose(f);
    return ok || sg_fail(err, "%s: cannot read the sky image %s", scene_path, file);
}

static bool compute_bounds_and_hash(SgScene *s, const char *path, SgError *err)
{
    for (int a = 0; a < 3; a++) {
        s->bounds_min[a] = INFINITY;
        s->bounds_max[a] = -INFINITY;
    }
    for (uint32_t t = 0; t < s->triangle_count; t++)
        for (int c = 0; c < 3; c++) {
            const double *p = s->positions + 3 * (size_t)s->indices[3 * (size_t)t + c];
            for (int a = 0; a < 3; a++) {
                s->bounds_min[a] = fmin(s->bounds_min[a], p[a]);
                s->bounds_max[a] = fmax(s->bounds_max[a], p[a]);
            }
        }
    /* Hash what the precompute sees: triangles (as coordinates, so that
     * vertex order in files does not matter less than geometry) and lights. */
    uint64_t h = SG_HASH_INIT;
    h = sg_hash_bytes(h, &s->triangle_count, sizeof s->triangle_count);
    for (uint32_t t = 0; t < s->triangle_count; t++) {
        for (int c = 0; c < 3; c++)
            h = sg_hash_bytes(h, s->positions + 3 * (size_t)s->indices[3 * (size_t)t + c],
                              3 * sizeof(double));
        uint32_t light = s->triangle_light[t];
        h = sg_hash_bytes(h, &light, sizeof light);
    }
    for (uint32_t k = 0; k < s->light_count; k++)
        h = sg_hash_bytes(h, s->lights[k].radiance, sizeof s->lights[k].radiance);
    /* lights that are not surfaces, field by field (no padding bytes); a
     * scene without any keeps the hash it always had */
    for (uint32_t k = 0; k < s->light_source_count; k++) {
        const SgLightSource *l = &s->light_sources[k];
        uint32_t kind = (uint32_t)l->kind, layout = (uint32_t)l->layout, portal = l->has_portal;
        h = sg_hash_bytes(h, &kind, sizeof kind);
        h = sg_hash_bytes(h, l->rgb, sizeof l->rgb);
        h = sg_hash_bytes(h, l->position, sizeof l->position);
        h = sg_hash_bytes(h, l->direction, sizeof l->direction);
        h = sg_hash_bytes(h, &l->cos_cone, sizeof l->cos_cone);
        h = sg_hash_bytes(h, &l->cos_falloff_start, sizeof l->cos_falloff_start);
        h = sg_hash_bytes(h, &l->angular_radius, sizeof l->angular_radius);
        if (l->image_path && !hash_file(&h, path, l->image_path, err))
            return false;
        if (l->image_pixels)
            h = sg_hash_bytes(h, l->image_pixels, sizeof(float) * 3 * (size_t)l->image_width * l->image_height);
        h = sg_hash_bytes(h, &layout, sizeof layout);
        h = sg_hash_bytes(h, l->light_to_world, sizeof l->light_to_world);
        h = sg_hash_bytes(h, &portal, sizeof portal);
        if (l->has_portal)
            h = sg_hash_bytes(h, l->portal, sizeof l->portal);
    }
    s->geometry_hash = h;
    return true;
}

void sg_scene_triangle_normal(const SgScene *scene, uint32_t t, double n[3])
{
    const uint32_t *idx = scene->indices + 3 * (size_t)t;
    const double *a = scene->positions + 3 * (size_t)idx[0];
    const double *b = scene->positions + 3 * (size_t)idx[1];
    const double *c = scene->positions + 3 * (size_t)idx[2];
    double e1[3], e2[3];
    d3_sub(b, a, e1);
    d3_sub(c, a, e2);
    d3_cross(e1, e2, n);
}

void sg_scene_free(SgScene *s)
{
    if (!s)
        return;
    /* the strings the arrays' items own, then the arrays */
    for (uint32_t i = 0; i < s->texture_count; i++)
        free(s->textures[i].path);
    for (uint32_t i = 0; i < s->light_source_count; i++) {
        free(s->light_sources[i].image_path);
        free(s->light_sources[i].image_pixels);
    }
    for (uint32_t i = 0; i < s->warning_count; i++)
        free(s->warnings[i]);
    void *arrays[] = {s->positions, s->indices,        s->triangle_material, s->triangle_light,
                      s->materials, s->textures,       s->uvs,               s->lights,
                      s->light_triangles, s->light_sources, s->warnings};
    for (size_t i = 0; i < sizeof arrays / sizeof arrays[0]; i++)
        free(arrays[i]);
    free(s);
}

bool sg_builder_begin(SgSceneBuilder *b, const char *path, SgError *err)
{
    memset(b, 0, sizeof *b);
    b->path = path;
    b->scene = calloc(1, sizeof *b->scene);
    if (!b->scene)
        return sg_fail(err, "%s: out of memory", path);
    snprintf(b->scene->path, sizeof b->scene->path, "%s", path);
    b->scene->source_hash = SG_HASH_INIT;
    return true;
}

void sg_builder_add_source(SgSceneBuilder *b, const char *text, size_t size)
{
    b->scene->source_hash = sg_hash_bytes(b->scene->source_hash, text, size);
}

bool sg_builder_finish(SgSceneBuilder *b, SgError *err)
{
    if (!group_lights(b, err))
        return false;
    if (b->scene->uvs && !reserve_uvs(b, b->scene->vertex_count, err)) /* the meshes after the last with uv */
        return false;
    b->scene->degenerate_dropped = b->dropped_degenerate;
    if (!compute_bounds_and_hash(b->scene, b->path, err))
        return false;
    for (size_t i = 0; i < b->warning_count; i++) {
        const SgBuilderWarning *w = &b->warnings[i];
        if (w->count > 1)
            sg_scene_add_warning(b->scene, "%s: %s (%u times)", w->where, w->kind, w->count);
        else
            sg_scene_add_warning(b->scene, "%s: %s", w->where, w->kind);
    }
    return true;
}

bool sg_shape_group_add(SgShapeGroup *g, const char *path, const double *positions, uint32_t vertex_count,
                        const uint32_t *indices, uint32_t triangle_count, const float *uvs,
                        const SgTransform *xf, uint32_t material, SgError *err)
{
    if (g->shape_count == g->shape_capacity) {
        size_t cap = g->shape_capacity ? 2 * g->shape_capacity : 8;
        SgGroupShape *grown = realloc(g->shapes, cap * sizeof *grown);
        if (!grown)
            return sg_fail(err, "%s: out of memory", path);
        g->shapes = grown;
        g->shape_capacity = cap;
    }
    SgGroupShape *s = &g->shapes[g->shape_count];
    memset(s, 0, sizeof *s);
    s->positions = malloc((size_t)vertex_count * 3 * sizeof(double) + 1);
    s->indices = malloc((size_t)triangle_count * 3 * sizeof(uint32_t) + 1);
    s->uvs = uvs ? malloc((size_t)vertex_count * 2 * sizeof(float) + 1) : NULL;
    if (!s->positions || !s->indices || (uvs && !s->uvs)) {
        free(s->positions);
        free(s->indices);
        free(s->uvs);
        return sg_fail(err, "%s: out of memory", path);
    }
    g->shape_count++;
    for (uint32_t v = 0; v < vertex_count; v++)
        sg_transform_point(xf, positions + 3 * (size_t)v, s->positions + 3 * (size_t)v);
    memcpy(s->indices, indices, (size_t)triangle_count * 3 * sizeof(uint32_t));
    if (uvs)
        memcpy(s->uvs, uvs, (size_t)vertex_count * 2 * sizeof(float));
    s->vertex_count = vertex_count;
    s->triangle_count = triangle_count;
    s->material = material;
    return true;
}

bool sg_builder_add_group(SgSceneBuilder *b, const char *what, const SgShapeGroup *g, const SgTransform *xf,
                          SgError *err)
{
    for (size_t i = 0; i < g->shape_count; i++) {
        const SgGroupShape *s = &g->shapes[i];
        uint32_t first = b->scene->vertex_count;
        if (!sg_builder_append_mesh(b, what, s->positions, s->vertex_count, s->indices, s->triangle_count, xf,
                                    s->material, err) ||
            (s->uvs && !sg_builder_set_uvs(b, first, s->vertex_count, s->uvs, err)))
            return false;
    }
    return true;
}

void sg_shape_group_release(SgShapeGroup *g)
{
    for (size_t i = 0; i < g->shape_count; i++) {
        free(g->shapes[i].positions);
        free(g->shapes[i].indices);
        free(g->shapes[i].uvs);
    }
    free(g->shapes);
    memset(g, 0, sizeof *g);
}

void sg_builder_release(SgSceneBuilder *b)
{
    free(b->warnings);
    free(b->emissive);
    sg_image_averages_free(&b->images);
    b->warnings = NULL;
    b->emissive = NULL;
    b->warning_count = b->emissive_count = 0;
}

void sg_builder_warnv(SgSceneBuilder *b, const char *where, const char *fmt, va_list ap)
{
    char kind[sizeof b->warnings->kind];
    vsnprintf(kind, sizeof kind, fmt, ap);
    for (size_t i = 0; i < b->warning_count; i++)
        if (!strcmp(b->warnings[i].kind, kind)) {
            b->warnings[i].count++;
            return;
        }
    /* a handful of kinds: grown one at a time */
    SgBuilderWarning *grown = realloc(b->warnings, (b->warning_count + 1) * sizeof *grown);
    if (!grown)
        return;
    b->warnings = grown;
    SgBuilderWarning *w = &b->warnings[b->warning_count++];
    snprintf(w->kind, sizeof w->kind, "%s", kind);
    snprintf(w->where, sizeof w->where, "%s", where);
    w->count = 1;
}

void sg_scene_add_warning(SgScene *s, const char *fmt, ...)
{
    char line[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    for (char *c = line; *c; c++)
        if (*c == '\n' || *c == '\r')
            *c = ' ';
    char **grown = realloc(s->warnings, (s->warning_count + 1) * sizeof *grown);
    if (!grown)
        return;
    s->warnings = grown;
    if ((grown[s->warning_count] = strdup(line)))
        s->warning_count++;
}

void sg_scene_print_warnings(const SgScene *s, const char *program, FILE *out)
{
    for (uint32_t i = 0; s && i < s->warning_count; i++)
        fprintf(out, "%s: warning: %s\n", program, s->warnings[i]);
}

bool sg_builder_add_light_source(SgSceneBuilder *b, const SgLightSource *light, SgError *err)
{
    SgScene *s = b->scene;
    for (int c = 0; c < 3; c++)
        if (!(isfinite(light->rgb[c]) && light->rgb[c] >= 0.0f))
            return sg_fail(err, "%s: a light's radiance must be finite and not negative", b->path);
    SgLightSource *grown = realloc(s->light_sources, (s->light_source_count + 1) * sizeof *grown);
    if (!grown)
        return sg_fail(err, "%s: out of memory", b->path);
    s->light_sources = grown;
    SgLightSource *l = &grown[s->light_source_count];
    *l = *light;
    l->image_path = NULL;
    l->image_pixels = NULL;
    if (light->image_path && !(l->image_path = strdup(light->image_path)))
        return sg_fail(err, "%s: out of memory", b->path);
    if (light->image_pixels) {
        size_t bytes = sizeof(float) * 3 * (size_t)light->image_width * light->image_height;
        if (!(light->image_width > 0 && light->image_height > 0) || !(l->image_pixels = malloc(bytes))) {
            free(l->image_path);
            return sg_fail(err, "%s: out of memory for a sky image", b->path);
        }
        memcpy(l->image_pixels, light->image_pixels, bytes);
    }
    s->light_source_count++;
    return true;
}
