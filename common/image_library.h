/* OpenImageIO, loaded when an image is first read or written.
 *
 * OpenImageIO brings some 250 shared objects (OpenCV, FFmpeg, GDAL...):
 * linked into a program, they cost half a second of CPU at every start,
 * more than voxelizing a small scene. So the two thin wrappers around it
 * (common/image_io.cpp, render/texture_images.cpp) are built into a shared
 * object of their own, libsg_images.so in the build folder, and the
 * functions of image_io.h and render/texture_images.h open it on first
 * use: a program that reads and writes only EXR files (common/exr_file.h,
 * OpenEXR linked in: every render and merge but for a PNG or an image
 * texture) never loads it. SG_IMAGES_LIBRARY names
 * another copy. */
#ifndef SG_IMAGE_LIBRARY_H
#define SG_IMAGE_LIBRARY_H

#include <stdbool.h>

#include "error.h"

/* The wrappers' function `name`, the library loaded first (once, thread
 * safe); NULL with the cause in err ("image support: " and the loader's
 * message, which names the file) when it cannot be loaded or lacks the
 * function. */
void *sg_image_library_symbol(const char *name, SgError *err);

#endif
