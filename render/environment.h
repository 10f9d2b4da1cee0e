/* The sky's radiance over the sphere of directions: an environment image
 * (pbrt-v4's equal-area square map or a lat-long map) times a colour,
 * importance-sampled in proportion to its luminance (piecewise constant
 * over the texels, the radiance looked up at the nearest texel, so that
 * the estimator and its pdf agree exactly). Directions are world space;
 * the map lives in light space (z up), turned by `to_world`. */
#ifndef SG_RENDER_ENVIRONMENT_H
#define SG_RENDER_ENVIRONMENT_H

#include <stdbool.h>

#include "error.h"
#include "scene.h"
#include "vecmath.h"

typedef struct Environment {
    int width, height;
    SgEnvironmentLayout layout; /* equal-area or lat-long, never by-shape */
    Vec3 *texels;     /* width x height, row 0 at the top, times the colour */
    double *weight;   /* height x width: texel probabilities (sum 1); one block with: */
    double *col_cdf;  /* height x width: cumulative weights within each row */
    double *row_cdf;  /* height: cumulative row weights, last = 1 */
    Vec3 to_world[3]; /* columns: light space's x, y, z in the world */
    Vec3 mean;        /* the map's mean radiance over the sphere */
} Environment;

/* From an image's texels (3 floats each, row 0 at the top) scaled by
 * `colour`; the layout by the image's shape where `layout` leaves it open
 * (square: equal-area, 2:1: lat-long). Fails naming `path`. */
bool environment_init(Environment *e, const float *rgb, int width, int height, SgEnvironmentLayout layout,
                      const float colour[3], const double light_to_world[3][3], const char *path, SgError *err);
/* Reads the image with OpenImageIO, then environment_init; an
 * `illuminance` > 0 scales it to that irradiance on an upward plane. */
bool environment_load(Environment *e, const SgLightSource *light, SgError *err);
void environment_free(Environment *e);

/* Radiance arriving from world direction w (unit). */
Vec3 environment_radiance(const Environment *e, Vec3 w);
/* A direction drawn in proportion to luminance, its pdf (solid angle). */
Vec3 environment_sample(const Environment *e, float u1, float u2, float *pdf);
float environment_pdf(const Environment *e, Vec3 w);

/* The two layouts' maps between the unit square and the unit sphere
 * (light space), exposed for the tests. */
Vec3 environment_square_to_sphere(SgEnvironmentLayout layout, float u, float v);
void environment_sphere_to_square(SgEnvironmentLayout layout, Vec3 w, float *u, float *v);
/* The area of the sphere one unit of the square covers at (u, v): the
 * Jacobian |dw / du dv|. */
float environment_jacobian(SgEnvironmentLayout layout, float u, float v);

#endif
