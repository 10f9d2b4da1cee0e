/* Daylight for scenes that ask for it by parameters rather than by an
 * image (Mitsuba's sky, sun and sunsky emitters): the sky of Preetham,
 * Shirley & Smits, "A Practical Analytic Model for Daylight" (SIGGRAPH
 * 1999), made into a lat-long image the renderer samples like any
 * environment map, and the sun as a disk of the radiance the same
 * atmosphere lets through. Radiometric values are in Preetham's units:
 * luminance in kcd/m^2, as Mitsuba's Preetham sky gives them. */
#ifndef SG_SUNSKY_H
#define SG_SUNSKY_H

#include <stdbool.h>

#include "error.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The sun's apparent angular radius in radians (0.2667 degrees). */
#define SG_SUN_ANGULAR_RADIUS 0.004654

/* The model for one turbidity and sun zenith angle (radians). */
typedef struct SgPreethamSky {
    double turbidity, theta_sun;
    double zenith_Y, zenith_x, zenith_y; /* at the zenith: luminance (kcd/m^2) and chromaticity */
    double perez_Y[5], perez_x[5], perez_y[5]; /* A..E of the Perez distribution of each */
} SgPreethamSky;

/* Preetham's zenith luminance (kcd/m^2): (4.0453 T - 4.9710) tan chi
 * - 0.2155 T + 2.4192, chi = (4/9 - T/120)(pi - 2 theta_sun). */
double sg_preetham_zenith_luminance(double turbidity, double theta_sun);
void sg_preetham_init(SgPreethamSky *sky, double turbidity, double theta_sun);
/* Perez's F(theta, gamma) = (1 + A e^(B / cos theta)) (1 + C e^(D gamma) + E cos^2 gamma). */
double sg_perez(const double coef[5], double theta, double gamma);
/* The sky's x, y and Y toward zenith angle theta at angle gamma from the sun
 * (theta at most a hair below the horizon, as Preetham's code clamps it). */
void sg_preetham_xyY(const SgPreethamSky *sky, double theta, double gamma, double xyY[3]);
/* The same as linear sRGB, negative parts clamped. */
void sg_preetham_rgb(const SgPreethamSky *sky, double theta, double gamma, float rgb[3]);

/* The sky as a width x height lat-long image (layout SG_ENVIRONMENT_LATLONG:
 * z up, u the azimuth from +x toward +y), the sun toward `sun` (unit, that
 * frame), times scale; black below the horizon unless `extend` carries the
 * horizon's radiance down. NULL with err set when out of memory. */
float *sg_sky_image(const SgPreethamSky *sky, const double sun[3], int width, int height, double scale, bool extend,
                    SgError *err);

/* The sun disk's radiance (linear sRGB, kcd/m^2 in luminance) through the
 * atmosphere of that turbidity at zenith angle theta_sun: the light outside
 * the atmosphere, thinned by Rayleigh and aerosol (Angstrom) extinction
 * along the air mass; 0 below the horizon. */
void sg_sun_radiance(double turbidity, double theta_sun, float rgb[3]);

/* Where the sun stands for a place and time (the PSA algorithm of Blanco-
 * Muriel et al. 2001, as Mitsuba uses it): zenith and azimuth (east of
 * north) in radians. Time is local, `timezone` hours ahead of UTC. */
void sg_sun_position(int year, int month, int day, double hour, double minute, double second, double timezone,
                     double latitude, double longitude, double *zenith, double *azimuth);

#ifdef __cplusplus
}
#endif
#endif
