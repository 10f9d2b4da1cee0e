/* Image files: EXR through OpenEXR (exr_file.h, linked in), every other
 * format through OpenImageIO (wrapper: image_io.cpp, loaded on first use;
 * image_io_lazy.c sends each file to one or the other). Images are linear
 * float RGB, row-major from the top-left pixel. */
#ifndef SG_IMAGE_IO_H
#define SG_IMAGE_IO_H

#include <stdbool.h>
#include <stddef.h>

#include "error.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct SgImageAttribute {
    const char *name;
    const char *value; /* stored as a string attribute */
} SgImageAttribute;

/* Loads OpenImageIO now (it loads on first use: common/image_library.h),
 * which PNG and every format but EXR need; false with the cause in err when
 * it cannot be. */
bool sg_image_io_ready(SgError *err);

/* Linear float RGB EXR with string attributes (spp, seconds, mode, seed...). */
bool sg_image_write_exr(const char *path, int width, int height, const float *rgb,
                        const SgImageAttribute *attributes, int attribute_count,
                        SgError *err);
/* 8-bit sRGB PNG of rgb * 2^exposure. */
bool sg_image_write_png(const char *path, int width, int height, const float *rgb,
                        double exposure, SgError *err);
/* Reads an EXR, or any image OpenImageIO knows, as float RGB; caller frees *rgb. */
bool sg_image_read(const char *path, int *width, int *height, float **rgb, SgError *err);
/* The attribute `name` of an EXR file's header as text (a string attribute
 * as written by sg_image_write_exr, other types as exr_file.h formats
 * them) into buf; false with the cause in err when the file cannot be
 * opened, is not an EXR file or has no such attribute. */
bool sg_image_read_attribute(const char *path, const char *name, char *buf, size_t size, SgError *err);
/* Every attribute of an EXR file's header as text (each as
 * sg_image_read_attribute gives it), in the header's order: one allocation
 * holds the *count entries and their strings; the caller frees *attributes.
 * false with the cause in err when the file cannot be read as an EXR file. */
bool sg_image_read_attributes(const char *path, SgImageAttribute **attributes, int *count, SgError *err);

#ifdef __cplusplus
}
#endif
#endif
