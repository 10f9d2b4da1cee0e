#include "film.h"

#include "color.h"
#include "error_metrics.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

bool film_init(Film *f, int width, int height)
{
    memset(f, 0, sizeof *f);
    size_t pixels = (size_t)width * height;
    f->width = width;
    f->height = height;
    f->sum = calloc(pixels * 3, sizeof *f->sum);
    f->square = calloc(pixels, sizeof *f->square);
    f->last = calloc(pixels * 3, sizeof *f->last);
    return f->sum && f->square && f->last;
}

static void free_groups(Film *f)
{
    for (int g = 0; g < f->group_count; g++) {
        free(f->groups[g].sum);
        free(f->groups[g].square);
    }
    memset(f->groups, 0, sizeof f->groups);
    f->group_count = 0;
}

void film_free(Film *f)
{
    free_groups(f);
    free(f->sum);
    free(f->square);
    free(f->last);
    f->sum = NULL;
    f->square = NULL;
    f->last = NULL;
}

void film_clear(Film *f)
{
    size_t pixels = (size_t)f->width * f->height;
    free_groups(f);
    memset(f->sum, 0, pixels * 3 * sizeof *f->sum);
    memset(f->square, 0, pixels * sizeof *f->square);
    memset(f->last, 0, pixels * 3 * sizeof *f->last);
    f->passes = 0;
    f->cost = 0.0;
}

bool film_close_group(Film *f)
{
    if (f->passes == 0)
        return true;
    if (f->group_count == FILM_GROUPS_MAX)
        return false;
    size_t pixels = (size_t)f->width * f->height;
    FilmGroup g = {.sum = malloc(pixels * 3 * sizeof(float)), .square = malloc(pixels * sizeof(float)),
                   .passes = f->passes, .cost = f->cost};
    if (!g.sum || !g.square) {
        free(g.sum);
        free(g.square);
        return false;
    }
    for (size_t i = 0; i < pixels * 3; i++)
        g.sum[i] = (float)f->sum[i];
    for (size_t i = 0; i < pixels; i++)
        g.square[i] = (float)f->square[i];
    f->groups[f->group_count++] = g;
    memset(f->sum, 0, pixels * 3 * sizeof *f->sum);
    memset(f->square, 0, pixels * sizeof *f->square);
    f->passes = 0;
    f->cost = 0.0;
    return true;
}

int film_passes(const Film *f)
{
    int n = f->passes;
    for (int g = 0; g < f->group_count; g++)
        n += f->groups[g].passes;
    return n;
}

/* ---- the groups' variances -------------------------------------------------- */

/* One group as the variance estimate reads it: sums in floats or doubles. */
typedef struct GroupView {
    const float *sum_f, *square_f;
    const double *sum_d, *square_d;
    int passes;
    double cost;
} GroupView;

static int group_views(const Film *f, GroupView *v)
{
    int n = 0;
    for (int g = 0; g < f->group_count; g++)
        v[n++] = (GroupView){.sum_f = f->groups[g].sum, .square_f = f->groups[g].square,
                             .passes = f->groups[g].passes, .cost = f->groups[g].cost};
    if (f->passes > 0)
        v[n++] = (GroupView){.sum_d = f->sum, .square_d = f->square, .passes = f->passes, .cost = f->cost};
    return n;
}

static inline double view_luminance_sum(const GroupView *v, size_t pix)
{
    if (v->sum_d)
        return sg_luminance(v->sum_d[3 * pix], v->sum_d[3 * pix + 1], v->sum_d[3 * pix + 2]);
    return sg_luminance(v->sum_f[3 * pix], v->sum_f[3 * pix + 1], v->sum_f[3 * pix + 2]);
}

static inline double view_square(const GroupView *v, size_t pix)
{
    return v->square_d ? v->square_d[pix] : (double)v->square_f[pix];
}

/* The variances per pass of n groups from their mean squared distances to
 * the image of all passes at equal weight, m[g]: that image holds each
 * pass too, so m = s (1 - 2/N) + V, with V the image's own variance,
 * sum n s / N^2, over N passes in all. Solved for s; fewer than 3 passes
 * cannot tell s from V (0: unknown). */
static void variances_from_distances(const GroupView *v, int n, int total, double *m)
{
    if (total < 3) {
        for (int g = 0; g < n; g++)
            m[g] = 0.0;
        return;
    }
    double a = 1.0 - 2.0 / total, weighted = 0.0;
    for (int g = 0; g < n; g++)
        weighted += v[g].passes * m[g];
    double image = weighted / (a * (double)total * total + total);
    for (int g = 0; g < n; g++)
        m[g] = fmax((m[g] - image) / a, 0.0);
}

/* The image of every pass at equal weight (luminance). */
static void equal_weight_image(const GroupView *v, int n, size_t pixels, int total, double *reference)
{
    for (size_t p = 0; p < pixels; p++) {
        double s = 0.0;
        for (int g = 0; g < n; g++)
            s += view_luminance_sum(&v[g], p);
        reference[p] = s / total;
    }
}

/* Each group's variance per pass, trimmed, from the distance of its passes
 * to the image of all passes (its own spread would be blind to what the
 * whole group missed). Absolute, not relative to the image: relative to a
 * dark scene's image, the darkest pixels' noise decides every weight (on
 * the dark corridor relative weights tripled the linear MSE of equal ones). */
int film_group_variances(const Film *f, double *variance, double *cost)
{
    GroupView v[FILM_GROUPS_MAX + 1];
    int n = group_views(f, v);
    size_t pixels = (size_t)f->width * f->height;
    int total = film_passes(f);
    for (int g = 0; g < n; g++) {
        variance[g] = 0.0; /* unknown: the groups then count by their passes alone */
        if (cost)
            cost[g] = v[g].cost / v[g].passes;
    }
    double *reference = malloc(pixels * sizeof *reference), *distance = malloc(pixels * sizeof *distance);
    if (!reference || !distance || total == 0 || pixels == 0) {
        free(reference);
        free(distance);
        return n;
    }
    equal_weight_image(v, n, pixels, total, reference);
    for (int g = 0; g < n; g++) {
        int k = v[g].passes;
        for (size_t p = 0; p < pixels; p++) {
            double r = reference[p];
            /* the sum over the group's passes of (y - r)^2, from its sums */
            double d = view_square(&v[g], p) - 2.0 * r * view_luminance_sum(&v[g], p) + k * r * r;
            distance[p] = fmax(d, 0.0) / k;
        }
        variance[g] = sg_trimmed_mean(distance, pixels);
    }
    variances_from_distances(v, n, total, variance);
    free(reference);
    free(distance);
    return n;
}

void film_image(const Film *f, float *rgb)
{
    size_t values = (size_t)f->width * f->height * 3;
    if (f->group_count == 0) { /* one group: the plain mean */
        double inv = f->passes > 0 ? 1.0 / f->passes : 0.0;
        for (size_t i = 0; i < values; i++)
            rgb[i] = (float)(f->sum[i] * inv);
        return;
    }
    GroupView v[FILM_GROUPS_MAX + 1];
    double variance[FILM_GROUPS_MAX + 1], weight[FILM_GROUPS_MAX + 1];
    int n = group_views(f, v);
    film_group_variances(f, variance, NULL);
    double most = 0.0;
    for (int g = 0; g < n; g++)
        most = fmax(most, variance[g]);
    /* weight per pass: 1 / variance (a group of no variance at all beside
     * others with some gets the most a billionth of theirs allows; all
     * without any: equal weights) */
    double total = 0.0;
    for (int g = 0; g < n; g++) {
        weight[g] = most > 0.0 && isfinite(most) ? 1.0 / fmax(variance[g], 1e-9 * most) : 1.0;
        total += weight[g] * v[g].passes;
    }
    for (int g = 0; g < n; g++)
        weight[g] /= total;
    for (size_t i = 0; i < values; i++) {
        double s = 0.0;
        for (int g = 0; g < n; g++)
            s += weight[g] * (v[g].sum_d ? v[g].sum_d[i] : (double)v[g].sum_f[i]);
        rgb[i] = (float)s;
    }
}
