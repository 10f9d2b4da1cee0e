/* The convergence benchmark's arithmetic (bench/lib/convergence_math.h) and its
 * tables (bench/lib/convergence_analyze.h) on synthetic curves whose answers are
 * known in closed form: error = C / t (unbiased Monte Carlo), a biased curve
 * that flattens, seeds with different pass times, a reference made of two
 * noisy halves, and four modes' logs and images run through `analyze`. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "bench/lib/convergence_math.h"
#include "bench/lib/convergence_analyze.h"
#include "image_io.h"
#include "rng.h"

/* error = c / t^p (relMSE) and 100 c / t^p (mse8) at n passes of dt. */
static SgCurve power_curve(double c, double p, double t0, double dt, size_t n)
{
    SgCurve curve;
    SgError err = {0};
    cr_assert(sg_curve_alloc(&curve, n, &err), "%s", err.message);
    for (size_t i = 0; i < n; i++) {
        double t = t0 + dt * (double)i;
        curve.seconds[i] = t;
        curve.spp[i] = (double)(i + 1);
        curve.error[SG_METRIC_RELMSE][i] = c / pow(t, p);
        curve.error[SG_METRIC_MSE8][i] = 100 * c / pow(t, p);
        curve.error[SG_METRIC_MSE][i] = 0.01 * c / pow(t, p);
    }
    return curve;
}

Test(bench_convergence, time_to_level_interpolates_a_one_over_t_curve)
{
    SgCurve c = power_curve(0.2, 1.0, 0.05, 0.05, 200); /* 0.05 .. 10 s */
    /* 0.2 / t = 0.04 at t = 5, between two passes only by log-log interpolation
     * when the level falls between them: try a level off the pass grid too */
    SgReach r = sg_curve_time_to_level(&c, SG_METRIC_RELMSE, 0.04);
    cr_assert_eq(r.kind, SG_REACH_INTERPOLATED);
    cr_assert_float_eq(r.seconds, 5.0, 1e-9);
    r = sg_curve_time_to_level(&c, SG_METRIC_RELMSE, 0.2 / 3.333);
    cr_assert_eq(r.kind, SG_REACH_INTERPOLATED);
    cr_assert_float_eq(r.seconds, 3.333, 1e-9);
    r = sg_curve_time_to_level(&c, SG_METRIC_MSE8, 100 * 0.2 / 7.777);
    cr_assert_float_eq(r.seconds, 7.777, 1e-9);
    sg_curve_free(&c);
}

Test(bench_convergence, level_beyond_the_run_is_extrapolated_along_one_over_t)
{
    SgCurve c = power_curve(0.2, 1.0, 0.05, 0.05, 200);
    SgReach r = sg_curve_time_to_level(&c, SG_METRIC_RELMSE, 0.2 / 41.2);
    cr_assert_eq(r.kind, SG_REACH_EXTRAPOLATED);
    cr_assert_float_eq(r.seconds, 41.2, 1e-6);
    char buf[64];
    sg_reach_format(r, buf, sizeof buf);
    cr_assert_str_eq(buf, "~41.2");
    /* further than 50 runs: only a bound */
    r = sg_curve_time_to_level(&c, SG_METRIC_RELMSE, 0.2 / 1000);
    cr_assert_eq(r.kind, SG_REACH_BEYOND);
    cr_assert_float_eq(r.seconds, 500.0, 1e-9);
    sg_reach_format(r, buf, sizeof buf);
    cr_assert_str_eq(buf, "> 500");
    sg_curve_free(&c);

    /* a noisy tail (x1.3 / x0.77 alternating) still extrapolates near 1/t */
    c = power_curve(0.2, 1.0, 0.05, 0.05, 200);
    for (size_t i = 0; i < c.count; i++)
        c.error[SG_METRIC_RELMSE][i] *= i % 2 ? 1.3 : 1 / 1.3;
    r = sg_curve_time_to_level(&c, SG_METRIC_RELMSE, 0.2 / 40);
    cr_assert_eq(r.kind, SG_REACH_EXTRAPOLATED);
    cr_assert(fabs(r.seconds / 40 - 1) < 0.05, "extrapolated %g s, want ~40", r.seconds);
    sg_curve_free(&c);
}

Test(bench_convergence, level_passed_at_the_first_pass_is_a_bound)
{
    SgCurve c = power_curve(0.2, 1.0, 0.05, 0.05, 200);
    SgReach r = sg_curve_time_to_level(&c, SG_METRIC_RELMSE, 10.0);
    cr_assert_eq(r.kind, SG_REACH_BEFORE_FIRST);
    cr_assert_float_eq(r.seconds, 0.05, 1e-12);
    char buf[64];
    sg_reach_format(r, buf, sizeof buf);
    cr_assert_str_eq(buf, "< 0.050");
    sg_curve_free(&c);
}

Test(bench_convergence, flat_biased_tail_is_never_extrapolated)
{
    /* a biased estimator: variance / t plus a squared bias it never loses */
    SgCurve c = power_curve(0.2, 1.0, 0.05, 0.05, 200);
    for (size_t i = 0; i < c.count; i++)
        c.error[SG_METRIC_RELMSE][i] += 0.05;
    cr_assert_gt(sg_curve_tail_slope(&c, SG_METRIC_RELMSE), SG_TAIL_SLOPE_LIMIT);
    SgReach r = sg_curve_time_to_level(&c, SG_METRIC_RELMSE, 0.01);
    cr_assert_eq(r.kind, SG_REACH_NEVER);
    /* the unbiased tail's slope is -1 */
    cr_assert_float_eq(sg_curve_tail_slope(&c, SG_METRIC_MSE8), -1.0, 1e-9);
    sg_curve_free(&c);
}

Test(bench_convergence, mean_of_seeds_with_different_pass_times)
{
    /* seed 1: 0.2/t every 0.05 s up to 10 s; seed 2: 0.6/t every 0.07 s up to
     * 8.4 s. Power laws interpolate exactly in log-log: the mean is 0.4/t
     * over the common range 0.07 .. 8.4 s. */
    SgCurve seeds[2] = {power_curve(0.2, 1.0, 0.05, 0.05, 200), power_curve(0.6, 1.0, 0.07, 0.07, 120)};
    SgCurve mean;
    SgError err = {0};
    cr_assert(sg_curve_mean(seeds, 2, 50, &mean, &err), "%s", err.message);
    cr_assert_eq(mean.count, 50);
    cr_assert_float_eq(mean.seconds[0], 0.07, 1e-12);
    cr_assert_float_eq(mean.seconds[49], 8.4, 1e-9);
    for (size_t i = 0; i < mean.count; i++) {
        double t = mean.seconds[i];
        cr_assert(i == 0 || t > mean.seconds[i - 1]);
        cr_assert_float_eq(mean.error[SG_METRIC_RELMSE][i], 0.4 / t, 1e-9 * 0.4 / t);
    }
    SgReach r = sg_curve_time_to_level(&mean, SG_METRIC_RELMSE, 0.1);
    cr_assert_float_eq(r.seconds, 4.0, 1e-9);
    sg_curve_free(&mean);

    /* no common time range: refused */
    SgCurve late = power_curve(0.2, 1.0, 20, 1, 5);
    cr_assert_not(sg_curve_mean((SgCurve[]){seeds[0], late}, 2, 50, &mean, &err));
    cr_assert(strstr(err.message, "no time range"), "%s", err.message);
    sg_curve_free(&late);
    sg_curve_free(&seeds[0]);
    sg_curve_free(&seeds[1]);
}

Test(bench_convergence, ratio_to_bsdf_carries_the_marks)
{
    const SgReach base = {SG_REACH_INTERPOLATED, 12.0}, first = {SG_REACH_BEFORE_FIRST, 0.5},
                  beyond = {SG_REACH_BEYOND, 600.0};
    const struct {
        SgReach bsdf, mode;
        const char *expected;
    } cases[] = {
        {base, {SG_REACH_INTERPOLATED, 4.0}, "3.00"},
        {base, {SG_REACH_EXTRAPOLATED, 24.0}, "~0.50"},
        {base, first, "> 24.00"},
        {first, {SG_REACH_INTERPOLATED, 2.0}, "< 0.25"},
        {base, beyond, "< 0.02"},
        {beyond, base, "> 50.00"},
        {beyond, first, "> 1200.00"},
        {first, first, "-"},
        {{SG_REACH_INTERPOLATED, 0.5}, {SG_REACH_EXTRAPOLATED, 200.0}, "~0.0025"},
        {base, {SG_REACH_NEVER, 0}, "0 (never)"},
        {base, {SG_REACH_NONE, 0}, "-"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char buf[64];
        sg_ratio_format(cases[i].bsdf, cases[i].mode, buf, sizeof buf);
        cr_assert_str_eq(buf, cases[i].expected, "case %zu", i);
    }
}

Test(bench_convergence, levels_round_up_to_two_significant_digits)
{
    cr_assert_float_eq(sg_level_at_least(0.0021), 0.0021, 1e-15);
    cr_assert_float_eq(sg_level_at_least(0.00214), 0.0022, 1e-15);
    cr_assert_float_eq(sg_level_at_least(2437.0), 2500.0, 1e-9);
    cr_assert_float_eq(sg_level_at_least(3322.47), 3400.0, 1e-9);
    cr_assert_float_eq(sg_level_at_least(99.1), 100.0, 1e-9);
    cr_assert_float_eq(sg_level_at_least(7.0), 7.0, 1e-12);
    cr_assert_float_eq(sg_level_at_least(2.6e-4), 2.6e-4, 1e-18);
    for (double x = 1e-6; x < 1e6; x *= 1.37) {
        double v = sg_level_at_least(x);
        cr_assert(v >= x && v <= x * 1.1 + 1e-300, "%g -> %g", x, v);
    }
    cr_assert(isnan(sg_level_at_least(0.0)));
}

Test(bench_convergence, reference_error_from_two_halves_matches_its_true_error)
{
    /* truth in [0, 2]; halves = truth + Gaussian noise of sd 0.1 (Box-Muller):
     * the mean's error is known exactly, the half-difference estimates it */
    const size_t n = 300000;
    float *truth = malloc(n * sizeof *truth), *a = malloc(n * sizeof *a), *b = malloc(n * sizeof *b);
    float *ref = malloc(n * sizeof *ref);
    cr_assert(truth && a && b && ref);
    SgRng rng;
    sg_rng_seed(&rng, 7, 1);
    for (size_t i = 0; i < n; i++) {
        truth[i] = 2.0f * sg_rng_float(&rng);
        for (int k = 0; k < 2; k++) {
            double u1 = 1.0 - sg_rng_float(&rng), u2 = sg_rng_float(&rng);
            double g = sqrt(-2 * log(u1)) * cos(2 * M_PI * u2);
            (k ? b : a)[i] = (float)(truth[i] + 0.1 * g);
        }
    }
    double relmse, mse8, mse;
    sg_reference_from_halves(a, b, n, 1.0f, ref, &relmse, &mse8, &mse);
    double true_rel = 0, true8 = 0, true_mse = 0;
    for (size_t i = 0; i < n; i++) {
        cr_assert_float_eq(ref[i], 0.5f * (a[i] + b[i]), 1e-6);
        double d = (double)ref[i] - truth[i];
        true_rel += sg_relmse_term(d, ref[i], sg_relmse_epsilon(1.0f)) / (double)n;
        true_mse += d * d / (double)n;
        double d8 = sg_srgb_byte(ref[i]) - sg_srgb_byte(truth[i]);
        true8 += d8 * d8 / (double)n;
    }
    cr_assert(fabs(relmse / true_rel - 1) < 0.03, "estimated relMSE %g, true %g", relmse, true_rel);
    cr_assert(fabs(mse8 / true8 - 1) < 0.15, "estimated mse8 %g, true %g", mse8, true8);
    /* the mean of two halves of sd 0.1 has variance 0.005 */
    cr_assert(fabs(mse / true_mse - 1) < 0.02, "estimated MSE %g, true %g", mse, true_mse);
    cr_assert(fabs(mse / 0.005 - 1) < 0.02, "estimated MSE %g, want 0.005", mse);
    /* identical halves: no error */
    sg_reference_from_halves(a, a, n, 1.0f, NULL, &relmse, &mse8, &mse);
    cr_assert_eq(relmse, 0.0);
    cr_assert_eq(mse8, 0.0);
    cr_assert_eq(mse, 0.0);
    free(truth);
    free(a);
    free(b);
    free(ref);
}

Test(bench_convergence, csv_reader_takes_render_logs_and_refuses_bad_ones)
{
    const char *path = "build/test_bench_convergence.csv";
    FILE *f = fopen(path, "w");
    cr_assert(f);
    fprintf(f, "seconds,spp,mse,relmse,mse8\n0.010000,1,0.5,0.25,400\n0.020000,2,0.25,0.125,200\n");
    fclose(f);
    SgCurve c;
    SgError err = {0};
    cr_assert(sg_curve_read_csv(path, &c, &err), "%s", err.message);
    cr_assert_eq(c.count, 2);
    cr_assert_float_eq(c.seconds[1], 0.02, 1e-12);
    cr_assert_float_eq(c.spp[1], 2, 1e-12);
    cr_assert_float_eq(c.error[SG_METRIC_RELMSE][1], 0.125, 1e-12);
    cr_assert_float_eq(c.error[SG_METRIC_MSE8][0], 400, 1e-12);
    cr_assert_float_eq(c.error[SG_METRIC_MSE][0], 0.5, 1e-12);
    cr_assert_float_eq(c.error[SG_METRIC_MSE][1], 0.25, 1e-12);
    sg_curve_free(&c);
    /* today's log: relmse_trimmed after the five */
    f = fopen(path, "w");
    fprintf(f, "seconds,spp,mse,relmse,mse8,relmse_trimmed\n0.01,1,0.5,0.25,400,0.2\n0.02,2,0.25,0.125,200,0.1\n");
    fclose(f);
    cr_assert(sg_curve_read_csv(path, &c, &err), "%s", err.message);
    cr_assert_eq(c.count, 2);
    cr_assert_float_eq(c.error[SG_METRIC_MSE8][1], 200, 1e-12);
    sg_curve_free(&c);

    static const char *const bad[][2] = {
        {"", "header"},
        {"seconds,spp,mse,relmse,mse8\n", "no rows"},
        {"seconds,spp,mse,relmse,mse8\n0.1,1,0.5,nan,3\n", "malformed"},
        {"seconds,spp,mse,relmse,mse8\n0.1,1,0.5,0.2\n", "malformed"},
        {"seconds,spp,mse,relmse,mse8\n0.1,1,0.5,0.2,3,4\n", "malformed"},
        {"seconds,spp,mse,relmse,mse8\n0.2,1,0.5,0.2,3\n0.1,2,0.5,0.2,3\n", "does not increase"},
        {"seconds,spp,mse,relmse,mse8\n0.2,1,0.5,-0.2,3\n", "negative"},
        {"seconds,spp,mse,relmse,mse8\n0.2,1,-0.5,0.2,3\n", "negative"},
        {"seconds,spp,mse,relmse,mse8,relmse_trimmed\n0.1,1,0.5,0.2,3\n", "malformed"},
    };
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        f = fopen(path, "w");
        fputs(bad[k][0], f);
        fclose(f);
        err = (SgError){0};
        cr_assert_not(sg_curve_read_csv(path, &c, &err), "case %zu accepted", k);
        cr_assert(strstr(err.message, path) && strstr(err.message, bad[k][1]), "case %zu: %s", k,
                  err.message);
        cr_assert(!strchr(err.message, '\n'));
    }
    unlink(path);
    err = (SgError){0};
    cr_assert_not(sg_curve_read_csv(path, &c, &err));
    cr_assert(strstr(err.message, path));
}

/* ---- analyze: the tables of several modes ------------------------------- */

/* A run directory under build/ for one test. */
static char analyze_base[64];

static void analyze_cleanup(void)
{
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", analyze_base);
    if (analyze_base[0] && system(cmd) != 0)
        fprintf(stderr, "could not remove %s\n", analyze_base);
}

static void analyze_dirs(char *runs, char *tables, size_t size)
{
    snprintf(analyze_base, sizeof analyze_base, "build/test_bench_analyze.XXXXXX");
    char *base = analyze_base;
    cr_assert(mkdtemp(base), "mkdtemp");
    snprintf(runs, size, "%s/runs", base);
    snprintf(tables, size, "%s/tables", base);
    cr_assert(mkdir(runs, 0755) == 0 && mkdir(tables, 0755) == 0);
}

/* RUNS/MODE-SEED.csv of a 1/t curve: relmse c/t, mse8 100 c/t, mse cm/t,
 * a pass every dt seconds up to 10 s. */
static void write_log(const char *runs, const char *mode, int seed, double c, double cm, double dt)
{
    char path[512];
    snprintf(path, sizeof path, "%s/%s-%d.csv", runs, mode, seed);
    FILE *f = fopen(path, "w");
    cr_assert(f, "%s", path);
    fprintf(f, "seconds,spp,mse,relmse,mse8\n");
    int n = (int)lround(10.0 / dt);
    for (int i = 1; i <= n; i++) {
        double t = dt * i;
        fprintf(f, "%.6f,%d,%.9g,%.9g,%.9g\n", t, i, cm / t, c / t, 100 * c / t);
    }
    fclose(f);
}

/* RUNS/MODE-SEED.exr, 2x2, with render's guide attributes */
static void write_image(const char *runs, const char *mode, int seed, const char *passes, const char *training,
                        const char *share)
{
    char path[512];
    snprintf(path, sizeof path, "%s/%s-%d.exr", runs, mode, seed);
    float rgb[12] = {0};
    SgImageAttribute attrs[] = {{"seconds", "10.000"},
                                {"sg:training_passes", passes},
                                {"sg:training_seconds", training},
                                {"sg:guide_share", share}};
    SgError err = {0};
    cr_assert(sg_image_write_exr(path, 2, 2, rgb, attrs, 4, &err), "%s", err.message);
}

/* the text of TABLES/FILE */
static char *slurp(const char *dir, const char *file)
{
    char path[512];
    snprintf(path, sizeof path, "%s/%s", dir, file);
    FILE *f = fopen(path, "r");
    if (!f)
        return NULL;
    static char buf[8][8192];
    static int next;
    char *b = buf[next++ % 8];
    size_t n = fread(b, 1, 8191, f);
    b[n] = '\0';
    fclose(f);
    return b;
}

/* line `row` (0-based) of text, cell `col` (0-based, between the |), trimmed */
static const char *cell(const char *text, int row, int col)
{
    static char out[8][128];
    static int next;
    char *o = out[next++ % 8];
    const char *p = text;
    for (int r = 0; r < row && p; r++) {
        p = strchr(p, '\n');
        if (p)
            p++;
    }
    cr_assert(p && *p == '|', "no row %d in:\n%s", row, text);
    p++;
    for (int c = 0; c < col; c++) {
        p = strchr(p, '|');
        cr_assert(p, "no cell %d in row %d:\n%s", col, row, text);
        p++;
    }
    while (*p == ' ')
        p++;
    const char *end = strchr(p, '|');
    cr_assert(end);
    while (end > p && end[-1] == ' ')
        end--;
    snprintf(o, 128, "%.*s", (int)(end - p), p);
    return o;
}

static double cell_number(const char *text, int row, int col)
{
    const char *s = cell(text, row, col);
    if (*s == '~')
        s++;
    char *end;
    double v = strtod(s, &end);
    cr_assert(end != s, "cell %d of row %d is %s", col, row, s);
    return v;
}

/* relMSE: bsdf 0.853/t; skeleton half as fast, guided 4x, openpgl 2x as
 * fast. Linear MSE the other way for guided, as on the Cornell box:
 * bsdf 0.0123/t, guided 3x the error, openpgl half. Two seeds at 0.5x and
 * 1.5x (mean 1x) with different pass times. */
static void write_four_modes(const char *runs)
{
    static const struct {
        const char *mode;
        double c, cm;
    } m[] = {{"bsdf", 0.853, 0.0123},
             {"skeleton", 2 * 0.853, 2 * 0.0123},
             {"guided", 0.853 / 4, 3 * 0.0123},
             {"openpgl", 0.853 / 2, 0.0123 / 2}};
    for (size_t k = 0; k < 4; k++) {
        write_log(runs, m[k].mode, 1, 0.5 * m[k].c, 0.5 * m[k].cm, 0.05);
        write_log(runs, m[k].mode, 2, 1.5 * m[k].c, 1.5 * m[k].cm, 0.04);
    }
    write_image(runs, "openpgl", 1, "64", "0.300", "0.4000");
    write_image(runs, "openpgl", 2, "64", "0.500", "0.5000");
    write_image(runs, "guided", 1, "0", "0.000", "0.6000"); /* trained nothing: no row */
}

static int run_analyze(const char *runs, const char *tables, const char *extra1, const char *extra2,
                       SgError *err)
{
    char *argv[] = {"convergence", "analyze", "corridor", (char *)runs, "2", (char *)tables,
                    "--size", "160x120", "--ref-relmse", "0.004", "--ref-mse8", "0.5",
                    "--ref-mse", "2e-4", "--ref-spp", "900", "--ref-seconds", "60",
                    "--ref-state", "kept", (char *)extra1, (char *)extra2, NULL};
    int argc = 20 + (extra1 != NULL) + (extra2 != NULL);
    return sg_convergence_analyze(argc, argv, err);
}

Test(bench_convergence, analyze_four_modes_times_speedups_and_guided_over_openpgl, .fini = analyze_cleanup)
{
    char runs[256], tables[256];
    analyze_dirs(runs, tables, sizeof runs);
    write_four_modes(runs);
    SgError err = {0};
    cr_assert_eq(run_analyze(runs, tables, NULL, NULL, &err), 0, "%s", err.message);

    /* modes discovered in the benchmark's order, guided over openpgl added */
    const char *head = slurp(tables, "table2-relmse.head");
    cr_assert_str_eq(head, "| scene | relMSE level | bsdf s | skeleton s | guided s | openpgl s | skeleton speed-up |"
                           " guided speed-up | openpgl speed-up | guided over openpgl |\n|---|---|---|---|---|---|---|"
                           "---|---|---|\n");
    /* levels from bsdf: 0.853/1.25 = 0.6824 -> 0.69 and 0.0853 -> 0.086 */
    const char *rel = slurp(tables, "table2-relmse.md");
    cr_assert_str_eq(cell(rel, 0, 1), "0.69");
    cr_assert_str_eq(cell(rel, 1, 1), "0.086");
    double level = 0.086;
    cr_assert_float_eq(cell_number(rel, 1, 2), 0.853 / level, 0.006);       /* bsdf 9.92 s */
    cr_assert_str_eq(cell(rel, 1, 3), "~19.8");                            /* skeleton, after its run */
    cr_assert_float_eq(cell_number(rel, 1, 4), 0.853 / 4 / level, 0.006);   /* guided 2.48 s */
    cr_assert_float_eq(cell_number(rel, 1, 5), 0.853 / 2 / level, 0.006);   /* openpgl 4.96 s */
    cr_assert_str_eq(cell(rel, 1, 6), "~0.50");
    cr_assert_str_eq(cell(rel, 1, 7), "4.00");
    cr_assert_str_eq(cell(rel, 1, 8), "2.00");
    cr_assert_str_eq(cell(rel, 1, 9), "2.00"); /* guided over openpgl */
    cr_assert_str_eq(cell(rel, 0, 9), "2.00");

    /* linear MSE: 0.00123 -> level 0.0013; guided slower than bsdf, openpgl
     * faster: guided over openpgl 1/6 */
    const char *mse = slurp(tables, "table2-mse.md");
    cr_assert_str_eq(cell(mse, 1, 1), "0.0013");
    cr_assert_float_eq(cell_number(mse, 1, 2), 0.0123 / 0.0013, 0.006);
    cr_assert_str_eq(cell(mse, 1, 4), "~28.4");
    cr_assert_str_eq(cell(mse, 1, 7), "~0.33");
    cr_assert_str_eq(cell(mse, 1, 8), "2.00");
    cr_assert_str_eq(cell(mse, 1, 9), "~0.17");
    cr_assert_str_eq(cell(mse, 0, 9), "0.17");
    const char *mse8 = slurp(tables, "table2-mse8.md");
    cr_assert_str_eq(cell(mse8, 1, 1), "8.6");
    cr_assert_str_eq(cell(mse8, 1, 9), "2.00");

    /* equal time at 10 s: errors and bsdf / mode per metric */
    const char *eq = slurp(tables, "equal-time.md");
    cr_assert_str_eq(cell(eq, 0, 2), "10.0");
    cr_assert_str_eq(cell(eq, 0, 3), "225 / 225 / 225 / 225");
    cr_assert_str_eq(cell(eq, 0, 5), "0.0853"); /* relMSE bsdf */
    cr_assert_str_eq(cell(eq, 0, 7), "0.0213"); /* guided */
    cr_assert_str_eq(cell(eq, 0, 9), "0.50 / 4.00 / 2.00");
    cr_assert_str_eq(cell(eq, 0, 15), "0.00123"); /* MSE bsdf */
    cr_assert_str_eq(cell(eq, 0, 17), "0.00369"); /* guided */
    cr_assert_str_eq(cell(eq, 0, 18), "6.15e-04"); /* openpgl */
    cr_assert_str_eq(cell(eq, 0, 19), "0.50 / 0.33 / 2.00");
    cr_assert_str_eq(cell(slurp(tables, "equal-time.head"), 0, 15), "MSE bsdf");

    /* openpgl's training: 64 passes, ended at 3.2 s (seed 1) and 2.56 s */
    const char *tr = slurp(tables, "training.md");
    cr_assert_str_eq(tr, "| corridor | openpgl | 2 | 225 | 64 | 0.40 | 4.0% | 2.88 | 28.8% | 45.0% |\n");

    /* the reference against the lowest levels: MSE's 2e-4 / 0.0013 is the worst */
    const char *ref = slurp(tables, "reference.md");
    cr_assert_str_eq(cell(ref, 0, 4), "0.004 / 0.5 / 2.00e-04");
    cr_assert_str_eq(cell(ref, 0, 5), "0.086 / 8.6 / 0.0013");
    cr_assert_str_eq(cell(ref, 0, 6), "0.15");

    /* headline: the old seven fields, then openpgl's three */
    const char *hl = slurp(tables, "headline.tsv");
    cr_assert(hl);
    char expect[256];
    snprintf(expect, sizeof expect, "corridor\t160x120\t0.086\t%s\t%s\t4.00\t~0.50\t%s\t2.00\t2.00\n",
             cell(rel, 1, 2), cell(rel, 1, 4), cell(rel, 1, 5));
    cr_assert_str_eq(hl, expect);

    /* the mean curves carry the MSE column */
    char *dat = slurp(runs, "openpgl.mean.dat");
    cr_assert(dat && strstr(dat, "# seconds spp relmse mse8 mse"));
    cr_assert_str_eq(slurp(runs, "levels.txt"), "relmse 0.69 0.086 mse8 69 8.6 mse 0.0099 0.0013\n");
}

Test(bench_convergence, analyze_three_modes_keeps_the_old_tables, .fini = analyze_cleanup)
{
    char runs[256], tables[256];
    analyze_dirs(runs, tables, sizeof runs);
    write_four_modes(runs);
    SgError err = {0};
    cr_assert_eq(run_analyze(runs, tables, "--modes", "bsdf,skeleton,guided", &err), 0, "%s", err.message);
    cr_assert_str_eq(slurp(tables, "table2-relmse.head"),
                     "| scene | relMSE level | bsdf s | skeleton s | guided s | skeleton speed-up | guided speed-up |\n"
                     "|---|---|---|---|---|---|---|\n");
    cr_assert_str_eq(slurp(tables, "table2-mse8.head"),
                     "| scene | mse8 level | bsdf s | skeleton s | guided s | skeleton speed-up | guided speed-up |\n"
                     "|---|---|---|---|---|---|---|\n");
    const char *eqh = slurp(tables, "equal-time.head");
    cr_assert(!strncmp(eqh,
                       "| scene | size | seconds | spp bsdf / skeleton / guided | µs/sample bsdf / skel. / guided |"
                       " relMSE bsdf | skeleton | guided | ratio skel. / guided | mse8 bsdf | skeleton | guided |"
                       " ratio skel. / guided | MSE bsdf |",
                       strlen("| scene | size | seconds | spp bsdf / skeleton / guided | µs/sample bsdf / skel. / "
                              "guided | relMSE bsdf | skeleton | guided | ratio skel. / guided | mse8 bsdf | "
                              "skeleton | guided | ratio skel. / guided | MSE bsdf |")),
              "%s", eqh);
    const char *rel = slurp(tables, "table2-relmse.md");
    cr_assert_str_eq(cell(rel, 1, 6), "4.00");
    /* seven cells a row, no training table, the seven-field headline */
    int bars = 0;
    for (const char *p = rel; *p && *p != '\n'; p++)
        bars += *p == '|';
    cr_assert_eq(bars, 8);
    cr_assert_null(slurp(tables, "training.md"));
    const char *hl = slurp(tables, "headline.tsv");
    int tabs = 0;
    for (const char *p = hl; *p; p++)
        tabs += *p == '\t';
    cr_assert_eq(tabs, 6, "%s", hl);
}

Test(bench_convergence, analyze_modes_discovery_compare_and_refusals, .fini = analyze_cleanup)
{
    char runs[256], tables[256];
    analyze_dirs(runs, tables, sizeof runs);
    write_four_modes(runs);
    write_log(runs, "zeta", 1, 0.853, 0.0123, 0.05);
    write_log(runs, "alpha", 3, 0.853, 0.0123, 0.05); /* seed 3 of 2: not a mode of this run */
    SgError err = {0};
    /* discovered: the known modes in order, then the others by name; an
     * explicit comparison replaces guided over openpgl */
    cr_assert_eq(run_analyze(runs, tables, "--compare", "openpgl:skeleton", &err), 0, "%s", err.message);
    const char *head = slurp(tables, "table2-relmse.head");
    cr_assert(strstr(head, "| openpgl s | zeta s | skeleton speed-up |"), "%s", head);
    cr_assert(strstr(head, "| zeta speed-up | openpgl over skeleton |\n"), "%s", head);
    cr_assert_null(strstr(head, "alpha"));
    cr_assert_str_eq(cell(slurp(tables, "table2-relmse.md"), 1, 11), "~4.00"); /* 19.8 s / 4.96 s */

    /* refusals */
    err = (SgError){0};
    cr_assert_neq(run_analyze(runs, tables, "--compare", "guided:nope", &err), 0);
    cr_assert(strstr(err.message, "guided:nope"), "%s", err.message);
    err = (SgError){0};
    cr_assert_neq(run_analyze(runs, tables, "--modes", "bsdf,,guided", &err), 0);
    err = (SgError){0};
    cr_assert_neq(run_analyze(runs, tables, "--modes", "bsdf,guided,bsdf", &err), 0);
    cr_assert(strstr(err.message, "twice"), "%s", err.message);
    /* a mode without runs keeps its columns, with "-" */
    err = (SgError){0};
    char empty[512];
    snprintf(empty, sizeof empty, "%s/../empty", tables);
    cr_assert(mkdir(empty, 0755) == 0);
    cr_assert_eq(run_analyze(runs, empty, "--modes", "bsdf,guided,openpgl,missing", &err), 0, "%s", err.message);
    const char *rel = slurp(empty, "table2-relmse.md");
    cr_assert_str_eq(cell(rel, 1, 5), "-");
    cr_assert_str_eq(cell(rel, 1, 8), "-");
    cr_assert_str_eq(cell(rel, 1, 9), "2.00");
    /* without bsdf there is nothing to compare with */
    char lone[512];
    snprintf(lone, sizeof lone, "%s/../lone", tables);
    cr_assert(mkdir(lone, 0755) == 0);
    write_log(lone, "guided", 1, 0.2, 0.01, 0.05);
    err = (SgError){0};
    cr_assert_neq(run_analyze(lone, empty, NULL, NULL, &err), 0);
    cr_assert(strstr(err.message, "no bsdf curve"), "%s", err.message);
}
