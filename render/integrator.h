/* The path integrator: one camera path through the scene, with next-event
 * estimation and MIS at every diffuse or glossy vertex, its bounces drawn
 * by the guide (render/guides/path_guide.h), cut short or split by the
 * roulette (render/roulette.h). */
#ifndef SG_RENDER_INTEGRATOR_H
#define SG_RENDER_INTEGRATOR_H

#include <stdbool.h>
#include <stdint.h>

#include "geometry.h"
#include "guides/path_guide.h"
#include "lights.h"
#include "material.h"
#include "rng.h"
#include "textures.h"
#include "vecmath.h"

/* What paths are traced through, as the renderer holds it. */
typedef struct Integrator {
    const Geometry *geo;
    const Material *materials;
    TextureSet *textures; /* NULL: no material is textured */
    const LightSet *lights;
    PathGuide *guide;
    int max_depth;        /* path length in segments from the camera */
} Integrator;

/* Counts a tile's paths add up (the renderer sums the tiles'). */
typedef struct PathStats {
    uint64_t rays;
    uint64_t backface;     /* camera rays of the first pass that hit a back face */
    uint64_t branches;     /* made by splitting, beyond the paths themselves */
    uint64_t bounces;      /* diffuse and glossy bounces drawn */
    uint64_t lobe_bounces; /* of which the guide drew the direction */
    uint64_t views;        /* extra camera rays for the light seen directly (render/edge_rays.h) */
} PathStats;

/* What one camera path needs besides the integrator. */
typedef struct PathCtx {
    SgRng *rng;
    PathStats *st;
    int thread;
    bool first_pass;
    bool record;           /* the guide records this pass's paths (record_*) */
    bool may_split;        /* the learned roulette may split (from SPLIT_FROM_PASS on) */
    int learn_tile;        /* >= 0: the path learns, its records go to this tile */
    float pixel_deviation; /* the pixel's noise for the learned roulette; 0: albedo roulette */
} PathCtx;

/* The radiance one camera path from o along d brings back; `seen` gets the
 * emission the camera ray itself hit (which the roulette does not act on). */
Vec3 integrator_trace(const Integrator *it, Vec3 o, Vec3 d, const PathCtx *pc, Vec3 *seen);

/* What a camera ray from o along d sees directly, integrator_trace's `seen`
 * alone: one ray, nothing shaded (counted in st->rays and st->views). */
Vec3 integrator_seen(const Integrator *it, Vec3 o, Vec3 d, int thread, PathStats *st);

#endif
