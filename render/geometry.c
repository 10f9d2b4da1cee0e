#include "geometry.h"

#include <math.h>
#include <stdlib.h>

#include "guides/mixture_learning.h"

bool geometry_init(Geometry *g, const SgScene *s, const char *path, SgError *err)
{
    *g = (Geometry){0};
    double extent = 0.0;
    for (int i = 0; i < 3; i++) {
        g->centre[i] = 0.5 * (s->bounds_min[i] + s->bounds_max[i]);
        extent = fmax(extent, s->bounds_max[i] - s->bounds_min[i]);
    }
    /* bounds may be unset by a hand-made scene: compute them if empty */
    if (!(extent > 0.0)) {
        double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (uint32_t v = 0; v < s->vertex_count; v++)
            for (int i = 0; i < 3; i++) {
                lo[i] = fmin(lo[i], s->positions[3 * v + i]);
                hi[i] = fmax(hi[i], s->positions[3 * v + i]);
            }
        for (int i = 0; i < 3; i++) {
            g->centre[i] = 0.5 * (lo[i] + hi[i]);
            extent = fmax(extent, hi[i] - lo[i]);
        }
    }
    if (!isfinite(extent) || !(extent > 0.0))
        return sg_fail(err, "%s: degenerate or non-finite scene bounds", path);
    g->scale = (float)extent;
    for (uint32_t m = 0; m < s->material_count; m++)
        g->has_cutouts = g->has_cutouts || (s->materials[m].cutout &&
                                            (s->materials[m].alpha_texture || s->materials[m].alpha < 1.0f));

    g->vertex_count = s->vertex_count;
    g->triangle_count = s->triangle_count;
    g->vertices = malloc(sizeof(Vec3) * s->vertex_count + 16);
    g->indices = malloc(sizeof(uint32_t) * 3 * s->triangle_count);
    g->tris = malloc(sizeof(TriInfo) * s->triangle_count);
    if (!g->vertices || !g->indices || !g->tris)
        return sg_fail(err, "%s: out of memory", path);
    for (uint32_t v = 0; v < s->vertex_count; v++)
        g->vertices[v] = v3((float)(s->positions[3 * v] - g->centre[0]),
                            (float)(s->positions[3 * v + 1] - g->centre[1]),
                            (float)(s->positions[3 * v + 2] - g->centre[2]));
    for (uint32_t t = 0; t < s->triangle_count; t++) {
        const uint32_t *id = s->indices + 3 * t;
        if (id[0] >= s->vertex_count || id[1] >= s->vertex_count || id[2] >= s->vertex_count ||
            s->triangle_material[t] >= s->material_count)
            return sg_fail(err, "%s: triangle %u has a bad vertex or material index", path, t);
        memcpy(g->indices + 3 * t, id, 3 * sizeof *id);
        TriInfo *ti = &g->tris[t];
        ti->material = s->triangle_material[t];
        ti->light = s->triangle_light ? s->triangle_light[t] : SG_NO_LIGHT;
        if (ti->light != SG_NO_LIGHT && ti->light >= s->light_count)
            ti->light = SG_NO_LIGHT;
        /* normal in double from the world positions: exact direction */
        double n[3], e1[3], e2[3];
        const double *p = s->positions;
        d3_sub(p + 3 * id[1], p + 3 * id[0], e1);
        d3_sub(p + 3 * id[2], p + 3 * id[0], e2);
        d3_cross(e1, e2, n);
        double nl = d3_length(n);
        ti->normal = nl > 0 ? v3((float)(n[0] / nl), (float)(n[1] / nl), (float)(n[2] / nl)) : v3(0, 0, 1);
        ti->normal_bin = (uint8_t)sg_mixture_normal_bin(ti->normal);
    }
    return true;
}

bool geometry_build(Geometry *g, const char *path, SgError *err)
{
    g->device = rtcNewDevice(NULL);
    if (!g->device)
        return sg_fail(err, "%s: Embree device: %d", path, (int)rtcGetDeviceError(NULL));
    g->scene = rtcNewScene(g->device);
    rtcSetSceneBuildQuality(g->scene, RTC_BUILD_QUALITY_HIGH);
    /* not RTC_SCENE_FLAG_ROBUST: 25% slower traversal on Sponza; the
     * furnace tests (closed boxes) show no leaks without it */
    RTCGeometry geom = rtcNewGeometry(g->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, g->vertices, 0, sizeof(Vec3),
                               g->vertex_count);
    rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, g->indices, 0,
                               3 * sizeof(uint32_t), g->triangle_count);
    rtcCommitGeometry(geom);
    rtcAttachGeometry(g->scene, geom);
    rtcReleaseGeometry(geom);
    rtcCommitScene(g->scene);
    enum RTCError e = rtcGetDeviceError(g->device);
    if (e != RTC_ERROR_NONE)
        return sg_fail(err, "%s: Embree scene build failed (error %d)", path, (int)e);
    return true;
}

void geometry_free(Geometry *g)
{
    if (g->scene)
        rtcReleaseScene(g->scene);
    if (g->device)
        rtcReleaseDevice(g->device);
    free(g->vertices);
    free(g->indices);
    free(g->tris);
    *g = (Geometry){0};
}

void geometry_bounds(const Geometry *g, Vec3 *lo, Vec3 *hi)
{
    *lo = v3(INFINITY, INFINITY, INFINITY);
    *hi = v3(-INFINITY, -INFINITY, -INFINITY);
    for (uint32_t t = 0; t < g->triangle_count; t++)
        for (int k = 0; k < 3; k++) {
            Vec3 v = g->vertices[g->indices[3 * t + k]];
            *lo = v3(fminf(lo->x, v.x), fminf(lo->y, v.y), fminf(lo->z, v.z));
            *hi = v3(fmaxf(hi->x, v.x), fmaxf(hi->y, v.y), fmaxf(hi->z, v.z));
        }
}
