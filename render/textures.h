/* The scene's textures while rendering: each SgTexture (common/scene.h)
 * evaluated at a hit's texture coordinates, images looked up through
 * render/texture_images.h and decoded to linear values. */
#ifndef SG_RENDER_TEXTURES_H
#define SG_RENDER_TEXTURES_H

#include <stdbool.h>
#include <stdint.h>

#include "error.h"
#include "scene.h"
#include "vecmath.h"

typedef struct TextureSet TextureSet;

/* Texture cache size when the options give none (megabytes). */
#define TEXTURE_CACHE_MB_DEFAULT 256.0

/* Does any material of s vary over its surface? */
bool textures_needed(const SgScene *s);

/* s's textures and texture coordinates (copied), its triangles' vertex
 * indices `indices` (kept: they must outlive the set), for `threads`
 * worker threads, with a texel cache of cache_mb megabytes. Fails, naming
 * path or the image, on an image that cannot be opened. */
TextureSet *texture_set_create(const SgScene *s, const uint32_t *indices, int threads, double cache_mb,
                               const char *path, SgError *err);
void texture_set_free(TextureSet *t);

/* Texture `texture` (1 + index in the scene's list) at barycentrics
 * (b1, b2) of triangle tri, looked up by worker `thread`. */
Vec3 texture_set_eval_at(const TextureSet *t, uint32_t texture, uint32_t tri, float b1, float b2, int thread);
/* The texture coordinates of triangle tri's corners; false: the scene has none. */
bool texture_set_triangle_uvs(const TextureSet *t, uint32_t tri, float uv[3][2]);
/* The same at texture coordinates (u, v). */
Vec3 texture_set_eval(const TextureSet *t, uint32_t texture, float u, float v, int thread);

/* Bytes of texels cached now; *images: all the images in full. */
size_t texture_set_cache_bytes(const TextureSet *t, size_t *images);

#endif
