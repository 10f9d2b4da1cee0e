/* pbrt-v4's analytic shapes (disk, sphere, cylinder) as triangle meshes in
 * object space, fine enough that a lamp looks round, and sized so that each
 * mesh's area is the shape's true area: a light's power and its area
 * sampling then match the analytic shape's. Triangles face outward (the
 * disk: +z), as the shapes' normals do in pbrt-v4. */
#ifndef SG_QUADRIC_MESH_H
#define SG_QUADRIC_MESH_H

#include <stdbool.h>
#include <stdint.h>

#include "error.h"

typedef struct SgQuadricMesh {
    double *positions; /* 3 per vertex */
    float *uvs;        /* 2 per vertex: pbrt-v4's (u, v) of the shape */
    uint32_t vertex_count;
    uint32_t *indices; /* 3 per triangle */
    uint32_t triangle_count;
} SgQuadricMesh;

/* Segments around a full turn; a partial one gets its share (at least 3). */
#define SG_QUADRIC_SEGMENTS 128

/* The disk at z = height between inner_radius and radius, phi in
 * [0, phi_max] (radians). */
bool sg_quadric_disk(double radius, double inner_radius, double height, double phi_max, SgQuadricMesh *mesh,
                     SgError *err);
/* The sphere of radius about the origin between z_min and z_max, phi in [0, phi_max]. */
bool sg_quadric_sphere(double radius, double z_min, double z_max, double phi_max, SgQuadricMesh *mesh,
                       SgError *err);
/* The cylinder of radius about the z axis between z_min and z_max, phi in [0, phi_max]. */
bool sg_quadric_cylinder(double radius, double z_min, double z_max, double phi_max, SgQuadricMesh *mesh,
                         SgError *err);
/* The true area of the shapes above. */
double sg_quadric_disk_area(double radius, double inner_radius, double phi_max);
double sg_quadric_sphere_area(double radius, double z_min, double z_max, double phi_max);
double sg_quadric_cylinder_area(double radius, double z_min, double z_max, double phi_max);
/* Triangle t's (unnormalized) winding normal and its centroid. */
void sg_quadric_triangle(const SgQuadricMesh *mesh, uint32_t t, double normal[3], double centroid[3]);
/* The mesh's area (sum of its triangles'). */
double sg_quadric_mesh_area(const SgQuadricMesh *mesh);
void sg_quadric_mesh_free(SgQuadricMesh *mesh);

#endif
