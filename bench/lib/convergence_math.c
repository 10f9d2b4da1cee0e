/* The convergence benchmark's arithmetic: see convergence_math.h. */
#include "convergence_math.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "shard_format.h" /* SG_ERROR_LOG_HEADER */

bool sg_curve_alloc(SgCurve *c, size_t count, SgError *err)
{
    memset(c, 0, sizeof *c);
    size_t n = count ? count : 1;
    c->seconds = calloc(n, sizeof(double));
    c->spp = calloc(n, sizeof(double));
    for (int m = 0; m < SG_METRIC_COUNT; m++)
        c->error[m] = calloc(n, sizeof(double));
    bool ok = c->seconds && c->spp;
    for (int m = 0; m < SG_METRIC_COUNT; m++)
        ok = ok && c->error[m];
    if (!ok) {
        sg_curve_free(c);
        return sg_fail(err, "curve: out of memory for %zu points", count);
    }
    c->count = count;
    return true;
}

void sg_curve_free(SgCurve *c)
{
    free(c->seconds);
    free(c->spp);
    for (int m = 0; m < SG_METRIC_COUNT; m++)
        free(c->error[m]);
    memset(c, 0, sizeof *c);
}

static bool sg_curve_parse_number(const char **p, double *v)
{
    char *end;
    errno = 0;
    *v = strtod(*p, &end);
    if (end == *p || errno == ERANGE || !isfinite(*v))
        return false;
    *p = end;
    return true;
}

bool sg_curve_read_csv(const char *path, SgCurve *c, SgError *err)
{
    memset(c, 0, sizeof *c);
    FILE *f = fopen(path, "r");
    if (!f)
        return sg_fail(err, "%s: cannot open: %s", path, strerror(errno));
    char line[512];
    /* the five columns read here; a log may carry more after them */
    const char *head = "seconds,spp,mse,relmse,mse8";
    if (!fgets(line, sizeof line, f) || strncmp(line, head, strlen(head)) != 0) {
        fclose(f);
        return sg_fail(err, "%s: not an error log (header %s missing)", path, head);
    }
    int extra = 0; /* columns after the five */
    for (const char *q = line + strlen(head); *q; q++)
        extra += *q == ',';
    size_t capacity = 0, row = 1;
    SgCurve grow = {0};
    bool ok = true;
    while (fgets(line, sizeof line, f)) {
        row++;
        if (line[0] == '\n' || line[0] == '\0')
            continue;
        if (!strchr(line, '\n') && !feof(f)) {
            ok = sg_fail(err, "%s:%zu: line too long", path, row);
            break;
        }
        double v[5], ignored;
        const char *p = line;
        bool row_ok = true;
        for (int k = 0; k < 5 + extra && row_ok; k++) {
            row_ok = sg_curve_parse_number(&p, k < 5 ? &v[k] : &ignored);
            if (row_ok && k < 4 + extra)
                row_ok = *p++ == ',';
        }
        while (row_ok && (*p == '\n' || *p == '\r' || *p == ' '))
            p++;
        if (!row_ok || *p != '\0') {
            ok = sg_fail(err, "%s:%zu: malformed row (want %d finite numbers)", path, row, 5 + extra);
            break;
        }
        if (v[0] < 0 || v[1] < 0 || v[2] < 0 || v[3] < 0 || v[4] < 0) {
            ok = sg_fail(err, "%s:%zu: negative value", path, row);
            break;
        }
        if (grow.count > 0 && v[0] <= grow.seconds[grow.count - 1]) {
            ok = sg_fail(err, "%s:%zu: time does not increase", path, row);
            break;
        }
        if (grow.count == capacity) {
            size_t cap = capacity ? 2 * capacity : 256;
            SgCurve next;
            if (!sg_curve_alloc(&next, cap, err)) {
                ok = false;
                break;
            }
            if (grow.count) {
                memcpy(next.seconds, grow.seconds, grow.count * sizeof(double));
                memcpy(next.spp, grow.spp, grow.count * sizeof(double));
                for (int m = 0; m < SG_METRIC_COUNT; m++)
                    memcpy(next.error[m], grow.error[m], grow.count * sizeof(double));
            }
            next.count = grow.count;
            sg_curve_free(&grow);
            grow = next;
            capacity = cap;
        }
        size_t i = grow.count++;
        grow.seconds[i] = v[0];
        grow.spp[i] = v[1];
        grow.error[SG_METRIC_RELMSE][i] = v[3];
        grow.error[SG_METRIC_MSE8][i] = v[4];
        grow.error[SG_METRIC_MSE][i] = v[2];
    }
    if (ok && ferror(f))
        ok = sg_fail(err, "%s: read error", path);
    fclose(f);
    if (ok && grow.count == 0)
        ok = sg_fail(err, "%s: no rows", path);
    if (!ok) {
        sg_curve_free(&grow);
        return false;
    }
    *c = grow;
    return true;
}

/* log that survives an exact zero (an image equal to its reference). */
static double sg_curve_log(double x) { return log(x > 1e-300 ? x : 1e-300); }

/* Index i with seconds[i] <= t <= seconds[i + 1]; false outside. */
static bool sg_curve_bracket(const SgCurve *c, double t, size_t *i)
{
    if (c->count == 0 || t < c->seconds[0] || t > c->seconds[c->count - 1])
        return false;
    size_t lo = 0, hi = c->count - 1;
    while (hi - lo > 1) {
        size_t mid = lo + (hi - lo) / 2;
        if (c->seconds[mid] <= t)
            lo = mid;
        else
            hi = mid;
    }
    *i = lo;
    return true;
}

bool sg_curve_at(const SgCurve *c, int metric, double t, double *value)
{
    size_t i;
    if (!sg_curve_bracket(c, t, &i))
        return false;
    const double *e = c->error[metric];
    if (c->count == 1 || t == c->seconds[i]) {
        *value = e[i];
        return true;
    }
    double lt0 = sg_curve_log(c->seconds[i]), lt1 = sg_curve_log(c->seconds[i + 1]);
    double w = (sg_curve_log(t) - lt0) / (lt1 - lt0);
    *value = exp((1 - w) * sg_curve_log(e[i]) + w * sg_curve_log(e[i + 1]));
    return true;
}

bool sg_curve_spp_at(const SgCurve *c, double t, double *spp)
{
    size_t i;
    if (!sg_curve_bracket(c, t, &i))
        return false;
    if (c->count == 1 || t == c->seconds[i]) {
        *spp = c->spp[i];
        return true;
    }
    double w = (t - c->seconds[i]) / (c->seconds[i + 1] - c->seconds[i]);
    *spp = (1 - w) * c->spp[i] + w * c->spp[i + 1];
    return true;
}

bool sg_curve_mean(const SgCurve *curves, size_t n, size_t points, SgCurve *mean, SgError *err)
{
    memset(mean, 0, sizeof *mean);
    if (n == 0 || points < 2)
        return sg_fail(err, "curve mean: needs at least one curve and two points");
    double t0 = 0, t1 = INFINITY;
    for (size_t k = 0; k < n; k++) {
        if (curves[k].count == 0)
            return sg_fail(err, "curve mean: curve %zu is empty", k);
        t0 = fmax(t0, curves[k].seconds[0]);
        t1 = fmin(t1, curves[k].seconds[curves[k].count - 1]);
    }
    if (!(t0 > 0) || !(t1 > t0))
        return sg_fail(err, "curve mean: the curves share no time range (%g to %g s)", t0, t1);
    if (!sg_curve_alloc(mean, points, err))
        return false;
    double lt0 = log(t0), lt1 = log(t1);
    for (size_t j = 0; j < points; j++) {
        /* both ends exact, so that no curve is asked outside its range */
        double t = j == 0 ? t0 : j == points - 1 ? t1 : exp(lt0 + (lt1 - lt0) * (double)j / (double)(points - 1));
        mean->seconds[j] = t;
        for (size_t k = 0; k < n; k++) {
            double v, s;
            for (int m = 0; m < SG_METRIC_COUNT; m++) {
                sg_curve_at(&curves[k], m, t, &v);
                mean->error[m][j] += v / (double)n;
            }
            sg_curve_spp_at(&curves[k], t, &s);
            mean->spp[j] += s / (double)n;
        }
    }
    return true;
}

/* First index of the last half of the curve in time. */
static size_t sg_curve_tail_start(const SgCurve *c)
{
    double half = 0.5 * c->seconds[c->count - 1];
    size_t i = c->count - 1;
    while (i > 0 && c->seconds[i - 1] >= half)
        i--;
    return i;
}

double sg_curve_tail_slope(const SgCurve *c, int metric)
{
    if (c->count < 3)
        return 0.0;
    size_t start = sg_curve_tail_start(c);
    size_t n = c->count - start;
    if (n < 3)
        return 0.0;
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (size_t i = start; i < c->count; i++) {
        double x = sg_curve_log(c->seconds[i]), y = sg_curve_log(c->error[metric][i]);
        sx += x;
        sy += y;
        sxx += x * x;
        sxy += x * y;
    }
    double d = (double)n * sxx - sx * sx;
    return d > 0 ? ((double)n * sxy - sx * sy) / d : 0.0;
}

SgReach sg_curve_time_to_level(const SgCurve *c, int metric, double level)
{
    SgReach r = {SG_REACH_NONE, 0.0};
    if (c->count == 0)
        return r;
    const double *e = c->error[metric];
    for (size_t i = 0; i < c->count; i++) {
        if (e[i] > level)
            continue;
        if (i == 0) {
            r.kind = SG_REACH_BEFORE_FIRST;
            r.seconds = c->seconds[0];
            return r;
        }
        double le0 = sg_curve_log(e[i - 1]), le1 = sg_curve_log(e[i]);
        double lt0 = sg_curve_log(c->seconds[i - 1]), lt1 = sg_curve_log(c->seconds[i]);
        double w = le1 < le0 ? (sg_curve_log(level) - le0) / (le1 - le0) : 1.0;
        r.kind = SG_REACH_INTERPOLATED;
        r.seconds = exp(lt0 + w * (lt1 - lt0));
        return r;
    }
    /* Not reached: error * time is constant under 1/t; its geometric mean
     * over the last half is steadier than the last point alone. */
    if (c->count < 3 || sg_curve_tail_slope(c, metric) > SG_TAIL_SLOPE_LIMIT) {
        r.kind = SG_REACH_NEVER;
        return r;
    }
    size_t start = sg_curve_tail_start(c);
    double s = 0;
    for (size_t i = start; i < c->count; i++)
        s += sg_curve_log(e[i]) + sg_curve_log(c->seconds[i]);
    r.kind = SG_REACH_EXTRAPOLATED;
    r.seconds = exp(s / (double)(c->count - start)) / level;
    double limit = SG_EXTRAPOLATION_LIMIT * c->seconds[c->count - 1];
    if (r.seconds > limit) {
        r.kind = SG_REACH_BEYOND;
        r.seconds = limit;
    }
    return r;
}

double sg_level_at_least(double x)
{
    if (!(x > 0) || !isfinite(x))
        return NAN;
    double unit = pow(10.0, floor(log10(x)) - 1);
    /* tolerate the rounding of pow/log10 around exact two-digit values */
    double v = ceil(x / unit * (1 - 1e-12)) * unit;
    return v;
}

/* Seconds with three significant figures, at most two decimals. */
static void sg_format_seconds(double s, char *buf, size_t size)
{
    if (s >= 100)
        snprintf(buf, size, "%.0f", s);
    else if (s >= 10)
        snprintf(buf, size, "%.1f", s);
    else if (s >= 0.1)
        snprintf(buf, size, "%.2f", s);
    else
        snprintf(buf, size, "%.3f", s);
}

void sg_reach_format(SgReach r, char *buf, size_t size)
{
    char s[64];
    sg_format_seconds(r.seconds, s, sizeof s);
    switch (r.kind) {
    case SG_REACH_INTERPOLATED: snprintf(buf, size, "%s", s); break;
    case SG_REACH_EXTRAPOLATED: snprintf(buf, size, "~%s", s); break;
    case SG_REACH_BEFORE_FIRST: snprintf(buf, size, "< %s", s); break;
    case SG_REACH_BEYOND: snprintf(buf, size, "> %s", s); break;
    case SG_REACH_NEVER: snprintf(buf, size, "never"); break;
    default: snprintf(buf, size, "-"); break;
    }
}

/* Which way a reported time may be off: 0 exact (or ~), -1 the true time
 * is at most this (before the first pass), +1 at least this. */
static int sg_reach_bound(SgReach r)
{
    return r.kind == SG_REACH_BEFORE_FIRST ? -1 : r.kind == SG_REACH_BEYOND ? 1 : 0;
}

void sg_ratio_format(SgReach base, SgReach mode, char *buf, size_t size)
{
    if (base.kind == SG_REACH_NONE || mode.kind == SG_REACH_NONE ||
        (base.kind == SG_REACH_NEVER && mode.kind == SG_REACH_NEVER)) {
        snprintf(buf, size, "-");
        return;
    }
    if (mode.kind == SG_REACH_NEVER) {
        snprintf(buf, size, "0 (never)");
        return;
    }
    if (base.kind == SG_REACH_NEVER) {
        snprintf(buf, size, "inf");
        return;
    }
    /* ratio = base / mode: a bound on base bounds it the same way, a bound
     * on mode the other way */
    int b = sg_reach_bound(base), m = -sg_reach_bound(mode);
    double ratio = base.seconds / mode.seconds;
    char r[32]; /* two decimals, two significant digits below 0.1 */
    snprintf(r, sizeof r, ratio >= 0.1 ? "%.2f" : "%.2g", ratio);
    if (b != 0 && m != 0 && b != m)
        snprintf(buf, size, "-");
    else if (b + m < 0)
        snprintf(buf, size, "< %s", r);
    else if (b + m > 0)
        snprintf(buf, size, "> %s", r);
    else {
        bool approx = base.kind == SG_REACH_EXTRAPOLATED || mode.kind == SG_REACH_EXTRAPOLATED;
        snprintf(buf, size, "%s%s", approx ? "~" : "", r);
    }
}

void sg_reference_from_halves(const float *a, const float *b, size_t n, float scale, float *ref,
                              double *relmse, double *mse8, double *mse)
{
    double rs = 0, s8 = 0, s = 0;
    double eps = sg_relmse_epsilon(scale); /* render's relMSE: on the exposed image */
    for (size_t i = 0; i < n; i++) {
        double r = 0.5 * ((double)a[i] + b[i]);
        double half = 0.5 * ((double)a[i] - b[i]);
        rs += sg_relmse_term(half, r, eps);
        s += half * half;
        double d8 = sg_srgb_byte(a[i] * scale) - sg_srgb_byte(b[i] * scale);
        s8 += 0.25 * d8 * d8;
        if (ref)
            ref[i] = (float)r;
    }
    *relmse = n ? rs / (double)n : 0.0;
    *mse8 = n ? s8 / (double)n : 0.0;
    *mse = n ? s / (double)n : 0.0;
}
