/* Extra camera rays where the light seen directly varies within a pixel
 * (render/edge_rays.h): how many a sample takes, from the pixel's views
 * and the image's noise. */
#include <criterion/criterion.h>
#include <math.h>

#include "render/edge_rays.h"

/* k + 1 = sqrt(Vs R / V), rounded, within [0, EDGE_RAYS_MAX]. */
Test(edge_rays, rays_balance_a_views_noise_against_the_images)
{
    cr_assert_eq(edge_rays_count_for(0.0, 1.0, 10.0, 16), 0, "a view that never varies takes none");
    cr_assert_eq(edge_rays_count_for(1.0, 0.0, 10.0, 16), 16, "the image's noise unknown: as many as allowed");
    cr_assert_eq(edge_rays_count_for(1.0, 0.0, 10.0, 5), 5);
    cr_assert_eq(edge_rays_count_for(1.0, 0.0, 10.0, 0), 0, "--edge-rays 0");
    cr_assert_eq(edge_rays_count_for(1.0, 1.0, 4.0, 16), 1, "sqrt(4) = 2 views: one more ray");
    cr_assert_eq(edge_rays_count_for(1.0, 1.0, 9.0, 16), 2, "sqrt(9) = 3 views");
    cr_assert_eq(edge_rays_count_for(4.0, 1.0, 4.0, 16), 3, "sqrt(16) = 4 views");
    cr_assert_eq(edge_rays_count_for(25.0, 1.0, 4.0, 16), 9, "sqrt(100) = 10 views");
    cr_assert_eq(edge_rays_count_for(1.0, 4.0, 1.0, 16), 0, "a view quieter than the image: no ray pays");
    cr_assert_eq(edge_rays_count_for(1000.0, 1.0, 10.0, 16), 16, "at most the most");
    cr_assert_eq(edge_rays_count_for(NAN, 1.0, 10.0, 16), 0);
    /* a sample costs at least its camera ray */
    cr_assert_eq(edge_rays_count_for(16.0, 1.0, 0.0, 16), 3, "sqrt(16 x 1) = 4 views");
}

/* n views of pixel pix, 0 and `hi` in turn (mean hi/2). */
static void views(EdgeRays *sl, size_t pix, int n, double hi)
{
    for (int i = 0; i < n; i++)
        edge_rays_add_view(sl, pix, i % 2 ? hi : 0.0);
}

/* n samples of every pixel, mean 1, spread s: 1 - s, 1 + s in turn. */
static void samples_everywhere(EdgeRays *sl, int n, double s)
{
    for (int i = 0; i < n; i++)
        for (size_t p = 0; p < (size_t)sl->width * sl->height; p++)
            edge_rays_add_sample(sl, p, i % 2 ? 1.0 + s : 1.0 - s);
}

Test(edge_rays, a_silhouette_takes_rays_by_its_noise_against_the_images)
{
    EdgeRays *sl = edge_rays_create(4, 1, EDGE_RAYS_MAX);
    cr_assert_not_null(sl);
    views(sl, 0, 1, 1.0);
    cr_assert_eq(edge_rays_count(sl, 0, 10.0), 0, "one view: nothing known to vary");
    edge_rays_add_view(sl, 0, 1.0);
    cr_assert_eq(edge_rays_count(sl, 0, 10.0), EDGE_RAYS_MAX, "a silhouette, the image's noise unknown: the most");
    views(sl, 1, 400, 2.0); /* Vs = 1 (n/(n-1) aside) */
    views(sl, 2, 400, 0.2); /* Vs = 0.01 */
    for (int i = 0; i < 64; i++)
        edge_rays_add_view(sl, 3, 17.25); /* wholly on a light */
    cr_assert_eq(edge_rays_count(sl, 3, 10.0), 0, "a constant view (rounding aside) takes none");
    /* samples of variance s^2 n/(n-1): s = 0.5 over 400 samples, V ~ 1/4 */
    samples_everywhere(sl, 2, 0.5);
    edge_rays_estimate(sl, EDGE_RAYS_FROM_PASS - 1);
    cr_assert_eq(sl->image_variance, 0.0, "V is not made before EDGE_RAYS_FROM_PASS passes");
    samples_everywhere(sl, 398, 0.5);
    edge_rays_estimate(sl, 400);
    cr_assert_float_eq(sl->image_variance, 0.25 * 400.0 / 399.0, 1e-9, "V = %g", sl->image_variance);
    /* k + 1 = sqrt(Vs R / V): sqrt(1 x 4 / 0.25) = 4, sqrt(0.01 x 4 / 0.25) = 0.4 */
    cr_assert_eq(edge_rays_count(sl, 1, 4.0), 3);
    cr_assert_eq(edge_rays_count(sl, 2, 4.0), 0, "a silhouette too faint for the image's noise");
    cr_assert_eq(edge_rays_count(sl, 2, 400.0), 3, "unless its samples cost 100x more: sqrt(0.01 x 400 / 0.25) = 4");
    edge_rays_free(sl);

    sl = edge_rays_create(1, 1, 0);
    views(sl, 0, 64, 1.0);
    cr_assert_eq(edge_rays_count(sl, 0, 10.0), 0, "--edge-rays 0 takes none");
    edge_rays_free(sl);
}
