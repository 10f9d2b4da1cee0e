#include "quadric_mesh.h"

#include <math.h>
#include <stdlib.h>

#include "vecmath.h"

static int segments_for(double phi_max)
{
    int n = (int)ceil(SG_QUADRIC_SEGMENTS * phi_max / (2.0 * M_PI));
    return n < 3 ? 3 : n;
}

/* A grid of (rows + 1) x (columns + 1) vertices, each row a ring of the
 * shape about z; `point` places the vertex at v = row / rows, angle phi =
 * phi_max column / columns, whose uv is (column / columns, v). */
typedef void (*GridPoint)(const void *shape, double v, double phi, double p[3]);

static bool grid_mesh(const void *shape, int rows, int columns, double phi_max, GridPoint point, SgQuadricMesh *m,
                      SgError *err)
{
    *m = (SgQuadricMesh){0};
    m->vertex_count = (uint32_t)((rows + 1) * (columns + 1));
    m->triangle_count = (uint32_t)(2 * rows * columns);
    m->positions = malloc(3 * sizeof(double) * m->vertex_count);
    m->uvs = malloc(2 * sizeof(float) * m->vertex_count);
    m->indices = malloc(3 * sizeof(uint32_t) * m->triangle_count);
    if (!m->positions || !m->uvs || !m->indices) {
        sg_quadric_mesh_free(m);
        return sg_fail(err, "out of memory for a shape's mesh");
    }
    for (int r = 0; r <= rows; r++)
        for (int c = 0; c <= columns; c++) {
            size_t v = (size_t)r * (columns + 1) + c;
            point(shape, (double)r / rows, phi_max * c / columns, m->positions + 3 * v);
            m->uvs[2 * v] = (float)((double)c / columns);
            m->uvs[2 * v + 1] = (float)((double)r / rows);
        }
    uint32_t *id = m->indices;
    for (int r = 0; r < rows; r++)
        for (int c = 0; c < columns; c++) {
            uint32_t a = (uint32_t)(r * (columns + 1) + c), b = a + 1;
            uint32_t d = a + (uint32_t)(columns + 1), e = d + 1;
            *id++ = a, *id++ = b, *id++ = e;
            *id++ = a, *id++ = e, *id++ = d;
        }
    return true;
}

void sg_quadric_triangle(const SgQuadricMesh *m, uint32_t t, double n[3], double centroid[3])
{
    const uint32_t *id = m->indices + 3 * (size_t)t;
    const double *a = m->positions + 3 * (size_t)id[0], *b = m->positions + 3 * (size_t)id[1],
                 *c = m->positions + 3 * (size_t)id[2];
    double e1[3], e2[3];
    d3_sub(b, a, e1);
    d3_sub(c, a, e2);
    d3_cross(e1, e2, n);
    for (int k = 0; k < 3; k++)
        centroid[k] = (a[k] + b[k] + c[k]) / 3.0;
}

/* Drops the triangles that collapsed where a ring is a point (a disk's
 * centre, a sphere's poles), then turns every triangle to face outward:
 * toward +z (axis_z), away from the z axis (radial_xy) or from the origin. */
static void face_outward(SgQuadricMesh *m, bool axis_z, bool radial_xy)
{
    uint32_t kept = 0;
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        double n[3], out[3];
        sg_quadric_triangle(m, t, n, out);
        if (d3_dot(n, n) > 0.0) {
            for (int k = 0; k < 3; k++)
                m->indices[3 * (size_t)kept + k] = m->indices[3 * (size_t)t + k];
            kept++;
        }
    }
    m->triangle_count = kept;
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        uint32_t *id = m->indices + 3 * (size_t)t;
        double n[3], out[3];
        sg_quadric_triangle(m, t, n, out);
        if (axis_z)
            out[0] = out[1] = 0.0, out[2] = 1.0;
        else if (radial_xy)
            out[2] = 0.0;
        if (d3_dot(n, out) < 0.0) {
            uint32_t k = id[1];
            id[1] = id[2];
            id[2] = k;
        }
    }
}

/* The grid mesh of a shape, its triangles facing outward as face_outward
 * says. */
static bool shape_mesh(const void *shape, int rows, int columns, double phi_max, GridPoint point, bool axis_z,
                       bool radial_xy, SgQuadricMesh *m, SgError *err)
{
    if (!grid_mesh(shape, rows, columns, phi_max, point, m, err))
        return false;
    face_outward(m, axis_z, radial_xy);
    return true;
}

double sg_quadric_mesh_area(const SgQuadricMesh *m)
{
    double area = 0.0;
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        double n[3], c[3];
        sg_quadric_triangle(m, t, n, c);
        area += 0.5 * d3_length(n);
    }
    return area;
}

/* ---- disk ---------------------------------------------------------------- */

typedef struct Disk {
    double radius, inner, height;
} Disk;

static void disk_point(const void *shape, double v, double phi, double p[3])
{
    const Disk *d = shape;
    double r = d->radius + (d->inner - d->radius) * v; /* pbrt-v4: v = 0 at the rim */
    p[0] = r * cos(phi), p[1] = r * sin(phi), p[2] = d->height;
}

double sg_quadric_disk_area(double radius, double inner_radius, double phi_max)
{
    return 0.5 * phi_max * (radius * radius - inner_radius * inner_radius);
}

bool sg_quadric_disk(double radius, double inner_radius, double height, double phi_max, SgQuadricMesh *m,
                     SgError *err)
{
    int columns = segments_for(phi_max);
    /* each wedge of angle a is a triangle (a trapezoid) of area r^2 sin(a) / 2
     * where the true sector has r^2 a / 2: scaling both radii by
     * sqrt(a / sin a) gives the true area exactly */
    double a = phi_max / columns, k = sqrt(a / sin(a));
    Disk d = {radius * k, inner_radius * k, height};
    return shape_mesh(&d, 1, columns, phi_max, disk_point, true, false, m, err);
}

/* ---- cylinder -------------------------------------------------------------- */

typedef struct Cylinder {
    double radius, z_min, z_max;
} Cylinder;

static void cylinder_point(const void *shape, double v, double phi, double p[3])
{
    const Cylinder *c = shape;
    p[0] = c->radius * cos(phi), p[1] = c->radius * sin(phi), p[2] = c->z_min + (c->z_max - c->z_min) * v;
}

double sg_quadric_cylinder_area(double radius, double z_min, double z_max, double phi_max)
{
    return phi_max * radius * fabs(z_max - z_min);
}

bool sg_quadric_cylinder(double radius, double z_min, double z_max, double phi_max, SgQuadricMesh *m, SgError *err)
{
    int columns = segments_for(phi_max);
    /* a facet is a chord 2 r sin(a / 2) wide where the arc is r a */
    double a = phi_max / columns, k = (0.5 * a) / sin(0.5 * a);
    Cylinder c = {radius * k, fmin(z_min, z_max), fmax(z_min, z_max)};
    return shape_mesh(&c, 1, columns, phi_max, cylinder_point, false, true, m, err);
}

/* ---- sphere ---------------------------------------------------------------- */

typedef struct Sphere {
    double radius, theta_min, theta_max;
} Sphere;

static void sphere_point(const void *shape, double v, double phi, double p[3])
{
    const Sphere *s = shape;
    double theta = s->theta_min + (s->theta_max - s->theta_min) * v;
    /* the sine from the cosine: exactly 0 at both poles (sin(pi) is not) */
    double ct = cos(theta), st = sqrt(fmax(0.0, 1.0 - ct * ct));
    p[0] = s->radius * st * cos(phi), p[1] = s->radius * st * sin(phi);
    p[2] = s->radius * ct;
}

double sg_quadric_sphere_area(double radius, double z_min, double z_max, double phi_max)
{
    double lo = fmax(fmin(z_min, z_max), -radius), hi = fmin(fmax(z_min, z_max), radius);
    return phi_max * radius * fmax(hi - lo, 0.0);
}

bool sg_quadric_sphere(double radius, double z_min, double z_max, double phi_max, SgQuadricMesh *m, SgError *err)
{
    double lo = fmax(fmin(z_min, z_max), -radius), hi = fmin(fmax(z_min, z_max), radius);
    /* pbrt-v4's v runs from z_min to z_max: theta from acos(z_min / r) down */
    Sphere s = {radius, acos(fmax(fmin(lo / radius, 1.0), -1.0)), acos(fmax(fmin(hi / radius, 1.0), -1.0))};
    int columns = segments_for(phi_max);
    int rows = (int)ceil((SG_QUADRIC_SEGMENTS / 2) * fabs(s.theta_max - s.theta_min) / M_PI);
    if (rows < 2)
        rows = 2;
    if (!shape_mesh(&s, rows, columns, phi_max, sphere_point, false, false, m, err))
        return false;
    /* the facets cut inside the sphere: a uniform scale about the centre
     * makes the mesh's area the true one */
    double mesh = sg_quadric_mesh_area(m), want = sg_quadric_sphere_area(radius, z_min, z_max, phi_max);
    if (mesh > 0.0 && want > 0.0) {
        double k = sqrt(want / mesh);
        for (uint32_t i = 0; i < 3 * m->vertex_count; i++)
            m->positions[i] *= k;
    }
    return true;
}

void sg_quadric_mesh_free(SgQuadricMesh *m)
{
    free(m->positions);
    free(m->uvs);
    free(m->indices);
    *m = (SgQuadricMesh){0};
}
