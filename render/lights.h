/* The scene's lights as the renderer samples them: one light picked by
 * power, a triangle of it by area, a point on it uniformly; and the guide's
 * choice of which light to follow. */
#ifndef SG_RENDER_LIGHTS_H
#define SG_RENDER_LIGHTS_H

#include <stdbool.h>
#include <math.h>
#include <stdint.h>

#include "error.h"
#include "material.h"
#include "scene.h"
#include "vecmath.h"

typedef struct LightTable {
    double pick_pdf;      /* probability that NEE picks this light */
    float inv_area;       /* 1 / area, in local (float) coordinates */
    uint32_t first, count; /* its triangles in r->light_tris / r->light_tri_cdf */
} LightTable;

typedef struct LightSet {
    uint32_t count;
    LightTable *lights;
    double *cdf;        /* count: by power */
    uint32_t *tris;     /* triangle ids grouped by light */
    double *tri_cdf;    /* per light, cumulative area fractions */
    double *follow_cdf; /* guide: cumulative follow probability per light */
} LightSet;

/* From the scene's lights, their triangles' local vertices and the
 * renderer's materials; `follow_weight` (per light, NULL: the lights'
 * power) is the guide's. Fails naming `path`. */
bool light_set_init(LightSet *ls, const SgScene *s, const Vec3 *vertices, const Material *materials,
                    const double *follow_weight, const char *path, SgError *err);
void light_set_free(LightSet *ls);

/* The index i with cdf[i - 1] <= u < cdf[i] (binary search). */
static inline uint32_t pick_cdf(const double *cdf, uint32_t n, double u)
{
    uint32_t lo = 0, hi = n - 1;
    while (lo < hi) {
        uint32_t mid = (lo + hi) / 2;
        if (u < cdf[mid])
            hi = mid;
        else
            lo = mid + 1;
    }
    return lo;
}

/* A point y on a light for next-event estimation from four random
 * numbers, and its triangle; false: no light has power. */
static inline bool light_set_sample(const LightSet *ls, const Vec3 *vertices, const uint32_t *indices, float ul,
                                    float ut, float ua, float ub, uint32_t *tri, Vec3 *y)
{
    if (!ls->count || !(ls->cdf[ls->count - 1] > 0.0))
        return false;
    uint32_t l = pick_cdf(ls->cdf, ls->count, ul * ls->cdf[ls->count - 1]);
    const LightTable *lt = &ls->lights[l];
    uint32_t k = lt->first + pick_cdf(ls->tri_cdf + lt->first, lt->count, ut);
    uint32_t t = ls->tris[k];
    const uint32_t *id = indices + 3 * t;
    float su = sqrtf(ua);
    float b0 = 1.0f - su, b1 = ub * su;
    *y = v3_add(v3_add(v3_scale(vertices[id[0]], b0), v3_scale(vertices[id[1]], b1)),
                v3_scale(vertices[id[2]], 1.0f - b0 - b1));
    *tri = t;
    return true;
}

/* The solid-angle pdf of next-event estimation reaching a point of light
 * `light` (SG_NO_LIGHT: none) at squared distance dist2, seen at cosine
 * cos_light from its side. */
static inline float light_set_pdf(const LightSet *ls, uint32_t light, float dist2, float cos_light)
{
    if (light == SG_NO_LIGHT || cos_light <= 0.0f)
        return 0.0f;
    return (float)ls->lights[light].pick_pdf * ls->lights[light].inv_area * dist2 / cos_light;
}

#endif
