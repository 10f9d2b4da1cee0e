/* bin/render: path traces a scene, optionally guided by an importance cache. */
#include <errno.h>
#include <inttypes.h>
#include <math.h>
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
#include "scene.h"

static const char *usage_head =
    "usage: render SCENE [--cache importance.cache] [--sampling MODE]\n"
    "              [--spp N | --time SECONDS] [--seed N] [--threads N] -o image.exr\n"
    "              [--png image.png] [--exposure STOPS] [--reference ref.exr --log curve.csv]\n"
    "              [--max-depth N] [--exponent P] [--alpha A] [--roulette learned|albedo]\n"
    "              [--size WxH] [--shard K/N] [--texture-cache MB] [--quiet]\n"
    "              [--field FIELD | --field-out FIELD [--training-passes N]] [--openpgl-mode ris|mis]\n"
    "              [--no-openings] [--edge-rays N]\n"
    "       render --describe [MODE]\n"
    "\n"
    "Path traces SCENE (.json or pbrt-v4 .pbrt; Embree 3) with next-event estimation and MIS.\n"
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
    "  --reference REF --log CSV  after every pass append seconds,spp,mse,relmse,mse8 against\n"
    "                    REF (measuring time is not counted; relmse: mean (x-r)^2/(r^2+0.01)\n"
    "                    on the image times 2^exposure; mse8: the paper's MSE of the 8-bit\n"
    "                    PNG values at --exposure)\n"
    "  --max-depth N     maximum path length (default: the scene's render.max_depth, else 8)\n"
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
    "  --field-out FIELD a mode that learns (--describe): run its training alone (its\n"
    "                    --training-passes, random numbers of their own), write what it\n"
    "                    learned to FIELD and the training passes' image to -o\n"
    "  --field FIELD     render with the field FIELD holds, frozen: nothing is learned on the\n"
    "                    clock (refused unless made for this scene, cache, size and options)\n"
    "  --training-passes N  the training's passes (default: the mode's, --describe)\n"
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
    const char *scene, *cache, *output, *png, *reference, *log, *field, *field_out;
    long training_passes;
    SgSampling sampling; /* sg_sampling_default, unless --sampling says */
    SgRoulette roulette;
    SgOpenPglMode openpgl_mode;
    long spp;
    double time;
    uint64_t seed;
    long threads, max_depth, width, height;
    long shard, shard_count;
    double exposure, exponent, alpha;
    bool has_exposure, has_exponent, has_alpha, quiet, no_openings, has_edge_rays;
    long edge_rays;
    double texture_cache_mb;
} Args;

static bool parse_args(int argc, char **argv, Args *a, SgError *err)
{
    memset(a, 0, sizeof *a);
    bool has_sampling = false;
    a->roulette = SG_ROULETTE_LEARNED;
    a->spp = -1;
    a->time = -1;
    a->threads = 0;
    a->shard_count = 1;
    for (int i = 1; i < argc; i++) {
        const char *s = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
#define NEED_VALUE()                                                 \
    do {                                                             \
        if (!v)                                                      \
            return sg_fail(err, "%s: needs a value (see --help)", s); \
        i++;                                                         \
    } while (0)
        if (!strcmp(s, "--cache")) { NEED_VALUE(); a->cache = v; }
        else if (!strcmp(s, "--sampling")) {
            NEED_VALUE();
            if (!sg_sampling_parse(v, &a->sampling)) {
                char names[256];
                mode_names(names, sizeof names);
                return sg_fail(err, "--sampling: '%s' is not %s", v, names);
            }
            has_sampling = true;
        } else if (!strcmp(s, "--roulette")) {
            NEED_VALUE();
            if (!sg_roulette_parse(v, &a->roulette))
                return sg_fail(err, "--roulette: '%s' is not learned or albedo", v);
        } else if (!strcmp(s, "--openpgl-mode")) {
            NEED_VALUE();
            if (strcmp(v, "ris") && strcmp(v, "mis"))
                return sg_fail(err, "--openpgl-mode: '%s' is not ris or mis", v);
            a->openpgl_mode = strcmp(v, "mis") ? SG_OPENPGL_RIS : SG_OPENPGL_MIS;
        }
        else if (!strcmp(s, "-o") || !strcmp(s, "--output")) { NEED_VALUE(); a->output = v; }
        else if (!strcmp(s, "--png")) { NEED_VALUE(); a->png = v; }
        else if (!strcmp(s, "--reference")) { NEED_VALUE(); a->reference = v; }
        else if (!strcmp(s, "--log")) { NEED_VALUE(); a->log = v; }
        else if (!strcmp(s, "--spp")) {
            NEED_VALUE();
            if (!sg_parse_long(v, 1, 1L << 30, &a->spp))
                return sg_fail(err, "--spp: '%s' is not a positive integer", v);
        } else if (!strcmp(s, "--time")) {
            NEED_VALUE();
            if (!sg_parse_double(v, 1e-6, 1e9, &a->time))
                return sg_fail(err, "--time: '%s' is not a positive number of seconds", v);
        } else if (!strcmp(s, "--seed")) {
            NEED_VALUE();
            char *end;
            errno = 0;
            unsigned long long x = strtoull(v, &end, 10);
            if (errno || end == v || *end || v[0] == '-')
                return sg_fail(err, "--seed: '%s' is not a non-negative integer", v);
            a->seed = x;
        } else if (!strcmp(s, "--threads")) {
            NEED_VALUE();
            if (!sg_parse_long(v, 1, 4096, &a->threads))
                return sg_fail(err, "--threads: '%s' is not a positive integer", v);
        } else if (!strcmp(s, "--max-depth")) {
            NEED_VALUE();
            if (!sg_parse_long(v, 1, 100000, &a->max_depth))
                return sg_fail(err, "--max-depth: '%s' is not a positive integer", v);
        } else if (!strcmp(s, "--exposure")) {
            NEED_VALUE();
            if (!sg_parse_double(v, -100, 100, &a->exposure))
                return sg_fail(err, "--exposure: '%s' is not a number of stops", v);
            a->has_exposure = true;
        } else if (!strcmp(s, "--exponent")) {
            NEED_VALUE();
            if (!sg_parse_double(v, 0, 1e5, &a->exponent))
                return sg_fail(err, "--exponent: '%s' is not in [0, 1e5]", v);
            a->has_exponent = true;
        } else if (!strcmp(s, "--alpha")) {
            NEED_VALUE();
            if (!sg_parse_double(v, 0, 1, &a->alpha) || a->alpha <= 0)
                return sg_fail(err, "--alpha: '%s' is not in (0, 1]", v);
            a->has_alpha = true;
        } else if (!strcmp(s, "--size")) {
            NEED_VALUE();
            char *end;
            long w = strtol(v, &end, 10);
            long h = *end == 'x' ? strtol(end + 1, &end, 10) : 0;
            if (*end || w <= 0 || h <= 0 || w > 65536 || h > 65536)
                return sg_fail(err, "--size: '%s' is not WxH", v);
            a->width = w;
            a->height = h;
        } else if (!strcmp(s, "--shard")) {
            NEED_VALUE();
            char *end;
            errno = 0;
            long k = strtol(v, &end, 10);
            long n = *end == '/' && end > v ? strtol(end + 1, &end, 10) : 0;
            if (errno || *end || v[0] == '-' || !sg_shard_valid(k, n))
                return sg_fail(err, "--shard: '%s' is not K/N with 0 <= K < N <= %d", v, SG_SHARDS_MAX);
            a->shard = k;
            a->shard_count = n;
        } else if (!strcmp(s, "--texture-cache")) {
            NEED_VALUE();
            if (!sg_parse_double(v, 1, 1048576, &a->texture_cache_mb))
                return sg_fail(err, "--texture-cache: '%s' is not a size in MB in [1, 1048576]", v);
        } else if (!strcmp(s, "--field")) {
            NEED_VALUE();
            a->field = v;
        } else if (!strcmp(s, "--field-out")) {
            NEED_VALUE();
            a->field_out = v;
        } else if (!strcmp(s, "--training-passes")) {
            NEED_VALUE();
            if (!sg_parse_long(v, 1, 1L << 20, &a->training_passes))
                return sg_fail(err, "--training-passes: '%s' is not a positive integer", v);
        } else if (!strcmp(s, "--quiet")) {
            a->quiet = true;
        } else if (!strcmp(s, "--no-openings")) {
            a->no_openings = true;
        } else if (!strcmp(s, "--edge-rays")) {
            NEED_VALUE();
            if (!sg_parse_long(v, 0, 16, &a->edge_rays))
                return sg_fail(err, "--edge-rays: '%s' is not an integer in [0, 16]", v);
            a->has_edge_rays = true;
        } else if (s[0] == '-' && s[1]) {
            return sg_fail(err, "%s: unknown option (see --help)", s);
        } else if (!a->scene) {
            a->scene = s;
        } else {
            return sg_fail(err, "%s: only one scene file, please", s);
        }
#undef NEED_VALUE
    }
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
        return sg_fail(err, "--field-out trains for --training-passes: no --spp, --time, --reference or --shard");
    if (a->training_passes && a->field)
        return sg_fail(err, "--training-passes: the field's training is done (it is for --field-out)");
    if (!has_sampling)
        a->sampling = sg_sampling_default(a->cache != NULL);
    const SgSamplingMode *mode = sg_sampling_mode(a->sampling);
    if (mode->uses_cache && !a->cache)
        return sg_fail(err, "--sampling %s needs --cache importance.cache", mode->name);
    if ((a->field || a->field_out) && !mode->learns)
        return sg_fail(err, "--sampling %s learns nothing: it has no field (--describe)", mode->name);
    return true;
}

typedef struct ErrorLog {
    SgOutputFile out;
    float *reference;
    float *image;
    size_t values;
} ErrorLog;

static void format_u64(char *buf, size_t size, uint64_t v) { snprintf(buf, size, "%" PRIu64, v); }

/* What bin/merge checks that shards agree on, as 16 hex digits each: the
 * scene (the text the loader read and the geometry it loaded), the cache
 * (its checksum, "none" where the mode reads none) and the recipe (every
 * option that shapes the image besides the shard, the spp and the time). */
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
    char recipe[4500]; /* the options and a field's path */
    int n = snprintf(recipe, sizeof recipe, "size %dx%d sampling %s seed %" PRIu64 " depth %d exponent %.9g alpha %.9g "
                     "roulette %s shards %d%s%s%s%s%s", o->width, o->height, sg_sampling_name(o->sampling), o->seed,
                     o->max_depth, o->lobe_exponent, o->alpha, sg_roulette_name(o->roulette), o->shard_count,
                     field ? " field " : "", field ? field : "",
                     o->sampling == SG_SAMPLING_OPENPGL ? " openpgl-mode " : "",
                     o->sampling == SG_SAMPLING_OPENPGL ? sg_openpgl_mode_name(o->openpgl_mode) : "",
                     o->no_openings ? " no-openings" : "");
    if (n < 0 || (size_t)n >= sizeof recipe)
        n = (int)strlen(recipe);
    snprintf(id->recipe, sizeof id->recipe, "%016" PRIx64, sg_hash_bytes(SG_HASH_INIT, recipe, (size_t)n));
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
    Args a;
    if (!parse_args(argc, argv, &a, &err)) {
        sg_error_print("render", &err);
        return 2; /* a usage error, as in every program */
    }
    const SgSamplingMode *mode = sg_sampling_mode(a.sampling);
    if (mode->available && !mode->available(&err)) { /* said before the scene is read */
        fprintf(stderr, "render: --sampling %s: %s\n", mode->name, err.message);
        return 1;
    }
    int status = 1;
    SgScene *scene = NULL;
    SgImportanceFile importance = {0};
    SgRenderer *r = NULL;
    float *image = NULL;
    ErrorLog log = {0};
    bool log_open = false;

    scene = sg_scene_load(a.scene, &err);
    if (!scene)
        goto done;
    if (!a.quiet)
        sg_scene_print_warnings(scene, "render", stderr);
    if (!scene->has_camera) {
        sg_fail(&err, "%s: no camera in the scene", a.scene);
        goto done;
    }

    SgRenderOptions o;
    sg_render_options_default(&o, scene);
    if (a.width) {
        o.width = (int)a.width;
        o.height = (int)a.height;
    }
    if (a.max_depth)
        o.max_depth = (int)a.max_depth;
    o.seed = a.seed;
    o.threads = (int)a.threads;
    if (a.has_exponent)
        o.lobe_exponent = (float)a.exponent;
    if (a.has_alpha)
        o.alpha = (float)a.alpha;
    o.sampling = a.sampling;
    o.roulette = a.roulette;
    o.openpgl_mode = a.openpgl_mode;
    o.no_openings = a.no_openings;
    if (a.has_edge_rays)
        o.edge_rays = (int)a.edge_rays;
    o.shard = (int)a.shard;
    o.shard_count = (int)a.shard_count;
    o.texture_cache_mb = a.texture_cache_mb;
    o.training_passes = (int)a.training_passes;
    if (!a.has_exponent && mode->lobe_exponent > 0.0f)
        o.lobe_exponent = mode->lobe_exponent;

    if (a.cache && mode->uses_cache) {
        if (!sg_importance_file_open(&importance, a.cache, scene, a.scene, &o.importance, &err))
            goto done;
        if (importance.dropped)
            fprintf(stderr, "render: %u of %u lights cannot reach the camera: the guide does not follow them%s\n",
                    importance.dropped, scene->light_count,
                    importance.dropped == scene->light_count ? " (so it samples the BSDF only)" : "");
    }

    int spp_total = a.spp > 0 ? (int)a.spp : scene->render.spp > 0 ? scene->render.spp : 16;
    int spp_target = sg_shard_pass_count(o.shard, o.shard_count, spp_total);
    if (spp_target < 1 && a.time <= 0) {
        sg_fail(&err, "%s: %d spp leave shard %d of %d no pass: ask for at least %d", a.scene, spp_total, o.shard,
                o.shard_count, o.shard_count);
        goto done;
    }
    double exposure = a.has_exposure ? a.exposure : scene->render.exposure;
    /* OpenImageIO for the PNG now, not after the passes: a render that
     * cannot write its image says so before it spends its time (the EXR
     * needs no library loaded) */
    if (a.png && !sg_image_io_ready(&err))
        goto done;

    r = sg_renderer_create(scene, &o, &err);
    if (!r)
        goto done;
    size_t values = (size_t)o.width * o.height * 3;
    image = malloc(values * sizeof *image);
    if (!image) {
        sg_fail(&err, "%s: out of memory for the image", a.scene);
        goto done;
    }
    if (a.reference) {
        int rw, rh;
        if (!sg_image_read(a.reference, &rw, &rh, &log.reference, &err))
            goto done;
        if (rw != o.width || rh != o.height) {
            sg_fail(&err, "%s: is %dx%d, the render is %dx%d", a.reference, rw, rh, o.width, o.height);
            goto done;
        }
        if (!sg_output_open(&log.out, a.log, &err))
            goto done;
        log_open = true;
        fprintf(log.out.file, "seconds,spp,mse,relmse,mse8\n");
    }

    SgProgress progress;
    double render_seconds = 0.0;
    if (a.field_out) { /* the training alone: its passes are the image */
        int passes = sg_renderer_train_begin(r, &err);
        if (passes < 0)
            goto done;
        sg_progress_begin(&progress, "render: training", (uint64_t)passes);
        for (int p = 0; p < passes; p++) {
            double t0 = sg_seconds();
            sg_renderer_pass(r);
            render_seconds += sg_seconds() - t0;
            sg_progress_update(&progress, (uint64_t)p + 1);
        }
        sg_renderer_train_end(r);
        sg_progress_end(&progress);
        if (!sg_renderer_write_field(r, a.field_out, &err))
            goto done;
    } else {
        if (a.field && !sg_renderer_read_field(r, a.field, &err))
            goto done;
        sg_progress_begin(&progress, "render", a.time > 0 ? 0 : (uint64_t)spp_target);
        for (;;) {
            double t0 = sg_seconds();
            sg_renderer_pass(r);
            render_seconds += sg_seconds() - t0;
            int spp = sg_renderer_spp(r);
            if (spp == 1 && sg_renderer_backface_fraction(r) > 0.9)
                fprintf(stderr,
                        "render: %s: the camera seems to be inside a solid (%.0f%% of its rays hit back faces)\n",
                        a.scene, 100.0 * sg_renderer_backface_fraction(r));
            if (log_open) {
                double mse, relmse, mse8;
                sg_renderer_image(r, image);
                sg_image_errors(image, log.reference, values, (float)exp2(exposure), &relmse, &mse8, &mse);
                fprintf(log.out.file, "%.6f,%d,%.9g,%.9g,%.9g\n", render_seconds, spp, mse, relmse, mse8);
            }
            sg_progress_update(&progress, (uint64_t)spp);
            if (a.time > 0 ? render_seconds >= a.time : spp >= spp_target)
                break;
        }
        sg_progress_end(&progress);
    }

    ShardIdentity id;
    shard_identity(scene, &o, importance.cache, a.field, &id);
    char shard_s[32], shard_count_s[32], exposure_s[32];
    snprintf(shard_s, sizeof shard_s, "%d", o.shard);
    snprintf(shard_count_s, sizeof shard_count_s, "%d", o.shard_count);
    snprintf(exposure_s, sizeof exposure_s, "%.9g", exposure);

    sg_renderer_image(r, image);
    char spp_s[32], sec_s[32], seed_s[32], nonfinite_s[32], depth_s[32], exp_s[32];
    snprintf(spp_s, sizeof spp_s, "%d", sg_renderer_spp(r));
    snprintf(sec_s, sizeof sec_s, "%.3f", render_seconds);
    format_u64(seed_s, sizeof seed_s, a.seed);
    format_u64(nonfinite_s, sizeof nonfinite_s, sg_renderer_nonfinite(r));
    snprintf(depth_s, sizeof depth_s, "%d", o.max_depth);
    snprintf(exp_s, sizeof exp_s, "%g", o.lobe_exponent);
    /* what the guide did: the share of bounces it drew, a learned field's training */
    SgRenderReport report;
    sg_renderer_report(r, &report);
    char guide_share_s[32], training_s[32], training_sec_s[32];
    snprintf(guide_share_s, sizeof guide_share_s, "%.4f", sg_renderer_lobe_share(r));
    snprintf(training_s, sizeof training_s, "%d", sg_renderer_training_passes(r));
    snprintf(training_sec_s, sizeof training_sec_s, "%.3f", sg_renderer_training_seconds(r));
    double branches = sg_renderer_branches_per_path(r);
    char roulette[80], branches_s[32], edge_rays_s[32];
    snprintf(branches_s, sizeof branches_s, "%.3f", branches);
    snprintf(edge_rays_s, sizeof edge_rays_s, "%.4f", sg_renderer_edge_rays_per_sample(r));
    if (report.roulette == SG_ROULETTE_LEARNED) /* it also splits paths */
        snprintf(roulette, sizeof roulette, "%s (%.2f branches split off a path)", sg_roulette_name(report.roulette),
                 branches);
    else
        snprintf(roulette, sizeof roulette, "%s", sg_roulette_name(report.roulette));
    SgImageAttribute attrs[] = {
        {SG_ATTR_SPP, spp_s},
        {SG_ATTR_SECONDS, sec_s},
        {SG_ATTR_SAMPLING, mode->name},
        {SG_ATTR_SEED, seed_s},
        {"sg:max_depth", depth_s},
        {"sg:lobe_exponent", exp_s},
        {"sg:alpha", report.alpha},
        {"sg:roulette", sg_roulette_name(report.roulette)},
        {"sg:branches_per_path", branches_s},
        {"sg:edge_rays_per_sample", edge_rays_s},
        {SG_ATTR_NONFINITE_SAMPLES, nonfinite_s},
        {SG_ATTR_GUIDE_SHARE, guide_share_s},
        {"sg:training_passes", training_s},
        {"sg:training_seconds", training_sec_s},
        {"sg:clamping", "none"},
        {"sg:scene", a.scene},
        {"sg:cache", importance.cache ? a.cache : ""},
        {"sg:field", a.field ? a.field : a.field_out ? a.field_out : ""},
        {"sg:training", a.field_out ? "yes" : "no"},
        {SG_ATTR_EXPOSURE, exposure_s},
        /* for bin/merge */
        {SG_ATTR_SHARDS, shard_s},
        {SG_ATTR_SHARD_COUNT, shard_count_s},
        {SG_ATTR_SCENE_HASH, id.scene},
        {SG_ATTR_CACHE_HASH, id.cache},
        {SG_ATTR_RECIPE, id.recipe},
    };
    /* The EXR last: it is make's target, so a run cut short before it
     * (a PNG or the curve written, then killed) is still run again. */
    if (a.png && !sg_image_write_png(a.png, o.width, o.height, image, exposure, &err))
        goto done;
    if (log_open) {
        log_open = false;
        if (!sg_output_commit(&log.out, &err))
            goto done;
    }
    if (!sg_image_write_exr(a.output, o.width, o.height, image, attrs,
                            (int)(sizeof attrs / sizeof attrs[0]), &err)) {
        if (a.field_out) /* no output of a failed run */
            remove(a.field_out);
        goto done;
    }
    if (!a.quiet) {
        char shard_line[64] = "";
        if (o.shard_count > 1)
            snprintf(shard_line, sizeof shard_line, ", shard %d of %d", o.shard, o.shard_count);
        size_t texture_images = 0, texture_cache = sg_renderer_texture_cache(r, &texture_images);
        if (texture_images)
            fprintf(stderr, "render: textures: %.1f MB cached of %.1f MB of images\n", texture_cache / 1048576.0,
                    texture_images / 1048576.0);
        double paths = (double)o.width * o.height * sg_renderer_spp(r);
        char openings[64] = "";
        if (report.openings)
            snprintf(openings, sizeof openings, ", sky sampled through %u opening%s", report.openings,
                     report.openings == 1 ? "" : "s");
        char edges[80] = "";
        double edge_rays = sg_renderer_edge_rays_per_sample(r);
        if (edge_rays > 0.0)
            snprintf(edges, sizeof edges, ", %.3g edge rays a sample", edge_rays);
        fprintf(stderr,
                "render: %dx%d, %d spp, %.2f s, %.3f Msamples/s, %.3f Mrays/s, sampling %s%s%s%s, roulette %s, seed "
                "%s, %s NaN/inf samples%s\n",
                o.width, o.height, sg_renderer_spp(r), render_seconds, paths / render_seconds * 1e-6,
                (double)sg_renderer_rays(r) / render_seconds * 1e-6, mode->name, report.guide, openings, edges,
                roulette, seed_s, nonfinite_s, shard_line);
    }
    status = 0;

done:
    if (status != 0)
        sg_error_print("render", &err);
    if (log_open)
        sg_output_abort(&log.out);
    free(log.reference);
    free(image);
    sg_renderer_free(r);
    sg_importance_file_close(&importance);
    if (scene)
        sg_scene_free(scene);
    return status;
}
