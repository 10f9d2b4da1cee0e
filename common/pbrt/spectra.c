/* pbrt scene files, colours: rgb, blackbody, spectra (pbrt's named metals
 * and glasses) and texture references, all reduced to linear RGB. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "color.h"
#include "named_metals.h"
#include "pbrt_parser.h"

static const Texture *find_texture(const Parser *p, const Token *name)
{
    for (size_t i = p->texture_count; i-- > 0;)
        if (pbrt_string_is(name, p->textures[i].name))
            return &p->textures[i];
    return NULL;
}

/* Complex index of refraction of pbrt's named metal spectra, reduced to
 * red, green and blue (approximate: evaluated near 650, 550 and 450 nm). */

/* Index of refraction of pbrt's named glasses near 550 nm. */
static const struct {
    const char *name;
    float eta;
} named_glasses[] = {
    {"glass-BK7", 1.5168f}, {"glass-BAF10", 1.6700f}, {"glass-FK51A", 1.4866f},
    {"glass-LASF9", 1.8503f}, {"glass-F5", 1.6034f},  {"glass-F10", 1.6200f},
    {"glass-F11", 1.6200f},  {"glass-SF5", 1.6727f}, {"glass-SF10", 1.7283f},
    {"glass-SF11", 1.7847f},
};

/* One lobe of the CIE 1931 matching functions' analytic fit (Wyman,
 * Sloan and Shirley 2013, "Simple analytic approximations to the CIE XYZ
 * colour matching functions"). */
static double cie_lobe(double lambda, double mu, double sigma_low, double sigma_high)
{
    double t = (lambda - mu) / (lambda < mu ? sigma_low : sigma_high);
    return exp(-0.5 * t * t);
}

/* Linear sRGB of a blackbody at kelvin, scaled to luminance 1 as pbrt
 * normalizes blackbody emitters. */
static void blackbody_rgb(double kelvin, float out[3])
{
    const double h = 6.62606957e-34, c = 299792458.0, kb = 1.3806488e-23;
    double xyz[3] = {0, 0, 0};
    for (double lambda = 360; lambda <= 830; lambda += 1) {
        double l = lambda * 1e-9;
        double planck = 2 * h * c * c / (pow(l, 5) * (exp(h * c / (l * kb * kelvin)) - 1));
        xyz[0] += planck * (1.056 * cie_lobe(lambda, 599.8, 37.9, 31.0) +
                            0.362 * cie_lobe(lambda, 442.0, 16.0, 26.7) -
                            0.065 * cie_lobe(lambda, 501.1, 20.4, 26.2));
        xyz[1] += planck * (0.821 * cie_lobe(lambda, 568.8, 46.9, 40.5) +
                            0.286 * cie_lobe(lambda, 530.9, 16.3, 31.1));
        xyz[2] += planck * (1.217 * cie_lobe(lambda, 437.0, 11.8, 36.0) +
                            0.681 * cie_lobe(lambda, 459.0, 26.0, 13.8));
    }
    double rgb[3] = {3.2406 * xyz[0] - 1.5372 * xyz[1] - 0.4986 * xyz[2],
                     -0.9689 * xyz[0] + 1.8758 * xyz[1] + 0.0415 * xyz[2],
                     0.0557 * xyz[0] - 0.2040 * xyz[1] + 1.0570 * xyz[2]};
    for (int a = 0; a < 3; a++)
        rgb[a] = fmax(rgb[a], 0); /* outside the sRGB gamut: clip */
    double y = sg_luminance(rgb[0], rgb[1], rgb[2]);
    for (int a = 0; a < 3; a++)
        out[a] = y > 0 ? (float)(rgb[a] / y) : 1.0f;
}

/* A spectrum or colour parameter as linear RGB. which: "eta"/"k" for
 * named metal spectra, NULL otherwise. Sets *present. */
bool pbrt_param_color(Parser *p, const char *name, const float fallback[3], float out[3],
                      bool *present)
{
    memcpy(out, fallback, 3 * sizeof(float));
    if (present)
        *present = false;
    const Param *param = pbrt_find_param(p, name);
    if (!param)
        return true;
    if (present)
        *present = true;
    Token at = pbrt_param_token(param);
    const char *type = param->type;
    if (!strcmp(type, "rgb")) {
        if (param->count != 3)
            return pbrt_fail_at(p, &at, "\"rgb %s\" needs 3 numbers, not %zu", name, param->count);
        for (int a = 0; a < 3; a++) {
            double v = p->numbers[param->first + a];
            if (v < 0)
                return pbrt_fail_at(p, &at, "\"rgb %s\" has a negative value", name);
            out[a] = (float)v;
        }
        return true;
    }
    if (!strcmp(type, "float")) {
        if (param->count != 1)
            return pbrt_fail_at(p, &at, "\"float %s\" needs 1 number", name);
        out[0] = out[1] = out[2] = (float)p->numbers[param->first];
        return true;
    }
    if (!strcmp(type, "texture")) {
        const Texture *tex = find_texture(p, &p->strings[param->first]);
        if (!tex)
            return pbrt_fail_at(p, &at, "\"texture %s\": no texture named \"%.*s\"", name,
                                (int)p->strings[param->first].len, p->strings[param->first].s);
        memcpy(out, tex->value, 3 * sizeof(float));
        return true;
    }
    if (!strcmp(type, "blackbody")) {
        /* pbrt-v3 wrote [kelvin scale] */
        if (param->count < 1 || param->count > 2 || !(p->numbers[param->first] > 0))
            return pbrt_fail_at(p, &at, "\"blackbody %s\" needs one temperature in kelvin", name);
        blackbody_rgb(p->numbers[param->first], out);
        double scale = param->count == 2 ? p->numbers[param->first + 1] : 1;
        if (!(scale >= 0))
            return pbrt_fail_at(p, &at, "\"blackbody %s\": negative scale", name);
        for (int a = 0; a < 3; a++)
            out[a] = (float)(out[a] * scale);
        return true;
    }
    if (!strcmp(type, "spectrum")) {
        if (param->kind == PARAM_NUMBERS) {
            if (param->count < 2 || param->count % 2)
                return pbrt_fail_at(p, &at, "\"spectrum %s\" needs (wavelength, value) pairs",
                                    name);
            double sum = 0;
            for (size_t i = 1; i < param->count; i += 2)
                sum += p->numbers[param->first + i];
            out[0] = out[1] = out[2] = (float)(sum / (double)(param->count / 2));
            pbrt_warn_at(p, &at, "sampled spectra are taken as grey (their mean value)");
            return true;
        }
        const Token *s = &p->strings[param->first];
        /* "metal-NAME-eta", "metal-NAME-k" */
        if (s->len > 6 && !memcmp(s->s, "metal-", 6)) {
            const char *name = s->s + 6, *dash = memchr(name, '-', s->len - 6);
            const SgNamedMetal *metal = dash ? sg_named_metal_n(name, (unsigned)(dash - name)) : NULL;
            size_t rest = dash ? s->len - (size_t)(dash + 1 - s->s) : 0;
            if (metal && rest == 3 && !memcmp(dash + 1, "eta", 3)) {
                memcpy(out, metal->eta, 3 * sizeof(float));
                return true;
            }
            if (metal && rest == 1 && dash[1] == 'k') {
                memcpy(out, metal->k, 3 * sizeof(float));
                return true;
            }
        }
        for (size_t i = 0; i < sizeof named_glasses / sizeof named_glasses[0]; i++)
            if (pbrt_string_is(s, named_glasses[i].name)) {
                out[0] = out[1] = out[2] = named_glasses[i].eta;
                return true;
            }
        if (pbrt_string_is(s, "stdillum-D65")) { /* the white of sRGB */
            out[0] = out[1] = out[2] = 1;
            return true;
        }
        pbrt_warn_at(p, &at, "spectrum \"%.*s\" is not known: taken as %s", (int)s->len, s->s,
                     strncmp(s->s, "stdillum", 8) ? "the default" : "white");
        if (!strncmp(s->s, "stdillum", 8))
            out[0] = out[1] = out[2] = 1;
        return true;
    }
    return pbrt_fail_at(p, &at, "\"%s %s\" is not a colour", type, name);
}

uint32_t pbrt_param_texture(Parser *p, const char *name)
{
    const Param *param = pbrt_find_param(p, name);
    if (!param || strcmp(param->type, "texture") || param->kind != PARAM_STRINGS || !param->count)
        return 0;
    const Texture *tex = find_texture(p, &p->strings[param->first]);
    return tex ? tex->scene_texture : 0;
}

/* A float parameter that may also be a (float) texture: its average. */
bool pbrt_param_scalar(Parser *p, const char *name, double fallback, double *out)
{
    const float f[3] = {(float)fallback, (float)fallback, (float)fallback};
    float v[3];
    if (!pbrt_param_color(p, name, f, v, NULL))
        return false;
    *out = pbrt_find_param(p, name) ? v[0] : fallback;
    return true;
}
