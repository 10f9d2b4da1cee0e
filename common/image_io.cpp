// OpenImageIO behind the C header image_io.h, for every format but EXR
// (exr_file.cpp: image_io_lazy.c sends each file to one or the other): no
// C++ type crosses it.
// Every write goes to a temporary name and is renamed into place.
#include "image_io.h"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imageio.h>

#include <cmath>
#include <cstdio>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "color.h"
#include "output_file.h"

using namespace OIIO;

namespace {

bool reads_back(const char *file, const char *format_name, const ImageSpec &spec, const void *pixels,
                TypeDesc pixel_type)
{
    auto in = ImageInput::create(format_name);
    if (!in)
        return false;
    ImageSpec config, got;
    if (!in->open(file, got, config))
        return false;
    bool same = got.width == spec.width && got.height == spec.height && got.nchannels == spec.nchannels;
    std::size_t bytes = (std::size_t)spec.width * spec.height * spec.nchannels * pixel_type.size();
    std::vector<unsigned char> back(same ? bytes : 0);
    same = same && in->read_image(0, 0, 0, spec.nchannels, pixel_type, back.data()) &&
           std::memcmp(back.data(), pixels, bytes) == 0;
    in->close();
    return same;
}

// Writes pixels (type `format` in memory is float RGB) through a temp file
// with an explicit format name, since the temp name has no usable extension.
bool write_through_temp(const char *path, const char *format_name, const ImageSpec &spec,
                        const void *pixels, TypeDesc pixel_type, SgError *err)
{
    char tmp[4096];
    sg_temp_path(path, tmp, sizeof tmp);
    auto out = ImageOutput::create(format_name);
    if (!out)
        return sg_fail(err, "%s: OpenImageIO has no %s writer", path, format_name);
    if (!out->open(tmp, spec)) {
        std::string msg = out->geterror();
        std::remove(tmp);
        return sg_fail(err, "%s: cannot write: %s", path, msg.c_str());
    }
    bool ok = out->write_image(pixel_type, pixels);
    std::string msg = ok ? std::string() : out->geterror();
    ok = out->close() && ok;
    if (!ok) {
        if (msg.empty())
            msg = out->geterror();
        std::remove(tmp);
        return sg_fail(err, "%s: cannot write: %s", path, msg.c_str());
    }
    // Writers do not all see a failed write (a full disk while OpenEXR
    // writes its offset table): the file must read back as written before
    // it takes the target's name. Both formats are lossless here.
    if (!reads_back(tmp, format_name, spec, pixels, pixel_type)) {
        std::remove(tmp);
        return sg_fail(err, "%s: cannot write: the file does not read back as written (disk full?)",
                       path);
    }
    return sg_commit_temp(tmp, path, err);
}

bool check_size(const char *path, int width, int height, const float *rgb, SgError *err)
{
    if (width <= 0 || height <= 0 || !rgb)
        return sg_fail(err, "%s: empty image (%dx%d)", path, width, height);
    return true;
}

} // namespace

extern "C" bool sg_image_write_png(const char *path, int width, int height, const float *rgb,
                                   double exposure, SgError *err)
{
    if (!check_size(path, width, height, rgb, err))
        return false;
    float scale = (float)std::exp2(exposure);
    size_t n = (size_t)width * (size_t)height * 3;
    std::vector<unsigned char> bytes(n);
    for (size_t i = 0; i < n; i++)
        bytes[i] = (unsigned char)sg_srgb_byte(rgb[i] * scale);
    ImageSpec spec(width, height, 3, TypeDesc::UINT8);
    spec.attribute("oiio:ColorSpace", "sRGB");
    return write_through_temp(path, "png", spec, bytes.data(), TypeDesc::UINT8, err);
}

extern "C" bool sg_image_read(const char *path, int *width, int *height, float **rgb,
                              SgError *err)
{
    *rgb = nullptr;
    auto in = ImageInput::open(path);
    if (!in) {
        std::string msg = OIIO::geterror();
        return sg_fail(err, "%s: cannot read: %s", path, msg.empty() ? "unknown format" : msg.c_str());
    }
    const ImageSpec &spec = in->spec();
    if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0 || spec.depth > 1) {
        in->close();
        return sg_fail(err, "%s: not a 2D image", path);
    }
    int w = spec.width, h = spec.height, nc = spec.nchannels;
    std::vector<float> all((size_t)w * h * nc);
    if (!in->read_image(0, 0, 0, nc, TypeDesc::FLOAT, all.data())) {
        std::string msg = in->geterror();
        in->close();
        return sg_fail(err, "%s: cannot read pixels: %s", path, msg.c_str());
    }
    in->close();
    float *out = (float *)malloc((size_t)w * h * 3 * sizeof(float));
    if (!out)
        return sg_fail(err, "%s: out of memory", path);
    for (size_t p = 0; p < (size_t)w * h; p++)
        for (int c = 0; c < 3; c++)
            out[p * 3 + c] = all[p * nc + (nc >= 3 ? c : 0)];
    *width = w;
    *height = h;
    *rgb = out;
    return true;
}
