/* OpenEXR files through the OpenEXR library itself (wrapper:
 * exr_file.cpp), linked into the programs: a few small shared objects,
 * where OpenImageIO brings some 250 (common/image_library.h). Every render
 * and merge reads or writes EXR, so they no longer pay OpenImageIO's half
 * second of start; image_io.h sends EXR files here and every other format
 * to OpenImageIO. Images are linear float RGB, row-major from the top-left
 * pixel; writes go to a temporary name and are renamed into place. */
#ifndef SG_EXR_FILE_H
#define SG_EXR_FILE_H

#include <stdbool.h>
#include <stddef.h>

#include "error.h"
#include "image_io.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Whether the file at path starts with OpenEXR's magic number; false with
 * the cause in err (naming path) when it cannot be opened, false with err
 * untouched when it is some other file. */
bool sg_exr_file_is_exr(const char *path, SgError *err);

/* Float RGB, ZIP compressed, each attribute a string; read back before it
 * takes the target's name (a full disk can go unseen by the writer). */
bool sg_exr_write(const char *path, int width, int height, const float *rgb, const SgImageAttribute *attributes,
                  int attribute_count, SgError *err);
/* The data window as float RGB (R, G, B; else Y; else the first channel in
 * all three); caller frees *rgb. */
bool sg_exr_read(const char *path, int *width, int *height, float **rgb, SgError *err);
/* Every attribute of the header as text (strings as they are, numbers,
 * vectors and boxes as numbers with spaces, other types by their type
 * name), in the header's order (by name); one allocation, the caller frees
 * *attributes. */
bool sg_exr_read_attributes(const char *path, SgImageAttribute **attributes, int *count, SgError *err);

#ifdef __cplusplus
}
#endif
#endif
