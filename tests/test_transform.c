/* common/transform.h: the one 4x4 transform of the scene front ends
 * (scene_json.c, pbrt/): products, inverse, rotation, points, normals. */
#include <criterion/criterion.h>
#include <math.h>

#include "transform.h"

static SgTransform from_rows(const double v[16])
{
    SgTransform t;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            t.m[i][j] = v[4 * i + j];
    return t;
}

static void expect_near(const SgTransform *a, const SgTransform *b, double tol)
{
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            cr_expect(fabs(a->m[i][j] - b->m[i][j]) <= tol, "[%d][%d]: %.17g against %.17g", i,
                      j, a->m[i][j], b->m[i][j]);
}

static void expect_vec(const double v[3], double x, double y, double z, double tol)
{
    cr_expect(fabs(v[0] - x) <= tol && fabs(v[1] - y) <= tol && fabs(v[2] - z) <= tol,
              "(%.17g %.17g %.17g), expected (%g %g %g)", v[0], v[1], v[2], x, y, z);
}

static const double A[16] = {2, 0, 1, 3, 1, 3, 0, -1, 0, 1, 4, 2, 0, 0, 0, 1};
static const double B[16] = {1, 2, 0, 0, 0, 1, 0, 5, 3, 0, 1, 0, 0, 0, 0, 1};

Test(transform, identity)
{
    SgTransform t;
    sg_transform_identity(&t);
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            cr_assert_eq(t.m[i][j], i == j ? 1.0 : 0.0);
    double p[3] = {1.5, -2, 7}, q[3];
    sg_transform_point(&t, p, q);
    expect_vec(q, 1.5, -2, 7, 0);
}

Test(transform, multiply_known_product_and_order)
{
    SgTransform a = from_rows(A), b = from_rows(B), ab, ba;
    sg_transform_multiply(&a, &b, &ab);
    /* A B worked by hand */
    const double AB[16] = {5, 4, 1, 3, 1, 5, 0, 14, 12, 1, 4, 7, 0, 0, 0, 1};
    SgTransform want = from_rows(AB);
    expect_near(&ab, &want, 0);
    /* b is applied first: (A B) p = A (B p) */
    double p[3] = {0.5, -1, 2}, bp[3], abp[3], direct[3];
    sg_transform_point(&b, p, bp);
    sg_transform_point(&a, bp, abp);
    sg_transform_point(&ab, p, direct);
    expect_vec(direct, abp[0], abp[1], abp[2], 1e-12);
    sg_transform_multiply(&b, &a, &ba);
    cr_assert(ba.m[0][0] != ab.m[0][0] || ba.m[0][3] != ab.m[0][3], "the order matters");
    /* out may alias either operand */
    SgTransform x = a;
    sg_transform_multiply(&x, &b, &x);
    expect_near(&x, &ab, 0);
    x = b;
    sg_transform_multiply(&a, &x, &x);
    expect_near(&x, &ab, 0);
}

Test(transform, inverse_round_trip)
{
    /* a general (projective) matrix: pbrt's CTM may be one */
    const double M[16] = {2, 1, 0, 4, -1, 3, 2, 0, 0.5, 0, 1, -2, 0.1, 0, 0.2, 1};
    SgTransform m = from_rows(M), inv, prod, id;
    sg_transform_identity(&id);
    cr_assert(sg_transform_inverse(&m, &inv));
    sg_transform_multiply(&m, &inv, &prod);
    expect_near(&prod, &id, 1e-14);
    sg_transform_multiply(&inv, &m, &prod);
    expect_near(&prod, &id, 1e-14);
    /* a translation's inverse is known exactly; in place */
    SgTransform t;
    sg_transform_identity(&t);
    t.m[0][3] = 3, t.m[1][3] = -4, t.m[2][3] = 0.5;
    cr_assert(sg_transform_inverse(&t, &t));
    cr_assert(t.m[0][3] == -3 && t.m[1][3] == 4 && t.m[2][3] == -0.5);
}

Test(transform, inverse_of_singular_fails)
{
    const double S[16] = {1, 2, 3, 0, 2, 4, 6, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    SgTransform s = from_rows(S), out;
    sg_transform_identity(&out);
    out.m[0][1] = 42;
    cr_assert_not(sg_transform_inverse(&s, &out));
    cr_assert_eq(out.m[0][1], 42.0, "out is left alone");
}

Test(transform, rotation)
{
    SgTransform r;
    const double z[3] = {0, 0, 5}; /* any length */
    cr_assert(sg_transform_rotation(&r, 90, z));
    double x[3] = {1, 0, 0}, q[3];
    sg_transform_point(&r, x, q);
    expect_vec(q, 0, 1, 0, 1e-15); /* right-handed: x to y */
    cr_assert_float_eq(sg_transform_determinant(&r), 1.0, 1e-15);
    cr_assert(r.m[3][0] == 0 && r.m[3][1] == 0 && r.m[3][2] == 0 && r.m[3][3] == 1);
    const double diag[3] = {1, 1, 1};
    cr_assert(sg_transform_rotation(&r, 120, diag));
    sg_transform_point(&r, x, q);
    expect_vec(q, 0, 1, 0, 1e-15); /* about (1,1,1): x to y to z */
    const double zero[3] = {0, 0, 0};
    r.m[0][0] = 7;
    cr_assert_not(sg_transform_rotation(&r, 30, zero));
    cr_assert_eq(r.m[0][0], 7.0);
}

Test(transform, point_and_determinant)
{
    SgTransform a = from_rows(A);
    double p[3] = {1, 2, 3}, q[3];
    sg_transform_point(&a, p, q);
    expect_vec(q, 2 + 3 + 3, 1 + 6 - 1, 2 + 12 + 2, 0);
    cr_assert_eq(sg_transform_determinant(&a), 2 * 12 - 0 + 1 * 1); /* 25 */
    SgTransform mirror;
    sg_transform_identity(&mirror);
    mirror.m[0][0] = -1;
    cr_assert_eq(sg_transform_determinant(&mirror), -1.0);
}

Test(transform, normal_stays_perpendicular)
{
    /* a plane through the origin with normal n; its tangents t1, t2 */
    double n[3] = {1, 1, 0}, t1[3] = {1, -1, 0}, t2[3] = {0, 0, 1};
    const double M[16] = {3, 0, 0, 1, 0, 1, 0, 2, 0, 0, 0.5, 3, 0, 0, 0, 1}; /* non-uniform scale */
    SgTransform m = from_rows(M), lin = m;
    for (int a = 0; a < 3; a++)
        lin.m[a][3] = 0;
    double nw[3], w1[3], w2[3];
    sg_transform_normal(&m, n, nw);
    sg_transform_point(&lin, t1, w1);
    sg_transform_point(&lin, t2, w2);
    cr_assert_float_eq(nw[0] * w1[0] + nw[1] * w1[1] + nw[2] * w1[2], 0.0, 1e-15);
    cr_assert_float_eq(nw[0] * w2[0] + nw[1] * w2[1] + nw[2] * w2[2], 0.0, 1e-15);
    /* cofactors of diag(3, 1, 0.5): diag(0.5, 1.5, 3) */
    expect_vec(nw, 0.5, 1.5, 0, 0);
    /* a mirror keeps the normal on the side it was: -x flips x, no more */
    SgTransform mirror;
    sg_transform_identity(&mirror);
    mirror.m[0][0] = -1;
    double up[3] = {0.6, 0.8, 0};
    sg_transform_normal(&mirror, up, nw);
    expect_vec(nw, -0.6, 0.8, 0, 0);
    /* a singular linear part gives zero */
    SgTransform flat;
    sg_transform_identity(&flat);
    flat.m[2][2] = 0;
    double side[3] = {1, 0, 0};
    sg_transform_normal(&flat, side, nw);
    expect_vec(nw, 0, 0, 0, 0);
}
