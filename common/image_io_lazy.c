/* image_io.h's functions: EXR files through OpenEXR, linked in
 * (exr_file.h); every other format through its namesake in
 * libsg_images.so (the OpenImageIO wrapper, common/image_io.cpp), loaded on
 * first use (image_library.h). A file is EXR by its magic number, not its
 * name. */
#include "image_io.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "exr_file.h"
#include "image_library.h"

/* Returns what `name` (of function type `type`) returns, false when the
 * library or the function cannot be had (err says why). */
#define CALL(name, type, err, ...)                                \
    do {                                                          \
        type f = (type)sg_image_library_symbol(#name, err);       \
        return f && f(__VA_ARGS__);                               \
    } while (0)

bool sg_image_io_ready(SgError *err) { return sg_image_library_symbol("sg_image_write_png", err) != NULL; }

typedef bool (*WritePng)(const char *, int, int, const float *, double, SgError *);
typedef bool (*Read)(const char *, int *, int *, float **, SgError *);

bool sg_image_write_exr(const char *path, int width, int height, const float *rgb,
                        const SgImageAttribute *attributes, int attribute_count, SgError *err)
{
    return sg_exr_write(path, width, height, rgb, attributes, attribute_count, err);
}

bool sg_image_write_png(const char *path, int width, int height, const float *rgb, double exposure, SgError *err)
{
    CALL(sg_image_write_png, WritePng, err, path, width, height, rgb, exposure, err);
}

/* 1: an EXR file, 0: another file, -1: cannot be opened (err says why). */
static int exr_or_other(const char *path, SgError *err)
{
    SgError e = {0};
    if (sg_exr_file_is_exr(path, &e))
        return 1;
    if (e.message[0]) {
        if (err)
            *err = e;
        return -1;
    }
    return 0;
}

bool sg_image_read(const char *path, int *width, int *height, float **rgb, SgError *err)
{
    *rgb = NULL;
    int kind = exr_or_other(path, err);
    if (kind != 0)
        return kind > 0 && sg_exr_read(path, width, height, rgb, err);
    CALL(sg_image_read, Read, err, path, width, height, rgb, err);
}

bool sg_image_read_attribute(const char *path, const char *name, char *buf, size_t size, SgError *err)
{
    if (size > 0)
        buf[0] = '\0';
    SgImageAttribute *all;
    int count;
    if (!sg_image_read_attributes(path, &all, &count, err))
        return false;
    int found = -1;
    for (int i = 0; i < count && found < 0; i++)
        if (!strcmp(all[i].name, name))
            found = i;
    if (found >= 0 && size > 0)
        snprintf(buf, size, "%s", all[found].value);
    free(all);
    return found >= 0 || sg_fail(err, "%s: no attribute %s", path, name);
}

bool sg_image_read_attributes(const char *path, SgImageAttribute **attributes, int *count, SgError *err)
{
    *attributes = NULL;
    *count = 0;
    int kind = exr_or_other(path, err);
    if (kind == 0)
        return sg_fail(err, "%s: cannot read: not an OpenEXR file (headers are read from EXR files only)", path);
    return kind > 0 && sg_exr_read_attributes(path, attributes, count, err);
}
