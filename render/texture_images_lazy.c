/* texture_images.h's functions: each calls its namesake in libsg_images.so
 * (the OpenImageIO wrapper, render/texture_images.cpp), loaded when the
 * first texture cache is made (common/image_library.h): a scene without
 * image textures never loads OpenImageIO. */
#include "texture_images.h"

#include <pthread.h>

#include "image_library.h"

typedef SgTextureImages *(*Create)(int, double, SgError *);
typedef void (*Free)(SgTextureImages *);
typedef SgTextureImage *(*Open)(SgTextureImages *, const char *, SgError *);
typedef void (*Lookup)(SgTextureImages *, SgTextureImage *, int, float, float, SgTextureWrap, float[3]);
typedef size_t (*CacheBytes)(const SgTextureImages *, size_t *);

/* Resolved once, by the first sg_texture_images_create: every other
 * function takes what it made, so they are set before any of them runs. */
static struct {
    Create create;
    Free free;
    Open open;
    Lookup lookup;
    CacheBytes cache_bytes;
    SgError error;
} calls;
static pthread_once_t resolve_once = PTHREAD_ONCE_INIT;

static void resolve(void)
{
    SgError *e = &calls.error;
    calls.create = (Create)sg_image_library_symbol("sg_texture_images_create", e);
    calls.free = (Free)sg_image_library_symbol("sg_texture_images_free", e);
    calls.open = (Open)sg_image_library_symbol("sg_texture_images_open", e);
    calls.lookup = (Lookup)sg_image_library_symbol("sg_texture_image_lookup", e);
    calls.cache_bytes = (CacheBytes)sg_image_library_symbol("sg_texture_images_cache_bytes", e);
}

SgTextureImages *sg_texture_images_create(int threads, double cache_mb, SgError *err)
{
    pthread_once(&resolve_once, resolve);
    if (!calls.create || !calls.free || !calls.open || !calls.lookup || !calls.cache_bytes)
        return sg_fail(err, "%s", calls.error.message), NULL;
    return calls.create(threads, cache_mb, err);
}

void sg_texture_images_free(SgTextureImages *t)
{
    if (t)
        calls.free(t);
}

SgTextureImage *sg_texture_images_open(SgTextureImages *t, const char *path, SgError *err)
{
    return calls.open(t, path, err);
}

void sg_texture_image_lookup(SgTextureImages *t, SgTextureImage *image, int thread, float s, float tc,
                             SgTextureWrap wrap, float rgb[3])
{
    calls.lookup(t, image, thread, s, tc, wrap, rgb);
}

size_t sg_texture_images_cache_bytes(const SgTextureImages *t, size_t *images)
{
    return calls.cache_bytes(t, images);
}
