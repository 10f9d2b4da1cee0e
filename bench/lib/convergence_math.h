/* The arithmetic of the convergence benchmark (bench/convergence.c), in the
 * bench library (libbench.a) so that tests/test_bench_convergence.c can
 * check it on synthetic curves.
 *
 * A curve is what `render --reference REF --log CSV` writes: one row per
 * pass, `seconds,spp,mse,relmse,mse8`. Errors of unbiased Monte Carlo fall
 * as 1/time, so curves are compared on log-log axes: interpolation between
 * two passes is linear in (log t, log error), and a level not reached
 * within the run is extrapolated along 1/t from the curve's last half. */
#ifndef SG_CONVERGENCE_MATH_H
#define SG_CONVERGENCE_MATH_H

#include <stdbool.h>
#include <stddef.h>

#include "color.h"
#include "error.h"
#include "error_metrics.h"

/* relMSE (on the exposed image), 8-bit MSE (the PNG's bytes) and the plain
 * MSE of the linear radiance (the CSV's mse column, unexposed). */
enum { SG_METRIC_RELMSE, SG_METRIC_MSE8, SG_METRIC_MSE, SG_METRIC_COUNT };

typedef struct SgCurve {
    size_t count;
    double *seconds;                 /* increasing */
    double *spp;
    double *error[SG_METRIC_COUNT];  /* relMSE, 8-bit MSE, linear MSE */
} SgCurve;

/* Allocates a curve of `count` zeroed points. */
bool sg_curve_alloc(SgCurve *c, size_t count, SgError *err);
void sg_curve_free(SgCurve *c);

/* Reads render's error log; refuses a missing header, a malformed or
 * non-finite number, decreasing time and an empty log ("FILE: cause"). */
bool sg_curve_read_csv(const char *path, SgCurve *c, SgError *err);

/* Value of a metric at time t (log-log interpolation between the passes
 * around t); false when t lies outside the curve. */
bool sg_curve_at(const SgCurve *c, int metric, double t, double *value);
/* The same for the spp column (linear in t). */
bool sg_curve_spp_at(const SgCurve *c, double t, double *spp);

/* Mean of n curves (e.g. seeds) on `points` log-spaced times spanning the
 * range every curve covers; fails when the curves share no time range. */
bool sg_curve_mean(const SgCurve *curves, size_t n, size_t points, SgCurve *mean, SgError *err);

/* Least-squares slope of log error against log time over the last half of
 * the curve in time (t >= t_end / 2); 0 with fewer than 3 points there. */
double sg_curve_tail_slope(const SgCurve *c, int metric);

typedef enum SgReachKind {
    SG_REACH_INTERPOLATED,  /* crossed between two points of the curve */
    SG_REACH_BEFORE_FIRST,  /* already below the level at the first point */
    SG_REACH_EXTRAPOLATED,  /* after the end: 1/t law from the last half */
    SG_REACH_BEYOND,        /* 1/t would take more than SG_EXTRAPOLATION_LIMIT
                               times the run: seconds is that lower bound */
    SG_REACH_NEVER,         /* not reached and the tail is too flat for 1/t
                               (a biased estimator stuck on its bias) */
    SG_REACH_NONE           /* no curve */
} SgReachKind;

typedef struct SgReach {
    SgReachKind kind;
    double seconds; /* the time; for BEFORE_FIRST the first point's time */
} SgReach;

/* Tails flatter than this (log-log slope) are not extrapolated. */
#define SG_TAIL_SLOPE_LIMIT (-0.5)
/* Extrapolations further than this many times the run's length are only
 * reported as a bound (the tail says little about that far). */
#define SG_EXTRAPOLATION_LIMIT 50.0

/* First time the curve is at or below `level`. */
SgReach sg_curve_time_to_level(const SgCurve *c, int metric, double level);

/* Smallest number of two significant digits >= x > 0 (0.00214 -> 0.0022,
 * 2437 -> 2500): a readable level that a curve through x still reaches. */
double sg_level_at_least(double x);

/* "3.21", "~41.2" (extrapolated), "< 0.02" (before the first point),
 * "> 600" (beyond the extrapolation limit), "never" (flat tail), "-" (no
 * curve). */
void sg_reach_format(SgReach r, char *buf, size_t size);
/* Speed-up of `mode` over `base` at one level, base seconds / mode seconds,
 * with the same marks: "~2.10" when either is extrapolated, "> 3.00" /
 * "< 3.00" when a time is a bound, "0 (never)" when only the mode never
 * gets there, "-" when it cannot be said. */
void sg_ratio_format(SgReach base, SgReach mode, char *buf, size_t size);

/* A reference made of two independent halves a and b (same spp) is
 * r = (a + b) / 2; (a - b)^2 / 4 estimates its squared error per value
 * without bias. Returns the reference's own relMSE (render's definition:
 * mean of e^2 / (r^2 + 0.01) on the image times `scale`), 8-bit MSE (at
 * `scale` = 2^exposure; the byte difference of the halves, halved: a
 * first-order estimate) and linear MSE (unscaled, like render's mse).
 * Writes r into `ref` (may be NULL). n counts floats. */
void sg_reference_from_halves(const float *a, const float *b, size_t n, float scale, float *ref,
                              double *relmse, double *mse8, double *mse);

#endif
