/* The convergence benchmark's arithmetic (bench/convergence_math.h) on
 * synthetic curves whose answers are known in closed form: error = C / t
 * (unbiased Monte Carlo), a biased curve that flattens, seeds with
 * different pass times, and a reference made of two noisy halves. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define SG_CONVERGENCE_MATH_IMPLEMENTATION
#include "bench/convergence_math.h"
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
    double relmse, mse8;
    sg_reference_from_halves(a, b, n, 1.0f, ref, &relmse, &mse8);
    double true_rel = 0, true8 = 0;
    for (size_t i = 0; i < n; i++) {
        cr_assert_float_eq(ref[i], 0.5f * (a[i] + b[i]), 1e-6);
        double d = (double)ref[i] - truth[i];
        true_rel += sg_relmse_term(d, ref[i], sg_relmse_epsilon(1.0f)) / (double)n;
        double d8 = sg_srgb_byte(ref[i]) - sg_srgb_byte(truth[i]);
        true8 += d8 * d8 / (double)n;
    }
    cr_assert(fabs(relmse / true_rel - 1) < 0.03, "estimated relMSE %g, true %g", relmse, true_rel);
    cr_assert(fabs(mse8 / true8 - 1) < 0.15, "estimated mse8 %g, true %g", mse8, true8);
    /* identical halves: no error */
    sg_reference_from_halves(a, a, n, 1.0f, NULL, &relmse, &mse8);
    cr_assert_eq(relmse, 0.0);
    cr_assert_eq(mse8, 0.0);
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
    sg_curve_free(&c);

    static const char *const bad[][2] = {
        {"", "header"},
        {"seconds,spp,mse,relmse,mse8\n", "no rows"},
        {"seconds,spp,mse,relmse,mse8\n0.1,1,0.5,nan,3\n", "malformed"},
        {"seconds,spp,mse,relmse,mse8\n0.1,1,0.5,0.2\n", "malformed"},
        {"seconds,spp,mse,relmse,mse8\n0.1,1,0.5,0.2,3,4\n", "malformed"},
        {"seconds,spp,mse,relmse,mse8\n0.2,1,0.5,0.2,3\n0.1,2,0.5,0.2,3\n", "does not increase"},
        {"seconds,spp,mse,relmse,mse8\n0.2,1,0.5,-0.2,3\n", "negative"},
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
