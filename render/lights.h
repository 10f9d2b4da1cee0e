/* The scene's lights as the renderer samples them: one light picked by
 * power, a triangle of it by area, a point on it uniformly; and the guide's
 * choice of which light to follow. */
#ifndef SG_RENDER_LIGHTS_H
#define SG_RENDER_LIGHTS_H

#include <stdbool.h>
#include <math.h>
#include <stdint.h>

#include "environment.h"
#include "error.h"
#include "material.h"
#include "sampling.h"
#include "scene.h"
#include "vecmath.h"

typedef struct LightTable {
    double pick_pdf;      /* probability that NEE picks this light */
    float inv_area;       /* 1 / area, in local (float) coordinates */
    uint32_t first, count; /* its triangles in r->light_tris / r->light_tri_cdf */
} LightTable;

/* A window the sky is seen through: the parallelogram p0 + u e1 + v e2,
 * u, v in [0, 1] (local coordinates). */
typedef struct Portal {
    Vec3 p0, e1, e2, n; /* n: unit normal */
    float area;
    float g11, g12, g22, inv_det; /* the edges' Gram matrix, to find (u, v) of a point */
} Portal;

/* Of an infinite light's light samples, the share drawn through its portals
 * (the rest from the sky's own distribution, so that directions no portal
 * covers keep their density), where nothing better is known: the guided
 * mode learns a share per region (render/guides/mixture_learning.h). Every
 * call below that takes a `portal_share` reads a negative one as this. */
#define PORTAL_SHARE 0.8f

/* A point, spot, distant or infinite light as the renderer samples it
 * (local coordinates). */
typedef struct LightSource {
    SgLightSourceKind kind;
    Vec3 rgb;          /* point, spot: intensity; distant: irradiance (a delta) or the
                        * disk's radiance; infinite: radiance (the map's, if any, is in it) */
    Vec3 position;     /* point, spot */
    Vec3 direction;    /* the way the light travels */
    float cos_cone, cos_falloff_start; /* spot */
    float sun_sin2;    /* distant: the sine squared of the sun's angular radius (0: a delta),
                        * and 1 - its cosine: what a small disk needs, kept without cancellation */
    float sun_one_minus_cos;
    Environment *map;  /* infinite: the image, or NULL: constant */
    uint32_t portal_count; /* infinite: windows to sample it through (hand-drawn or found) */
    Portal *portals;
    double pick_pdf;
} LightSource;

typedef struct LightSet {
    uint32_t count;     /* area lights: the scene's SgLight, in order */
    LightTable *lights;
    uint32_t source_count; /* then the other lights */
    LightSource *sources;
    bool has_escaping;  /* a light seen by rays that leave the scene (sky, sun disk) */
    double *cdf;        /* count + source_count: by power */
    double total_power; /* what cdf was made from: area times luminance (power / pi) */
    uint32_t *tris;     /* triangle ids grouped by light */
    double *tri_cdf;    /* per light, cumulative area fractions */
    uint32_t follow_count; /* the guide's lights (SgGuideLight): area, point and spot, the outside */
    double *follow_cdf; /* guide: cumulative follow probability per guide light */
} LightSet;

/* From the scene's lights, their triangles' local vertices and the
 * renderer's materials; `follow_weight` (per guide light, NULL: the
 * lights' power) is the guide's; `centre` the local origin (world = local +
 * centre). Fails naming `path` (an environment image naming its own). */
bool light_set_init(LightSet *ls, const SgScene *s, const Vec3 *vertices, const Material *materials,
                    const double *follow_weight, const double centre[3], const char *path, SgError *err);
/* The total power next-event estimation picks from (0: no usable light). */
double light_set_power(const LightSet *ls);
void light_set_free(LightSet *ls);

/* The light next-event estimation draws with random number ul: an area
 * light below ls->count, a light source from there; false: no light has
 * power. */
static inline bool light_set_pick(const LightSet *ls, float ul, uint32_t *light)
{
    uint32_t n = ls->count + ls->source_count;
    if (!n || !(ls->cdf[n - 1] > 0.0))
        return false;
    *light = sg_piecewise_pick(ls->cdf, n, ul * ls->cdf[n - 1]);
    return true;
}

/* A point y on area light l for next-event estimation from three random
 * numbers, and its triangle. */
static inline void light_set_sample_area(const LightSet *ls, uint32_t l, const Vec3 *vertices,
                                         const uint32_t *indices, float ut, float ua, float ub, uint32_t *tri, Vec3 *y)
{
    const LightTable *lt = &ls->lights[l];
    uint32_t k = lt->first + sg_piecewise_pick(ls->tri_cdf + lt->first, lt->count, ut);
    uint32_t t = ls->tris[k];
    const uint32_t *id = indices + 3 * t;
    float su = sqrtf(ua);
    float b0 = 1.0f - su, b1 = ub * su;
    *y = v3_add(v3_add(v3_scale(vertices[id[0]], b0), v3_scale(vertices[id[1]], b1)),
                v3_scale(vertices[id[2]], 1.0f - b0 - b1));
    *tri = t;
}

/* What next-event estimation sees of a light source from `origin`. */
typedef struct LightSourcePoint {
    Vec3 wi;    /* unit, toward the light */
    float dist; /* INFINITY: from outside the scene */
    Vec3 le;    /* radiance arriving; a delta light: the value that stands for it (intensity / r^2, irradiance) */
    float pdf;  /* solid angle, the pick included; a delta light: the pick's probability */
    bool delta;
    /* a sky with portals: the two strategies' densities of wi (no pick, no
     * share), which a learned share is chosen from; else both 0 */
    float pdf_portals, pdf_sky;
} LightSourcePoint;

/* Light source i (index among the sources) seen from `origin` with three
 * random numbers (u0 chooses a sky's strategy: its portals, with
 * probability portal_share, or its map); false: it sends nothing there. */
bool light_source_sample(const LightSet *ls, uint32_t i, Vec3 origin, float portal_share, float u0, float u1,
                         float u2, LightSourcePoint *out);

/* What a ray leaving the scene along unit d from the vertex at x brings:
 * each escaping light's radiance, weighted by the power heuristic against
 * the pdf the ray was drawn with (bsdf_pdf < 0: a specular or camera ray,
 * weight 1) and the light samples of that vertex (its portal share). */
Vec3 light_set_escaped(const LightSet *ls, Vec3 x, Vec3 d, float bsdf_pdf, float portal_share);
/* The pdf (solid angle, pick included) of next-event estimation at x
 * drawing direction d toward light source i; 0 for delta lights. */
float light_source_pdf(const LightSet *ls, uint32_t i, Vec3 x, Vec3 d, float portal_share);
/* Gives infinite light i these portals (local coordinates, copied);
 * corners c[4] each, in order round the window. False: out of memory or a
 * degenerate window. */
bool light_source_set_portals(LightSet *ls, uint32_t i, const Vec3 (*corners)[4], uint32_t count);

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
