/* The path tracer (Embree 3): an SgScene in, progressive passes out.
 * Every pass adds one sample to every pixel; a pixel's random numbers come
 * from a stream keyed by (seed, pixel, pass), so the image is the same for
 * any thread count. */
#ifndef SG_RENDERER_H
#define SG_RENDERER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "error.h"
#include "importance_cache.h"
#include "scene.h"
#include "shard_format.h" /* SG_SHARDS_MAX, the pass rule of SgRenderOptions.shard */

#ifdef __cplusplus
extern "C" {
#endif

/* The sampling modes, one line each: its name in the enum, on the command
 * line, and the guide that implements it (render/guides/guide_FILE.c, FILE
 * the mode's name; it holds everything else about the mode: SgSamplingMode
 * below). A new mode is one file there and one line here. */
#define SG_SAMPLING_MODES(X)        \
    X(BSDF, bsdf, bsdf)             \
    X(SKELETON, skeleton, skeleton) \
    X(GUIDED, guided, guided)       \
    X(OPENPGL, openpgl, openpgl)

typedef enum SgSampling {
#define SG_SAMPLING_ENUM(id, name, file) SG_SAMPLING_##id,
    SG_SAMPLING_MODES(SG_SAMPLING_ENUM)
#undef SG_SAMPLING_ENUM
    SG_SAMPLING_COUNT
} SgSampling;

/* What a sampling mode is, before any renderer is made: what bin/render's
 * command line, `render --describe` (the farm script) and the benchmarks
 * ask of it instead of knowing the modes themselves. */
typedef struct SgSamplingMode {
    const char *name;
    const char *help;          /* a line or two for --help, lines after the first indented */
    bool uses_cache;           /* it needs the importance cache (--cache) */
    bool default_with_cache;   /* what render samples by, --sampling not given, with a cache */
    bool default_without_cache;/* ... and without one */
    float lobe_exponent;       /* its default --exponent (0: it has no lobe) */
    bool learns;               /* it learns from its own paths while it renders */
    bool learned_roulette;     /* it can run the learned roulette (SgRoulette) */
    int training_passes;       /* its training's passes by default (learns; render --field-out) */
    /* learning within a render, it stops when a further stretch would no
     * longer pay (sg_renderer_set_budget), not after training_passes */
    bool stops_learning_itself;
    bool biased;
    /* NULL: always available; else false, saying why, where this build
     * lacks what it needs */
    bool (*available)(SgError *err);
} SgSamplingMode;

const SgSamplingMode *sg_sampling_mode(SgSampling s);
const char *sg_sampling_name(SgSampling s);
bool sg_sampling_parse(const char *name, SgSampling *s);
/* The mode render samples by when --sampling is not given. */
SgSampling sg_sampling_default(bool has_cache);

/* Where the importance points come from: the importance cache in
 * bin/render (render/guides/importance_file.h), an analytic stand-in in
 * tests. Returns false when it has no importance point
 * for world position p and light `light` (p outside the medium...). */
typedef bool (*SgImportanceFn)(void *ctx, const double p[3], uint32_t light, double point[3]);

typedef struct SgImportanceSource {
    SgImportanceFn importance_point; /* NULL: none (only modes without a lobe run) */
    void *ctx;
    /* Optional: the importance cache behind importance_point. The renderer
     * then reads it directly in its own coordinates (the same answers, a
     * third of the work per bounce); importance_point stays the fallback. */
    const SgImportanceCache *cache;
    /* Probability weight of following each light (scene light order);
     * NULL: the lights' power. A zero weight never follows that light. */
    const double *light_weight;
    /* The points are asked for at the hit point moved this far (world units) along
     * the normal facing the incoming ray: a cache's voxel size, so that the
     * query lands in the free space on the point's own side of the wall. */
    double query_offset;
} SgImportanceSource;

#define SG_ALPHA_LEARNED (-1.0f)

/* How paths are cut short (unbiased either way: a surviving path is
 * divided by its survival probability). */
typedef enum SgRoulette {
    /* guided with a learned alpha: survival by what the path may still
     * bring (its throughput times the learner's regional radiance) against
     * the noise its pixel has anyway (efficiency-aware roulette, Rath et
     * al. 2022): paths that head into the dark die, paths toward the light
     * live on. Elsewhere, and where the learner knows too little yet, as
     * SG_ROULETTE_ALBEDO. */
    SG_ROULETTE_LEARNED,
    /* after the second bounce, survival = the product of the albedos so
     * far (pbrt's rule), whatever the light ahead */
    SG_ROULETTE_ALBEDO,
} SgRoulette;

const char *sg_roulette_name(SgRoulette r);
bool sg_roulette_parse(const char *name, SgRoulette *r);

/* openpgl: how the guide's distribution and the BSDF share a bounce, as
 * Cycles' guiding_directional_sampling_type: RIS (Cycles' default; zero,
 * what options start as) resamples a BSDF and a guide candidate, glossy
 * lobes too; MIS, Cycles' older mode, mixes them by one-sample MIS at
 * diffuse lobes only. */
typedef enum SgOpenPglMode { SG_OPENPGL_RIS, SG_OPENPGL_MIS } SgOpenPglMode;

static inline const char *sg_openpgl_mode_name(SgOpenPglMode m) { return m == SG_OPENPGL_MIS ? "mis" : "ris"; }

typedef struct SgRenderOptions {
    int width, height;
    int max_depth;        /* maximum path length in segments from the camera */
    SgSampling sampling;
    uint64_t seed;
    int threads;          /* <= 0: every core */
    float lobe_exponent;  /* p_skel of the cosine-power lobe toward the importance point */
    /* guided: probability of BSDF sampling in the mixture, in (0, 1]; or
     * SG_ALPHA_LEARNED: chosen per region of the scene from the second
     * moments of the bounces traced so far (render/mixture_learning.h) */
    float alpha;
    SgRoulette roulette;
    SgImportanceSource importance;
    /* A shard of a render split into shard_count (render farm): this
     * renderer's pass p is pass shard + p * shard_count of the whole
     * render, whose random numbers and pixel positions it takes, so that
     * the shards' passes are disjoint and together are the whole render's.
     * What a guide learns stays within its shard. Default 0 of 1. */
    int shard, shard_count;
    double texture_cache_mb; /* texels held in memory at most; 0: TEXTURE_CACHE_MB_DEFAULT (render/textures.h) */
    /* modes that learn: the passes their training takes (sg_renderer_train,
     * and rendering on the clock without a field); 0: the mode's default */
    int training_passes;
    SgOpenPglMode openpgl_mode; /* openpgl: RIS or MIS (default RIS, Cycles') */
    /* a sky is sampled over its whole sphere, not through the openings the
     * precompute found (render/openings.h); a hand-drawn portal still counts */
    bool no_openings;
    /* at a pixel where the light the camera sees directly varies (a light's
     * or the sky's silhouette), the most extra camera rays a sample takes
     * to look for it (render/edge_rays.h); default EDGE_RAYS_MAX (16), 0: none */
    int edge_rays;
} SgRenderOptions;

/* Defaults: image size and depth from the scene (320x240 and
 * SG_MAX_DEPTH_DEFAULT when not given), bsdf sampling, seed 0, every core,
 * lobe exponent 16, alpha learned, learned roulette, shard 0 of 1, 16 edge
 * rays. */
void sg_render_options_default(SgRenderOptions *o, const SgScene *scene);

/* The options that shape what a render draws and learns, in words: max
 * depth, lobe exponent, alpha, roulette, openpgl's mode, the openings (not
 * the image size, mode, seed, shard, threads or passes: a field serves any
 * view). The one summary of them: a field file keeps it, refusing a render
 * made otherwise, and a shard's recipe hashes it with the image size,
 * bin/merge refusing shards made otherwise. */
void sg_render_options_summary(const SgRenderOptions *o, char *buf, size_t size);

typedef struct SgRenderer SgRenderer;

/* Fails on a scene without triangles or camera, a bad option, a guide
 * missing for a guided mode, openpgl in a build without Open PGL, or an
 * Embree error. */
SgRenderer *sg_renderer_create(const SgScene *scene, const SgRenderOptions *o, SgError *err);
void sg_renderer_free(SgRenderer *r);

/* One more sample in every pixel. */
void sg_renderer_pass(SgRenderer *r);
int sg_renderer_spp(const SgRenderer *r);
/* Mean radiance per pixel, linear RGB, width * height * 3 floats. */
void sg_renderer_image(const SgRenderer *r, float *rgb);
/* The samples of the last pass alone (for variance estimates in tests). */
const float *sg_renderer_last_pass(const SgRenderer *r);
/* What the passes so far did, in numbers (since the last freeze). */
typedef struct SgRenderStats {
    int spp;                     /* the passes */
    uint64_t rays;               /* rays traced: camera, bounce, shadow and edge rays */
    uint64_t nonfinite;          /* samples that came out NaN or infinite (counted as zero, never in the image) */
    /* the share of the first pass's camera rays that hit the back of a
     * surface: near 1 means the camera is inside a solid */
    double backface_fraction;
    /* guided with a learned alpha: the share of the learner's bounces that
     * fall where the mixture now uses the lobe (alpha < 1); -1 otherwise */
    double guided_fraction;
    /* the share of the diffuse and glossy bounces whose direction the
     * guide's lobe drew (the rest: the BSDF's sampler); 0 before any */
    double lobe_share;
    /* a learned mode: the passes whose paths trained the field (the first
     * SgRenderOptions.training_passes; openpgl's default is
     * SG_OPENPGL_TRAINING_PASSES) and the seconds its updates took; 0 in
     * other modes */
    int training_passes;
    int training_updates;        /* openpgl: the field's updates from those passes */
    double training_seconds;
    double branches_per_path;    /* branches the learned roulette split off, per camera path */
    /* extra camera rays a sample took, on average, where the light seen
     * directly varies (SgRenderOptions.edge_rays) */
    double edge_rays_per_sample;
    /* bytes of texels the texture cache holds, and the images' full size
     * (0 and 0 without textures) */
    size_t texture_cache_bytes, texture_image_bytes;
} SgRenderStats;

/* Openpgl's training by default: Cycles' 128 updates, the first from 1
 * pass, the second from 2, the rest from 4. */
#define SG_OPENPGL_TRAINING_PASSES (1 + 2 + 4 * 126)

void sg_renderer_stats(const SgRenderer *r, SgRenderStats *stats);

/* A learned mode's training as a step of its own (render --field-out,
 * --field), so that a render's clock counts no learning and the shards of
 * a farm share one field. Training renders the mode's training passes
 * (with random numbers of their own: the render that follows draws others)
 * into the film; freeze then stops the guide's learning for good and
 * starts the film, the pass count and the counters again, the learned
 * roulette keeping what it knows of the pixels' noise. A field file holds
 * what freeze keeps, and what it was made for: reading one into a renderer
 * of the same scene, cache and options (before its first pass) gives the
 * renderer frozen with it, which renders the same image, bit for bit, as
 * the renderer that wrote it after freeze. Fails on a mode that does not
 * learn, and (read) on a field made for something else, naming the file. */
bool sg_renderer_train(SgRenderer *r, SgError *err);
/* The same in steps, for a caller that shows progress: begin returns the
 * training's passes (-1: the mode learns nothing), each sg_renderer_pass
 * then trains, until end. */
int sg_renderer_train_begin(SgRenderer *r, SgError *err);
void sg_renderer_train_end(SgRenderer *r);
void sg_renderer_freeze(SgRenderer *r);
bool sg_renderer_write_field(const SgRenderer *r, const char *path, SgError *err);
bool sg_renderer_read_field(SgRenderer *r, const char *path, SgError *err);

/* Learning within the render (a learned mode, no field read, no training
 * apart): the guide learns from the first pass and the image keeps every
 * pass, each stretch of learning weighted by its estimated variance
 * (render/film.h). Learning stops after the mode's training passes, or, for
 * a mode that judges it (SgSamplingMode.stops_learning_itself, unless
 * --training-passes is given), once a further stretch would not pay within
 * the render's budget, set here: its passes in all, or its seconds (0: not
 * known). sg_renderer_learning tells whether the guide still learns (a
 * caller writes the field when it stops); sg_renderer_learned_passes, the
 * passes it learned from when it stopped (0: it has not). */
void sg_renderer_set_budget(SgRenderer *r, int passes, double seconds);
bool sg_renderer_learning(const SgRenderer *r);
/* Stops the learning within the render now (the field then holds what it
 * learned); the passes so far stay in the image. */
void sg_renderer_stop_learning(SgRenderer *r);
int sg_renderer_learned_passes(const SgRenderer *r);

/* What the render did, in words, for bin/render's summary line and EXR. */
typedef struct SgRenderReport {
    SgRoulette roulette; /* the roulette that ran: learned only where the guide learns what bounces bring */
    char alpha[96];      /* the mixture's weight: the options' number, or how it was learned */
    char guide[320];     /* the guide's part of the summary line, "" or ", ..." */
    uint32_t openings;   /* windows the precompute found, through which the sky is sampled */
} SgRenderReport;
void sg_renderer_report(const SgRenderer *r, SgRenderReport *report);

#ifdef __cplusplus
}
#endif
#endif
