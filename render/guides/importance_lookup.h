/* The skeleton's importance points as the skeleton and guided modes look
 * them up (the paper, section 3.4): at a vertex, the axis toward the
 * importance point of the skeleton node nearest the vertex, for a light
 * chosen in proportion to its power. */
#ifndef SG_RENDER_IMPORTANCE_LOOKUP_H
#define SG_RENDER_IMPORTANCE_LOOKUP_H

#include <math.h>
#include <stdbool.h>
#include <stdint.h>

#include "error.h"
#include "importance_cache.h"
#include "../lights.h"
#include "../renderer.h"
#include "rng.h"
#include "vecmath.h"

/* At a vertex: which light to follow, and the importance point of the
 * skeleton node nearest the vertex for that light, from the importance
 * cache read in the renderer's frame (a query is then a voxel lookup and a
 * table read, with no call through the source's function and no
 * conversion to world coordinates), or from the source's function. */
typedef struct ImportanceLookup {
    const SgImportanceCache *cache;
    Vec3 origin;       /* voxel (0,0,0)'s corner, local coordinates */
    float inv_voxel;   /* 1 / voxel size */
    float offset;      /* the source's query offset */
    uint32_t light_count;
    float *points;     /* [node][light][3] importance points, local; NaN: the
                        * light cannot be reached from the node */
    const uint32_t *decoded; /* node per voxel (sg_cache_decoded), or NULL */
    const uint32_t *octants; /* of its mixed wall voxels (sg_cache_decoded_octants) */
    float extent[3];   /* the grid's size in voxels */
    int64_t stride[3]; /* of x, y, z in the decoded table */
    /* where `points` is NULL (no cache, or its table too large): the
     * source's function, in world coordinates */
    SgImportanceSource source;
    double centre[3];  /* world = local + centre */
    float min_length;  /* an importance point nearer than this gives no direction */
    const LightSet *lights; /* its follow_cdf: which light to follow */
} ImportanceLookup;

/* `source` as the renderer was given it, `centre` the world position of
 * the local origin, `scale` the scene's extent. Its table is copied to
 * local coordinates; one too large for memory leaves the source's function
 * to answer (same answers, slower). Fails on a cache with another light
 * count than the scene's. */
bool importance_lookup_init(ImportanceLookup *g, const SgImportanceSource *source, const double centre[3], float scale,
                         const LightSet *lights, const char *path, SgError *err);
void importance_lookup_free(ImportanceLookup *g);

/* A lookup in two halves, around the bounce's shadow ray: the first
 * picks the light and starts loading the cache's voxel, the second reads
 * it (by then in cache) and makes the lobe's axis. */
typedef struct ImportanceQuery {
    uint32_t light;
    float voxel[3]; /* the query point in the cache's voxel units */
    int64_t index;  /* its voxel in the decoded table, -1: ask the cache */
} ImportanceQuery;

/* The query's first half. False: no light to follow. */
static inline bool importance_lookup_begin(const ImportanceLookup *g, Vec3 p, Vec3 n, SgRng *rng, ImportanceQuery *gq)
{
    float u = sg_rng_float(rng); /* drawn always: keeps the streams aligned */
    const LightSet *ls = g->lights;
    uint32_t count = ls->follow_count;
    if (!count || ls->follow_cdf[count - 1] <= 0.0)
        return false;
    gq->light = count == 1 ? 0 : sg_piecewise_pick(ls->follow_cdf, count, u * ls->follow_cdf[count - 1]);
    if (g->points) {
        Vec3 w = v3_add(p, v3_scale(n, g->offset));
        gq->voxel[0] = (w.x - g->origin.x) * g->inv_voxel;
        gq->voxel[1] = (w.y - g->origin.y) * g->inv_voxel;
        gq->voxel[2] = (w.z - g->origin.z) * g->inv_voxel;
        const float *v = gq->voxel;
        gq->index = -1;
        if (g->decoded && v[0] >= 0.0f && v[1] >= 0.0f && v[2] >= 0.0f && v[0] < g->extent[0] &&
            v[1] < g->extent[1] && v[2] < g->extent[2]) {
            /* v >= 0: truncation is floor */
            gq->index = (int64_t)(int)v[0] + g->stride[1] * (int)v[1] + g->stride[2] * (int)v[2];
            __builtin_prefetch(g->decoded + gq->index);
        }
    }
    return true;
}

/* The importance point (local coordinates), or false. */
static inline bool importance_lookup_point(const ImportanceLookup *g, const ImportanceQuery *gq, Vec3 p, Vec3 n, Vec3 *q)
{
    if (g->points) {
        uint32_t node = SG_CACHE_NONE;
        if (gq->index >= 0) {
            const float *v = gq->voxel; /* v >= 0: truncation is floor */
            unsigned octant = (v[0] - (float)(int)v[0] >= 0.5f) | (v[1] - (float)(int)v[1] >= 0.5f) << 1 |
                              (v[2] - (float)(int)v[2] >= 0.5f) << 2;
            node = sg_cache_entry_node(g->decoded[gq->index], g->octants, octant);
        }
        /* no one node for the octant, or outside the grid: the cache searches the neighbours */
        if (node == SG_CACHE_NONE && !sg_cache_nearest_node_voxel(g->cache, gq->voxel, &node))
            return false;
        const float *pt = g->points + 3 * ((size_t)node * g->light_count + gq->light);
        *q = v3(pt[0], pt[1], pt[2]);
        return pt[0] == pt[0]; /* NaN: the light cannot reach the node */
    }
    double off = g->source.query_offset;
    double world[3] = {p.x + g->centre[0] + off * n.x, p.y + g->centre[1] + off * n.y,
                       p.z + g->centre[2] + off * n.z};
    double wq[3];
    if (!g->source.importance_point(g->source.ctx, world, gq->light, wq))
        return false;
    *q = v3((float)(wq[0] - g->centre[0]), (float)(wq[1] - g->centre[1]), (float)(wq[2] - g->centre[2]));
    return true;
}

/* The direction toward the importance point, or false (none, or below the surface). */
static inline bool importance_lookup_end(const ImportanceLookup *g, const ImportanceQuery *gq, Vec3 p, Vec3 n, Vec3 *axis)
{
    Vec3 q;
    if (!importance_lookup_point(g, gq, p, n, &q))
        return false;
    Vec3 d = v3_sub(q, p);
    float len2 = v3_dot(d, d);
    /* a point at the shading point has no direction; one at infinity (a
     * bad source) would give a NaN axis that passes the test below */
    float min_len = g->min_length;
    if (!(len2 > min_len * min_len) || !(len2 < INFINITY))
        return false;
    Vec3 a = v3_scale(d, 1.0f / sqrtf(len2));
    if (v3_dot(a, n) <= 0.0f)
        return false; /* below the surface: back to BSDF sampling */
    *axis = a;
    return true;
}

#endif
