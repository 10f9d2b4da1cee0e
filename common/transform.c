#include "transform.h"

#include <math.h>
#include <string.h>

void sg_transform_identity(SgTransform *t)
{
    memset(t, 0, sizeof *t);
    t->m[0][0] = t->m[1][1] = t->m[2][2] = t->m[3][3] = 1;
}

void sg_transform_multiply(const SgTransform *a, const SgTransform *b, SgTransform *out)
{
    SgTransform r;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            double v = 0;
            for (int k = 0; k < 4; k++)
                v += a->m[i][k] * b->m[k][j];
            r.m[i][j] = v;
        }
    *out = r;
}

bool sg_transform_inverse(const SgTransform *m, SgTransform *out)
{
    double a[4][8];
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 8; j++)
            a[i][j] = j < 4 ? m->m[i][j] : (j - 4 == i);
    for (int c = 0; c < 4; c++) {
        int pivot = c;
        for (int r = c + 1; r < 4; r++)
            if (fabs(a[r][c]) > fabs(a[pivot][c]))
                pivot = r;
        if (!(fabs(a[pivot][c]) > 1e-300))
            return false;
        for (int j = 0; j < 8; j++) {
            double t = a[c][j];
            a[c][j] = a[pivot][j];
            a[pivot][j] = t;
        }
        double inv = 1 / a[c][c];
        for (int j = 0; j < 8; j++)
            a[c][j] *= inv;
        for (int r = 0; r < 4; r++)
            if (r != c) {
                double f = a[r][c];
                for (int j = 0; j < 8; j++)
                    a[r][j] -= f * a[c][j];
            }
    }
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            out->m[i][j] = a[i][j + 4];
    return true;
}

bool sg_transform_rotation(SgTransform *t, double degrees, const double axis[3])
{
    double len = sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    if (!(len > 0))
        return false;
    double x = axis[0] / len, y = axis[1] / len, z = axis[2] / len;
    double a = degrees * M_PI / 180, c = cos(a), s = sin(a), C = 1 - c;
    double r[3][3] = {{x * x * C + c, x * y * C - z * s, x * z * C + y * s},
                      {y * x * C + z * s, y * y * C + c, y * z * C - x * s},
                      {z * x * C - y * s, z * y * C + x * s, z * z * C + c}};
    sg_transform_identity(t);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            t->m[i][j] = r[i][j];
    return true;
}

void sg_transform_point(const SgTransform *t, const double p[3], double out[3])
{
    for (int r = 0; r < 3; r++)
        out[r] = t->m[r][0] * p[0] + t->m[r][1] * p[1] + t->m[r][2] * p[2] + t->m[r][3];
}

double sg_transform_determinant(const SgTransform *t)
{
    const double(*a)[4] = t->m;
    return a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
           a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
           a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
}

void sg_transform_normal(const SgTransform *t, const double n[3], double out[3])
{
    double cof[3][3];
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) {
            int r1 = (r + 1) % 3, r2 = (r + 2) % 3, c1 = (c + 1) % 3, c2 = (c + 2) % 3;
            cof[r][c] = t->m[r1][c1] * t->m[r2][c2] - t->m[r1][c2] * t->m[r2][c1];
        }
    double v[3];
    for (int r = 0; r < 3; r++)
        v[r] = cof[r][0] * n[0] + cof[r][1] * n[1] + cof[r][2] * n[2];
    bool mirrored = sg_transform_determinant(t) < 0;
    for (int a = 0; a < 3; a++)
        out[a] = mirrored ? -v[a] : v[a];
}
