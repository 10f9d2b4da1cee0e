/* common/color.h: the sRGB curve (encoding to bytes, decoding) and the
 * Rec. 709 luminance weights, the one copy that render's PNG, its --log
 * mse8, the benchmarks, the scene loaders and the tests share. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <unistd.h>

#include "color.h"
#include "image_io.h"

Test(srgb, byte_known_values)
{
    /* linear 0.5 -> sRGB 0.7354 -> 187.5 + 0.5 -> 188 */
    cr_assert_eq(sg_srgb_byte(0.5f), 188);
    cr_assert_eq(sg_srgb_byte(0.18f), 118);
    /* the linear segment: 12.92 * 0.001 * 255 = 3.29, rounded half up: 3 */
    cr_assert_eq(sg_srgb_byte(0.001f), 3);
    cr_assert_eq(sg_srgb_byte(0.0031308f), 10); /* the knee: 0.04045 * 255 = 10.3 */
    cr_assert_eq(sg_srgb_byte(0.99f), 254);
    cr_assert_eq(sg_srgb_byte(0.996f), 255);
    cr_assert_eq(sg_srgb_byte(1.0f), 255);
    cr_assert_eq(sg_srgb_byte(1e30f), 255, "clamped");
    cr_assert_eq(sg_srgb_byte(INFINITY), 255);
    cr_assert_eq(sg_srgb_byte(0.0f), 0);
    cr_assert_eq(sg_srgb_byte(-1.0f), 0);
    cr_assert_eq(sg_srgb_byte(NAN), 0);
}

Test(srgb, byte_is_monotone)
{
    int last = 0;
    for (int i = 0; i <= 100000; i++) {
        int b = sg_srgb_byte(i * 1.1e-5f);
        cr_assert(b >= last && b <= 255, "byte %d after %d at %d", b, last, i);
        last = b;
    }
    cr_assert_eq(last, 255);
}

Test(srgb, decode_known_values)
{
    cr_assert_eq(sg_srgb_to_linear(0.0), 0.0);
    cr_assert_float_eq(sg_srgb_to_linear(1.0), 1.0, 1e-15);
    cr_assert_float_eq(sg_srgb_to_linear(0.5), 0.214041140482232, 1e-14);
    cr_assert_float_eq(sg_srgb_to_linear(0.04045), 0.04045 / 12.92, 1e-17);
    /* the two pieces meet at the knee */
    double below = sg_srgb_to_linear(0.04045), above = sg_srgb_to_linear(0.0404501);
    cr_assert(above > below && above - below < 1e-7, "%.17g %.17g", below, above);
}

Test(srgb, every_byte_round_trips)
{
    for (int b = 0; b < 256; b++) {
        float linear = (float)sg_srgb_to_linear(b / 255.0);
        cr_assert_eq(sg_srgb_byte(linear), b, "byte %d decodes to %.9g, encodes to %d", b,
                     linear, sg_srgb_byte(linear));
    }
}

/* The PNG writer encodes with sg_srgb_byte: its bytes read back equal it. */
Test(srgb, png_writer_uses_it)
{
    enum { N = 300 };
    float rgb[N * 3];
    for (int i = 0; i < N * 3; i++)
        rgb[i] = i % 7 == 0 ? -0.5f : (float)pow(i / (double)(N * 3 - 1), 2.2) * 1.2f;
    const char *path = "build/test_color.png";
    SgError err = {0};
    const double exposure = -0.5;
    cr_assert(sg_image_write_png(path, N, 1, rgb, exposure, &err), "%s", err.message);
    int w = 0, h = 0;
    float *back = NULL;
    cr_assert(sg_image_read(path, &w, &h, &back, &err), "%s", err.message);
    cr_assert(w == N && h == 1);
    float scale = (float)exp2(exposure);
    for (int i = 0; i < N * 3; i++)
        cr_assert_eq((int)lrintf(back[i] * 255.0f), sg_srgb_byte(rgb[i] * scale), "value %d", i);
    free(back);
    unlink(path);
}

Test(luminance, weights)
{
    cr_assert_eq(sg_luminance(1, 0, 0), 0.2126);
    cr_assert_eq(sg_luminance(0, 1, 0), 0.7152);
    cr_assert_eq(sg_luminance(0, 0, 1), 0.0722);
    cr_assert_float_eq(sg_luminance(1, 1, 1), 1.0, 1e-15, "grey keeps its value");
    cr_assert_float_eq(sg_luminance(2, 4, 8), 2 * 0.2126 + 4 * 0.7152 + 8 * 0.0722, 1e-15);
    cr_assert_eq(sg_luminance(0, 0, 0), 0.0);
}

Test(luminance, float_version)
{
    cr_assert_eq(sg_luminancef(1, 0, 0), 0.2126f);
    cr_assert_eq(sg_luminancef(0, 1, 0), 0.7152f);
    cr_assert_eq(sg_luminancef(0, 0, 1), 0.0722f);
    cr_assert_float_eq(sg_luminancef(1, 1, 1), 1.0f, 1e-6f);
    cr_assert_float_eq(sg_luminancef(0.3f, 0.6f, 0.9f), (float)sg_luminance(0.3, 0.6, 0.9), 1e-6f);
}
