/* pbrt scene files, textures: each `Texture` becomes its average colour
 * (image maps: the mean of the image file). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "color.h"
#include "image_average.h"
#include "pbrt_parser.h"

/* A texture's operand: another texture (by reference) or a constant. */
static bool texture_input(Parser *p, const char *name, const float fallback[3], SgTextureInput *in, float mean[3])
{
    if (!pbrt_param_color(p, name, fallback, mean, NULL))
        return false;
    in->texture = pbrt_param_texture(p, name);
    memcpy(in->value, mean, sizeof in->value);
    return true;
}

/* The (u, v) mapping every 2D texture has: pbrt-v4's "uv" with its scale
 * and offset; the others are taken as "uv". */
static bool texture_mapping(Parser *p, const Token *statement, SgTexture *t)
{
    double su, sv, du, dv;
    if (!pbrt_param_float(p, "uscale", 1, &su) || !pbrt_param_float(p, "vscale", 1, &sv) ||
        !pbrt_param_float(p, "udelta", 0, &du) || !pbrt_param_float(p, "vdelta", 0, &dv))
        return false;
    const Token *mapping = pbrt_param_string(p, "mapping");
    if (mapping && !pbrt_string_is(mapping, "uv"))
        pbrt_warn_at(p, statement, "texture mappings other than \"uv\" are taken as \"uv\"");
    t->uscale = (float)su;
    t->vscale = (float)sv;
    t->udelta = (float)du;
    t->vdelta = (float)dv;
    return true;
}

static const float grey[3] = {0.5f, 0.5f, 0.5f}, one[3] = {1, 1, 1}, zero[3] = {0, 0, 0};

/* scale: tex x scale */
static bool scale_texture(Parser *p, SgTexture *st, float value[3], bool *varies)
{
    float tex[3], scale[3];
    if (!texture_input(p, "tex", one, &st->input[0], tex) || !texture_input(p, "scale", one, &st->input[1], scale))
        return false;
    for (int a = 0; a < 3; a++)
        value[a] = tex[a] * scale[a];
    st->kind = SG_TEXTURE_SCALE;
    *varies = st->input[0].texture || st->input[1].texture;
    return true;
}

/* mix (by amount) and checkerboard (2D; a 3D one is its mean) of tex1, tex2 */
static bool mix_texture(Parser *p, const Token *statement, bool mix, SgTexture *st, float value[3], bool *varies)
{
    float a[3], b[3], amount[3] = {0.5f, 0.5f, 0.5f};
    if (!texture_input(p, "tex1", one, &st->input[0], a) || !texture_input(p, "tex2", zero, &st->input[1], b) ||
        (mix && !texture_input(p, "amount", amount, &st->input[2], amount)))
        return false;
    for (int c = 0; c < 3; c++)
        value[c] = (1 - amount[0]) * a[c] + amount[0] * b[c];
    double dimension;
    if (!mix && (!pbrt_param_float(p, "dimension", 2, &dimension)))
        return false;
    if (!mix && dimension != 2)
        pbrt_warn_at(p, statement, "3D checkerboards are taken as their mean colour");
    st->kind = mix ? SG_TEXTURE_MIX : SG_TEXTURE_CHECKERBOARD;
    *varies = mix ? st->input[0].texture || st->input[1].texture || st->input[2].texture : dimension == 2;
    return true;
}

/* An imagemap's gamma: its "encoding", else what the file's kind implies
 * (0: linear, -1: sRGB). */
static double image_gamma(const Token *encoding, const char *path)
{
    double gamma = sg_image_default_gamma(path);
    if (encoding && pbrt_string_is(encoding, "linear"))
        gamma = 0;
    else if (encoding && pbrt_string_is(encoding, "sRGB"))
        gamma = -1;
    else if (encoding && encoding->len > 6 && encoding->len < 40 && !memcmp(encoding->s, "gamma ", 6)) {
        char number[40];
        snprintf(number, sizeof number, "%.*s", (int)encoding->len - 6, encoding->s + 6);
        gamma = atof(number) > 0 ? atof(number) : -1;
    }
    return gamma;
}

static SgTextureWrap image_wrap(Parser *p, const Token *statement, const Token *wrap)
{
    if (wrap && !pbrt_string_is(wrap, "repeat") && !pbrt_string_is(wrap, "clamp") && !pbrt_string_is(wrap, "black"))
        pbrt_warn_at(p, statement, "texture wrap \"%.*s\" is taken as \"black\"", (int)wrap->len, wrap->s);
    return !wrap || pbrt_string_is(wrap, "repeat") ? SG_WRAP_REPEAT
           : pbrt_string_is(wrap, "clamp")         ? SG_WRAP_CLAMP
                                                   : SG_WRAP_BLACK;
}

/* imagemap: the image file (st->path points into path), its mean as the value */
static bool image_texture(Parser *p, const Token *statement, SgTexture *st, float value[3], char *path,
                          size_t path_size)
{
    const Token *file = pbrt_param_string(p, "filename");
    const Token *wrap = pbrt_param_string(p, "wrap");
    double scale;
    bool invert;
    if (!pbrt_param_float(p, "scale", 1, &scale) || !pbrt_param_bool(p, "invert", false, &invert))
        return false;
    if (!file)
        return pbrt_fail_at(p, statement, "imagemap texture without \"string filename\"");
    if (!pbrt_resolve_path(p, statement, file, path, path_size))
        return false;
    double gamma = image_gamma(pbrt_param_string(p, "encoding"), path);
    float average[3];
    bool readable = sg_image_average(&p->core.images, path, gamma, average, NULL);
    if (!readable) {
        memcpy(average, grey, sizeof average);
        pbrt_warn_at(p, statement, "image textures that cannot be read (missing files) are "
                                   "taken as grey 0.5");
    }
    for (int c = 0; c < 3; c++) {
        value[c] = average[c] * (float)scale;
        if (invert)
            value[c] = value[c] < 1 ? 1 - value[c] : 0;
    }
    st->kind = SG_TEXTURE_IMAGE;
    st->path = readable ? path : NULL;
    st->gamma = (float)gamma;
    st->scale = (float)scale;
    st->invert = invert;
    st->wrap = image_wrap(p, statement, wrap);
    return true;
}

/* The named texture: a scene texture where it varies, its value always. */
static bool add_texture(Parser *p, const Token *name, SgTexture *st, const float value[3], bool varies)
{
    if (!RESERVE(p, p->textures, p->texture_count, p->texture_capacity, 1))
        return false;
    Texture *t = &p->textures[p->texture_count];
    t->scene_texture = 0;
    if (varies) {
        memcpy(st->mean, value, sizeof st->mean);
        uint32_t id;
        if (!sg_builder_add_texture(&p->core, st, &id, p->err))
            return false;
        t->scene_texture = id + 1;
    }
    if (!(t->name = pbrt_token_dup(name)))
        return sg_fail(p->err, "%s: out of memory", p->core.path);
    memcpy(t->value, value, sizeof t->value);
    p->texture_count++;
    return true;
}

bool pbrt_texture_statement(Parser *p, const Token *statement)
{
    Token name, type, klass;
    if (!pbrt_need_string(p, statement, &name) || !pbrt_need_string(p, statement, &type) ||
        !pbrt_need_string(p, statement, &klass) || !pbrt_parse_params(p))
        return false;
    if (!pbrt_string_is(&type, "spectrum") && !pbrt_string_is(&type, "float") &&
        !pbrt_string_is(&type, "color"))
        return pbrt_fail_at(p, &type, "Texture \"%.*s\": type must be \"spectrum\" or \"float\"",
                            (int)name.len, name.s);
    float value[3];
    memcpy(value, grey, sizeof value);
    /* what varies over the surface becomes a scene texture; a constant stays a value */
    SgTexture st = {0};
    bool varies = false, ok = true;
    char path[8192]; /* an image's file: st.path points here until the texture is added */
    if (!texture_mapping(p, statement, &st))
        return false;
    if (pbrt_string_is(&klass, "constant"))
        ok = pbrt_param_color(p, "value", one, value, NULL);
    else if (pbrt_string_is(&klass, "scale"))
        ok = scale_texture(p, &st, value, &varies);
    else if (pbrt_string_is(&klass, "mix") || pbrt_string_is(&klass, "checkerboard"))
        ok = mix_texture(p, statement, pbrt_string_is(&klass, "mix"), &st, value, &varies);
    else if (pbrt_string_is(&klass, "imagemap")) {
        ok = image_texture(p, statement, &st, value, path, sizeof path);
        /* a missing image is its grey mean everywhere: it still counts as
         * a texture, so that a comparison can tell it from a colour */
        varies = true;
    } else
        pbrt_warn_at(p, statement, "Texture \"%.*s\" is not supported: taken as grey 0.5",
                     (int)klass.len, klass.s);
    return ok && add_texture(p, &name, &st, value, varies);
}
