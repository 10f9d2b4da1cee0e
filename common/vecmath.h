/* Small vector helpers for the renderer and tools (single precision). */
#ifndef SG_VECMATH_H
#define SG_VECMATH_H

#include <math.h>
#ifdef __SSE__
#include <xmmintrin.h>
#endif

typedef struct Vec3 {
    float x, y, z;
} Vec3;

/* max and min in one instruction (fmaxf and fminf are libm calls unless
 * NaN semantics are given up for the whole build); a NaN in b is returned,
 * one in a is not. The ternary means the same, but GCC often compiles it
 * to a compare and a jump, mispredicted where the sign is random (a
 * cosine clamped at 0); MAXSS and MINSS are that ternary exactly. */
#ifdef __SSE__
static inline float sg_maxf(float a, float b)
{
    return _mm_cvtss_f32(_mm_max_ss(_mm_set_ss(a), _mm_set_ss(b)));
}
static inline float sg_minf(float a, float b)
{
    return _mm_cvtss_f32(_mm_min_ss(_mm_set_ss(a), _mm_set_ss(b)));
}
#else
static inline float sg_maxf(float a, float b) { return a > b ? a : b; }
static inline float sg_minf(float a, float b) { return a < b ? a : b; }
#endif

static inline Vec3 v3(float x, float y, float z) { Vec3 r = {x, y, z}; return r; }
static inline Vec3 v3_add(Vec3 a, Vec3 b) { return v3(a.x + b.x, a.y + b.y, a.z + b.z); }
static inline Vec3 v3_sub(Vec3 a, Vec3 b) { return v3(a.x - b.x, a.y - b.y, a.z - b.z); }
static inline Vec3 v3_mul(Vec3 a, Vec3 b) { return v3(a.x * b.x, a.y * b.y, a.z * b.z); }
static inline Vec3 v3_scale(Vec3 a, float s) { return v3(a.x * s, a.y * s, a.z * s); }
static inline float v3_dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline Vec3 v3_cross(Vec3 a, Vec3 b)
{
    return v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline float v3_length(Vec3 a) { return sqrtf(v3_dot(a, a)); }
static inline Vec3 v3_normalize(Vec3 a)
{
    float l = v3_length(a);
    return l > 0 ? v3_scale(a, 1.0f / l) : a;
}
static inline float v3_max_component(Vec3 a)
{
    return sg_maxf(a.x, sg_maxf(a.y, a.z));
}

/* Orthonormal basis around unit n with no precision loss near n = -z
 * (Duff et al. 2017, "Building an orthonormal basis, revisited"). */
static inline void v3_basis(Vec3 n, Vec3 *t, Vec3 *b)
{
    float sign = copysignf(1.0f, n.z);
    float a = -1.0f / (sign + n.z);
    float c = n.x * n.y * a;
    *t = v3(1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x);
    *b = v3(c, sign + n.y * n.y * a, -n.y);
}

/* Double-precision 3-vectors as plain arrays, for the precompute. */
static inline double d3_dot(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
static inline void d3_sub(const double a[3], const double b[3], double r[3])
{
    r[0] = a[0] - b[0]; r[1] = a[1] - b[1]; r[2] = a[2] - b[2];
}
static inline void d3_cross(const double a[3], const double b[3], double r[3])
{
    double x = a[1] * b[2] - a[2] * b[1];
    double y = a[2] * b[0] - a[0] * b[2];
    double z = a[0] * b[1] - a[1] * b[0];
    r[0] = x; r[1] = y; r[2] = z;
}
static inline double d3_length(const double a[3]) { return sqrt(d3_dot(a, a)); }
/* r = a x b made unit (a and b not parallel): the axis perpendicular to both. */
static inline void d3_unit_cross(const double a[3], const double b[3], double r[3])
{
    d3_cross(a, b, r);
    double len = d3_length(r);
    for (int c = 0; c < 3; c++)
        r[c] /= len;
}

#endif
