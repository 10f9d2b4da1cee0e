/* The mean colour of image files: what stands in for an image texture
 * where (u, v) cannot be looked up (SgTexture.mean, the material's
 * diffuse). Shared by the pbrt and the Assimp loaders; each keeps a cache,
 * as scenes name one file from many materials. */
#ifndef SG_IMAGE_AVERAGE_H
#define SG_IMAGE_AVERAGE_H

#include <stdbool.h>
#include <stddef.h>

typedef struct SgImageAverage {
    char *path;
    double gamma; /* the encoding it was averaged with */
    float value[3];
    bool readable;
} SgImageAverage;

typedef struct SgImageAverages {
    SgImageAverage *entries;
    size_t count, capacity;
} SgImageAverages;

/* pbrt's default encoding of an image file: float formats (.exr, .pfm,
 * .hdr) hold linear values (0), the others 8-bit sRGB (-1). */
double sg_image_default_gamma(const char *path);

/* The mean linear colour of an image file, cached in c by path and
 * encoding. gamma: 0 linear, -1 sRGB, else the exponent. False if the file
 * cannot be read (out untouched). *first (if given): true when this call
 * tried the file, false when the answer came from the cache, so that a
 * caller can warn once per file. */
bool sg_image_average(SgImageAverages *c, const char *path, double gamma, float out[3], bool *first);
void sg_image_averages_free(SgImageAverages *c);

#endif
