#include "error_metrics.h"

#include <math.h>
#include <stdlib.h>

/* The k-th smallest of a[0..n-1] (Hoare's selection: many equal values,
 * a black image's, cost no more than any). Reorders a. */
static double select_kth(double *a, size_t n, size_t k)
{
    size_t lo = 0, hi = n - 1;
    while (lo < hi) {
        double pivot = a[lo + (hi - lo) / 2];
        size_t i = lo, j = hi;
        while (i <= j) {
            while (a[i] < pivot)
                i++;
            while (a[j] > pivot)
                j--;
            if (i <= j) {
                double t = a[i];
                a[i] = a[j];
                a[j] = t;
                i++;
                if (j == 0)
                    break;
                j--;
            }
        }
        if (k <= j)
            hi = j;
        else if (k >= i)
            lo = i;
        else
            return a[k];
    }
    return a[k];
}

double sg_trimmed_mean(double *a, size_t n)
{
    size_t drop = n / 1000, keep = n - drop;
    if (keep == 0)
        return 0.0;
    double cut = drop ? select_kth(a, n, keep - 1) : INFINITY;
    double sum = 0.0;
    size_t counted = 0;
    for (size_t i = 0; i < n; i++)
        if (a[i] < cut) {
            sum += a[i];
            counted++;
        }
    /* values equal to the cut fill the kept count */
    return (sum + (double)(keep - counted) * (drop ? cut : 0.0)) / (double)keep;
}

double sg_image_relmse_trimmed(const float *x, const float *ref, size_t pixels, float scale)
{
    double *e = malloc((pixels ? pixels : 1) * sizeof *e);
    if (!e)
        return NAN;
    double eps = sg_relmse_epsilon(scale);
    for (size_t p = 0; p < pixels; p++) {
        double s = 0.0;
        for (int c = 0; c < 3; c++)
            s += sg_relmse_term((double)x[3 * p + c] - ref[3 * p + c], ref[3 * p + c], eps);
        e[p] = s / 3.0;
    }
    double m = sg_trimmed_mean(e, pixels);
    free(e);
    return m;
}
