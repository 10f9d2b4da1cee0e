/* The number work of bench/sections/60-convergence.sh (the paper's table 2):
 *
 *   convergence size SCENE PIXELS
 *       prints "WxH EXPOSURE": the scene's image scaled to about PIXELS
 *       pixels with its aspect kept, and its PNG exposure in stops.
 *   convergence reference HALF_A.exr HALF_B.exr -o REF.exr --exposure E
 *       REF = (A + B) / 2; prints "relmse X mse8 Y", the reference's own
 *       error estimated from the halves' difference.
 *   convergence analyze NAME RUNDIR SEEDS TABLEDIR [options]
 *       reads RUNDIR/MODE-SEED.csv for the modes bsdf, skeleton, guided and
 *       seeds 1..SEEDS, writes each mode's mean curve RUNDIR/MODE.mean.dat
 *       (seconds spp relmse mse8) and RUNDIR/levels.txt, and appends
 *       markdown rows to TABLEDIR/{table2-relmse,table2-mse8,equal-time,
 *       reference}.md and one line to TABLEDIR/headline.tsv.
 *       options: --size WxH --ref-relmse X --ref-mse8 Y --ref-spp N
 *                --ref-seconds S --ref-state TEXT
 *   convergence strip REF.exr --exposure E -o STRIP.png [--crop X,Y,W,H]
 *                     [--scale K] IMAGE.exr...
 *       the same crop of every IMAGE and then of REF, side by side, exposed
 *       like the scene's PNG; without --crop, the square (half the image's
 *       shorter side) where the first IMAGE's relative error is largest.
 *       Prints "crop X,Y,W,H".
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define SG_CONVERGENCE_MATH_IMPLEMENTATION
#include "convergence_math.h"

#include "image_io.h"
#include "output_file.h"
#include "scene.h"

#define MODE_COUNT 3
static const char *const mode_names[MODE_COUNT] = {"bsdf", "skeleton", "guided"};
/* points of a mean curve, log-spaced in time */
#define MEAN_POINTS 120

static const char usage[] =
    "usage: convergence size SCENE PIXELS\n"
    "       convergence reference HALF_A.exr HALF_B.exr -o REF.exr --exposure STOPS\n"
    "       convergence analyze NAME RUNDIR SEEDS TABLEDIR [--size WxH] [--ref-relmse X]\n"
    "                   [--ref-mse8 Y] [--ref-spp N] [--ref-seconds S] [--ref-state TEXT]\n"
    "       convergence strip REF.exr --exposure STOPS -o STRIP.png [--crop X,Y,W,H] [--scale K]\n"
    "                   IMAGE.exr...\n"
    "The arithmetic of bench/sections/60-convergence.sh (see the comment at the top of\n"
    "bench/convergence.c).\n";

static bool parse_double(const char *s, double *v)
{
    char *end;
    *v = strtod(s, &end);
    return end != s && *end == '\0' && isfinite(*v);
}

/* ---- size ---------------------------------------------------------------- */

static int cmd_size(int argc, char **argv, SgError *err)
{
    double pixels;
    if (argc != 4 || !parse_double(argv[3], &pixels) || pixels < 64)
        return sg_fail(err, "size: want SCENE PIXELS (PIXELS >= 64)"), 1;
    SgScene *scene = sg_scene_load(argv[2], err);
    if (!scene)
        return 1;
    int w = scene->camera.width > 0 ? scene->camera.width : 320;
    int h = scene->camera.height > 0 ? scene->camera.height : 240;
    double k = sqrt(pixels / ((double)w * h));
    int sw = (int)lround(w * k), sh = (int)lround(h * k);
    printf("%dx%d %g\n", sw < 1 ? 1 : sw, sh < 1 ? 1 : sh, scene->render.exposure);
    sg_scene_free(scene);
    return 0;
}

/* ---- reference ----------------------------------------------------------- */

static int cmd_reference(int argc, char **argv, SgError *err)
{
    const char *halves[2] = {NULL, NULL}, *out = NULL;
    double exposure = 0;
    int nh = 0;
    for (int i = 2; i < argc; i++) {
        if (!strcmp(argv[i], "-o") && i + 1 < argc)
            out = argv[++i];
        else if (!strcmp(argv[i], "--exposure") && i + 1 < argc) {
            if (!parse_double(argv[++i], &exposure))
                return sg_fail(err, "reference: --exposure %s: not a number", argv[i]), 1;
        } else if (argv[i][0] != '-' && nh < 2)
            halves[nh++] = argv[i];
        else
            return sg_fail(err, "reference: unexpected argument %s", argv[i]), 1;
    }
    if (nh != 2 || !out)
        return sg_fail(err, "reference: want HALF_A.exr HALF_B.exr -o REF.exr"), 1;
    int w[2], h[2];
    float *rgb[2] = {NULL, NULL};
    int status = 1;
    if (!sg_image_read(halves[0], &w[0], &h[0], &rgb[0], err) ||
        !sg_image_read(halves[1], &w[1], &h[1], &rgb[1], err))
        goto done;
    if (w[0] != w[1] || h[0] != h[1]) {
        sg_fail(err, "%s: is %dx%d, %s is %dx%d", halves[1], w[1], h[1], halves[0], w[0], h[0]);
        goto done;
    }
    size_t n = (size_t)w[0] * h[0] * 3;
    double relmse, mse8;
    /* the mean goes into the first half's buffer */
    sg_reference_from_halves(rgb[0], rgb[1], n, (float)exp2(exposure), rgb[0], &relmse, &mse8);
    SgImageAttribute attrs[] = {{"sg:reference", "mean of two independent bsdf halves"}};
    if (!sg_image_write_exr(out, w[0], h[0], rgb[0], attrs, 1, err))
        goto done;
    printf("relmse %.6g mse8 %.6g\n", relmse, mse8);
    status = 0;
done:
    free(rgb[0]);
    free(rgb[1]);
    return status;
}

/* ---- analyze ------------------------------------------------------------- */

typedef struct ModeResult {
    bool present;
    int seeds;             /* curves read */
    SgCurve mean;
    double us_per_sample;  /* wall time per sample over all threads, mean of seeds */
    double final_spp;      /* mean of seeds */
} ModeResult;

static bool load_mode(const char *dir, const char *mode, int seeds, ModeResult *res, SgError *err)
{
    memset(res, 0, sizeof *res);
    SgCurve curves[64];
    int n = 0;
    for (int s = 1; s <= seeds && n < 64; s++) {
        char path[4096];
        snprintf(path, sizeof path, "%s/%s-%d.csv", dir, mode, s);
        SgError e = {0};
        if (!sg_curve_read_csv(path, &curves[n], &e)) {
            /* a failed run is reported and left out; the others still count */
            fprintf(stderr, "convergence: %s (left out)\n", e.message);
            continue;
        }
        n++;
    }
    if (n == 0)
        return true;
    bool ok = sg_curve_mean(curves, (size_t)n, MEAN_POINTS, &res->mean, err);
    for (int k = 0; k < n; k++) {
        const SgCurve *c = &curves[k];
        res->final_spp += c->spp[c->count - 1] / n;
        res->us_per_sample += c->seconds[c->count - 1] / c->spp[c->count - 1] / n;
        sg_curve_free(&curves[k]);
    }
    res->present = ok;
    res->seeds = n;
    return ok;
}

static bool write_mean(const char *dir, const char *mode, const SgCurve *c, SgError *err)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s.mean.dat", dir, mode);
    SgOutputFile out;
    if (!sg_output_open(&out, path, err))
        return false;
    fprintf(out.file, "# seconds spp relmse mse8 (mean of seeds)\n");
    for (size_t i = 0; i < c->count; i++)
        fprintf(out.file, "%.6g %.6g %.6g %.6g\n", c->seconds[i], c->spp[i],
                c->error[SG_METRIC_RELMSE][i], c->error[SG_METRIC_MSE8][i]);
    return sg_output_commit(&out, err);
}

static bool append_line(const char *dir, const char *file, const char *line, SgError *err)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, file);
    FILE *f = fopen(path, "a");
    if (!f)
        return sg_fail(err, "%s: cannot append", path);
    fputs(line, f);
    bool ok = !ferror(f);
    ok = fclose(f) == 0 && ok;
    return ok ? true : sg_fail(err, "%s: write error", path);
}

/* "%.3g" without the exponent form for the usual ranges of our errors. */
static void format_error(double v, char *buf, size_t size)
{
    if (!isfinite(v))
        snprintf(buf, size, "-");
    else if (v != 0 && (fabs(v) < 1e-3 || fabs(v) >= 1e5))
        snprintf(buf, size, "%.2e", v);
    else if (fabs(v) >= 1)
        snprintf(buf, size, "%.4g", v);
    else
        snprintf(buf, size, "%.3g", v);
}

static int cmd_analyze(int argc, char **argv, SgError *err)
{
    if (argc < 6)
        return sg_fail(err, "analyze: want NAME RUNDIR SEEDS TABLEDIR"), 1;
    const char *name = argv[2], *dir = argv[3], *tables = argv[5];
    int seeds = atoi(argv[4]);
    if (seeds < 1 || seeds > 64)
        return sg_fail(err, "analyze: SEEDS %s: want 1 to 64", argv[4]), 1;
    const char *size = "?", *ref_state = "";
    double ref_err[SG_METRIC_COUNT] = {NAN, NAN}, ref_spp = NAN, ref_seconds = NAN;
    for (int i = 6; i < argc; i++) {
        bool has = i + 1 < argc;
        double *target = NULL;
        if (has && !strcmp(argv[i], "--size"))
            size = argv[++i];
        else if (has && !strcmp(argv[i], "--ref-state"))
            ref_state = argv[++i];
        else if (has && !strcmp(argv[i], "--ref-relmse"))
            target = &ref_err[SG_METRIC_RELMSE];
        else if (has && !strcmp(argv[i], "--ref-mse8"))
            target = &ref_err[SG_METRIC_MSE8];
        else if (has && !strcmp(argv[i], "--ref-spp"))
            target = &ref_spp;
        else if (has && !strcmp(argv[i], "--ref-seconds"))
            target = &ref_seconds;
        else
            return sg_fail(err, "analyze: unexpected argument %s", argv[i]), 1;
        if (target && !parse_double(argv[++i], target))
            return sg_fail(err, "analyze: %s %s: not a number", argv[i - 1], argv[i]), 1;
    }

    ModeResult res[MODE_COUNT];
    int status = 1;
    memset(res, 0, sizeof res);
    for (int m = 0; m < MODE_COUNT; m++) {
        if (!load_mode(dir, mode_names[m], seeds, &res[m], err))
            goto done;
        if (res[m].present && !write_mean(dir, mode_names[m], &res[m].mean, err))
            goto done;
    }
    const ModeResult *base = &res[0];
    if (!base->present) {
        sg_fail(err, "%s: no bsdf curve: nothing to compare with", dir);
        goto done;
    }

    /* Levels from the baseline only, the same for every mode: bsdf's mean
     * error at the end of its run and at an eighth of it, each rounded up
     * to two significant digits (so bsdf reaches them just before). */
    double levels[SG_METRIC_COUNT][2];
    const SgCurve *bc = &base->mean;
    double t_end = bc->seconds[bc->count - 1], t_early = fmax(t_end / 8, bc->seconds[0]);
    for (int k = 0; k < SG_METRIC_COUNT; k++) {
        double end = bc->error[k][bc->count - 1], early;
        if (!sg_curve_at(bc, k, t_early, &early))
            early = end;
        levels[k][1] = sg_level_at_least(end);
        levels[k][0] = sg_level_at_least(early);
        if (!(levels[k][0] > levels[k][1])) /* a flat curve: still two levels */
            levels[k][0] = sg_level_at_least(1.5 * levels[k][1]);
    }
    char line[2048], a[64], b[64], c[64], d[64], e[64];
    snprintf(line, sizeof line, "relmse %.6g %.6g mse8 %.6g %.6g\n", levels[0][0], levels[0][1],
             levels[1][0], levels[1][1]);
    {
        char path[4096];
        snprintf(path, sizeof path, "%s/levels.txt", dir);
        SgOutputFile out;
        if (!sg_output_open(&out, path, err))
            goto done;
        fputs(line, out.file);
        if (!sg_output_commit(&out, err))
            goto done;
    }

    /* table 2: one row per level */
    static const char *const table_file[SG_METRIC_COUNT] = {"table2-relmse.md", "table2-mse8.md"};
    SgReach headline[MODE_COUNT];
    for (int k = 0; k < SG_METRIC_COUNT; k++)
        for (int l = 0; l < 2; l++) {
            SgReach r[MODE_COUNT];
            for (int m = 0; m < MODE_COUNT; m++) {
                r[m] = res[m].present ? sg_curve_time_to_level(&res[m].mean, k, levels[k][l])
                                      : (SgReach){SG_REACH_NONE, 0};
                if (k == SG_METRIC_RELMSE && l == 1)
                    headline[m] = r[m];
            }
            char lv[64];
            format_error(levels[k][l], lv, sizeof lv);
            sg_reach_format(r[0], a, sizeof a);
            sg_reach_format(r[1], b, sizeof b);
            sg_reach_format(r[2], c, sizeof c);
            sg_ratio_format(r[0], r[1], d, sizeof d);
            sg_ratio_format(r[0], r[2], e, sizeof e);
            snprintf(line, sizeof line, "| %s | %s | %s | %s | %s | %s | %s |\n", name, lv, a, b, c, d, e);
            if (!append_line(tables, table_file[k], line, err))
                goto done;
        }

    /* equal time: every mode at the time all of them reached */
    double t_eq = INFINITY;
    for (int m = 0; m < MODE_COUNT; m++)
        if (res[m].present)
            t_eq = fmin(t_eq, res[m].mean.seconds[res[m].mean.count - 1]);
    double eq[MODE_COUNT][SG_METRIC_COUNT];
    for (int m = 0; m < MODE_COUNT; m++)
        for (int k = 0; k < SG_METRIC_COUNT; k++)
            if (!res[m].present || !sg_curve_at(&res[m].mean, k, t_eq, &eq[m][k]))
                eq[m][k] = NAN;
    char cells[MODE_COUNT][SG_METRIC_COUNT][64], ratio[MODE_COUNT][SG_METRIC_COUNT][64];
    for (int m = 0; m < MODE_COUNT; m++)
        for (int k = 0; k < SG_METRIC_COUNT; k++) {
            format_error(eq[m][k], cells[m][k], sizeof cells[m][k]);
            double q = eq[0][k] / eq[m][k];
            if (isfinite(q))
                snprintf(ratio[m][k], sizeof ratio[m][k], "%.2f", q);
            else
                snprintf(ratio[m][k], sizeof ratio[m][k], "-");
        }
    char us[MODE_COUNT][32], spp[MODE_COUNT][32];
    int w = 0, h = 0;
    double pixels = sscanf(size, "%dx%d", &w, &h) == 2 ? (double)w * h : NAN;
    for (int m = 0; m < MODE_COUNT; m++) {
        if (res[m].present && isfinite(pixels)) {
            snprintf(us[m], sizeof us[m], "%.3f", 1e6 * res[m].us_per_sample / pixels);
            snprintf(spp[m], sizeof spp[m], "%.0f", res[m].final_spp);
        } else {
            snprintf(us[m], sizeof us[m], "-");
            snprintf(spp[m], sizeof spp[m], "-");
        }
    }
    snprintf(line, sizeof line,
             "| %s | %s | %.1f | %s / %s / %s | %s / %s / %s | %s | %s | %s | %s / %s | %s | %s | %s | %s / %s |\n",
             name, size, t_eq, spp[0], spp[1], spp[2], us[0], us[1], us[2],
             cells[0][0], cells[1][0], cells[2][0], ratio[1][0], ratio[2][0],
             cells[0][1], cells[1][1], cells[2][1], ratio[1][1], ratio[2][1]);
    if (!append_line(tables, "equal-time.md", line, err))
        goto done;

    /* the reference against the smallest levels it has to resolve */
    for (int k = 0; k < SG_METRIC_COUNT; k++) {
        format_error(ref_err[k], k ? b : a, 64);
        format_error(levels[k][1], k ? d : c, 64);
    }
    double worst = fmax(ref_err[0] / levels[0][1], ref_err[1] / levels[1][1]);
    const char *verdict = !isfinite(worst) ? "unknown"
                          : worst <= 0.25  ? "good (< 1/4 of the lowest level)"
                          : worst <= 0.5   ? "fair (< 1/2 of the lowest level)"
                                           : "too noisy: lengthen it (SG_REF_SECONDS)";
    snprintf(line, sizeof line, "| %s | %s | %.0f | %.0f | %s / %s | %s / %s | %.2f | %s | %s |\n", name,
             size, ref_spp, ref_seconds, a, b, c, d, worst, verdict, ref_state);
    if (!append_line(tables, "reference.md", line, err))
        goto done;

    /* README headline: relMSE at the lower level */
    char lv[64];
    format_error(levels[0][1], lv, sizeof lv);
    sg_reach_format(headline[0], a, sizeof a);
    sg_reach_format(headline[2], b, sizeof b);
    sg_ratio_format(headline[0], headline[2], c, sizeof c);
    sg_ratio_format(headline[0], headline[1], d, sizeof d);
    snprintf(line, sizeof line, "%s\t%s\t%s\t%s\t%s\t%s\t%s\n", name, size, lv, a, b, c, d);
    if (!append_line(tables, "headline.tsv", line, err))
        goto done;
    status = 0;
done:
    for (int m = 0; m < MODE_COUNT; m++)
        sg_curve_free(&res[m].mean);
    return status;
}

/* ---- strip --------------------------------------------------------------- */

/* The square of side s where the relative squared error of x against ref
 * sums highest (a summed-area table, so every position is O(1)); the
 * per-value error is relMSE's term (error_metrics.h) with the eps given. */
static bool worst_square(const float *x, const float *ref, int w, int h, int s, double eps, int *bx,
                         int *by, SgError *err)
{
    size_t stride = (size_t)w + 1;
    double *sat = calloc(stride * ((size_t)h + 1), sizeof *sat);
    if (!sat)
        return sg_fail(err, "strip: out of memory");
    for (int y = 0; y < h; y++)
        for (int xx = 0; xx < w; xx++) {
            double e = 0;
            for (int c = 0; c < 3; c++) {
                size_t i = ((size_t)y * w + xx) * 3 + c;
                double d = (double)x[i] - ref[i];
                e += sg_relmse_term(d, ref[i], eps);
            }
            sat[(y + 1) * stride + xx + 1] =
                e + sat[y * stride + xx + 1] + sat[(y + 1) * stride + xx] - sat[y * stride + xx];
        }
    double best = -1;
    for (int y = 0; y + s <= h; y++)
        for (int xx = 0; xx + s <= w; xx++) {
            double v = sat[(y + s) * stride + xx + s] - sat[y * stride + xx + s] -
                       sat[(y + s) * stride + xx] + sat[y * stride + xx];
            if (v > best) {
                best = v;
                *bx = xx;
                *by = y;
            }
        }
    free(sat);
    return true;
}

static int cmd_strip(int argc, char **argv, SgError *err)
{
    const char *ref_path = NULL, *out = NULL, *images[8];
    int count = 0, scale = 0, cx = -1, cy = -1, cw = 0, ch = 0;
    double exposure = 0;
    for (int i = 2; i < argc; i++) {
        bool has = i + 1 < argc;
        if (has && !strcmp(argv[i], "-o"))
            out = argv[++i];
        else if (has && !strcmp(argv[i], "--exposure")) {
            if (!parse_double(argv[++i], &exposure))
                return sg_fail(err, "strip: --exposure %s: not a number", argv[i]), 1;
        } else if (has && !strcmp(argv[i], "--scale"))
            scale = atoi(argv[++i]);
        else if (has && !strcmp(argv[i], "--crop")) {
            if (sscanf(argv[++i], "%d,%d,%d,%d", &cx, &cy, &cw, &ch) != 4 || cx < 0 || cy < 0 || cw < 1 || ch < 1)
                return sg_fail(err, "strip: --crop %s: want X,Y,W,H", argv[i]), 1;
        } else if (argv[i][0] == '-')
            return sg_fail(err, "strip: unexpected argument %s", argv[i]), 1;
        else if (!ref_path)
            ref_path = argv[i];
        else if (count < 8)
            images[count++] = argv[i];
        else
            return sg_fail(err, "strip: at most 8 images"), 1;
    }
    if (!ref_path || !out || count == 0)
        return sg_fail(err, "strip: want REF.exr -o STRIP.png IMAGE.exr..."), 1;
    float *ref = NULL, *img[8] = {NULL}, *strip = NULL;
    int w, h, status = 1;
    if (!sg_image_read(ref_path, &w, &h, &ref, err))
        goto done;
    for (int k = 0; k < count; k++) {
        int iw, ih;
        if (!sg_image_read(images[k], &iw, &ih, &img[k], err))
            goto done;
        if (iw != w || ih != h) {
            sg_fail(err, "%s: is %dx%d, the reference %dx%d", images[k], iw, ih, w, h);
            goto done;
        }
    }
    if (cx < 0) {
        cw = ch = (w < h ? w : h) / 2;
        if (cw < 1)
            cw = ch = 1;
        if (!worst_square(img[0], ref, w, h, cw, 0.01 / exp2(2.0 * exposure), &cx, &cy, err))
            goto done;
    }
    if (cx + cw > w || cy + ch > h) {
        sg_fail(err, "strip: crop %d,%d,%d,%d outside the %dx%d image", cx, cy, cw, ch, w, h);
        goto done;
    }
    if (scale < 1) /* tiles of about 160 pixels: big enough to see noise, small files */
        scale = cw >= 160 ? 1 : (160 + cw / 2) / cw;
    const int gap = 4, tiles = count + 1;
    int tw = cw * scale, th = ch * scale;
    int sw = tiles * tw + (tiles - 1) * gap;
    strip = malloc((size_t)sw * th * 3 * sizeof *strip);
    if (!strip) {
        sg_fail(err, "strip: out of memory");
        goto done;
    }
    /* the gaps white at any exposure */
    for (size_t i = 0; i < (size_t)sw * th * 3; i++)
        strip[i] = 1e6f;
    for (int k = 0; k < tiles; k++) {
        const float *src = k < count ? img[k] : ref;
        int x0 = k * (tw + gap);
        for (int y = 0; y < th; y++)
            for (int x = 0; x < tw; x++)
                for (int c = 0; c < 3; c++)
                    strip[((size_t)y * sw + x0 + x) * 3 + c] =
                        src[((size_t)(cy + y / scale) * w + cx + x / scale) * 3 + c];
    }
    if (!sg_image_write_png(out, sw, th, strip, exposure, err))
        goto done;
    printf("crop %d,%d,%d,%d\n", cx, cy, cw, ch);
    status = 0;
done:
    free(ref);
    free(strip);
    for (int k = 0; k < count; k++)
        free(img[k]);
    return status;
}

int main(int argc, char **argv)
{
    if (argc < 2 || !strcmp(argv[1], "--help") || !strcmp(argv[1], "-h")) {
        fputs(usage, argc < 2 ? stderr : stdout);
        return argc < 2 ? 2 : 0;
    }
    SgError err = {0};
    int status;
    if (!strcmp(argv[1], "size"))
        status = cmd_size(argc, argv, &err);
    else if (!strcmp(argv[1], "reference"))
        status = cmd_reference(argc, argv, &err);
    else if (!strcmp(argv[1], "analyze"))
        status = cmd_analyze(argc, argv, &err);
    else if (!strcmp(argv[1], "strip"))
        status = cmd_strip(argc, argv, &err);
    else {
        sg_fail(&err, "unknown command %s (size, reference, analyze, strip)", argv[1]);
        status = 2;
    }
    if (status)
        sg_error_print("convergence", &err);
    return status;
}
