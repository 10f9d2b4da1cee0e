/* bin/render: path traces a scene, optionally guided by an importance cache. */
#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "guides/importance_file.h"
#include "cli.h"
#include "color.h"
#include "error.h"
#include "error_metrics.h"
#include "hash.h"
#include "image_io.h"
#include "output_file.h"
#include "progress.h"
#include "renderer.h"
#include "scene_load.h"

#define SG_STRING_(x) #x
#define SG_STRING(x) SG_STRING_(x)

static const char *usage_head =
    "usage: render SCENE [--cache importance.cache] [--sampling MODE]\n"
    "              [--spp N | --time SECONDS] [--seed N] [--threads N] -o image.exr\n"
    "              [--png image.png] [--exposure STOPS] [--reference ref.exr --log curve.csv]\n"
    "              [--max-depth N] [--exponent P] [--alpha A] [--roulette learned|albedo]\n"
    "              [--size WxH] [--shard K/N] [--texture-cache MB] [--quiet]\n"
    "              [--field FIELD | --field-out FIELD | --save-field FIELD] [--training-passes N]\n"
    "              [--openpgl-mode ris|mis]\n"
    "              [--no-openings] [--edge-rays N]\n"
    "       render --describe [MODE]\n"
    "\n"
    "Path traces SCENE (.json, pbrt-v4 .pbrt or Mitsuba .xml; Embree 3) with next-event estimation and MIS.\n"
    "  --cache FILE      importance cache from bin/importance for this scene's geometry\n"
    "  --sampling MODE   how bounces are drawn:\n";

static const char *usage_tail =
    "  --spp N           samples per pixel (default: the scene's render.spp, else 16)\n"
    "  --time SECONDS    render progressive passes until this much time has passed\n"
    "  --seed N          random seed (default 0); the image depends only on the seed\n"
    "  --threads N       worker threads (default: every core)\n"
    "  -o FILE.exr       linear float RGB with spp, seconds, sampling, seed as metadata\n"
    "  --png FILE.png    8-bit sRGB image of the render times 2^exposure\n"
    "  --exposure STOPS  PNG exposure (default: the scene's render.exposure, else 0)\n"
    "  --reference REF --log CSV  after every pass append " SG_ERROR_LOG_HEADER " against\n"
    "                    REF (measuring time is not counted; relmse: mean (x-r)^2/(r^2+0.01)\n"
    "                    on the image times 2^exposure; mse8: the paper's MSE of the 8-bit\n"
    "                    PNG values at --exposure)\n"
    "  --max-depth N     maximum path length (default: the scene's render.max_depth, else " SG_STRING(SG_MAX_DEPTH_DEFAULT) ")\n"
    "  --exponent P      cosine-power exponent of the lobe (default: the mode's, above)\n"
    "  --alpha A         guided: probability of BSDF sampling in the mixture, (0, 1]; default:\n"
    "                    learned per region of the scene while rendering (docs/render.md)\n"
    "  --roulette R      how paths are cut short: learned (default, where the mode learns what\n"
    "                    bounces bring back: guided with a learned alpha; by expected\n"
    "                    contribution against the pixel's, docs/render.md) or albedo\n"
    "                    (survival = product of albedos after 2 bounces, as bsdf); openpgl:\n"
    "                    learned is Open PGL's guided roulette where it is built with radiance caches\n"
    "  --openpgl-mode M  openpgl: ris (default, Cycles' default: BSDF and guide candidates\n"
    "                    resampled, glossy lobes guided above roughness 0.05) or mis (Cycles'\n"
    "                    older one-sample mixture, diffuse lobes only)\n"
    "  --no-openings     a sky is sampled over its whole sphere, not through the windows the\n"
    "                    precompute found in the cache (a hand-drawn portal still counts)\n"
    "  --edge-rays N     where the light the camera sees directly varies within a pixel (a\n"
    "                    light's or the sky's silhouette), a sample takes up to N more camera\n"
    "                    rays that look for it alone, as many as pay for themselves (0-16,\n"
    "                    default 16; 0: none)\n"
    "  --size WxH        image size (default: the scene's image size, else 320x240)\n"
    "  --shard K/N       render only shard K (0 <= K < N) of the render split into N: its\n"
    "                    passes K, K+N, K+2N... of --spp in all (with --time: for that long);\n"
    "                    bin/merge makes the whole image from the N shards' EXRs\n"
    "  --texture-cache MB  texels held in memory at most (default 256): image textures\n"
    "                    load tile by tile as paths look them up\n"
    "  --quiet           no summary line\n"
    "  (a mode that learns, --describe, learns within the render from its first pass: the\n"
    "   image keeps every pass, each stretch of learning weighted by its variance; guided\n"
    "   stops learning when a further stretch no longer pays within --spp or --time)\n"
    "  --save-field FIELD  write what the render learned to FIELD when its learning stops,\n"
    "                    for the next render of the scene (--field)\n"
    "  --field-out FIELD a mode that learns: run its training alone (its --training-passes,\n"
    "                    random numbers of their own), write what it learned to FIELD and the\n"
    "                    training passes' image to -o (a farm's shards share it)\n"
    "  --field FIELD     render with the field FIELD holds, frozen: nothing is learned on the\n"
    "                    clock (refused unless made for this scene, cache, size and options)\n"
    "  --training-passes N  the passes a mode learns from (default: the mode's, --describe;\n"
    "                    guided within a render: until learning stops paying)\n"
    "  --describe [MODE] what each sampling mode (or MODE) is, one JSON object per line:\n"
    "                    uses_cache, its defaults, whether it learns, is biased, is built\n";

/* --help: the modes from their own descriptions (path_guide.h). */
static void print_usage(void)
{
    fputs(usage_head, stdout);
    for (int i = 0; i < SG_SAMPLING_COUNT; i++) {
        const SgSamplingMode *m = sg_sampling_mode((SgSampling)i);
        printf("                    %s: ", m->name);
        for (const char *c = m->help; *c; c++) /* continuation lines under the text */
            *c == '\n' ? printf("\n                      ") : putchar(*c);
        if (m->lobe_exponent > 0.0f)
            printf(" [exponent %g]", m->lobe_exponent);
        putchar('\n');
    }
    fputs(usage_tail, stdout);
}

/* --describe: what a mode is, for scripts (the farm script asks whether
 * a mode needs the precompute). */
static void describe_mode(const SgSamplingMode *m)
{
    SgError e = {0};
    bool available = !m->available || m->available(&e);
    printf("{\"name\": \"%s\", \"uses_cache\": %s, \"default_with_cache\": %s, \"default_without_cache\": %s, "
           "\"lobe_exponent\": %g, \"learns\": %s, \"training_passes\": %d, \"learned_roulette\": %s, "
           "\"biased\": %s, \"available\": %s}\n",
           m->name, m->uses_cache ? "true" : "false", m->default_with_cache ? "true" : "false",
           m->default_without_cache ? "true" : "false", m->lobe_exponent, m->learns ? "true" : "false",
           m->training_passes, m->learned_roulette ? "true" : "false", m->biased ? "true" : "false", available ? "true" : "false");
}

static int describe(int argc, char **argv)
{
    if (argc > 3) {
        fprintf(stderr, "render: --describe takes at most one mode\n");
        return 2;
    }
    SgSampling only;
    if (argc == 3 && !sg_sampling_parse(argv[2], &only)) {
        fprintf(stderr, "render: --describe: '%s' is not a sampling mode\n", argv[2]);
        return 2;
    }
    for (int i = 0; i < SG_SAMPLING_COUNT; i++)
        if (argc < 3 || (SgSampling)i == only)
            describe_mode(sg_sampling_mode((SgSampling)i));
    return 0;
}

/* "a, b or c": the modes' names, for an error. */
static void mode_names(char *buf, size_t size)
{
    size_t used = 0;
    buf[0] = '\0';
    for (int i = 0; i < SG_SAMPLING_COUNT && used < size; i++)
        used += (size_t)snprintf(buf + used, size - used, "%s%s", i == 0 ? "" : i + 1 < SG_SAMPLING_COUNT ? ", " : " or ",
                                 sg_sampling_name((SgSampling)i));
}

typedef struct Args {
    const char *scene, *cache, *output, *png, *reference, *log, *field, *field_out, *save_field;
    long training_passes;
    bool has_sampling;
    SgSampling sampling; /* sg_sampling_default, unless --sampling says */
    SgRoulette roulette;
    SgOpenPglMode openpgl_mode;
    long spp;            /* -1: not given */
    double time;         /* -1: not given */
    uint64_t seed;
    long threads, max_depth, width, height;
    long shard, shard_count;
    double exposure, exponent, alpha; /* NAN: not given */
    bool quiet, no_openings;
    long edge_rays;      /* -1: not given */
    double texture_cache_mb;
} Args;

/* ---- options -------------------------------------------------------------
 * Each parser takes option s with its value v (NULL: none follows) if it is
 * one of its own: it returns the arguments it took (1 or 2), 0 where s is
 * not its own, -1 on a bad value (err says). */

static int needs_value(const char *s, SgError *err)
{
    sg_fail(err, "%s: needs a value (see --help)", s);
    return -1;
}

static int parse_flag(const char *s, Args *a)
{
    bool *flag = !strcmp(s, "--quiet") ? &a->quiet : !strcmp(s, "--no-openings") ? &a->no_openings : NULL;
    if (!flag)
        return 0;
    *flag = true;
    return 1;
}

static int parse_path(const char *s, const char *v, Args *a, SgError *err)
{
    const char **path = !strcmp(s, "--cache")                        ? &a->cache
                        : !strcmp(s, "-o") || !strcmp(s, "--output") ? &a->output
                        : !strcmp(s, "--png")                        ? &a->png
                        : !strcmp(s, "--reference")                  ? &a->reference
                        : !strcmp(s, "--log")                        ? &a->log
                        : !strcmp(s, "--field")                      ? &a->field
                        : !strcmp(s, "--field-out")                  ? &a->field_out
                        : !strcmp(s, "--save-field")                 ? &a->save_field
                                                                     : NULL;
    if (!path)
        return 0;
    if (!v)
        return needs_value(s, err);
    *path = v;
    return 2;
}

/* The options that are a number in a range, and what else they must be. */
typedef struct NumberOption {
    const char *name;
    size_t at;           /* offsetof(Args, ...): a long, or a double where `real` */
    bool real;
    double min, max;
    bool above_min;      /* the range is open at min */
    const char *is_not;  /* "--spp: '%s' is not ..." */
} NumberOption;

static const NumberOption number_options[] = {
    {"--spp", offsetof(Args, spp), false, 1, 1L << 30, false, "a positive integer"},
    {"--time", offsetof(Args, time), true, 1e-6, 1e9, false, "a positive number of seconds"},
    {"--threads", offsetof(Args, threads), false, 1, 4096, false, "a positive integer"},
    {"--max-depth", offsetof(Args, max_depth), false, 1, 100000, false, "a positive integer"},
    {"--exposure", offsetof(Args, exposure), true, -100, 100, false, "a number of stops"},
    {"--exponent", offsetof(Args, exponent), true, 0, 1e5, false, "in [0, 1e5]"},
    {"--alpha", offsetof(Args, alpha), true, 0, 1, true, "in (0, 1]"},
    {"--texture-cache", offsetof(Args, texture_cache_mb), true, 1, 1048576, false, "a size in MB in [1, 1048576]"},
    {"--training-passes", offsetof(Args, training_passes), false, 1, 1L << 20, false, "a positive integer"},
    {"--edge-rays", offsetof(Args, edge_rays), false, 0, 16, false, "an integer in [0, 16]"},
};

static int parse_number(const char *s, const char *v, Args *a, SgError *err)
{
    for (size_t k = 0; k < sizeof number_options / sizeof number_options[0]; k++) {
        const NumberOption *n = &number_options[k];
        if (strcmp(s, n->name))
            continue;
        if (!v)
            return needs_value(s, err);
        bool ok;
        if (n->real) {
            double *x = (double *)((char *)a + n->at);
            ok = sg_parse_double(v, n->min, n->max, x) && !(n->above_min && *x <= n->min);
        } else {
            ok = sg_parse_long(v, (long)n->min, (long)n->max, (long *)((char *)a + n->at));
        }
        if (!ok)
            sg_fail(err, "%s: '%s' is not %s", s, v, n->is_not);
        return ok ? 2 : -1;
    }
    return 0;
}

/* Which of three options s is, 0 to 2; -1: none of them. */
static int one_of(const char *s, const char *first, const char *second, const char *third)
{
    return !strcmp(s, first) ? 0 : !strcmp(s, second) ? 1 : !strcmp(s, third) ? 2 : -1;
}

/* --sampling, --roulette, --openpgl-mode: a name of a few. */
static int parse_choice(const char *s, const char *v, Args *a, SgError *err)
{
    int which = one_of(s, "--sampling", "--roulette", "--openpgl-mode");
    if (which < 0 || !v)
        return which < 0 ? 0 : needs_value(s, err);
    if (which == 0) {
        if (!sg_sampling_parse(v, &a->sampling)) {
            char names[256];
            mode_names(names, sizeof names);
            return sg_fail(err, "--sampling: '%s' is not %s", v, names), -1;
        }
        a->has_sampling = true;
    } else if (which == 1) {
        if (!sg_roulette_parse(v, &a->roulette))
            return sg_fail(err, "--roulette: '%s' is not learned or albedo", v), -1;
    } else {
        if (strcmp(v, "ris") && strcmp(v, "mis"))
            return sg_fail(err, "--openpgl-mode: '%s' is not ris or mis", v), -1;
        a->openpgl_mode = strcmp(v, "mis") ? SG_OPENPGL_RIS : SG_OPENPGL_MIS;
    }
    return 2;
}

/* --seed N, --size WxH, --shard K/N: numbers of their own shape. */
static int parse_shaped(const char *s, const char *v, Args *a, SgError *err)
{
    int which = one_of(s, "--seed", "--size", "--shard");
    if (which < 0 || !v)
        return which < 0 ? 0 : needs_value(s, err);
    char *end;
    errno = 0;
    if (which == 0) {
        unsigned long long x = strtoull(v, &end, 10);
        if (errno || end == v || *end || v[0] == '-')
            return sg_fail(err, "--seed: '%s' is not a non-negative integer", v), -1;
        a->seed = x;
    } else if (which == 1) {
        long w = strtol(v, &end, 10);
        long h = *end == 'x' ? strtol(end + 1, &end, 10) : 0;
        if (*end || w <= 0 || h <= 0 || w > 65536 || h > 65536)
            return sg_fail(err, "--size: '%s' is not WxH", v), -1;
        a->width = w;
        a->height = h;
    } else {
        long k = strtol(v, &end, 10);
        long n = *end == '/' && end > v ? strtol(end + 1, &end, 10) : 0;
        if (errno || *end || v[0] == '-' || !sg_shard_valid(k, n))
            return sg_fail(err, "--shard: '%s' is not K/N with 0 <= K < N <= %d", v, SG_SHARDS_MAX), -1;
        a->shard = k;
        a->shard_count = n;
    }
    return 2;
}

/* What the options must be together. */
static bool check_args(Args *a, SgError *err)
{
    if (!a->scene)
        return sg_fail(err, "no scene file given (see --help)");
    if (!a->output)
        return sg_fail(err, "no output given: -o image.exr (see --help)");
    if (a->spp > 0 && a->time > 0)
        return sg_fail(err, "--spp and --time: give one or the other");
    if (!a->reference != !a->log)
        return sg_fail(err, "--reference and --log go together");
    if (a->field && a->field_out)
        return sg_fail(err, "--field and --field-out: a render uses a field or trains one, not both");
    if (a->field_out && (a->spp > 0 || a->time > 0 || a->reference || a->shard_count > 1))
        return sg_fail(err, "--field-out trains for --training-passes: no --spp, --time, --reference or --shard "
                            "(--save-field keeps what a render learns)");
    if (a->save_field && (a->field || a->field_out))
        return sg_fail(err, "--save-field: a render that reads or trains a field learns nothing more to save");
    if (a->save_field && a->shard_count > 1)
        return sg_fail(err, "--save-field: a shard learns from its own passes alone: train the field apart (--field-out)");
    if (a->training_passes && a->field)
        return sg_fail(err, "--training-passes: the field's training is done (it is for --field-out)");
    if (!a->has_sampling)
        a->sampling = sg_sampling_default(a->cache != NULL);
    const SgSamplingMode *mode = sg_sampling_mode(a->sampling);
    if (mode->uses_cache && !a->cache)
        return sg_fail(err, "--sampling %s needs --cache importance.cache", mode->name);
    if ((a->field || a->field_out || a->save_field) && !mode->learns)
        return sg_fail(err, "--sampling %s learns nothing: it has no field (--describe)", mode->name);
    return true;
}

static bool parse_args(int argc, char **argv, Args *a, SgError *err)
{
    *a = (Args){.roulette = SG_ROULETTE_LEARNED, .spp = -1, .time = -1, .shard_count = 1, .exposure = NAN,
                .exponent = NAN, .alpha = NAN, .edge_rays = -1};
    for (int i = 1; i < argc; i++) {
        const char *s = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        int took = parse_flag(s, a);
        if (!took)
            took = parse_path(s, v, a, err);
        if (!took)
            took = parse_number(s, v, a, err);
        if (!took)
            took = parse_choice(s, v, a, err);
        if (!took)
            took = parse_shaped(s, v, a, err);
        if (took < 0)
            return false;
        if (took > 0)
            i += took - 1;
        else if (s[0] == '-' && s[1])
            return sg_fail(err, "%s: unknown option (see --help)", s);
        else if (!a->scene)
            a->scene = s;
        else
            return sg_fail(err, "%s: only one scene file, please", s);
    }
    return check_args(a, err);
}

/* The render options: the scene's, then the mode's, then the command line's. */
static void render_options(const Args *a, const SgScene *scene, const SgSamplingMode *mode, SgRenderOptions *o)
{
    sg_render_options_default(o, scene);
    if (a->width) {
        o->width = (int)a->width;
        o->height = (int)a->height;
    }
    if (a->max_depth)
        o->max_depth = (int)a->max_depth;
    o->seed = a->seed;
    o->threads = (int)a->threads;
    if (!isnan(a->exponent))
        o->lobe_exponent = (float)a->exponent;
    else if (mode->lobe_exponent > 0.0f)
        o->lobe_exponent = mode->lobe_exponent;
    if (!isnan(a->alpha))
        o->alpha = (float)a->alpha;
    o->sampling = a->sampling;
    o->roulette = a->roulette;
    o->openpgl_mode = a->openpgl_mode;
    o->no_openings = a->no_openings;
    if (a->edge_rays >= 0)
        o->edge_rays = (int)a->edge_rays;
    o->shard = (int)a->shard;
    o->shard_count = (int)a->shard_count;
    o->texture_cache_mb = a->texture_cache_mb;
    o->training_passes = (int)a->training_passes;
}

/* ---- the run -------------------------------------------------------------- */

/* What one run holds, from the scene to the image; freed by run_close. */
typedef struct Run {
    Args a;
    const SgSamplingMode *mode;
    SgScene *scene;
    SgImportanceFile importance;
    SgRenderOptions o;
    SgRenderer *r;
    int spp_target;  /* this shard's passes (without --time) */
    double exposure; /* the PNG's, and relmse's and mse8's */
    float *image;    /* width * height * 3 */
    size_t values;
    float *reference; /* --reference: the image the error log measures against */
    SgOutputFile log;
    bool log_open;
    double seconds;  /* the passes' time, measuring the error not counted */
    double started;  /* sg_seconds() when the program started */
    double setup;    /* seconds from the start to the first pass: the scene, the cache, the renderer */
} Run;

static bool open_cache(Run *run, SgError *err)
{
    const Args *a = &run->a;
    if (!a->cache || !run->mode->uses_cache)
        return true;
    SgImportanceFile *f = &run->importance;
    if (!sg_importance_file_open(f, a->cache, run->scene, a->scene, &run->o.importance, err))
        return false;
    if (f->dropped)
        fprintf(stderr, "render: %u of %u lights cannot reach the camera: the guide does not follow them%s\n",
                f->dropped, run->scene->light_count,
                f->dropped == run->scene->light_count ? " (so it samples the BSDF only)" : "");
    return true;
}

static bool open_error_log(Run *run, SgError *err)
{
    const Args *a = &run->a;
    int rw, rh;
    if (!sg_image_read(a->reference, &rw, &rh, &run->reference, err))
        return false;
    if (rw != run->o.width || rh != run->o.height)
        return sg_fail(err, "%s: is %dx%d, the render is %dx%d", a->reference, rw, rh, run->o.width, run->o.height);
    if (!sg_output_open(&run->log, a->log, err))
        return false;
    run->log_open = true;
    fprintf(run->log.file, SG_ERROR_LOG_HEADER "\n");
    return true;
}

/* The scene, the cache, the renderer, the image and the error log. */
static bool run_open(Run *run, SgError *err)
{
    const Args *a = &run->a;
    if (!(run->scene = sg_scene_load(a->scene, err)))
        return false;
    if (!a->quiet)
        sg_scene_print_warnings(run->scene, "render", stderr);
    if (!run->scene->has_camera)
        return sg_fail(err, "%s: no camera in the scene", a->scene);
    SgRenderOptions *o = &run->o;
    render_options(a, run->scene, run->mode, o);
    if (!open_cache(run, err))
        return false;
    int spp_total = a->spp > 0 ? (int)a->spp : run->scene->render.spp > 0 ? run->scene->render.spp : 16;
    run->spp_target = sg_shard_pass_count(o->shard, o->shard_count, spp_total);
    if (run->spp_target < 1 && a->time <= 0)
        return sg_fail(err, "%s: %d spp leave shard %d of %d no pass: ask for at least %d", a->scene, spp_total,
                       o->shard, o->shard_count, o->shard_count);
    run->exposure = !isnan(a->exposure) ? a->exposure : run->scene->render.exposure;
    /* OpenImageIO for the PNG now, not after the passes: a render that
     * cannot write its image says so before it spends its time (the EXR
     * needs no library loaded) */
    if (a->png && !sg_image_io_ready(err))
        return false;
    if (!(run->r = sg_renderer_create(run->scene, o, err)))
        return false;
    run->values = (size_t)o->width * o->height * 3;
    if (!(run->image = malloc(run->values * sizeof *run->image)))
        return sg_fail(err, "%s: out of memory for the image", a->scene);
    return !a->reference || open_error_log(run, err);
}

static void run_close(Run *run)
{
    if (run->log_open)
        sg_output_abort(&run->log);
    free(run->reference);
    free(run->image);
    sg_renderer_free(run->r);
    sg_importance_file_close(&run->importance);
    if (run->scene)
        sg_scene_free(run->scene);
}

/* --field-out: the training alone, its passes the image. */
static bool run_training(Run *run, SgError *err)
{
    int passes = sg_renderer_train_begin(run->r, err);
    if (passes < 0)
        return false;
    SgProgress progress;
    sg_progress_begin(&progress, "render: training", (uint64_t)passes);
    for (int p = 0; p < passes; p++) {
        double t0 = sg_seconds();
        sg_renderer_pass(run->r);
        run->seconds += sg_seconds() - t0;
        sg_progress_update(&progress, (uint64_t)p + 1);
    }
    sg_renderer_train_end(run->r);
    sg_progress_end(&progress);
    return sg_renderer_write_field(run->r, run->a.field_out, err);
}

/* After a pass: the camera inside a solid said, the error logged. */
static void after_pass(Run *run, int spp)
{
    if (spp == 1) {
        SgRenderStats stats;
        sg_renderer_stats(run->r, &stats);
        if (stats.backface_fraction > 0.9)
            fprintf(stderr, "render: %s: the camera seems to be inside a solid (%.0f%% of its rays hit back faces)\n",
                    run->a.scene, 100.0 * stats.backface_fraction);
    }
    if (run->log_open) {
        double mse, relmse, mse8;
        sg_renderer_image(run->r, run->image);
        float scale = (float)exp2(run->exposure);
        sg_image_errors(run->image, run->reference, run->values, scale, &relmse, &mse8, &mse);
        double trimmed = sg_image_relmse_trimmed(run->image, run->reference, run->values / 3, scale);
        fprintf(run->log.file, "%.6f,%d,%.9g,%.9g,%.9g,%.9g\n", run->seconds, spp, mse, relmse, mse8, trimmed);
    }
}

/* The passes, to --spp or for --time (with --field: frozen from it; a
 * mode that learns, without: learning within them, and with --save-field
 * the field written when the learning stops). */
static bool run_passes(Run *run, SgError *err)
{
    const Args *a = &run->a;
    if (a->field && !sg_renderer_read_field(run->r, a->field, err))
        return false;
    sg_renderer_set_budget(run->r, a->time > 0 ? 0 : run->spp_target, a->time > 0 ? a->time : 0.0);
    run->setup = sg_seconds() - run->started;
    bool field_written = false;
    SgProgress progress;
    sg_progress_begin(&progress, "render", a->time > 0 ? 0 : (uint64_t)run->spp_target);
    for (;;) {
        double t0 = sg_seconds();
        sg_renderer_pass(run->r);
        run->seconds += sg_seconds() - t0;
        int spp = sg_renderer_spp(run->r);
        after_pass(run, spp);
        sg_progress_update(&progress, (uint64_t)spp);
        bool done = a->time > 0 ? run->seconds >= a->time : spp >= run->spp_target;
        if (a->save_field && !field_written && (done || !sg_renderer_learning(run->r))) {
            sg_renderer_stop_learning(run->r);
            if (!sg_renderer_write_field(run->r, a->save_field, err))
                return false;
            field_written = true;
        }
        if (done)
            break;
    }
    sg_progress_end(&progress);
    return true;
}

/* ---- the outputs ---------------------------------------------------------- */

/* What bin/merge checks that shards agree on, as 16 hex digits each: the
 * scene (the text the loader read and the geometry it loaded), the cache
 * (its checksum, "none" where the mode reads none) and the recipe (the
 * options' summary, sg_render_options_summary, and what else shapes the
 * image besides the shard, the spp and the time). */
typedef struct ShardIdentity {
    char scene[17], cache[17], recipe[17];
} ShardIdentity;

static void shard_identity(const SgScene *scene, const SgRenderOptions *o, const SgImportanceCache *cache,
                           const char *field, ShardIdentity *id)
{
    uint64_t h = sg_hash_bytes(scene->source_hash, &scene->geometry_hash, sizeof scene->geometry_hash);
    snprintf(id->scene, sizeof id->scene, "%016" PRIx64, h);
    if (cache)
        snprintf(id->cache, sizeof id->cache, "%016" PRIx64, sg_cache_checksum(cache));
    else
        snprintf(id->cache, sizeof id->cache, "none");
    char summary[256], recipe[4500]; /* the options and a field's path */
    sg_render_options_summary(o, summary, sizeof summary);
    int n = snprintf(recipe, sizeof recipe, "%dx%d, %s, sampling %s, seed %" PRIu64 ", shards %d%s%s", o->width,
                     o->height, summary, sg_sampling_name(o->sampling), o->seed, o->shard_count,
                     field ? ", field " : "", field ? field : "");
    if (n < 0 || (size_t)n >= sizeof recipe)
        n = (int)strlen(recipe);
    snprintf(id->recipe, sizeof id->recipe, "%016" PRIx64, sg_hash_bytes(SG_HASH_INIT, recipe, (size_t)n));
}

/* The EXR's attributes, as text, and the strings they point into. */
typedef struct Attributes {
    char spp[32], seconds[32], seed[32], nonfinite[32], depth[32], exponent[32], guide_share[32], training[32],
        training_seconds[32], branches[32], edge_rays[32], shard[32], shard_count[32], exposure[32], learned[32],
        setup[32];
    ShardIdentity id;
    SgImageAttribute list[27];
    int count;
} Attributes;

static void add_attribute(Attributes *at, const char *name, const char *value)
{
    at->list[at->count++] = (SgImageAttribute){name, value};
}

static void make_attributes(const Run *run, const SgRenderStats *st, const SgRenderReport *report, Attributes *at)
{
    const Args *a = &run->a;
    const SgRenderOptions *o = &run->o;
    shard_identity(run->scene, o, run->importance.cache, a->field, &at->id);
    snprintf(at->spp, sizeof at->spp, "%d", st->spp);
    snprintf(at->seconds, sizeof at->seconds, "%.3f", run->seconds);
    snprintf(at->seed, sizeof at->seed, "%" PRIu64, a->seed);
    snprintf(at->nonfinite, sizeof at->nonfinite, "%" PRIu64, st->nonfinite);
    snprintf(at->depth, sizeof at->depth, "%d", o->max_depth);
    snprintf(at->exponent, sizeof at->exponent, "%g", o->lobe_exponent);
    /* what the guide did: the share of bounces it drew, a learned field's training */
    snprintf(at->guide_share, sizeof at->guide_share, "%.4f", st->lobe_share);
    snprintf(at->training, sizeof at->training, "%d", st->training_passes);
    snprintf(at->training_seconds, sizeof at->training_seconds, "%.3f", st->training_seconds);
    snprintf(at->learned, sizeof at->learned, "%d", sg_renderer_learned_passes(run->r));
    snprintf(at->branches, sizeof at->branches, "%.3f", st->branches_per_path);
    snprintf(at->edge_rays, sizeof at->edge_rays, "%.4f", st->edge_rays_per_sample);
    snprintf(at->shard, sizeof at->shard, "%d", o->shard);
    snprintf(at->shard_count, sizeof at->shard_count, "%d", o->shard_count);
    snprintf(at->exposure, sizeof at->exposure, "%.9g", run->exposure);
    at->count = 0;
    add_attribute(at, SG_ATTR_SPP, at->spp);
    add_attribute(at, SG_ATTR_SECONDS, at->seconds);
    snprintf(at->setup, sizeof at->setup, "%.3f", run->setup);
    add_attribute(at, SG_ATTR_SETUP_SECONDS, at->setup);
    add_attribute(at, SG_ATTR_SAMPLING, run->mode->name);
    add_attribute(at, SG_ATTR_SEED, at->seed);
    add_attribute(at, SG_ATTR_MAX_DEPTH, at->depth);
    add_attribute(at, SG_ATTR_LOBE_EXPONENT, at->exponent);
    add_attribute(at, SG_ATTR_ALPHA, report->alpha);
    add_attribute(at, SG_ATTR_ROULETTE, sg_roulette_name(report->roulette));
    add_attribute(at, SG_ATTR_BRANCHES_PER_PATH, at->branches);
    add_attribute(at, SG_ATTR_EDGE_RAYS_PER_SAMPLE, at->edge_rays);
    add_attribute(at, SG_ATTR_NONFINITE_SAMPLES, at->nonfinite);
    add_attribute(at, SG_ATTR_GUIDE_SHARE, at->guide_share);
    add_attribute(at, SG_ATTR_TRAINING_PASSES, at->training);
    add_attribute(at, SG_ATTR_TRAINING_SECONDS, at->training_seconds);
    add_attribute(at, SG_ATTR_CLAMPING, "none");
    add_attribute(at, SG_ATTR_SCENE, a->scene);
    add_attribute(at, SG_ATTR_CACHE, run->importance.cache ? a->cache : "");
    add_attribute(at, SG_ATTR_FIELD, a->field ? a->field : a->field_out ? a->field_out : a->save_field ? a->save_field : "");
    add_attribute(at, SG_ATTR_TRAINING, a->field_out ? "yes" : "no");
    add_attribute(at, SG_ATTR_LEARNED_PASSES, at->learned);
    add_attribute(at, SG_ATTR_EXPOSURE, at->exposure);
    /* for bin/merge */
    add_attribute(at, SG_ATTR_SHARDS, at->shard);
    add_attribute(at, SG_ATTR_SHARD_COUNT, at->shard_count);
    add_attribute(at, SG_ATTR_SCENE_HASH, at->id.scene);
    add_attribute(at, SG_ATTR_CACHE_HASH, at->id.cache);
    add_attribute(at, SG_ATTR_RECIPE, at->id.recipe);
}

/* The summary line (and the textures' line) on stderr. */
static void print_summary(const Run *run, const SgRenderStats *st, const SgRenderReport *report, const char *seed,
                          const char *nonfinite)
{
    const SgRenderOptions *o = &run->o;
    char shard_line[64] = "";
    if (o->shard_count > 1)
        snprintf(shard_line, sizeof shard_line, ", shard %d of %d", o->shard, o->shard_count);
    if (st->texture_image_bytes)
        fprintf(stderr, "render: textures: %.1f MB cached of %.1f MB of images\n", st->texture_cache_bytes / 1048576.0,
                st->texture_image_bytes / 1048576.0);
    double paths = (double)o->width * o->height * st->spp;
    char openings[64] = "";
    if (report->openings)
        snprintf(openings, sizeof openings, ", sky sampled through %u opening%s", report->openings,
                 report->openings == 1 ? "" : "s");
    char edges[80] = "";
    if (st->edge_rays_per_sample > 0.0)
        snprintf(edges, sizeof edges, ", %.3g edge rays a sample", st->edge_rays_per_sample);
    char learned[80] = "";
    int learned_passes = sg_renderer_learned_passes(run->r);
    if (learned_passes > 0)
        snprintf(learned, sizeof learned, ", learned within its first %d passes", learned_passes);
    else if (sg_renderer_learning(run->r))
        snprintf(learned, sizeof learned, ", learning to the end");
    char roulette[80];
    if (report->roulette == SG_ROULETTE_LEARNED) /* it also splits paths */
        snprintf(roulette, sizeof roulette, "%s (%.2f branches split off a path)", sg_roulette_name(report->roulette),
                 st->branches_per_path);
    else
        snprintf(roulette, sizeof roulette, "%s", sg_roulette_name(report->roulette));
    fprintf(stderr,
            "render: %dx%d, %d spp, %.2f s, %.3f Msamples/s, %.3f Mrays/s, sampling %s%s%s%s%s, roulette %s, seed "
            "%s, %s NaN/inf samples%s\n",
            o->width, o->height, st->spp, run->seconds, paths / run->seconds * 1e-6,
            (double)st->rays / run->seconds * 1e-6, run->mode->name, report->guide, learned, openings, edges, roulette,
            seed, nonfinite, shard_line);
}

/* The PNG, the error log and the EXR, then the summary. */
static bool run_outputs(Run *run, SgError *err)
{
    const Args *a = &run->a;
    const SgRenderOptions *o = &run->o;
    SgRenderStats stats;
    sg_renderer_stats(run->r, &stats);
    SgRenderReport report;
    sg_renderer_report(run->r, &report);
    sg_renderer_image(run->r, run->image);
    Attributes at;
    make_attributes(run, &stats, &report, &at);
    /* The EXR last: it is make's target, so a run cut short before it
     * (a PNG or the curve written, then killed) is still run again. */
    if (a->png && !sg_image_write_png(a->png, o->width, o->height, run->image, run->exposure, err))
        return false;
    if (run->log_open) {
        run->log_open = false;
        if (!sg_output_commit(&run->log, err))
            return false;
    }
    if (!sg_image_write_exr(a->output, o->width, o->height, run->image, at.list, at.count, err)) {
        if (a->field_out || a->save_field) /* no output of a failed run */
            remove(a->field_out ? a->field_out : a->save_field);
        return false;
    }
    if (!a->quiet)
        print_summary(run, &stats, &report, at.seed, at.nonfinite);
    return true;
}

int main(int argc, char **argv)
{
    for (int i = 1; i < argc; i++)
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            print_usage();
            return 0;
        }
    if (argc > 1 && !strcmp(argv[1], "--describe"))
        return describe(argc, argv);
    SgError err = {0};
    Run run = {.started = sg_seconds()};
    if (!parse_args(argc, argv, &run.a, &err)) {
        sg_error_print("render", &err);
        return 2; /* a usage error, as in every program */
    }
    run.mode = sg_sampling_mode(run.a.sampling);
    if (run.mode->available && !run.mode->available(&err)) { /* said before the scene is read */
        fprintf(stderr, "render: --sampling %s: %s\n", run.mode->name, err.message);
        return 1;
    }
    bool ok = run_open(&run, &err) && (run.a.field_out ? run_training(&run, &err) : run_passes(&run, &err)) &&
              run_outputs(&run, &err);
    if (!ok)
        sg_error_print("render", &err);
    run_close(&run);
    return ok ? 0 : 1;
}
