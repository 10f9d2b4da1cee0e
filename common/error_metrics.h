/* relMSE, the relative mean squared error of an image against a reference,
 * as render --log and the benchmarks define it: the mean over all values of
 * e^2 / (r^2 + eps), e the error and r the reference value. eps = 0.01 on
 * the image as shown (x scale, scale = 2^exposure) keeps black pixels
 * finite, so that a dark scene shown at +6 stops is measured relatively
 * too, not as 100x its plain MSE. */
#ifndef SG_ERROR_METRICS_H
#define SG_ERROR_METRICS_H

/* eps of relMSE for an image shown at `scale`: 0.01 / scale^2. */
static inline double sg_relmse_epsilon(float scale) { return 0.01 / ((double)scale * scale); }

/* One value's term of relMSE: error^2 / (reference^2 + epsilon). */
static inline double sg_relmse_term(double error, double reference, double epsilon)
{
    return error * error / (reference * reference + epsilon);
}

#endif
