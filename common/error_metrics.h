/* relMSE, the relative mean squared error of an image against a reference,
 * as render --log and the benchmarks define it: the mean over all values of
 * e^2 / (r^2 + eps), e the error and r the reference value. eps = 0.01 on
 * the image as shown (x scale, scale = 2^exposure) keeps black pixels
 * finite, so that a dark scene shown at +6 stops is measured relatively
 * too, not as 100x its plain MSE. */
#ifndef SG_ERROR_METRICS_H
#define SG_ERROR_METRICS_H

#include <stddef.h>

#include "color.h"

/* eps of relMSE for an image shown at `scale`: 0.01 / scale^2. */
static inline double sg_relmse_epsilon(float scale) { return 0.01 / ((double)scale * scale); }

/* One value's term of relMSE: error^2 / (reference^2 + epsilon). */
static inline double sg_relmse_term(double error, double reference, double epsilon)
{
    return error * error / (reference * reference + epsilon);
}

/* An image x against a reference, n floats: relMSE on the image times
 * `scale` (2^exposure), mse8 the paper's MSE of the 8-bit sRGB values of
 * the PNG at that exposure ("MSE 100" ~ 28 dB PSNR), and the plain MSE of
 * the linear values. What render --log writes and the bench compares. */
static inline void sg_image_errors(const float *x, const float *ref, size_t n, float scale, double *relmse,
                                   double *mse8, double *mse)
{
    double eps = sg_relmse_epsilon(scale);
    double s = 0.0, rs = 0.0, s8 = 0.0;
    for (size_t i = 0; i < n; i++) {
        double d = (double)x[i] - ref[i];
        s += d * d;
        rs += sg_relmse_term(d, ref[i], eps);
        double d8 = sg_srgb_byte(x[i] * scale) - sg_srgb_byte(ref[i] * scale);
        s8 += d8 * d8;
    }
    *mse = n ? s / (double)n : 0.0;
    *relmse = n ? rs / (double)n : 0.0;
    *mse8 = n ? s8 / (double)n : 0.0;
}

/* The mean of a[0..n-1] without its largest n/1000 values (reorders a):
 * what one firefly cannot decide. */
double sg_trimmed_mean(double *a, size_t n);

/* relMSE over the pixels (RGB, 3 floats each) with the worst 0.1 % of the
 * pixels' errors left out, as recent guiding papers report it: in a sunlit
 * room one firefly can be nearly all of the plain relMSE. NaN: out of memory. */
double sg_image_relmse_trimmed(const float *x, const float *ref, size_t pixels, float scale);

#endif
