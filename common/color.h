/* Colour in one place: the sRGB transfer curve (IEC 61966-2-1) and the
 * luminance of linear sRGB / Rec. 709 primaries. Header-only so that C and
 * C++ callers (image_io.cpp) inline the same arithmetic. */
#ifndef SG_COLOR_H
#define SG_COLOR_H

#include <math.h>

/* The 8-bit sRGB value of a linear value: the sRGB curve, then * 255,
 * rounded half up, clamped to 0..255; zero, negatives and NaN give 0. The
 * PNGs that render writes and the 8-bit MSE (render --log, bench) use it. */
static inline int sg_srgb_byte(float linear)
{
    if (!(linear > 0.0f)) /* also maps NaN to 0 */
        return 0;
    float s = linear <= 0.0031308f ? 12.92f * linear : 1.055f * powf(linear, 1.0f / 2.4f) - 0.055f;
    float v = s * 255.0f + 0.5f;
    return v >= 255.0f ? 255 : (int)v;
}

/* The inverse curve: an sRGB-encoded value in 0..1 to linear. */
static inline double sg_srgb_to_linear(double c)
{
    return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4);
}

/* Luminance Y of linear sRGB (Rec. 709 weights), in double... */
static inline double sg_luminance(double r, double g, double b)
{
    return 0.2126 * r + 0.7152 * g + 0.0722 * b;
}

/* ...and in float, for single-precision callers (the same weights rounded
 * to float; not bit-identical to sg_luminance). */
static inline float sg_luminancef(float r, float g, float b)
{
    return 0.2126f * r + 0.7152f * g + 0.0722f * b;
}

#endif
