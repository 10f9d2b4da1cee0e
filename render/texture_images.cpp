#include "texture_images.h"

#include <OpenImageIO/texture.h>

#include <new>
#include <string>
#include <vector>

using OIIO::TextureOpt;
using OIIO::TextureSystem;
using OIIO::ustring;

struct SgTextureImage {
    TextureSystem::TextureHandle *handle;
    int channels;
};

struct SgTextureImages {
    TextureSystem *ts;
    std::vector<TextureSystem::Perthread *> threads;
    std::vector<SgTextureImage *> images;
};

extern "C" SgTextureImages *sg_texture_images_create(int threads, double cache_mb, SgError *err)
{
    SgTextureImages *t = new (std::nothrow) SgTextureImages();
    if (!t)
        return sg_fail(err, "textures: out of memory"), nullptr;
    t->ts = TextureSystem::create(false); /* our own cache, not the process-wide one */
    /* bounded texel memory; untiled files (TGA, PNG, JPEG) are cut into
     * 64x64 tiles so that only what is looked up is held; no MIP levels
     * are made, as lookups are point samples */
    t->ts->attribute("max_memory_MB", (float)cache_mb);
    t->ts->attribute("autotile", 64);
    t->ts->attribute("automip", 0);
    t->ts->attribute("accept_untiled", 1);
    t->ts->attribute("max_open_files", 64);
    for (int i = 0; i < threads; i++)
        t->threads.push_back(t->ts->create_thread_info());
    return t;
}

extern "C" void sg_texture_images_free(SgTextureImages *t)
{
    if (!t)
        return;
    for (TextureSystem::Perthread *p : t->threads)
        t->ts->destroy_thread_info(p);
    for (SgTextureImage *i : t->images)
        delete i;
    /* under ASan: new_delete_type_mismatch=0 (tests/run-tests.sh); teardown:
     * without it OpenImageIO 2.4 leaks the private cache of a texture system
     * that never opened a file (a scene whose only textures are
     * checkerboards or missing images) */
    TextureSystem::destroy(t->ts, true);
    delete t;
}

extern "C" SgTextureImage *sg_texture_images_open(SgTextureImages *t, const char *path, SgError *err)
{
    ustring name(path);
    TextureSystem::TextureHandle *handle = t->ts->get_texture_handle(name);
    int channels = 0;
    if (!handle || !t->ts->good(handle) || !t->ts->get_texture_info(handle, nullptr, 0, ustring("channels"),
                                                                     OIIO::TypeInt, &channels) ||
        channels < 1) {
        std::string why = t->ts->has_error() ? t->ts->geterror() : std::string("cannot be read");
        size_t eol = why.find('\n');
        return sg_fail(err, "%s: %s", path, why.substr(0, eol).c_str()), nullptr;
    }
    SgTextureImage *image = new (std::nothrow) SgTextureImage{handle, channels};
    if (!image)
        return sg_fail(err, "%s: out of memory", path), nullptr;
    t->images.push_back(image);
    return image;
}

static TextureOpt::Wrap oiio_wrap(SgTextureWrap w)
{
    switch (w) {
    case SG_WRAP_CLAMP: return TextureOpt::WrapClamp;
    case SG_WRAP_BLACK: return TextureOpt::WrapBlack;
    case SG_WRAP_REPEAT: break;
    }
    return TextureOpt::WrapPeriodic;
}

extern "C" void sg_texture_image_lookup(SgTextureImages *t, SgTextureImage *image, int thread, float s, float tc,
                                        SgTextureWrap wrap, float rgb[3])
{
    TextureOpt opt;
    opt.swrap = opt.twrap = oiio_wrap(wrap);
    opt.mipmode = TextureOpt::MipModeNoMIP;
    opt.interpmode = TextureOpt::InterpBilinear;
    float texel[3] = {0, 0, 0};
    int n = image->channels >= 3 ? 3 : 1;
    if (!t->ts->texture(image->handle, t->threads[(size_t)thread], opt, s, tc, 0, 0, 0, 0, n, texel))
        t->ts->geterror(); /* a tile that cannot be read gives black; clear the message */
    if (n == 1)
        texel[1] = texel[2] = texel[0];
    rgb[0] = texel[0];
    rgb[1] = texel[1];
    rgb[2] = texel[2];
}

extern "C" size_t sg_texture_images_cache_bytes(const SgTextureImages *t, size_t *images)
{
    long long used = 0, total = 0; /* the texture system answers for its cache */
    t->ts->getattribute("stat:cache_memory_used", OIIO::TypeInt64, &used);
    t->ts->getattribute("stat:image_size", OIIO::TypeInt64, &total);
    if (images)
        *images = (size_t)total;
    return (size_t)used;
}
