// OpenEXR behind the C header exr_file.h: no C++ type crosses it, and no
// exception: each one becomes an error naming the file.
#include "exr_file.h"

#include <ImfBoxAttribute.h>
#include <ImfChannelList.h>
#include <ImfCompressionAttribute.h>
#include <ImfDoubleAttribute.h>
#include <ImfFloatAttribute.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfIntAttribute.h>
#include <ImfLineOrderAttribute.h>
#include <ImfOutputFile.h>
#include <ImfStringAttribute.h>
#include <ImfVecAttribute.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>
#include <utility>
#include <vector>

#include "output_file.h"

namespace {

// A file's pixels beyond this are refused rather than allocated: a corrupt
// data window can claim billions (2^28 float RGB pixels are 3 GB).
constexpr long long max_pixels = 1LL << 28;

// The data window as float RGB in one malloc'ed block (*rgb, the caller's
// to free; NULL on failure).
bool read_pixels(const char *path, int *width, int *height, float **rgb, SgError *err)
{
    *rgb = nullptr;
    try {
        Imf::InputFile in(path);
        const Imath::Box2i dw = in.header().dataWindow();
        long long w = (long long)dw.max.x - dw.min.x + 1, h = (long long)dw.max.y - dw.min.y + 1;
        if (w <= 0 || h <= 0 || w * h > max_pixels)
            return sg_fail(err, "%s: cannot read: a data window of %lldx%lld pixels", path, w, h);
        const Imf::ChannelList &channels = in.header().channels();
        const char *names[3] = {"R", "G", "B"};
        if (!channels.findChannel("R") || !channels.findChannel("G") || !channels.findChannel("B")) {
            const char *one = channels.findChannel("Y") ? "Y"
                              : channels.begin() != channels.end() ? channels.begin().name()
                                                                   : nullptr;
            if (!one)
                return sg_fail(err, "%s: cannot read: no channels", path);
            names[0] = names[1] = names[2] = one;
        }
        float *pixels = (float *)calloc((size_t)(w * h * 3), sizeof(float));
        if (!pixels)
            return sg_fail(err, "%s: out of memory for %lldx%lld pixels", path, w, h);
        *rgb = pixels;
        Imf::FrameBuffer frame;
        int distinct = names[0] == names[1] ? 1 : 3; // a frame buffer takes a channel once
        for (int c = 0; c < distinct; c++)
            frame.insert(names[c], Imf::Slice::Make(Imf::FLOAT, pixels + c, dw, 3 * sizeof(float),
                                                    (size_t)w * 3 * sizeof(float)));
        in.setFrameBuffer(frame);
        in.readPixels(dw.min.y, dw.max.y);
        if (distinct == 1)
            for (size_t p = 0; p < (size_t)(w * h); p++)
                pixels[p * 3 + 1] = pixels[p * 3 + 2] = pixels[p * 3];
        *width = (int)w;
        *height = (int)h;
        return true;
    } catch (const std::exception &e) {
        free(*rgb);
        *rgb = nullptr;
        return sg_fail(err, "%s: cannot read: %s", path, e.what());
    }
}

// Attribute values as text: the types EXR headers hold in practice.
std::string attribute_text(const Imf::Attribute &a)
{
    char buf[256];
    if (auto *s = dynamic_cast<const Imf::StringAttribute *>(&a))
        return s->value();
    if (auto *i = dynamic_cast<const Imf::IntAttribute *>(&a))
        return std::to_string(i->value());
    if (auto *f = dynamic_cast<const Imf::FloatAttribute *>(&a)) {
        snprintf(buf, sizeof buf, "%.9g", f->value());
        return buf;
    }
    if (auto *d = dynamic_cast<const Imf::DoubleAttribute *>(&a)) {
        snprintf(buf, sizeof buf, "%.17g", d->value());
        return buf;
    }
    if (auto *v = dynamic_cast<const Imf::V2fAttribute *>(&a)) {
        snprintf(buf, sizeof buf, "%.9g %.9g", v->value().x, v->value().y);
        return buf;
    }
    if (auto *v = dynamic_cast<const Imf::V2iAttribute *>(&a)) {
        snprintf(buf, sizeof buf, "%d %d", v->value().x, v->value().y);
        return buf;
    }
    if (auto *b = dynamic_cast<const Imf::Box2iAttribute *>(&a)) {
        const Imath::Box2i &v = b->value();
        snprintf(buf, sizeof buf, "%d %d %d %d", v.min.x, v.min.y, v.max.x, v.max.y);
        return buf;
    }
    if (auto *c = dynamic_cast<const Imf::CompressionAttribute *>(&a)) {
        static const char *const names[] = {"none", "rle", "zips", "zip", "piz", "pxr24", "b44", "b44a", "dwaa",
                                            "dwab"};
        unsigned k = (unsigned)c->value();
        return k < sizeof names / sizeof *names ? names[k] : "unknown";
    }
    if (auto *l = dynamic_cast<const Imf::LineOrderAttribute *>(&a))
        return l->value() == Imf::INCREASING_Y ? "increasingY"
               : l->value() == Imf::DECREASING_Y ? "decreasingY"
                                                 : "randomY";
    return std::string("(") + a.typeName() + ")";
}

} // namespace

extern "C" bool sg_exr_file_is_exr(const char *path, SgError *err)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return sg_fail(err, "%s: cannot read: %s", path, strerror(errno));
    unsigned char magic[4] = {0};
    size_t n = fread(magic, 1, 4, f);
    fclose(f);
    return n == 4 && magic[0] == 0x76 && magic[1] == 0x2f && magic[2] == 0x31 && magic[3] == 0x01;
}

extern "C" bool sg_exr_write(const char *path, int width, int height, const float *rgb,
                             const SgImageAttribute *attributes, int attribute_count, SgError *err)
{
    if (width <= 0 || height <= 0 || !rgb)
        return sg_fail(err, "%s: empty image (%dx%d)", path, width, height);
    char tmp[4096];
    sg_temp_path(path, tmp, sizeof tmp);
    try {
        Imf::Header header(width, height);
        header.compression() = Imf::ZIP_COMPRESSION;
        const char *names[3] = {"R", "G", "B"};
        Imf::FrameBuffer frame;
        for (int c = 0; c < 3; c++) {
            header.channels().insert(names[c], Imf::Channel(Imf::FLOAT));
            frame.insert(names[c], Imf::Slice(Imf::FLOAT, (char *)(rgb + c), 3 * sizeof(float),
                                              (size_t)width * 3 * sizeof(float)));
        }
        for (int i = 0; i < attribute_count; i++)
            header.insert(attributes[i].name, Imf::StringAttribute(attributes[i].value ? attributes[i].value : ""));
        Imf::OutputFile out(tmp, header);
        out.setFrameBuffer(frame);
        out.writePixels(height);
    } catch (const std::exception &e) {
        std::remove(tmp);
        return sg_fail(err, "%s: cannot write: %s", path, e.what());
    }
    // The writer does not see every failed write (a full disk while the
    // file's offset table is written in its destructor): the file must read
    // back as written before it takes the target's name.
    float *back = nullptr;
    int w = 0, h = 0;
    SgError ignored = {};
    bool same = read_pixels(tmp, &w, &h, &back, &ignored) && w == width && h == height &&
                std::memcmp(back, rgb, (size_t)width * height * 3 * sizeof(float)) == 0;
    free(back);
    if (!same) {
        std::remove(tmp);
        return sg_fail(err, "%s: cannot write: the file does not read back as written (disk full?)", path);
    }
    return sg_commit_temp(tmp, path, err);
}

extern "C" bool sg_exr_read(const char *path, int *width, int *height, float **rgb, SgError *err)
{
    return read_pixels(path, width, height, rgb, err);
}

extern "C" bool sg_exr_read_attributes(const char *path, SgImageAttribute **attributes, int *count, SgError *err)
{
    *attributes = nullptr;
    *count = 0;
    std::vector<std::pair<std::string, std::string>> all;
    std::size_t bytes = 0;
    try {
        Imf::InputFile in(path);
        for (auto it = in.header().begin(); it != in.header().end(); ++it) {
            all.emplace_back(it.name(), attribute_text(it.attribute()));
            bytes += all.back().first.size() + all.back().second.size() + 2;
        }
    } catch (const std::exception &e) {
        return sg_fail(err, "%s: cannot read: %s", path, e.what());
    }
    // The table, then its strings, in one block: the caller has one free().
    std::size_t table = all.size() * sizeof(SgImageAttribute);
    auto *out = (SgImageAttribute *)malloc(table + bytes + 1);
    if (!out)
        return sg_fail(err, "%s: out of memory for %zu attributes", path, all.size());
    char *text = (char *)out + table;
    for (std::size_t i = 0; i < all.size(); i++) {
        out[i].name = text;
        std::memcpy(text, all[i].first.c_str(), all[i].first.size() + 1);
        text += all[i].first.size() + 1;
        out[i].value = text;
        std::memcpy(text, all[i].second.c_str(), all[i].second.size() + 1);
        text += all[i].second.size() + 1;
    }
    *attributes = out;
    *count = (int)all.size();
    return true;
}
