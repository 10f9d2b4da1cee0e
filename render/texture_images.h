/* Image textures through OpenImageIO's TextureSystem: point lookups with
 * bilinear filtering (a path tracer at many samples per pixel needs no
 * ray-differential filtering), from a tile cache of bounded memory, so that
 * a scene's textures cost at most that much however many and large they are.
 * Thread safe: each worker thread looks up with its own per-thread slot. */
#ifndef SG_RENDER_TEXTURE_IMAGES_H
#define SG_RENDER_TEXTURE_IMAGES_H

#include <stdbool.h>
#include <stddef.h>

#include "error.h"
#include "scene.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct SgTextureImages SgTextureImages;
typedef struct SgTextureImage SgTextureImage; /* one file, opened */

/* A cache of at most cache_mb megabytes of texels, for `threads` worker
 * threads (thread indices in [0, threads)). */
SgTextureImages *sg_texture_images_create(int threads, double cache_mb, SgError *err);
void sg_texture_images_free(SgTextureImages *t);

/* Opens path (its header only: texels load tile by tile as looked up);
 * NULL with "path: cause" if it cannot be read. */
SgTextureImage *sg_texture_images_open(SgTextureImages *t, const char *path, SgError *err);

/* The texel colour at (s, t) (s right, t down, [0, 1) across the image),
 * bilinear; grey images give (g, g, g). Raw values: decoding is the
 * caller's. */
void sg_texture_image_lookup(SgTextureImages *t, SgTextureImage *image, int thread, float s, float tc,
                             SgTextureWrap wrap, float rgb[3]);

/* Bytes of texels the cache holds; *images: what all the opened images
 * would take in full. */
size_t sg_texture_images_cache_bytes(const SgTextureImages *t, size_t *images);

#ifdef __cplusplus
}
#endif
#endif
