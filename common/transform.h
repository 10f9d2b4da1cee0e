/* 4x4 transforms in double precision, row-major, acting on column vectors
 * (p' = M p): the one matrix type of the scene front ends (scene_json.c's JSON
 * transforms, the pbrt CTM and camera) and its operations. */
#ifndef SG_TRANSFORM_H
#define SG_TRANSFORM_H

#include <stdbool.h>

typedef struct SgTransform {
    double m[4][4];
} SgTransform;

void sg_transform_identity(SgTransform *t);
/* out = a * b (b is applied first); out may alias a or b. */
void sg_transform_multiply(const SgTransform *a, const SgTransform *b, SgTransform *out);
/* Gauss-Jordan with partial pivoting; false (out untouched) if singular.
 * out may alias m. */
bool sg_transform_inverse(const SgTransform *m, SgTransform *out);
/* Rotation by `degrees` about `axis` (any length; right-handed). False if
 * the axis is zero (t untouched). */
bool sg_transform_rotation(SgTransform *t, double degrees, const double axis[3]);

/* The rest read t as affine (the last row taken as 0 0 0 1). */
void sg_transform_point(const SgTransform *t, const double p[3], double out[3]);
/* Determinant of the linear part: negative when the transform mirrors. */
double sg_transform_determinant(const SgTransform *t);
/* A normal (or any surface-perpendicular direction) n transformed: the
 * cofactor matrix of the linear part (its inverse transpose times its
 * determinant) times n, negated when the determinant is negative, so that
 * the result is the inverse transpose times n scaled by |det|: not
 * normalized, zero when the linear part is singular. */
void sg_transform_normal(const SgTransform *t, const double n[3], double out[3]);

#endif
