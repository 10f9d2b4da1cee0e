#include "environment.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "color.h"
#include "image_io.h"
#include "sampling.h"

/* ---- the two layouts --------------------------------------------------------- */

/* Clarberg's equal-area map of the square onto the sphere through the
 * octahedron (the map pbrt-v4 stores its environment images in): each
 * quarter of the square's inner diamond to the upper hemisphere's quadrant,
 * the corners to the lower one; |dw / du dv| = 4 pi everywhere. */
static Vec3 equal_area_to_sphere(float u, float v)
{
    float x = 2.0f * u - 1.0f, y = 2.0f * v - 1.0f;
    float ax = fabsf(x), ay = fabsf(y);
    float signed_distance = 1.0f - (ax + ay); /* > 0 inside the diamond: upper hemisphere */
    float r = 1.0f - fabsf(signed_distance);
    float phi = (r == 0.0f ? 1.0f : (ay - ax) / r + 1.0f) * (SG_PI / 4.0f);
    float z = copysignf(1.0f - r * r, signed_distance);
    float s = r * sqrtf(fmaxf(2.0f - r * r, 0.0f));
    return v3(copysignf(cosf(phi), x) * s, copysignf(sinf(phi), y) * s, z);
}

static void sphere_to_equal_area(Vec3 w, float *u, float *v)
{
    float ax = fabsf(w.x), ay = fabsf(w.y), az = fabsf(w.z);
    float r = sqrtf(fmaxf(1.0f - az, 0.0f));
    float a = fmaxf(ax, ay), b = fminf(ax, ay);
    float phi = a == 0.0f ? 0.0f : atanf(b / a) * (2.0f / SG_PI); /* in [0, 1] over the octant */
    if (ax < ay)
        phi = 1.0f - phi;
    float y = phi * r, x = r - y;
    if (w.z < 0.0f) { /* the lower hemisphere folds out to the corners */
        float t = x;
        x = 1.0f - y;
        y = 1.0f - t;
    }
    x = copysignf(x, w.x);
    y = copysignf(y, w.y);
    *u = 0.5f * (x + 1.0f);
    *v = 0.5f * (y + 1.0f);
}

Vec3 environment_square_to_sphere(SgEnvironmentLayout layout, float u, float v)
{
    if (layout == SG_ENVIRONMENT_LATLONG) {
        float theta = v * SG_PI, phi = u * 2.0f * SG_PI;
        float st = sinf(theta);
        return v3(st * cosf(phi), st * sinf(phi), cosf(theta));
    }
    return equal_area_to_sphere(u, v);
}

void environment_sphere_to_square(SgEnvironmentLayout layout, Vec3 w, float *u, float *v)
{
    if (layout == SG_ENVIRONMENT_LATLONG) {
        float phi = atan2f(w.y, w.x);
        if (phi < 0.0f)
            phi += 2.0f * SG_PI;
        *u = phi * (0.5f / SG_PI);
        *v = acosf(fminf(fmaxf(w.z, -1.0f), 1.0f)) * SG_INV_PI;
        return;
    }
    sphere_to_equal_area(w, u, v);
}

float environment_jacobian(SgEnvironmentLayout layout, float u, float v)
{
    (void)u;
    if (layout == SG_ENVIRONMENT_LATLONG) /* sin theta, never 0: the density is finite off the exact pole */
        return 2.0f * SG_PI * SG_PI * fmaxf(sinf(v * SG_PI), 1e-7f);
    return 4.0f * SG_PI;
}

/* The same at a direction (light space): sin theta from x and y, exact
 * near the poles where acos is not. */
static float jacobian_at(SgEnvironmentLayout layout, Vec3 l)
{
    if (layout == SG_ENVIRONMENT_LATLONG)
        return 2.0f * SG_PI * SG_PI * fmaxf(sqrtf(l.x * l.x + l.y * l.y), 1e-7f);
    return 4.0f * SG_PI;
}

/* ---- the map ------------------------------------------------------------------ */

static Vec3 to_light(const Environment *e, Vec3 w)
{
    return v3(v3_dot(w, e->to_world[0]), v3_dot(w, e->to_world[1]), v3_dot(w, e->to_world[2]));
}

static Vec3 to_world(const Environment *e, Vec3 l)
{
    return v3_add(v3_add(v3_scale(e->to_world[0], l.x), v3_scale(e->to_world[1], l.y)), v3_scale(e->to_world[2], l.z));
}

static int texel_index(int n, float t)
{
    int i = (int)(t * (float)n);
    return i < 0 ? 0 : i >= n ? n - 1 : i;
}

bool environment_init(Environment *e, const float *rgb, int width, int height, SgEnvironmentLayout layout,
                      const float colour[3], const double light_to_world[3][3], const char *path, SgError *err)
{
    memset(e, 0, sizeof *e);
    if (layout == SG_ENVIRONMENT_BY_SHAPE) {
        if (width == height)
            layout = SG_ENVIRONMENT_EQUAL_AREA;
        else if (width == 2 * height)
            layout = SG_ENVIRONMENT_LATLONG;
        else
            return sg_fail(err, "%s: an environment image must be square (equal-area) or 2:1 (lat-long), not %dx%d",
                           path, width, height);
    }
    if (width < 1 || height < 1)
        return sg_fail(err, "%s: empty environment image", path);
    e->width = width;
    e->height = height;
    e->layout = layout;
    for (int c = 0; c < 3; c++)
        e->to_world[c] = v3((float)light_to_world[0][c], (float)light_to_world[1][c], (float)light_to_world[2][c]);
    size_t n = (size_t)width * height;
    e->texels = malloc(n * sizeof *e->texels);
    e->weight = malloc((2 * n + (size_t)height) * sizeof *e->weight);
    if (!e->texels || !e->weight) {
        environment_free(e);
        return sg_fail(err, "%s: out of memory for the environment map", path);
    }
    e->col_cdf = e->weight + n;
    e->row_cdf = e->col_cdf + n;
    /* each texel's share: its luminance times the solid angle it covers */
    double total = 0.0, mean[3] = {0, 0, 0};
    for (int y = 0; y < height; y++) {
        float jac = environment_jacobian(layout, 0.5f, (y + 0.5f) / height);
        double row = 0.0;
        for (int x = 0; x < width; x++) {
            size_t i = (size_t)y * width + x;
            float t[3];
            for (int c = 0; c < 3; c++) {
                t[c] = rgb[3 * i + c] * colour[c];
                if (!(isfinite(t[c]) && t[c] >= 0.0f)) {
                    environment_free(e);
                    return sg_fail(err, "%s: texel (%d, %d) is negative or not finite", path, x, y);
                }
                mean[c] += (double)t[c] * jac;
            }
            e->texels[i] = v3(t[0], t[1], t[2]);
            double w = sg_luminance(t[0], t[1], t[2]) * jac;
            if (!(w > 0.0) && (t[0] > 0.0f || t[1] > 0.0f || t[2] > 0.0f))
                w = 1e-30; /* a colour of zero luminance still gets drawn */
            e->weight[i] = w;
            row += w;
            e->col_cdf[i] = row;
        }
        total += row;
        e->row_cdf[y] = total;
    }
    for (int c = 0; c < 3; c++)
        mean[c] /= (double)n * 4.0 * M_PI;
    e->mean = v3((float)mean[0], (float)mean[1], (float)mean[2]);
    if (!(total > 0.0)) { /* black: never drawn (the light's power is 0) */
        for (size_t i = 0; i < n; i++)
            e->weight[i] = 1.0 / n, e->col_cdf[i] = (double)(i % width + 1) / width;
        for (int y = 0; y < height; y++)
            e->row_cdf[y] = (double)(y + 1) / height;
        return true;
    }
    for (int y = 0; y < height; y++) {
        size_t r = (size_t)y * width;
        double row = e->col_cdf[r + width - 1];
        for (int x = 0; x < width; x++)
            e->col_cdf[r + x] = row > 0.0 ? e->col_cdf[r + x] / row : (double)(x + 1) / width;
        e->row_cdf[y] /= total;
    }
    for (size_t i = 0; i < n; i++)
        e->weight[i] /= total;
    return true;
}

bool environment_load(Environment *e, const SgLightSource *light, SgError *err)
{
    int w, h;
    float *rgb;
    bool made = light->image_pixels != NULL; /* a sky made at load time */
    if (made) {
        w = light->image_width;
        h = light->image_height;
        rgb = light->image_pixels;
    } else if (!sg_image_read(light->image_path, &w, &h, &rgb, err)) {
        return false;
    }
    const char *name = made ? "the sky" : light->image_path;
    bool ok = environment_init(e, rgb, w, h, light->layout, light->rgb, light->light_to_world, name, err);
    if (!made)
        free(rgb);
    if (!ok || !(light->illuminance > 0.0))
        return ok;
    /* pbrt-v4's "illuminance": the upper hemisphere's cosine-weighted
     * radiance, in light space (z up), made the value asked for */
    double k = 0.0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            float u = (x + 0.5f) / w, v = (y + 0.5f) / h;
            Vec3 d = environment_square_to_sphere(e->layout, u, v);
            if (d.z > 0.0f) {
                Vec3 t = e->texels[(size_t)y * w + x];
                k += sg_luminance(t.x, t.y, t.z) * d.z * environment_jacobian(e->layout, u, v) / ((double)w * h);
            }
        }
    if (!(k > 0.0)) {
        environment_free(e);
        return sg_fail(err, "%s: \"illuminance\" asked of an image dark above the horizon", name);
    }
    float s = (float)(light->illuminance / k);
    for (size_t i = 0; i < (size_t)w * h; i++)
        e->texels[i] = v3_scale(e->texels[i], s);
    e->mean = v3_scale(e->mean, s);
    return true;
}

void environment_free(Environment *e)
{
    free(e->texels);
    free(e->weight); /* and the two tables after it */
    memset(e, 0, sizeof *e);
}

static size_t texel_at(const Environment *e, Vec3 w, Vec3 *l)
{
    float u, v;
    *l = to_light(e, w);
    environment_sphere_to_square(e->layout, *l, &u, &v);
    return (size_t)texel_index(e->height, v) * e->width + texel_index(e->width, u);
}

Vec3 environment_radiance(const Environment *e, Vec3 w)
{
    Vec3 l;
    return e->texels[texel_at(e, w, &l)];
}

float environment_pdf(const Environment *e, Vec3 w)
{
    Vec3 l;
    size_t i = texel_at(e, w, &l);
    return (float)(e->weight[i] * (double)e->width * e->height) / jacobian_at(e->layout, l);
}

Vec3 environment_sample(const Environment *e, float u1, float u2, float *pdf)
{
    /* the row, then the texel within it, then a point uniform in the texel:
     * the probability u1 had left over places the point */
    SgPiecewise2D texels = {e->row_cdf, e->col_cdf, (uint32_t)e->width, (uint32_t)e->height};
    uint32_t ux, uy;
    double within_x, within_y;
    sg_piecewise2d_sample(&texels, u1, u2, &ux, &uy, &within_x, &within_y);
    int x = (int)ux, y = (int)uy;
    float fx = (float)within_x, fy = (float)within_y;
    float u = (x + fminf(fmaxf(fx, 0.0f), 0.99999f)) / e->width;
    float v = (y + fminf(fmaxf(fy, 0.0f), 0.99999f)) / e->height;
    Vec3 l = environment_square_to_sphere(e->layout, u, v);
    size_t i = (size_t)y * e->width + x;
    *pdf = (float)(e->weight[i] * (double)e->width * e->height) / jacobian_at(e->layout, l);
    return to_world(e, l);
}
