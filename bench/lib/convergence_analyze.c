/* `convergence analyze`: see convergence_analyze.h. */
#include "convergence_analyze.h"

#include <dirent.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "convergence_math.h"
#include "image_io.h"
#include "output_file.h"
#include "render/renderer.h"

/* points of a mean curve, log-spaced in time */
#define SG_ANALYZE_MEAN_POINTS 120

static const char *const sg_metric_key[SG_METRIC_COUNT] = {"relmse", "mse8", "mse"};
static const char *const sg_metric_title[SG_METRIC_COUNT] = {"relMSE", "mse8", "MSE"};

typedef struct SgModeResult {
    bool present;
    int seeds;             /* curves read */
    SgCurve mean;
    double us_per_sample;  /* wall time per sample over all threads, mean of seeds */
    double final_spp;      /* mean of seeds */
    /* from the runs' EXR attributes (means over the runs that have them) */
    int trained_runs;
    double training_passes, training_seconds, run_seconds, guide_share;
    double training_phase;  /* seconds until the last training pass ended */
} SgModeResult;

static double sg_attr_number(const char *path, const char *name, bool *ok)
{
    char buf[128];
    SgError e = {0};
    if (!sg_image_read_attribute(path, name, buf, sizeof buf, &e)) {
        *ok = false;
        return NAN;
    }
    char *end;
    double v = strtod(buf, &end);
    if (end == buf || !isfinite(v))
        *ok = false;
    return v;
}

static bool sg_analyze_load_mode(const char *dir, const char *mode, int seeds, SgModeResult *res, SgError *err)
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
        /* what the guide did, from the image (absent or 0 passes: no field) */
        snprintf(path, sizeof path, "%s/%s-%d.exr", dir, mode, s);
        bool ok = true;
        double passes = sg_attr_number(path, SG_ATTR_TRAINING_PASSES, &ok);
        double tsec = sg_attr_number(path, SG_ATTR_TRAINING_SECONDS, &ok);
        double run = sg_attr_number(path, "seconds", &ok);
        double share = sg_attr_number(path, SG_ATTR_GUIDE_SHARE, &ok);
        if (ok && passes > 0 && run > 0) {
            const SgCurve *c = &curves[n];
            double phase = c->seconds[c->count - 1];
            for (size_t i = 0; i < c->count; i++)
                if (c->spp[i] >= passes) {
                    phase = c->seconds[i];
                    break;
                }
            res->trained_runs++;
            res->training_passes += passes;
            res->training_seconds += tsec;
            res->run_seconds += run;
            res->guide_share += share;
            res->training_phase += phase;
        }
        n++;
    }
    if (res->trained_runs > 0) {
        double k = res->trained_runs;
        res->training_passes /= k;
        res->training_seconds /= k;
        res->run_seconds /= k;
        res->guide_share /= k;
        res->training_phase /= k;
    }
    if (n == 0)
        return true;
    bool ok = sg_curve_mean(curves, (size_t)n, SG_ANALYZE_MEAN_POINTS, &res->mean, err);
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

/* Opens DIR/NAME SUFFIX for writing (through a temporary name until committed). */
static bool sg_analyze_open(SgOutputFile *out, const char *dir, const char *name, const char *suffix,
                            SgError *err)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s%s", dir, name, suffix);
    return sg_output_open(out, path, err);
}

static bool sg_analyze_write_mean(const char *dir, const char *mode, const SgCurve *c, SgError *err)
{
    SgOutputFile out;
    if (!sg_analyze_open(&out, dir, mode, ".mean.dat", err))
        return false;
    fprintf(out.file, "# seconds spp relmse mse8 mse (mean of seeds)\n");
    for (size_t i = 0; i < c->count; i++)
        fprintf(out.file, "%.6g %.6g %.6g %.6g %.6g\n", c->seconds[i], c->spp[i], c->error[SG_METRIC_RELMSE][i],
                c->error[SG_METRIC_MSE8][i], c->error[SG_METRIC_MSE][i]);
    return sg_output_commit(&out, err);
}

static bool sg_analyze_append(const char *dir, const char *file, const char *text, SgError *err)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, file);
    FILE *f = fopen(path, "a");
    if (!f)
        return sg_fail(err, "%s: cannot append", path);
    fputs(text, f);
    bool ok = !ferror(f);
    ok = fclose(f) == 0 && ok;
    return ok ? true : sg_fail(err, "%s: write error", path);
}

/* TABLEDIR/FILE.head (FILE without .md) := the header and its rule */
static bool sg_analyze_header(const char *dir, const char *table, const char *header, SgError *err)
{
    SgOutputFile out;
    if (!sg_analyze_open(&out, dir, table, ".head", err))
        return false;
    fprintf(out.file, "%s\n|", header);
    for (const char *p = header + 1; *p; p++) /* one |---| per column */
        if (*p == '|')
            fputs("---|", out.file);
    fputc('\n', out.file);
    return sg_output_commit(&out, err);
}

/* "%.3g" without the exponent form for the usual ranges of our errors. */
static void sg_format_error(double v, char *buf, size_t size)
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

/* Appends printf output to a growing line (silently cut at `size`). */
static void sg_cat(char *line, size_t size, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static void sg_cat(char *line, size_t size, const char *fmt, ...)
{
    size_t used = strlen(line);
    if (used + 1 >= size)
        return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line + used, size - used, fmt, ap);
    va_end(ap);
}

/* the name in the tables' crowded cells */
static const char *sg_short_mode(const char *m) { return !strcmp(m, "skeleton") ? "skel." : m; }

static int sg_mode_index(char names[][64], int count, const char *name)
{
    for (int m = 0; m < count; m++)
        if (!strcmp(names[m], name))
            return m;
    return -1;
}

/* the order of discovered modes: render's sampling modes in their own
 * order; any other (a variant such as guided-albedo) after, by name */
static int sg_known_rank(const char *name)
{
    SgSampling s;
    return sg_sampling_parse(name, &s) ? (int)s : SG_SAMPLING_COUNT;
}

static int sg_mode_order(const void *a, const void *b)
{
    const char *x = a, *y = b;
    int rx = sg_known_rank(x), ry = sg_known_rank(y);
    return rx != ry ? rx - ry : strcmp(x, y);
}

/* The modes with a RUNDIR/MODE-SEED.csv, SEED in 1..seeds. */
static bool sg_discover_modes(const char *dir, int seeds, char names[][64], int *count, SgError *err)
{
    DIR *d = opendir(dir);
    if (!d)
        return sg_fail(err, "%s: cannot list", dir);
    *count = 0;
    struct dirent *e;
    bool ok = true;
    while ((e = readdir(d))) {
        const char *s = e->d_name, *dash = strrchr(s, '-');
        size_t len = strlen(s);
        if (!dash || dash == s || len < 5 || strcmp(s + len - 4, ".csv"))
            continue;
        char *end;
        long seed = strtol(dash + 1, &end, 10);
        if (end != s + len - 4 || end == dash + 1 || seed < 1 || seed > seeds)
            continue;
        size_t nlen = (size_t)(dash - s);
        if (nlen >= 64)
            continue;
        char name[64];
        memcpy(name, s, nlen);
        name[nlen] = '\0';
        if (sg_mode_index(names, *count, name) >= 0)
            continue;
        if (*count == SG_ANALYZE_MAX_MODES) {
            ok = sg_fail(err, "%s: more than %d modes", dir, SG_ANALYZE_MAX_MODES);
            break;
        }
        memcpy(names[(*count)++], name, nlen + 1);
    }
    closedir(d);
    if (!ok)
        return false;
    qsort(names, (size_t)*count, sizeof names[0], sg_mode_order);
    if (*count == 0 || strcmp(names[0], "bsdf"))
        return sg_fail(err, "%s: no bsdf curve: nothing to compare with", dir);
    return true;
}

/* "a,b,c" into names */
static bool sg_parse_modes(const char *list, char names[][64], int *count, SgError *err)
{
    *count = 0;
    const char *p = list;
    while (*p) {
        const char *comma = strchr(p, ',');
        size_t len = comma ? (size_t)(comma - p) : strlen(p);
        if (len == 0 || len >= 64 || memchr(p, '/', len))
            return sg_fail(err, "analyze: --modes %s: want names separated by commas", list);
        if (*count == SG_ANALYZE_MAX_MODES)
            return sg_fail(err, "analyze: --modes %s: at most %d modes", list, SG_ANALYZE_MAX_MODES);
        memcpy(names[*count], p, len);
        names[*count][len] = '\0';
        if (sg_mode_index(names, *count, names[*count]) >= 0)
            return sg_fail(err, "analyze: --modes %s: %s twice", list, names[*count]);
        (*count)++;
        p += len + (comma ? 1 : 0);
        if (comma && !*p)
            return sg_fail(err, "analyze: --modes %s: want names separated by commas", list);
    }
    return *count > 0 ? true : sg_fail(err, "analyze: --modes: empty");
}

/* What the command line asks for. */
typedef struct SgAnalyzeOptions {
    const char *name, *dir, *tables, *size, *ref_state, *modes_arg;
    int seeds;
    const char *compare_arg[SG_ANALYZE_MAX_COMPARE];
    int compare_args;
    double ref_err[SG_METRIC_COUNT], ref_spp, ref_seconds;
} SgAnalyzeOptions;

/* The modes compared, their mean curves and the levels they are timed to. */
typedef struct SgAnalysis {
    char names[SG_ANALYZE_MAX_MODES][64];
    int nm;
    int cmp[SG_ANALYZE_MAX_COMPARE][2], nc; /* speed-up columns: mode index over mode index */
    int i_guided, i_pgl, i_skel;
    SgModeResult res[SG_ANALYZE_MAX_MODES];
    double levels[SG_METRIC_COUNT][2];
    SgReach headline[SG_ANALYZE_MAX_MODES]; /* relMSE at the lower level */
} SgAnalysis;

static bool sg_analyze_parse_options(int argc, char **argv, SgAnalyzeOptions *o, SgError *err)
{
    if (argc < 6)
        return sg_fail(err, "analyze: want NAME RUNDIR SEEDS TABLEDIR");
    *o = (SgAnalyzeOptions){.name = argv[2], .dir = argv[3], .tables = argv[5], .size = "?", .ref_state = "",
                            .ref_spp = NAN, .ref_seconds = NAN};
    o->seeds = atoi(argv[4]);
    if (o->seeds < 1 || o->seeds > 64)
        return sg_fail(err, "analyze: SEEDS %s: want 1 to 64", argv[4]);
    for (int k = 0; k < SG_METRIC_COUNT; k++)
        o->ref_err[k] = NAN;
    for (int i = 6; i < argc; i++) {
        bool has = i + 1 < argc;
        double *target = NULL;
        if (has && !strcmp(argv[i], "--size"))
            o->size = argv[++i];
        else if (has && !strcmp(argv[i], "--ref-state"))
            o->ref_state = argv[++i];
        else if (has && !strcmp(argv[i], "--modes"))
            o->modes_arg = argv[++i];
        else if (has && !strcmp(argv[i], "--compare")) {
            if (o->compare_args == SG_ANALYZE_MAX_COMPARE)
                return sg_fail(err, "analyze: at most %d --compare", SG_ANALYZE_MAX_COMPARE);
            o->compare_arg[o->compare_args++] = argv[++i];
        } else if (has && !strcmp(argv[i], "--ref-relmse"))
            target = &o->ref_err[SG_METRIC_RELMSE];
        else if (has && !strcmp(argv[i], "--ref-mse8"))
            target = &o->ref_err[SG_METRIC_MSE8];
        else if (has && !strcmp(argv[i], "--ref-mse"))
            target = &o->ref_err[SG_METRIC_MSE];
        else if (has && !strcmp(argv[i], "--ref-spp"))
            target = &o->ref_spp;
        else if (has && !strcmp(argv[i], "--ref-seconds"))
            target = &o->ref_seconds;
        else
            return sg_fail(err, "analyze: unexpected argument %s", argv[i]);
        if (target) {
            char *end;
            *target = strtod(argv[++i], &end);
            if (end == argv[i] || *end || !isfinite(*target))
                return sg_fail(err, "analyze: %s %s: not a number", argv[i - 1], argv[i]);
        }
    }
    return true;
}

/* The modes (named or discovered) and the speed-up columns between them. */
static bool sg_analyze_choose_modes(const SgAnalyzeOptions *o, SgAnalysis *a, SgError *err)
{
    if (o->modes_arg ? !sg_parse_modes(o->modes_arg, a->names, &a->nm, err)
                     : !sg_discover_modes(o->dir, o->seeds, a->names, &a->nm, err))
        return false;
    for (int c = 0; c < o->compare_args; c++) {
        char x[64], y[64];
        const char *arg = o->compare_arg[c], *colon = strchr(arg, ':');
        size_t la = colon ? (size_t)(colon - arg) : 0;
        if (!colon || la == 0 || la >= 64 || strlen(colon + 1) >= 64)
            return sg_fail(err, "analyze: --compare %s: want MODE:MODE", arg);
        memcpy(x, arg, la);
        x[la] = '\0';
        snprintf(y, sizeof y, "%s", colon + 1);
        int *pair = a->cmp[a->nc];
        pair[0] = sg_mode_index(a->names, a->nm, x);
        pair[1] = sg_mode_index(a->names, a->nm, y);
        if (pair[0] < 0 || pair[1] < 0 || pair[0] == pair[1])
            return sg_fail(err, "analyze: --compare %s: want two different modes of the run", arg);
        a->nc++;
    }
    a->i_guided = sg_mode_index(a->names, a->nm, "guided");
    a->i_pgl = sg_mode_index(a->names, a->nm, "openpgl");
    a->i_skel = sg_mode_index(a->names, a->nm, "skeleton");
    if (o->compare_args == 0 && a->i_guided > 0 && a->i_pgl > 0) {
        a->cmp[0][0] = a->i_guided;
        a->cmp[0][1] = a->i_pgl;
        a->nc = 1;
    }
    return true;
}

/* Every mode's mean curve, written as RUNDIR/MODE.mean.dat. */
static bool sg_analyze_load_modes(const SgAnalyzeOptions *o, SgAnalysis *a, SgError *err)
{
    for (int m = 0; m < a->nm; m++) {
        if (!sg_analyze_load_mode(o->dir, a->names[m], o->seeds, &a->res[m], err))
            return false;
        if (a->res[m].present && !sg_analyze_write_mean(o->dir, a->names[m], &a->res[m].mean, err))
            return false;
    }
    if (!a->res[0].present)
        return sg_fail(err, "%s: no %s curve: nothing to compare with", o->dir, a->names[0]);
    return true;
}

/* Levels from the baseline only, the same for every mode: its mean error at
 * the end of its run and at an eighth of it, each rounded up to two
 * significant digits (so the baseline reaches them just before). Written to
 * RUNDIR/levels.txt. */
static bool sg_analyze_levels(const SgAnalyzeOptions *o, SgAnalysis *a, SgError *err)
{
    const SgCurve *bc = &a->res[0].mean;
    double t_end = bc->seconds[bc->count - 1], t_early = fmax(t_end / 8, bc->seconds[0]);
    for (int k = 0; k < SG_METRIC_COUNT; k++) {
        double end = bc->error[k][bc->count - 1], early;
        if (!sg_curve_at(bc, k, t_early, &early))
            early = end;
        a->levels[k][1] = sg_level_at_least(end);
        a->levels[k][0] = sg_level_at_least(early);
        if (!(a->levels[k][0] > a->levels[k][1])) /* a flat curve: still two levels */
            a->levels[k][0] = sg_level_at_least(1.5 * a->levels[k][1]);
    }
    char line[4096] = "";
    for (int k = 0; k < SG_METRIC_COUNT; k++)
        sg_cat(line, sizeof line, "%s%s %.6g %.6g", k ? " " : "", sg_metric_key[k], a->levels[k][0],
               a->levels[k][1]);
    sg_cat(line, sizeof line, "\n");
    SgOutputFile out;
    if (!sg_analyze_open(&out, o->dir, "levels.txt", "", err))
        return false;
    fputs(line, out.file);
    return sg_output_commit(&out, err);
}

/* One row of table 2: the time each mode takes to reach one level. */
static bool sg_analyze_level_row(const SgAnalyzeOptions *o, SgAnalysis *a, int k, int l, const char *file,
                                 SgError *err)
{
    SgReach r[SG_ANALYZE_MAX_MODES];
    for (int m = 0; m < a->nm; m++) {
        r[m] = a->res[m].present ? sg_curve_time_to_level(&a->res[m].mean, k, a->levels[k][l])
                                 : (SgReach){SG_REACH_NONE, 0};
        if (k == SG_METRIC_RELMSE && l == 1)
            a->headline[m] = r[m];
    }
    char line[4096], cell[64];
    sg_format_error(a->levels[k][l], cell, sizeof cell);
    snprintf(line, sizeof line, "| %s | %s |", o->name, cell);
    for (int m = 0; m < a->nm; m++) {
        sg_reach_format(r[m], cell, sizeof cell);
        sg_cat(line, sizeof line, " %s |", cell);
    }
    for (int m = 1; m < a->nm; m++) {
        sg_ratio_format(r[0], r[m], cell, sizeof cell);
        sg_cat(line, sizeof line, " %s |", cell);
    }
    for (int c = 0; c < a->nc; c++) {
        sg_ratio_format(r[a->cmp[c][1]], r[a->cmp[c][0]], cell, sizeof cell);
        sg_cat(line, sizeof line, " %s |", cell);
    }
    sg_cat(line, sizeof line, "\n");
    return sg_analyze_append(o->tables, file, line, err);
}

/* table 2: one row per level, a table per metric */
static bool sg_analyze_time_to_level(const SgAnalyzeOptions *o, SgAnalysis *a, SgError *err)
{
    for (int k = 0; k < SG_METRIC_COUNT; k++) {
        char head[4096], file[64];
        snprintf(head, sizeof head, "| scene | %s level |", sg_metric_title[k]);
        for (int m = 0; m < a->nm; m++)
            sg_cat(head, sizeof head, " %s s |", a->names[m]);
        for (int m = 1; m < a->nm; m++)
            sg_cat(head, sizeof head, " %s speed-up |", a->names[m]);
        for (int c = 0; c < a->nc; c++)
            sg_cat(head, sizeof head, " %s over %s |", a->names[a->cmp[c][0]], a->names[a->cmp[c][1]]);
        snprintf(file, sizeof file, "table2-%s", sg_metric_key[k]);
        if (!sg_analyze_header(o->tables, file, head, err))
            return false;
        snprintf(file, sizeof file, "table2-%s.md", sg_metric_key[k]);
        for (int l = 0; l < 2; l++)
            if (!sg_analyze_level_row(o, a, k, l, file, err))
                return false;
    }
    return true;
}

static bool sg_analyze_equal_time_header(const SgAnalyzeOptions *o, const SgAnalysis *a, SgError *err)
{
    char head[4096];
    snprintf(head, sizeof head, "| scene | size | seconds | spp");
    for (int m = 0; m < a->nm; m++)
        sg_cat(head, sizeof head, "%s %s", m ? " /" : "", a->names[m]);
    sg_cat(head, sizeof head, " | µs/sample");
    for (int m = 0; m < a->nm; m++)
        sg_cat(head, sizeof head, "%s %s", m ? " /" : "", sg_short_mode(a->names[m]));
    sg_cat(head, sizeof head, " |");
    for (int k = 0; k < SG_METRIC_COUNT; k++) {
        sg_cat(head, sizeof head, " %s %s |", sg_metric_title[k], a->names[0]);
        for (int m = 1; m < a->nm; m++)
            sg_cat(head, sizeof head, " %s |", a->names[m]);
        sg_cat(head, sizeof head, " ratio");
        for (int m = 1; m < a->nm; m++)
            sg_cat(head, sizeof head, "%s %s", m > 1 ? " /" : "", sg_short_mode(a->names[m]));
        sg_cat(head, sizeof head, " |");
    }
    return sg_analyze_header(o->tables, "equal-time", head, err);
}

/* equal time: every mode at the time all of them reached */
static bool sg_analyze_equal_time(const SgAnalyzeOptions *o, const SgAnalysis *a, SgError *err)
{
    const SgModeResult *res = a->res;
    int nm = a->nm;
    double t_eq = INFINITY;
    for (int m = 0; m < nm; m++)
        if (res[m].present)
            t_eq = fmin(t_eq, res[m].mean.seconds[res[m].mean.count - 1]);
    double eq[SG_ANALYZE_MAX_MODES][SG_METRIC_COUNT];
    for (int m = 0; m < nm; m++)
        for (int k = 0; k < SG_METRIC_COUNT; k++)
            if (!res[m].present || !sg_curve_at(&res[m].mean, k, t_eq, &eq[m][k]))
                eq[m][k] = NAN;
    int w = 0, h = 0;
    double pixels = sscanf(o->size, "%dx%d", &w, &h) == 2 ? (double)w * h : NAN;
    if (!sg_analyze_equal_time_header(o, a, err))
        return false;
    char line[4096];
    snprintf(line, sizeof line, "| %s | %s | %.1f |", o->name, o->size, t_eq);
    for (int pass = 0; pass < 2; pass++) { /* spp, then µs per sample */
        for (int m = 0; m < nm; m++) {
            sg_cat(line, sizeof line, "%s", m ? " /" : "");
            if (res[m].present && isfinite(pixels)) {
                if (pass == 0)
                    sg_cat(line, sizeof line, " %.0f", res[m].final_spp);
                else
                    sg_cat(line, sizeof line, " %.3f", 1e6 * res[m].us_per_sample / pixels);
            } else
                sg_cat(line, sizeof line, " -");
        }
        sg_cat(line, sizeof line, " |");
    }
    for (int k = 0; k < SG_METRIC_COUNT; k++) {
        char cell[64];
        for (int m = 0; m < nm; m++) {
            sg_format_error(eq[m][k], cell, sizeof cell);
            sg_cat(line, sizeof line, " %s |", cell);
        }
        for (int m = 1; m < nm; m++) {
            double q = eq[0][k] / eq[m][k];
            if (isfinite(q)) /* like sg_ratio_format: two digits below 0.1 */
                sg_cat(line, sizeof line, q >= 0.1 ? "%s %.2f" : "%s %.2g", m > 1 ? " /" : "", q);
            else
                sg_cat(line, sizeof line, "%s -", m > 1 ? " /" : "");
        }
        sg_cat(line, sizeof line, " |");
    }
    sg_cat(line, sizeof line, "\n");
    return sg_analyze_append(o->tables, "equal-time.md", line, err);
}

/* the reference against the smallest levels it has to resolve */
static bool sg_analyze_reference(const SgAnalyzeOptions *o, const SgAnalysis *a, SgError *err)
{
    char own[256] = "", low[256] = "", cell[64], head[4096], line[4096];
    double worst = NAN; /* the worst of the metrics known */
    for (int k = 0; k < SG_METRIC_COUNT; k++) {
        sg_format_error(o->ref_err[k], cell, sizeof cell);
        sg_cat(own, sizeof own, "%s%s", k ? " / " : "", cell);
        sg_format_error(a->levels[k][1], cell, sizeof cell);
        sg_cat(low, sizeof low, "%s%s", k ? " / " : "", cell);
        worst = fmax(worst, o->ref_err[k] / a->levels[k][1]); /* fmax skips a NaN */
    }
    const char *verdict = !isfinite(worst) ? "unknown"
                          : worst <= 0.25  ? "good (< 1/4 of the lowest level)"
                          : worst <= 0.5   ? "fair (< 1/2 of the lowest level)"
                                           : "too noisy: lengthen it (SG_REF_SECONDS)";
    snprintf(head, sizeof head, "| scene | size | spp | seconds | own relMSE / mse8 / MSE |"
                                " lowest level relMSE / mse8 / MSE | own / level (worst) | verdict | this run |");
    if (!sg_analyze_header(o->tables, "reference", head, err))
        return false;
    snprintf(line, sizeof line, "| %s | %s | %.0f | %.0f | %s | %s | %.2f | %s | %s |\n", o->name, o->size,
             o->ref_spp, o->ref_seconds, own, low, worst, verdict, o->ref_state);
    return sg_analyze_append(o->tables, "reference.md", line, err);
}

/* where a learned field's training went (openpgl) */
static bool sg_analyze_training(const SgAnalyzeOptions *o, const SgAnalysis *a, SgError *err)
{
    for (int m = 0; m < a->nm; m++) {
        const SgModeResult *r = &a->res[m];
        if (!r->present || r->trained_runs == 0)
            continue;
        char head[4096], line[4096];
        snprintf(head, sizeof head, "| scene | mode | runs | spp | training passes | field updates s | of the run |"
                                    " training passes took s | of the run | guide drew, of bounces |");
        if (!sg_analyze_header(o->tables, "training", head, err))
            return false;
        snprintf(line, sizeof line, "| %s | %s | %d | %.0f | %.0f | %.2f | %.1f%% | %.2f | %.1f%% | %.1f%% |\n",
                 o->name, a->names[m], r->trained_runs, r->final_spp, r->training_passes, r->training_seconds,
                 100 * r->training_seconds / r->run_seconds, r->training_phase,
                 100 * r->training_phase / r->run_seconds, 100 * r->guide_share);
        if (!sg_analyze_append(o->tables, "training.md", line, err))
            return false;
    }
    return true;
}

/* README headline: relMSE at the lower level */
static bool sg_analyze_headline(const SgAnalyzeOptions *o, const SgAnalysis *a, SgError *err)
{
    const SgReach none = {SG_REACH_NONE, 0}, *headline = a->headline;
    SgReach g = a->i_guided >= 0 ? headline[a->i_guided] : none, s = a->i_skel >= 0 ? headline[a->i_skel] : none;
    char line[4096], lv[64], w[64], x[64], y[64], z[64];
    sg_format_error(a->levels[0][1], lv, sizeof lv);
    sg_reach_format(headline[0], w, sizeof w);
    sg_reach_format(g, x, sizeof x);
    sg_ratio_format(headline[0], g, y, sizeof y);
    sg_ratio_format(headline[0], s, z, sizeof z);
    snprintf(line, sizeof line, "%s\t%s\t%s\t%s\t%s\t%s\t%s", o->name, o->size, lv, w, x, y, z);
    if (a->i_pgl >= 0) {
        SgReach p = headline[a->i_pgl];
        sg_reach_format(p, w, sizeof w);
        sg_ratio_format(headline[0], p, x, sizeof x);
        sg_ratio_format(p, g, y, sizeof y);
        sg_cat(line, sizeof line, "\t%s\t%s\t%s", w, x, y);
    }
    sg_cat(line, sizeof line, "\n");
    return sg_analyze_append(o->tables, "headline.tsv", line, err);
}

int sg_convergence_analyze(int argc, char **argv, SgError *err)
{
    SgAnalyzeOptions o;
    if (!sg_analyze_parse_options(argc, argv, &o, err))
        return 1;
    SgAnalysis *a = calloc(1, sizeof *a);
    if (!a)
        return sg_fail(err, "analyze: out of memory"), 1;
    bool ok = sg_analyze_choose_modes(&o, a, err) && sg_analyze_load_modes(&o, a, err) &&
              sg_analyze_levels(&o, a, err) && sg_analyze_time_to_level(&o, a, err) &&
              sg_analyze_equal_time(&o, a, err) && sg_analyze_reference(&o, a, err) &&
              sg_analyze_training(&o, a, err) && sg_analyze_headline(&o, a, err);
    for (int m = 0; m < a->nm; m++)
        sg_curve_free(&a->res[m].mean);
    free(a);
    return ok ? 0 : 1;
}
