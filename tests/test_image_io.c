/* Image files (OpenEXR, and OpenImageIO for the rest): EXR round trip with metadata, PNG exposure and
 * sRGB encoding, errors that name the file, no partial outputs. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "image_io.h"
#include "image_library.h"
#include "input_file.h"
#include "support_files.h"

/* The whole file (the reader the parsers use); the test fails if it cannot be read. */
static char *read_all(const char *path, size_t *size)
{
    char *data;
    SgError err = {0};
    cr_assert(sg_read_file(path, NULL, (size_t)1 << 30, &data, size, &err), "%s", err.message);
    return data;
}

static bool contains(const char *buf, size_t n, const char *needle)
{
    size_t k = strlen(needle);
    for (size_t i = 0; i + k <= n; i++)
        if (memcmp(buf + i, needle, k) == 0)
            return true;
    return false;
}

Test(image_io, exr_round_trip_is_exact_with_metadata)
{
    const int w = 7, h = 5;
    float rgb[7 * 5 * 3];
    for (int i = 0; i < w * h * 3; i++)
        rgb[i] = (float)(i * 0.37 - 3.0) * (i % 4 == 0 ? 1e4f : 1.0f);
    SgImageAttribute attrs[] = {{"spp", "64"}, {"sampling", "guided"}};
    const char *path = "build/test_image_io.exr";
    SgError err = {0};
    cr_assert(sg_image_write_exr(path, w, h, rgb, attrs, 2, &err), "%s", err.message);
    int rw = 0, rh = 0;
    float *back = NULL;
    cr_assert(sg_image_read(path, &rw, &rh, &back, &err), "%s", err.message);
    cr_assert_eq(rw, w);
    cr_assert_eq(rh, h);
    cr_assert(memcmp(back, rgb, sizeof rgb) == 0, "EXR pixels changed on the way");
    free(back);
    /* string attributes sit in the EXR header as name, type "string", value */
    size_t n;
    char *bytes = read_all(path, &n);
    cr_assert(contains(bytes, n, "spp") && contains(bytes, n, "64"));
    cr_assert(contains(bytes, n, "sampling") && contains(bytes, n, "guided"));
    free(bytes);
    /* and read back by name */
    char value[16];
    cr_assert(sg_image_read_attribute(path, "spp", value, sizeof value, &err), "%s", err.message);
    cr_assert_str_eq(value, "64");
    cr_assert(sg_image_read_attribute(path, "sampling", value, 4, &err), "%s", err.message);
    cr_assert_str_eq(value, "gui", "cut to the buffer");
    err = (SgError){0};
    cr_assert_not(sg_image_read_attribute(path, "sg:nothing", value, sizeof value, &err));
    cr_assert(strstr(err.message, path) && strstr(err.message, "sg:nothing"), "%s", err.message);
    cr_assert_str_eq(value, "");
    unlink(path);
    err = (SgError){0};
    cr_assert_not(sg_image_read_attribute(path, "spp", value, sizeof value, &err));
    cr_assert(strstr(err.message, path), "%s", err.message);
}

Test(image_io, every_attribute_read_back_at_once)
{
    float rgb[2 * 1 * 3] = {1, 2, 3, 4, 5, 6};
    SgImageAttribute attrs[] = {{"spp", "64"}, {"sg:shards", "0,2"}, {"sg:scene", "a scene with spaces.json"}};
    const char *path = "build/test_image_io_attributes.exr";
    SgError err = {0};
    cr_assert(sg_image_write_exr(path, 2, 1, rgb, attrs, 3, &err), "%s", err.message);
    SgImageAttribute *back = NULL;
    int count = 0;
    cr_assert(sg_image_read_attributes(path, &back, &count, &err), "%s", err.message);
    /* ours, each once with its value, among the format's own (compression...) */
    for (int a = 0; a < 3; a++) {
        int found = 0;
        for (int i = 0; i < count; i++)
            if (!strcmp(back[i].name, attrs[a].name)) {
                found++;
                cr_assert_str_eq(back[i].value, attrs[a].value);
            }
        cr_assert_eq(found, 1, "%s found %d times", attrs[a].name, found);
    }
    cr_assert_gt(count, 3, "the EXR header's own fields are missing");
    free(back); /* one allocation */
    unlink(path);
    err = (SgError){0};
    cr_assert_not(sg_image_read_attributes(path, &back, &count, &err));
    cr_assert(strstr(err.message, path), "%s", err.message);
    cr_assert_null(back);
    cr_assert_eq(count, 0);
}

Test(image_io, png_applies_exposure_and_srgb)
{
    const int w = 4, h = 1;
    /* 0.5 linear -> sRGB 0.7354 -> 188; 0.5 at +1 stop -> 1.0 -> 255;
     * 0.001 -> 12.92 * 0.001 -> 3; negative and NaN -> 0 */
    float rgb[4 * 3] = {0.5f, 0.5f, 0.5f, 0.001f, 0.001f, 0.001f, -1, -1, -1, NAN, NAN, NAN};
    const char *path = "build/test_image_io.png";
    SgError err = {0};
    cr_assert(sg_image_write_png(path, w, h, rgb, 0.0, &err), "%s", err.message);
    int rw, rh;
    float *back = NULL;
    cr_assert(sg_image_read(path, &rw, &rh, &back, &err), "%s", err.message);
    cr_assert_float_eq(back[0] * 255.0f, 188.0f, 1e-3);
    cr_assert_float_eq(back[3] * 255.0f, 3.0f, 1e-3);
    cr_assert_float_eq(back[6], 0.0f, 1e-6);
    cr_assert_float_eq(back[9], 0.0f, 1e-6);
    free(back);
    cr_assert(sg_image_write_png(path, w, h, rgb, 1.0, &err), "%s", err.message);
    cr_assert(sg_image_read(path, &rw, &rh, &back, &err), "%s", err.message);
    cr_assert_float_eq(back[0] * 255.0f, 255.0f, 1e-3);
    free(back);
    unlink(path);
}

Test(image_io, errors_name_the_file_and_leave_no_partial_output)
{
    SgError err = {0};
    int w, h;
    float *rgb = NULL;
    cr_assert_not(sg_image_read("build/no-such-image.exr", &w, &h, &rgb, &err));
    cr_assert(strstr(err.message, "build/no-such-image.exr") != NULL, "%s", err.message);
    cr_assert_null(rgb);

    /* a file that is not an image */
    const char *junk = "build/test_image_io_junk.exr";
    FILE *f = fopen(junk, "wb");
    fputs("not an image at all", f);
    fclose(f);
    err = (SgError){0};
    cr_assert_not(sg_image_read(junk, &w, &h, &rgb, &err));
    cr_assert(strstr(err.message, junk) != NULL, "%s", err.message);

    /* a failed write does not touch the existing file */
    err = (SgError){0};
    float px[3] = {1, 2, 3};
    cr_assert_not(sg_image_write_exr(junk, 0, 1, px, NULL, 0, &err));
    size_t n;
    char *bytes = read_all(junk, &n);
    cr_assert(n == strlen("not an image at all") && memcmp(bytes, "not an image at all", n) == 0);
    free(bytes);
    unlink(junk);

    err = (SgError){0};
    cr_assert_not(sg_image_write_exr("build/no/such/dir/x.exr", 1, 1, px, NULL, 0, &err));
    cr_assert(strstr(err.message, "build/no/such/dir/x.exr") != NULL, "%s", err.message);
    cr_assert(access("build/no/such/dir/x.exr", F_OK) != 0);
}

/* OpenImageIO loads on first use (common/image_library.h): without its
 * library a PNG cannot be written, and the program learns it in one line
 * naming the cause, with no file left; an EXR (OpenEXR, linked in) is
 * written and read all the same, and OpenImageIO is never loaded for it. */
Test(image_io, without_the_image_library_no_png_but_exr_all_the_same)
{
    char dir[] = "/tmp/sg-test-nolib-XXXXXX";
    cr_assert_not_null(mkdtemp(dir));
    cr_assert_eq(setenv("SG_IMAGES_LIBRARY", "/nonexistent/libsg_images.so", 1), 0);
    char png[64], exr[64];
    snprintf(png, sizeof png, "%s/a.png", dir);
    snprintf(exr, sizeof exr, "%s/a.exr", dir);
    const float rgb[3] = {1, 2, 3};
    SgImageAttribute spp = {"spp", "4"};
    SgError err = {0};
    cr_assert(sg_image_write_exr(exr, 1, 1, rgb, &spp, 1, &err), "%s", err.message);
    int w, h;
    float *back = NULL;
    cr_assert(sg_image_read(exr, &w, &h, &back, &err), "%s", err.message);
    cr_assert(w == 1 && h == 1 && back[0] == 1 && back[1] == 2 && back[2] == 3);
    free(back);
    char value[8];
    cr_assert(sg_image_read_attribute(exr, "spp", value, sizeof value, &err), "%s", err.message);
    cr_assert_str_eq(value, "4");
    unlink(exr);

    cr_assert_not(sg_image_io_ready(&err));
    cr_assert(strstr(err.message, "image support") && strstr(err.message, "/nonexistent/libsg_images.so"), "%s",
              err.message);
    cr_assert(strchr(err.message, '\n') == NULL);
    SgError write_err = {0};
    cr_assert_not(sg_image_write_png(png, 1, 1, rgb, 0.0, &write_err));
    cr_assert_str_eq(write_err.message, err.message);
    cr_assert_neq(access(png, F_OK), 0, "a file was left");
    rmdir(dir);
}

/* Our EXR reader (OpenEXR) gives, bit for bit, what OpenImageIO reads from
 * EXR files others wrote: half floats with PIZ (Tungsten's reference), a
 * data window away from the origin with alpha, one luminance channel. */
static void readers_agree(const char *path)
{
    typedef bool (*Read)(const char *, int *, int *, float **, SgError *);
    SgError err = {0};
    Read oiio_read = (Read)sg_image_library_symbol("sg_image_read", &err);
    cr_assert_not_null(oiio_read, "%s", err.message);
    int w, h, ow, oh;
    float *ours = NULL, *theirs = NULL;
    cr_assert(sg_image_read(path, &w, &h, &ours, &err), "%s", err.message);
    cr_assert(oiio_read(path, &ow, &oh, &theirs, &err), "%s", err.message);
    cr_assert(w == ow && h == oh, "%s: %dx%d, OpenImageIO %dx%d", path, w, h, ow, oh);
    size_t differ = 0;
    for (size_t i = 0; i < (size_t)w * h * 3; i++)
        differ += memcmp(&ours[i], &theirs[i], sizeof(float)) != 0;
    cr_assert_eq(differ, 0, "%s: %zu of %zu values differ from OpenImageIO's", path, differ, (size_t)w * h * 3);
    free(ours);
    free(theirs);
}

Test(image_io, exr_files_others_wrote_read_as_openimageio_reads_them)
{
    const char *tmp = sg_test_tmpdir();
    char cmd[9000], a[4200], b[4200];
    snprintf(a, sizeof a, "%s/rgba-half-offset.exr", tmp);
    snprintf(b, sizeof b, "%s/luminance.exr", tmp);
    snprintf(cmd, sizeof cmd,
             "oiiotool --pattern checker:width=3:height=2:color1=0.25,2,7,1:color2=-1,0.5,3e4,0.5 9x7 4 "
             "--origin +5+3 -d half --compression piz -o %s && "
             "oiiotool --pattern fill:top=0.1:bottom=9 6x5 1 --chnames Y -d float -o %s",
             a, b);
    char err[2048] = "";
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 0, "oiiotool: %s", err);
    readers_agree(a);
    readers_agree(b);
    if (sg_test_have_shared_scenes())
        readers_agree(sg_test_source_path("../shared/scenes/staircase/TungstenRender.exr"));
}
