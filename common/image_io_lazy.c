/* image_io.h's functions: each calls its namesake in libsg_images.so (the
 * OpenImageIO wrapper, common/image_io.cpp), loaded on first use
 * (image_library.h). */
#include "image_io.h"

#include "image_library.h"

/* Returns what `name` (of function type `type`) returns, false when the
 * library or the function cannot be had (err says why). */
#define CALL(name, type, err, ...)                                \
    do {                                                          \
        type f = (type)sg_image_library_symbol(#name, err);       \
        return f && f(__VA_ARGS__);                               \
    } while (0)

bool sg_image_io_ready(SgError *err) { return sg_image_library_symbol("sg_image_write_exr", err) != NULL; }

typedef bool (*WriteExr)(const char *, int, int, const float *, const SgImageAttribute *, int, SgError *);
typedef bool (*WritePng)(const char *, int, int, const float *, double, SgError *);
typedef bool (*Read)(const char *, int *, int *, float **, SgError *);
typedef bool (*ReadAttribute)(const char *, const char *, char *, size_t, SgError *);
typedef bool (*ReadAttributes)(const char *, SgImageAttribute **, int *, SgError *);

bool sg_image_write_exr(const char *path, int width, int height, const float *rgb,
                        const SgImageAttribute *attributes, int attribute_count, SgError *err)
{
    CALL(sg_image_write_exr, WriteExr, err, path, width, height, rgb, attributes, attribute_count, err);
}

bool sg_image_write_png(const char *path, int width, int height, const float *rgb, double exposure, SgError *err)
{
    CALL(sg_image_write_png, WritePng, err, path, width, height, rgb, exposure, err);
}

bool sg_image_read(const char *path, int *width, int *height, float **rgb, SgError *err)
{
    CALL(sg_image_read, Read, err, path, width, height, rgb, err);
}

bool sg_image_read_attribute(const char *path, const char *name, char *buf, size_t size, SgError *err)
{
    CALL(sg_image_read_attribute, ReadAttribute, err, path, name, buf, size, err);
}

bool sg_image_read_attributes(const char *path, SgImageAttribute **attributes, int *count, SgError *err)
{
    CALL(sg_image_read_attributes, ReadAttributes, err, path, attributes, count, err);
}
