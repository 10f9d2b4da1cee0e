/* common/error_metrics.h: relMSE's epsilon and per-value term, shared by
 * render --log and the benchmarks' reference error (bench/lib/convergence_math.h). */
#include <criterion/criterion.h>
#include <math.h>

#include "error_metrics.h"
#include "bench/lib/convergence_math.h"

Test(relmse, epsilon_is_one_hundredth_on_the_exposed_image)
{
    cr_assert_eq(sg_relmse_epsilon(1.0f), 0.01);
    cr_assert_eq(sg_relmse_epsilon(2.0f), 0.0025);
    cr_assert_float_eq(sg_relmse_epsilon(0.125f), 0.64, 1e-15);
    /* exposing the image by s scales error and reference alike: the term stays */
    double e = 0.3, r = 0.7;
    for (float s = 0.25f; s <= 8; s *= 2)
        cr_assert_float_eq(sg_relmse_term(e * s, r * s, sg_relmse_epsilon(1.0f)),
                           sg_relmse_term(e, r, sg_relmse_epsilon(s)), 1e-15, "scale %g", s);
}

Test(relmse, term_known_values)
{
    cr_assert_eq(sg_relmse_term(0, 5, 0.01), 0.0);
    cr_assert_float_eq(sg_relmse_term(0.1, 1, 0.01), 0.01 / 1.01, 1e-17);
    cr_assert_float_eq(sg_relmse_term(-0.1, 1, 0.01), 0.01 / 1.01, 1e-17, "sign of the error");
    cr_assert_float_eq(sg_relmse_term(0.1, -1, 0.01), 0.01 / 1.01, 1e-17, "sign of the reference");
    cr_assert_float_eq(sg_relmse_term(0.5, 0, 0.01), 25.0, 1e-12, "black reference: e^2 / eps");
    cr_assert_float_eq(sg_relmse_term(2, 100, 0), 4e-4, 1e-18);
}

/* The bench's reference error is the same relMSE: halves 1 and 3 make
 * r = 2, error 1, so every value gives 1 / (4 + 0.01 / scale^2). */
Test(relmse, reference_from_halves_uses_it)
{
    float a[4] = {1, 3, 1, 3}, b[4] = {3, 1, 3, 1}, ref[4];
    double relmse = -1, mse8 = -1, mse = -1;
    sg_reference_from_halves(a, b, 4, 1.0f, ref, &relmse, &mse8, &mse);
    cr_assert_float_eq(relmse, 1 / 4.01, 1e-15);
    cr_assert_float_eq(mse, 1.0, 1e-15, "linear MSE: the error 1 squared");
    for (int i = 0; i < 4; i++)
        cr_assert_eq(ref[i], 2.0f);
    sg_reference_from_halves(a, b, 4, 0.5f, NULL, &relmse, &mse8, &mse);
    cr_assert_float_eq(relmse, 1 / 4.04, 1e-15);
    cr_assert_float_eq(mse, 1.0, 1e-15, "linear MSE takes no exposure");
}
