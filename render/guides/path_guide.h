/* The guides: how the path tracer draws a bounce at a diffuse or glossy
 * vertex. The integrator (render/integrator.c) does not know which guide
 * it runs; each sampling mode is one file implementing these calls:
 *   guide_bsdf.c           bsdf: the material's own sampler
 *   guide_skeleton.c       skeleton: the paper's rule (section 3.4), biased
 *   guide_guided.c         guided: BSDF and a lobe toward the skeleton's
 *                          importance point, mixed per region as learned
 *   guide_openpgl.c        openpgl: the peer, Open PGL's learned field
 * A new guide is a new file defining its PathGuideKind (what the mode is,
 * and its `create`) and one line in renderer.h's SG_SAMPLING_MODES.
 *
 * The calls, in the order a pass makes them:
 *   pass_begin      before the pass: whether paths record events for the
 *                   guide, whether a side job runs beside the tiles
 *   path_learns     per camera path: does it report what its bounces
 *                   brought back (learn)
 *   vertex_begin    at a diffuse or glossy vertex, before the light
 *                   sample's shadow ray (a cache query can load meanwhile)
 *   vertex_end      after it, told whether the vertex is directly lit
 *   survival        optional: its roulette's verdict on the bounce
 *   pdf, sample     the bounce's density (also for next-event estimation's
 *                   MIS weight) and a direction drawn from it
 *   learn           when the path's branch has ended: what a bounce of
 *                   the vertex brought back
 *   record_*        on recording passes, the path's events as Cycles
 *                   hands them to Open PGL (guiding_record_*)
 *   pass_end        after the pass: update what was learned
 * Every call may be NULL where the guide has nothing to do, except pdf and
 * sample. Unbiased guides keep each pass's distribution fixed while the
 * pass runs; deterministic ones depend only on (seed, pixel, pass). */
#ifndef SG_RENDER_PATH_GUIDE_H
#define SG_RENDER_PATH_GUIDE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "../bsdf.h"
#include "error.h"
#include "../field_file.h"
#include "../geometry.h"
#include "../lights.h"
#include "../material.h"
#include "../renderer.h"
#include "rng.h"
#include "../sampling.h"
#include "vecmath.h"

typedef struct PathGuide PathGuide;
typedef struct GuideSegment GuideSegment; /* a recorded vertex, the guide's own */

/* What a guide is made from. */
typedef struct PathGuideSetup {
    const SgRenderOptions *opt;
    int training_passes;    /* a learned mode's training: the options', else the mode's default */
    const Geometry *geo;    /* triangles, bounds, local frame */
    const LightSet *lights;
    int threads;            /* worker threads: thread indices are in [0, threads) */
    uint32_t tiles;         /* image tiles: learn() gets a tile index in [0, tiles) */
    const char *path;       /* the scene, for errors */
} PathGuideSetup;

/* A diffuse or glossy vertex, as a guide sees it. */
typedef struct GuideHit {
    Vec3 p;               /* the point, local coordinates */
    Vec3 n;               /* the shading normal, on the incoming ray's side */
    uint32_t normal_bin;  /* sg_mixture_normal_bin(n) */
    const Material *m;
    int thread;
    bool may_learn;       /* the path learns and can keep one more record */
} GuideHit;

/* A vertex's light sample of a sky with portals, as a learner of the
 * portal share needs it: what the sample brought to the pixel (luminance,
 * the path's throughput and the pick's probability included, no strategy
 * density: 0 where the shadow ray was blocked) and the two strategies'
 * densities of its direction, with the share it was drawn with. */
typedef struct SkyLightSample {
    bool taken;
    float contribution;
    float pdf_portals, pdf_sky, share;
} SkyLightSample;

/* The bounce's distribution at a vertex: the BSDF's part is the
 * integrator's, the rest the guide's (`state`, its own layout). Plain data:
 * the integrator copies it where the path splits and where it keeps a
 * record for learn(). */
#define GUIDE_VERTEX_STATE 128
typedef struct GuideVertex {
    Bsdf bsdf;         /* the material's BSDF; bsdf.lobe.n is the shading normal */
    /* set by vertex_begin */
    bool learn;        /* learn() hears what this vertex's bounce brought back */
    float rms;         /* the root mean square of what a bounce from here
                        * brings back per unit throughput (the learned
                        * roulette's input); < 0 unknown */
    float portal_share; /* of a sky's light samples here, the share drawn
                         * through its portals; < 0: PORTAL_SHARE */
    /* set by the integrator before vertex_begin: the least BSDF share a
     * learned mixture may take here, so that the path's weight stays within
     * WEIGHT_RATIO_MAX of what BSDF sampling would give it (integrator.c);
     * a guide may lower it where its mixture is the user's choice */
    float alpha_floor;
    /* set by the integrator where the vertex learns */
    SkyLightSample sky;
    /* set by sample */
    bool by_guide;     /* the guide, not the BSDF's sampler, drew the direction */
    float pdf_bsdf;    /* > 0: the BSDF sampler's density of the direction drawn,
                        * where a mixture drew it; <= 0 (as the integrator
                        * starts it): the BSDF's sampler alone drew it */
    float mis_pdf;     /* >= 0: the density the bounce's MIS against the lights
                        * weighs by, where it is not the one drawn from (RIS:
                        * pdf() of the direction); < 0 (as the integrator
                        * starts it): sample's pdf */
    _Alignas(16) unsigned char state[GUIDE_VERTEX_STATE];
} GuideVertex;

/* What a recorded bounce brought back, once its branch ended. */
typedef struct BounceOutcome {
    float radiance;    /* all that came after the bounce (luminance, per unit
                        * throughput of the bounce) */
    float weight;      /* the bounce's weight in its pixel: the squared
                        * luminance of its throughput */
    bool bounced;      /* a direction above the surface was drawn */
    bool cut;          /* the roulette cut the path here, before the bounce */
    float distance;    /* how far the bounce's ray went to the next surface (INFINITY: none) */
} BounceOutcome;

/* What a guide tells of the coming pass. */
typedef struct GuidePass {
    bool training;  /* set by the renderer: every path learns (a training pass apart, or the learning within a render) */
    bool record;    /* paths call record_* */
    bool side_job;  /* side_job runs once, beside the pass's tiles */
} GuidePass;

/* For the render line and the EXR. */
typedef struct GuideStats {
    double guided_fraction;  /* of the learner's bounces, where it uses the lobe; -1 none */
    double learned_axis_fraction; /* of those, where the lobe is around the learned axis */
    int training_passes;     /* passes whose paths trained a learned field */
    int training_updates;    /* openpgl: the field's updates from them */
    double training_seconds; /* the updates' time */
    double lobe_share;       /* the integrator's count: bounces the guide drew (by_guide) */
} GuideStats;

typedef struct PathGuideOps {
    const char *name;
    /* vertex_end needs `lit` even where the light sample is behind the
     * surface: the integrator then traces that shadow ray too */
    bool lit_below_horizon;
    void (*destroy)(PathGuide *g);

    void (*pass_begin)(PathGuide *g, int pass, uint64_t pass_key, GuidePass *plan);
    void (*side_job)(PathGuide *g);
    void (*pass_end)(PathGuide *g, int pass);
    bool (*path_learns)(const PathGuide *g, size_t pixel);

    void (*vertex_begin)(PathGuide *g, const GuideHit *h, SgRng *rng, GuideVertex *v);
    void (*vertex_end)(PathGuide *g, const GuideHit *h, bool lit, SgRng *rng, GuideVertex *v);
    /* w a unit direction, cos_n its cosine with bsdf.lobe.n (> 0) */
    float (*pdf)(const GuideVertex *v, Vec3 w, float cos_n);
    /* a direction from u[0..2] and its density pdf() (any side of the
     * surface: the integrator ends the path below it); sets by_guide */
    Vec3 (*sample)(GuideVertex *v, const float u[3], float *pdf);
    void (*learn)(PathGuide *g, int tile, const GuideVertex *v, const BounceOutcome *o);
    /* Optional, the guide's own roulette (Open PGL's guided roulette) where
     * the learned one does not run: at each diffuse or glossy vertex, after
     * its light sample, the bounce's survival probability in (0, 1] for a
     * path of throughput beta, or < 0 where the guide has none (the albedo
     * roulette decides). `estimate`: the path's own slot (zero at its start,
     * copied where it splits) for what the guide expects the path to bring
     * its pixel, set from its first vertices. Used from vertex ROULETTE_DEPTH
     * (render/roulette.h) on. */
    float (*survival)(const GuideVertex *v, Vec3 beta, Vec3 *estimate);

    /* recording passes: every vertex of the path in order, then its end */
    GuideSegment *(*record_vertex)(PathGuide *g, int thread, Vec3 p, Vec3 wo, Vec3 n);
    void (*record_emission)(GuideSegment *s, Vec3 le, float mis_weight);
    void (*record_direct)(GuideSegment *s, Vec3 c); /* per unit throughput, MIS applied */
    void (*record_bounce)(GuideSegment *s, Vec3 wi, float pdf, Vec3 weight, bool delta, float eta,
                          float roughness);
    void (*record_survival)(GuideSegment *s, float probability);
    void (*record_path_end)(PathGuide *g, int thread);

    void (*stats)(const PathGuide *g, GuideStats *s);
    /* its part of the render's summary line and its alpha (the renderer
     * sets the roulette, alpha as the options' number and an empty line) */
    void (*describe)(const PathGuide *g, const GuideStats *s, SgRenderReport *report);

    /* Modes that learn (SgSamplingMode.learns): what they learned, as
     * bytes for a field file, and learning stopped for good: after
     * training (freeze), or with what a field file holds (load, before the
     * first pass; false, saying why, on bytes it cannot take). A frozen
     * guide's distributions depend only on what it holds, so that a
     * loaded field renders as the one it was stored from. */
    bool (*field_store)(const PathGuide *g, FieldBytes *out);
    bool (*field_load)(PathGuide *g, FieldReader *in, SgError *err);
    void (*freeze)(PathGuide *g);
} PathGuideOps;

/* Every guide's struct begins with this. */
struct PathGuide {
    const PathGuideOps *ops;
    /* GuideVertex.rms is known at some vertices: the learned roulette can run */
    bool estimates_radiance;
};

typedef PathGuide *(*PathGuideCreate)(const PathGuideSetup *setup, SgError *err);

/* A sampling mode: what it is, and the guide that implements it. The
 * renderer checks what the mode says it needs (uses_cache, available)
 * before `create` runs. */
typedef struct PathGuideKind {
    SgSamplingMode mode;
    PathGuideCreate create;
} PathGuideKind;

#define PATH_GUIDE_KIND_DECLARE(id, name, file) extern const PathGuideKind guide_##file##_kind;
SG_SAMPLING_MODES(PATH_GUIDE_KIND_DECLARE)
#undef PATH_GUIDE_KIND_DECLARE

/* sg_renderer_create with the guide `create` makes, whatever o->sampling
 * names: how a test tries a guide that no mode has yet. */
SgRenderer *sg_renderer_create_with_guide(const SgScene *scene, const SgRenderOptions *o, PathGuideCreate create,
                                          SgError *err);

/* A guide's struct of `size` bytes (its PathGuide first), zeroed, with its
 * ops; NULL, err saying so, when out of memory. */
void *path_guide_alloc(size_t size, const PathGuideOps *ops, const PathGuideSetup *setup, SgError *err);

/* The guide of a sampling mode, once what the mode needs is checked. */
PathGuide *path_guide_create(SgSampling mode, const PathGuideSetup *setup, SgError *err);
void path_guide_free(PathGuide *g);
void path_guide_stats(const PathGuide *g, GuideStats *s);

/* The BSDF's own sampler, the fallback of every guide. */
static inline float guide_bsdf_pdf(const GuideVertex *v, Vec3 w, float cos_n)
{
    (void)cos_n;
    return bsdf_pdf(&v->bsdf, w);
}
static inline Vec3 guide_bsdf_sample(GuideVertex *v, const float u[3], float *pdf)
{
    Vec3 w = bsdf_sample(&v->bsdf, u[0], u[1], u[2]);
    v->by_guide = false;
    *pdf = bsdf_pdf(&v->bsdf, w);
    return w;
}

#endif
