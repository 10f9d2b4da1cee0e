/* The number work of bench/sections/60-convergence.sh (the paper's table 2):
 *
 *   convergence size SCENE PIXELS
 *       prints "WxH EXPOSURE": the scene's image scaled to about PIXELS
 *       pixels with its aspect kept, and its PNG exposure in stops.
 *   convergence reference HALF_A.exr HALF_B.exr -o REF.exr --exposure E
 *       REF = (A + B) / 2; prints "relmse X mse8 Y mse Z", the reference's
 *       own error estimated from the halves' difference.
 *   convergence analyze NAME RUNDIR SEEDS TABLEDIR [options]
 *       reads RUNDIR/MODE-SEED.csv for the modes of --modes (the first the
 *       baseline) or, without it, every mode that has such files (bsdf
 *       first) and seeds 1..SEEDS, writes each mode's mean curve
 *       RUNDIR/MODE.mean.dat (seconds spp relmse mse8 mse) and
 *       RUNDIR/levels.txt, and appends markdown rows to TABLEDIR/
 *       {table2-relmse,table2-mse8,table2-mse,equal-time,reference,
 *       training}.md (headers in TABLE.head) and one line to
 *       TABLEDIR/headline.tsv: see bench/lib/convergence_analyze.h.
 *       options: --modes A,B,... --compare X:Y --size WxH --ref-relmse X
 *                --ref-mse8 Y --ref-mse Z --ref-spp N --ref-seconds S
 *                --ref-state TEXT
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

#include "bench/lib/convergence_math.h"
#include "bench/lib/convergence_analyze.h"

#include "image_io.h"
#include "output_file.h"
#include "scene_load.h"
#include "shard_format.h"

static const char usage[] =
    "usage: convergence size SCENE PIXELS\n"
    "       convergence reference HALF_A.exr HALF_B.exr -o REF.exr --exposure STOPS\n"
    "       convergence analyze NAME RUNDIR SEEDS TABLEDIR [--modes bsdf,A,B...] [--compare X:Y]\n"
    "                   [--size WxH] [--ref-relmse X] [--ref-mse8 Y] [--ref-mse Z] [--ref-spp N]\n"
    "                   [--ref-seconds S] [--ref-state TEXT]\n"
    "       convergence strip REF.exr --exposure STOPS -o STRIP.png [--crop X,Y,W,H] [--scale K]\n"
    "                   IMAGE.exr...\n"
    "       convergence error IMAGE.exr REF.exr --exposure STOPS   (prints relmse X mse8 Y mse Z)\n"
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

/* Two images of one size: `reference` NULL, the errors of a against b;
 * else a and b are two independent halves, their mean is written to
 * `reference` and their own error printed. */
static int compare(const char *a, const char *b, double exposure, const char *reference, SgError *err)
{
    int w, h, wb, hb, status = 1;
    float *rgb[2] = {NULL, NULL};
    if (!sg_image_read(a, &w, &h, &rgb[0], err) || !sg_image_read(b, &wb, &hb, &rgb[1], err))
        goto done;
    if (wb != w || hb != h) {
        sg_fail(err, "%s: is %dx%d, %s is %dx%d", b, wb, hb, a, w, h);
        goto done;
    }
    size_t n = (size_t)w * h * 3;
    double relmse, mse8, mse;
    if (reference) { /* the mean goes into the first half's buffer */
        sg_reference_from_halves(rgb[0], rgb[1], n, (float)exp2(exposure), rgb[0], &relmse, &mse8, &mse);
        SgImageAttribute attrs[] = {{SG_ATTR_REFERENCE, "mean of two independent bsdf halves"}};
        if (!sg_image_write_exr(reference, w, h, rgb[0], attrs, 1, err))
            goto done;
    } else {
        sg_image_errors(rgb[0], rgb[1], n, (float)exp2(exposure), &relmse, &mse8, &mse);
    }
    printf("relmse %.6g mse8 %.6g mse %.6g relmse_trimmed %.6g\n", relmse, mse8, mse,
           sg_image_relmse_trimmed(rgb[0], rgb[1], n / 3, (float)exp2(exposure)));
    status = 0;
done:
    free(rgb[0]);
    free(rgb[1]);
    return status;
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
    return compare(halves[0], halves[1], exposure, out, err);
}

/* ---- error --------------------------------------------------------------- */

static int cmd_error(int argc, char **argv, SgError *err)
{
    double exposure;
    if (argc != 6 || strcmp(argv[4], "--exposure") || !parse_double(argv[5], &exposure))
        return sg_fail(err, "error: want IMAGE.exr REF.exr --exposure STOPS"), 1;
    return compare(argv[2], argv[3], exposure, NULL, err);
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
        status = sg_convergence_analyze(argc, argv, &err);
    else if (!strcmp(argv[1], "strip"))
        status = cmd_strip(argc, argv, &err);
    else if (!strcmp(argv[1], "error"))
        status = cmd_error(argc, argv, &err);
    else {
        sg_fail(&err, "unknown command %s (size, reference, analyze, strip, error)", argv[1]);
        status = 2;
    }
    if (status)
        sg_error_print("convergence", &err);
    return status;
}
