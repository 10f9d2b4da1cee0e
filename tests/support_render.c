#include "support_render.h"
#include <criterion/criterion.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "color.h"
#include "memory.h"
#include "scene_load.h"

SgScene *sgt_scene_new(void)
{
    SgScene *s = calloc(1, sizeof *s);
    strcpy(s->path, "test-scene");
    return s;
}

void sgt_scene_free(SgScene *s)
{
    /* Test scenes are allocated like loaded ones: the loader's free fits. */
    sg_scene_free(s);
}

uint32_t sgt_add_material(SgScene *s, SgMaterialType type, const float albedo[3],
                          const float emission[3])
{
    s->materials = realloc(s->materials, (s->material_count + 1) * sizeof *s->materials);
    SgMaterial *m = &s->materials[s->material_count];
    memset(m, 0, sizeof *m);
    m->type = type;
    m->exponent = 1;
    m->ior = 1.5f;
    for (int i = 0; i < 3; i++) {
        m->diffuse[i] = albedo ? albedo[i] : 0;
        m->emission[i] = emission ? emission[i] : 0;
    }
    return s->material_count++;
}

SgMaterial *sgt_material(SgScene *s, uint32_t m) { return &s->materials[m]; }

/* A test scene's arrays grow as sg_reserve grows them, doubling from 8,
 * so their capacity follows from their count (a realloc per quad is
 * quadratic, and minutes under AddressSanitizer, which always copies). */
static void *grow_to(void *p, size_t count, size_t added, size_t item)
{
    size_t capacity = 0;
    if (count)
        for (capacity = 8; capacity < count; capacity *= 2)
            ;
    if (!sg_reserve(&p, &capacity, count + added, item, 8))
        abort();
    return p;
}

void sgt_add_quad(SgScene *s, const double c[4][3], uint32_t material)
{
    uint32_t v0 = s->vertex_count;
    s->positions = grow_to(s->positions, v0, 4, 3 * sizeof(double));
    for (int k = 0; k < 4; k++)
        for (int i = 0; i < 3; i++)
            s->positions[3 * (v0 + k) + i] = c[k][i];
    s->vertex_count += 4;
    uint32_t t0 = s->triangle_count;
    s->indices = grow_to(s->indices, t0, 2, 3 * sizeof(uint32_t));
    s->triangle_material = grow_to(s->triangle_material, t0, 2, sizeof(uint32_t));
    s->triangle_light = grow_to(s->triangle_light, t0, 2, sizeof(uint32_t));
    uint32_t tri[6] = {v0, v0 + 1, v0 + 2, v0, v0 + 2, v0 + 3};
    memcpy(s->indices + 3 * t0, tri, sizeof tri);
    s->triangle_material[t0] = s->triangle_material[t0 + 1] = material;
    s->triangle_light[t0] = s->triangle_light[t0 + 1] = SG_NO_LIGHT;
    s->triangle_count += 2;
}

void sgt_add_box_inside(SgScene *s, const double lo[3], const double hi[3], uint32_t material)
{
    double x0 = lo[0], y0 = lo[1], z0 = lo[2], x1 = hi[0], y1 = hi[1], z1 = hi[2];
    /* each face wound so that (c1-c0)x(c2-c0) points into the box */
    const double faces[6][4][3] = {
        {{x0, y0, z0}, {x1, y0, z0}, {x1, y0, z1}, {x0, y0, z1}}, /* floor, +y */
        {{x0, y1, z0}, {x0, y1, z1}, {x1, y1, z1}, {x1, y1, z0}}, /* ceiling, -y */
        {{x0, y0, z0}, {x0, y0, z1}, {x0, y1, z1}, {x0, y1, z0}}, /* x0 wall, +x */
        {{x1, y0, z0}, {x1, y1, z0}, {x1, y1, z1}, {x1, y0, z1}}, /* x1 wall, -x */
        {{x0, y0, z0}, {x0, y1, z0}, {x1, y1, z0}, {x1, y0, z0}}, /* z0 wall, +z */
        {{x0, y0, z1}, {x1, y0, z1}, {x1, y1, z1}, {x0, y1, z1}}, /* z1 wall, -z */
    };
    for (int f = 0; f < 6; f++) {
        /* listed counter-clockwise seen from outside: reverse them */
        const double q[4][3] = {{faces[f][0][0], faces[f][0][1], faces[f][0][2]},
                                {faces[f][3][0], faces[f][3][1], faces[f][3][2]},
                                {faces[f][2][0], faces[f][2][1], faces[f][2][2]},
                                {faces[f][1][0], faces[f][1][1], faces[f][1][2]}};
        sgt_add_quad(s, q, material);
    }
}

void sgt_set_camera(SgScene *s, const double pos[3], const double at[3], const double up[3],
                    double fov, int width, int height)
{
    s->has_camera = true;
    memcpy(s->camera.position, pos, sizeof s->camera.position);
    memcpy(s->camera.look_at, at, sizeof s->camera.look_at);
    memcpy(s->camera.up, up, sizeof s->camera.up);
    s->camera.fov_deg = fov;
    s->camera.width = width;
    s->camera.height = height;
}

void sgt_finish_looking(SgScene *s, const double pos[3], const double at[3], double fov, int width, int height)
{
    static const double up[3] = {0, 1, 0};
    sgt_set_camera(s, pos, at, up, fov, width, height);
    sgt_finish(s);
}

void sgt_finish(SgScene *s)
{
    for (int i = 0; i < 3; i++) {
        s->bounds_min[i] = INFINITY;
        s->bounds_max[i] = -INFINITY;
    }
    for (uint32_t v = 0; v < s->vertex_count; v++)
        for (int i = 0; i < 3; i++) {
            s->bounds_min[i] = fmin(s->bounds_min[i], s->positions[3 * v + i]);
            s->bounds_max[i] = fmax(s->bounds_max[i], s->positions[3 * v + i]);
        }
    /* one light per emissive quad (triangle pairs) */
    free(s->lights);
    free(s->light_triangles);
    s->lights = calloc(s->triangle_count / 2 + 1, sizeof *s->lights);
    s->light_triangles = calloc(s->triangle_count + 1, sizeof *s->light_triangles);
    s->light_count = 0;
    uint32_t k = 0;
    for (uint32_t t = 0; t + 1 < s->triangle_count; t += 2) {
        const SgMaterial *m = &s->materials[s->triangle_material[t]];
        if (m->emission[0] + m->emission[1] + m->emission[2] <= 0)
            continue;
        SgLight *L = &s->lights[s->light_count];
        L->first_triangle = k;
        L->triangle_count = 2;
        double area = 0, n[3] = {0, 0, 0}, c[3] = {0, 0, 0};
        for (uint32_t j = t; j < t + 2; j++) {
            double tn[3], e1[3], e2[3];
            const double *p = s->positions;
            const uint32_t *id = s->indices + 3 * j;
            for (int i = 0; i < 3; i++) {
                e1[i] = p[3 * id[1] + i] - p[3 * id[0] + i];
                e2[i] = p[3 * id[2] + i] - p[3 * id[0] + i];
            }
            tn[0] = e1[1] * e2[2] - e1[2] * e2[1];
            tn[1] = e1[2] * e2[0] - e1[0] * e2[2];
            tn[2] = e1[0] * e2[1] - e1[1] * e2[0];
            double a = 0.5 * sqrt(tn[0] * tn[0] + tn[1] * tn[1] + tn[2] * tn[2]);
            area += a;
            for (int i = 0; i < 3; i++) {
                n[i] += tn[i];
                for (int v = 0; v < 3; v++)
                    c[i] += a / 3.0 * s->positions[3 * s->indices[3 * j + v] + i];
            }
            s->light_triangles[k++] = j;
            s->triangle_light[j] = s->light_count;
        }
        double nl = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int i = 0; i < 3; i++) {
            L->normal[i] = n[i] / nl;
            L->position[i] = c[i] / area;
            L->radiance[i] = m->emission[i];
        }
        L->area = area;
        L->power = M_PI * area * sg_luminance(m->emission[0], m->emission[1], m->emission[2]);
        s->light_count++;
    }
}

void sgt_scale_offset(SgScene *s, double scale, const double offset[3])
{
    for (uint32_t v = 0; v < s->vertex_count; v++)
        for (int i = 0; i < 3; i++)
            s->positions[3 * v + i] = s->positions[3 * v + i] * scale + offset[i];
    for (int i = 0; i < 3; i++) {
        s->camera.position[i] = s->camera.position[i] * scale + offset[i];
        s->camera.look_at[i] = s->camera.look_at[i] * scale + offset[i];
    }
}

bool sgt_fixed_point_guide(void *ctx, const double p[3], uint32_t light, double q[3])
{
    (void)p;
    (void)light;
    memcpy(q, ((SgtFixedPoint *)ctx)->point, sizeof(double) * 3);
    return true;
}

SgScene *sgt_furnace_scene(void)
{
    SgScene *s = sgt_scene_new();
    const float half[3] = {0.5f, 0.5f, 0.5f};
    uint32_t m = sgt_add_material(s, SG_MATERIAL_DIFFUSE, half, half);
    const double lo[3] = {-1, -1, -1}, hi[3] = {1, 1.5, 2};
    sgt_add_box_inside(s, lo, hi, m);
    const double pos[3] = {0.2, 0.1, 0.3}, at[3] = {1, 0.5, 2};
    sgt_finish_looking(s, pos, at, 90, 32, 24);
    return s;
}

float *sgt_render_image(const SgScene *s, const SgRenderOptions *o, int passes, SgError *err)
{
    SgRenderer *r = sg_renderer_create(s, o, err);
    if (!r)
        return NULL;
    for (int i = 0; i < passes; i++)
        sg_renderer_pass(r);
    float *rgb = malloc(sizeof(float) * 3 * o->width * o->height);
    if (rgb)
        sg_renderer_image(r, rgb);
    else
        sg_fail(err, "out of memory for a %dx%d image", o->width, o->height);
    sg_renderer_free(r);
    return rgb;
}

float *sgt_render_default(const SgScene *s, SgRenderOptions *o, int passes, SgError *err)
{
    sg_render_options_default(o, s);
    o->threads = 2;
    return sgt_render_image(s, o, passes, err);
}

SgtSampleMean sgt_passes_mean(SgRenderer *r, int passes, size_t pixels)
{
    double sum = 0.0, sum2 = 0.0;
    long n = 0;
    for (int p = 0; p < passes; p++) {
        sg_renderer_pass(r);
        const float *last = sg_renderer_last_pass(r);
        for (size_t i = 0; i < pixels; i++, n++) {
            double v = last[3 * i];
            sum += v;
            sum2 += v * v;
        }
    }
    SgtSampleMean m = {.mean = sum / n};
    m.std_error = sqrt(fmax(0.0, sum2 / n - m.mean * m.mean) / (n - 1));
    return m;
}

SgRenderOptions sgt_options(const SgScene *s, SgSampling mode)
{
    SgRenderOptions o;
    sg_render_options_default(&o, s);
    o.sampling = mode;
    o.threads = 2;
    o.seed = 7;
    return o;
}

SgScene *sgt_scene_from_text(const char *name, const char *text, SgError *err)
{
    char path[256];
    snprintf(path, sizeof path, "/tmp/sg_test_scene_%d_%s", (int)getpid(), name);
    FILE *f = fopen(path, "w");
    if (!f)
        return sg_fail(err, "%s: cannot write the test scene", path), NULL;
    fputs(text, f);
    fclose(f);
    SgScene *s = sg_scene_load(path, err);
    remove(path);
    return s;
}

SgScene *sgt_load_ok(const char *path)
{
    SgError err = {0};
    SgScene *s = sg_scene_load(path, &err);
    cr_assert(s, "%s: %s", path, err.message);
    return s;
}

/* ---- two rooms and a window -------------------------------------------------- */

static void add_wall_piece(SgScene *s, double y0, double y1, double z0, double z1, uint32_t m)
{
    const double a[4][3] = {{2, y0, z0}, {2, y1, z0}, {2, y1, z1}, {2, y0, z1}};
    const double b[4][3] = {{2, y0, z0}, {2, y0, z1}, {2, y1, z1}, {2, y1, z0}};
    sgt_add_quad(s, a, m);
    sgt_add_quad(s, b, m);
}

SgScene *sgt_window_rooms(void)
{
    SgScene *s = sgt_scene_new();
    const float white[3] = {0.7f, 0.7f, 0.7f}, em[3] = {20, 20, 20}, black[3] = {0, 0, 0};
    uint32_t w = sgt_add_material(s, SG_MATERIAL_DIFFUSE, white, NULL);
    uint32_t lm = sgt_add_material(s, SG_MATERIAL_DIFFUSE, black, em);
    const double lo[3] = {0, 0, 0}, hi[3] = {4, 2, 2};
    sgt_add_box_inside(s, lo, hi, w);
    /* partition at x = 2 around a window y, z in [0.75, 1.25] */
    add_wall_piece(s, 0, 0.75, 0, 2, w);
    add_wall_piece(s, 1.25, 2, 0, 2, w);
    add_wall_piece(s, 0.75, 1.25, 0, 0.75, w);
    add_wall_piece(s, 0.75, 1.25, 1.25, 2, w);
    const double l[4][3] = {{0.8, 1.99, 0.8}, {1.2, 1.99, 0.8}, {1.2, 1.99, 1.2}, {0.8, 1.99, 1.2}};
    sgt_add_quad(s, l, lm);
    const double pos[3] = {2.3, 1.0, 1.0}, at[3] = {4, 0.9, 1.1};
    sgt_finish_looking(s, pos, at, 80, 40, 30);
    return s;
}
