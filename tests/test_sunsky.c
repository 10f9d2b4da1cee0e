/* The daylight model (common/sunsky.h) against Preetham, Shirley & Smits
 * (1999) as published: the zenith luminance formula and chromaticity
 * matrices, the Perez distribution at its defining points, the sky image's
 * layout, the sun's reddening through air, and the sun's position for
 * places and dates whose answer is known. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>

#include "color.h"
#include "sunsky.h"

/* The paper's zenith luminance, written out: (4.0453 T - 4.9710) tan chi -
 * 0.2155 T + 2.4192, chi = (4/9 - T/120)(pi - 2 theta_s), kcd/m^2. */
Test(sunsky, zenith_luminance_is_preethams_formula)
{
    const double turbidity[] = {2, 3, 6, 10}, theta_deg[] = {0, 30, 60, 85};
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            double t = turbidity[i], ts = theta_deg[j] * M_PI / 180;
            double chi = (4.0 / 9.0 - t / 120.0) * (M_PI - 2 * ts);
            double expected = (4.0453 * t - 4.9710) * tan(chi) - 0.2155 * t + 2.4192;
            cr_expect_float_eq(sg_preetham_zenith_luminance(t, ts), expected, 1e-12);
        }
    /* a clear sky (T 2) with the sun 30 degrees from the zenith: 5.88
     * kcd/m^2 at the zenith (worked by hand); hazier skies are brighter there */
    cr_expect(fabs(sg_preetham_zenith_luminance(2, M_PI / 6) - 5.88) < 0.01, "%g",
              sg_preetham_zenith_luminance(2, M_PI / 6));
    cr_expect_gt(sg_preetham_zenith_luminance(6, M_PI / 6), sg_preetham_zenith_luminance(2, M_PI / 6));
}

Test(sunsky, sky_at_the_zenith_and_near_the_sun)
{
    SgPreethamSky sky;
    double ts = 40 * M_PI / 180;
    sg_preetham_init(&sky, 3, ts);
    /* the appendix's matrices at T 3, theta_s 40 degrees */
    double t3 = ts * ts * ts, t2 = ts * ts;
    double xz = (0.00166 * t3 - 0.00375 * t2 + 0.00209 * ts) * 9 +
                (-0.02903 * t3 + 0.06377 * t2 - 0.03202 * ts + 0.00394) * 3 +
                (0.11693 * t3 - 0.21196 * t2 + 0.06052 * ts + 0.25886);
    cr_expect_float_eq(sky.zenith_x, xz, 1e-12);
    cr_expect(sky.zenith_x > 0.2 && sky.zenith_x < 0.3127 && sky.zenith_y > 0.2 && sky.zenith_y < 0.329,
              "a zenith bluer than daylight white (0.3127, 0.329): x %g y %g", sky.zenith_x, sky.zenith_y);
    /* at the zenith, by construction, the zenith values; the Perez
     * coefficients of Y at T 3 (A = 0.1787 T - 1.4630, ...) */
    double xyY[3];
    sg_preetham_xyY(&sky, 0, ts, xyY);
    cr_expect_float_eq(xyY[2], sky.zenith_Y, 1e-9);
    cr_expect_float_eq(sky.perez_Y[0], 0.1787 * 3 - 1.4630, 1e-12);
    cr_expect_float_eq(sky.perez_Y[3], 0.1206 * 3 - 2.5771, 1e-12);
    /* the circumsolar region outshines the opposite sky at the same height */
    double near[3], far[3];
    sg_preetham_xyY(&sky, ts, 0.05, near);
    sg_preetham_xyY(&sky, ts, 2 * ts, far);
    cr_expect_gt(near[2], 3 * far[2]);
    /* RGB keeps the luminance */
    float rgb[3];
    sg_preetham_rgb(&sky, 0.7, 1.2, rgb);
    sg_preetham_xyY(&sky, 0.7, 1.2, xyY);
    cr_expect(fabs(sg_luminance(rgb[0], rgb[1], rgb[2]) - xyY[2]) < 0.02 * xyY[2]);
    cr_expect_gt(rgb[2], rgb[0], "the sky away from the sun is blue");
}

Test(sunsky, image_is_lat_long_with_the_sun_where_asked)
{
    SgPreethamSky sky;
    sg_preetham_init(&sky, 3, M_PI / 4);
    const double sun[3] = {sqrt(0.5), 0, sqrt(0.5)}; /* azimuth 0 (+x), 45 degrees up */
    SgError err = {0};
    int w = 64, h = 32;
    float *img = sg_sky_image(&sky, sun, w, h, 2.0, false, &err);
    cr_assert_not_null(img, "%s", err.message);
    /* brightest above the horizon near the sun: the column of azimuth 0, a quarter down */
    int best = 0;
    for (int i = 0; i < w * h / 2; i++)
        if (img[3 * i + 1] > img[3 * best + 1])
            best = i;
    int bx = best % w, by = best / w;
    cr_expect(by >= h / 4 - 2 && by <= h / 4 + 1 && (bx <= 1 || bx >= w - 2), "brightest at (%d, %d)", bx, by);
    float once[3];
    double theta = (0.5 / h) * M_PI, phi = (0.5 / w) * 2 * M_PI;
    double d[3] = {sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta)};
    sg_preetham_rgb(&sky, theta, acos(d[0] * sun[0] + d[2] * sun[2]), once);
    cr_expect_float_eq(img[1], 2 * once[1], 1e-4 * once[1], "scaled by 2");
    free(img);
}

Test(sunsky, sun_reddens_toward_the_horizon)
{
    float high[3], low[3], gone[3];
    sg_sun_radiance(3, 0.2, high);
    sg_sun_radiance(3, 85 * M_PI / 180, low);
    sg_sun_radiance(3, 95 * M_PI / 180, gone);
    cr_expect(high[0] > 1e6 && high[0] < 2e6, "a high sun: about 1.6e6 kcd/m^2 (%g)", high[0]);
    cr_expect_gt(low[0] / low[2], high[0] / high[2]);
    cr_expect_lt(sg_luminance(low[0], low[1], low[2]), sg_luminance(high[0], high[1], high[2]));
    cr_expect(gone[0] == 0 && gone[1] == 0 && gone[2] == 0);
    float hazy[3];
    sg_sun_radiance(8, 0.2, hazy);
    cr_expect_lt(hazy[1], high[1], "a hazier sky lets less through");
}

/* Known positions: the equinox noon on the equator nearly overhead; a
 * midsummer noon at 45 north about 21.6 degrees from the zenith, due south. */
Test(sunsky, sun_position_of_known_places_and_times)
{
    double zenith, azimuth;
    /* 2010-03-20 12:07 UTC at longitude 0 (the equation of time is about -7.5 min) */
    sg_sun_position(2010, 3, 20, 12, 7, 0, 0, 0, 0, &zenith, &azimuth);
    cr_expect_lt(zenith * 180 / M_PI, 1.0, "equinox noon on the equator: zenith %g deg", zenith * 180 / M_PI);
    /* 2010-06-21 local solar noon at 45 N, 0 E (12:02 UTC) */
    sg_sun_position(2010, 6, 21, 12, 2, 0, 0, 45, 0, &zenith, &azimuth);
    cr_expect(fabs(zenith * 180 / M_PI - 21.56) < 0.3, "midsummer noon at 45 N: zenith %g deg", zenith * 180 / M_PI);
    cr_expect(fabs(azimuth * 180 / M_PI - 180) < 2, "due south: azimuth %g deg", azimuth * 180 / M_PI);
    /* a morning sun is in the east (azimuth near 90) */
    sg_sun_position(2010, 6, 21, 7, 0, 0, 0, 45, 0, &zenith, &azimuth);
    cr_expect(azimuth * 180 / M_PI > 50 && azimuth * 180 / M_PI < 110, "morning azimuth %g deg", azimuth * 180 / M_PI);
}
