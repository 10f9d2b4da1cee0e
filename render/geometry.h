/* The scene's triangles as the renderer traces them: in local coordinates
 * (world minus the centre of the scene's bounds, so that float coordinates
 * keep their precision far from the origin), with what a hit needs of its
 * triangle packed in one place, in an Embree 3 scene. */
#ifndef SG_RENDER_GEOMETRY_H
#define SG_RENDER_GEOMETRY_H

#include <embree3/rtcore.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#include "error.h"
#include "scene.h"
#include "vecmath.h"

typedef struct TriInfo {
    Vec3 normal;       /* unit geometric normal (winding order) */
    uint32_t material;
    uint32_t light;    /* SG_NO_LIGHT if not emissive */
    uint8_t normal_bin; /* the learner's bin of the normal (sg_mixture_normal_bin) */
} TriInfo;

typedef struct Geometry {
    double centre[3];  /* world = local + centre */
    float scale;       /* the scene's extent, for scale-free ray offsets */
    uint32_t vertex_count, triangle_count;
    Vec3 *vertices;    /* local coordinates */
    uint32_t *indices;
    TriInfo *tris;     /* per triangle, packed: one cache line per hit */
    bool has_cutouts;  /* some material lets rays through (render/integrator.c walks past it) */
    RTCDevice device;
    RTCScene scene;
} Geometry;

/* The triangles of s (bounds computed where the scene has none), checked:
 * fails on degenerate or non-finite bounds and on a bad vertex or
 * material index, naming `path`. Then geometry_build hands them to Embree. */
bool geometry_init(Geometry *g, const SgScene *s, const char *path, SgError *err);
bool geometry_build(Geometry *g, const char *path, SgError *err);
void geometry_free(Geometry *g);
/* The triangles' bounds, local coordinates. */
void geometry_bounds(const Geometry *g, Vec3 *lo, Vec3 *hi);

static inline float int_as_float(int32_t i) { float f; memcpy(&f, &i, 4); return f; }
static inline int32_t float_as_int(float f) { int32_t i; memcpy(&i, &f, 4); return i; }

/* Self-intersection: move p off the surface along n (toward the side the
 * new ray leaves by) by a few ULPs of p's coordinates; near zero, where ULPs
 * vanish, by a small fraction of the scene's size (Waechter & Binder 2019,
 * made scale-free). */
static inline Vec3 offset_origin(const Geometry *g, Vec3 p, Vec3 n)
{
    const float int_scale = 256.0f;
    const float near_zero = g->scale * (1.0f / 32.0f);
    const float float_scale = g->scale * (1.0f / 65536.0f);
    float pc[3] = {p.x, p.y, p.z}, nc[3] = {n.x, n.y, n.z}, out[3];
    for (int i = 0; i < 3; i++) {
        int32_t of = (int32_t)(int_scale * nc[i]);
        float pi = int_as_float(float_as_int(pc[i]) + (pc[i] < 0 ? -of : of));
        out[i] = fabsf(pc[i]) < near_zero ? pc[i] + float_scale * nc[i] : pi;
    }
    return v3(out[0], out[1], out[2]);
}

typedef struct Hit {
    bool found;
    uint32_t tri;
    float t;
    float b1, b2; /* barycentrics: the point is (1 - b1 - b2) a + b1 b + b2 c */
    Vec3 p;
} Hit;

/* The first hit along o + t d with tnear < t < tfar. */
static inline Hit intersect_between(const Geometry *g, Vec3 o, Vec3 d, float tnear, float tfar)
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    struct RTCRayHit rh;
    rh.ray.org_x = o.x; rh.ray.org_y = o.y; rh.ray.org_z = o.z;
    rh.ray.dir_x = d.x; rh.ray.dir_y = d.y; rh.ray.dir_z = d.z;
    rh.ray.tnear = tnear;
    rh.ray.tfar = tfar;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.ray.flags = 0;
    rh.ray.time = 0.0f;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(g->scene, &ctx, &rh);
    Hit h = {0};
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID)
        return h;
    h.found = true;
    h.tri = rh.hit.primID;
    h.t = rh.ray.tfar;
    /* the hit point from the barycentrics (more accurate than o + t d) */
    const uint32_t *id = g->indices + 3 * h.tri;
    Vec3 a = g->vertices[id[0]], b = g->vertices[id[1]], c = g->vertices[id[2]];
    float u = rh.hit.u, v = rh.hit.v;
    h.b1 = u;
    h.b2 = v;
    h.p = v3_add(v3_add(v3_scale(a, 1.0f - u - v), v3_scale(b, u)), v3_scale(c, v));
    return h;
}

static inline Hit intersect(const Geometry *g, Vec3 o, Vec3 d, float tfar)
{
    return intersect_between(g, o, d, 0.0f, tfar);
}

static inline bool occluded(const Geometry *g, Vec3 o, Vec3 d, float tfar)
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    struct RTCRay ray;
    ray.org_x = o.x; ray.org_y = o.y; ray.org_z = o.z;
    ray.dir_x = d.x; ray.dir_y = d.y; ray.dir_z = d.z;
    ray.tnear = 0.0f;
    ray.tfar = tfar;
    ray.mask = 0xFFFFFFFFu;
    ray.flags = 0;
    ray.time = 0.0f;
    rtcOccluded1(g->scene, &ctx, &ray);
    return ray.tfar < 0.0f;
}

#endif
