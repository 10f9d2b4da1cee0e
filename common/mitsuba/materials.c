/* Mitsuba scene files, bsdfs and textures mapped onto our materials:
 * diffuse, plastic and roughplastic as the coated diffuse, conductor and
 * roughconductor (named or explicit eta and k; "none" a mirror),
 * dielectric, roughdielectric and thindielectric as glass, phong as the
 * glossy material, difftrans as diffuse transmission; twosided passes its
 * inner bsdf through, mask makes it a cut-out, bumpmap and normalmap give
 * it shading normals, blendbsdf blends two diffuse ones and otherwise
 * keeps the heavier. A homogeneous medium that absorbs only, inside a
 * dielectric, is its sigma_a. Textures: bitmap, checkerboard and scale. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "mitsuba_parser.h"
#include "named_metals.h"

/* ---- textures ----------------------------------------------------------- */

/* The uv scale of a texture: Mitsuba 3's to_uv (its scale and offset), or
 * the 0.x uscale, vscale, uoffset, voffset. */
static bool texture_uv(MtsParser *p, const XmlNode *n, SgTexture *t)
{
    SgTransform uv;
    bool has_uv;
    double su, sv, du, dv;
    if (!mts_transform(p, n, "to_uv", &uv, &has_uv) || !mts_float(p, n, "uscale", 1, &su) ||
        !mts_float(p, n, "vscale", 1, &sv) || !mts_float(p, n, "uoffset", 0, &du) ||
        !mts_float(p, n, "voffset", 0, &dv))
        return false;
    if (has_uv) {
        if (fabs(uv.m[0][1]) > 1e-9 || fabs(uv.m[1][0]) > 1e-9)
            mts_warn(p, n, "rotated texture coordinates (to_uv) keep only their scale and offset");
        su = uv.m[0][0];
        sv = uv.m[1][1];
        du = uv.m[0][3];
        dv = uv.m[1][3];
    }
    t->uscale = (float)su;
    t->vscale = (float)sv;
    t->udelta = (float)du;
    t->vdelta = (float)dv;
    return true;
}

static bool bitmap(MtsParser *p, const XmlNode *n, SgTexture *t, char *path, size_t path_size)
{
    const char *file, *wrap, *filter;
    bool raw;
    if (!mts_string(p, n, "filename", NULL, &file) || !mts_string(p, n, "wrap_mode", "repeat", &wrap) ||
        !mts_string(p, n, "filter_type", "bilinear", &filter) || !mts_bool(p, n, "raw", false, &raw) ||
        !texture_uv(p, n, t))
        return false;
    if (!file)
        return mts_fail(p, n, "bitmap texture without a \"filename\"");
    mts_resolve(p, n, file, path, path_size);
    double gamma = raw ? 0 : sg_image_default_gamma(path), file_gamma;
    if (!mts_float(p, n, "gamma", 0, &file_gamma)) /* 0.x: the file's encoding, -1 sRGB */
        return false;
    if (file_gamma == -1 || file_gamma > 0)
        gamma = file_gamma == 1 ? 0 : file_gamma;
    float mean[3] = {0.5f, 0.5f, 0.5f};
    bool readable = sg_image_average(&p->core.images, path, gamma, mean, NULL);
    if (!readable)
        mts_warn(p, n, "bitmap textures that cannot be read (missing files) are taken as grey 0.5");
    if (strcasecmp(filter, "bilinear"))
        mts_warn(p, n, "bitmap filter_type \"%s\" is taken as bilinear", filter);
    t->kind = SG_TEXTURE_IMAGE;
    t->path = readable ? path : NULL;
    t->gamma = (float)gamma;
    t->scale = 1;
    t->wrap = !strcasecmp(wrap, "clamp") ? SG_WRAP_CLAMP : !strcasecmp(wrap, "zero") ? SG_WRAP_BLACK
                                                                                    : SG_WRAP_REPEAT;
    if (strcasecmp(wrap, "repeat") && strcasecmp(wrap, "clamp") && strcasecmp(wrap, "zero"))
        mts_warn(p, n, "bitmap wrap_mode \"%s\" is taken as repeat", wrap);
    memcpy(t->mean, mean, sizeof mean);
    return true;
}

/* Mitsuba's checkerboard: color0 where the halves of u and v agree (squares
 * of half a unit), color1 elsewhere: our checkerboard at twice the scale. */
static bool checkerboard(MtsParser *p, const XmlNode *n, SgTexture *t)
{
    float c0[3], c1[3];
    static const float dark[3] = {0.4f, 0.4f, 0.4f}, darker[3] = {0.2f, 0.2f, 0.2f};
    if (!mts_color(p, n, "color0", dark, c0, &t->input[0].texture, NULL) ||
        !mts_color(p, n, "color1", darker, c1, &t->input[1].texture, NULL) || !texture_uv(p, n, t))
        return false;
    t->kind = SG_TEXTURE_CHECKERBOARD;
    t->uscale *= 2;
    t->vscale *= 2;
    t->udelta *= 2;
    t->vdelta *= 2;
    for (int c = 0; c < 3; c++) {
        t->input[0].value[c] = c0[c];
        t->input[1].value[c] = c1[c];
        t->mean[c] = 0.5f * (c0[c] + c1[c]);
    }
    return true;
}

/* A texture element: its scene texture (cached) and mean. */
static bool texture(MtsParser *p, const XmlNode *n, uint32_t *scene_texture, float mean[3])
{
    for (size_t i = 0; i < p->texture_count; i++)
        if (p->textures[i].node == n) {
            *scene_texture = p->textures[i].scene_texture;
            memcpy(mean, p->textures[i].mean, 3 * sizeof(float));
            return true;
        }
    const char *type = mts_attr(p, n, "type");
    if (!type)
        return p->err->failed ? false : mts_fail(p, n, "<texture> without a type");
    SgTexture t;
    memset(&t, 0, sizeof t);
    char path[8192];
    bool varies = true;
    if (!strcmp(type, "bitmap")) {
        if (!bitmap(p, n, &t, path, sizeof path))
            return false;
    } else if (!strcmp(type, "checkerboard")) {
        if (!checkerboard(p, n, &t))
            return false;
    } else if (!strcmp(type, "scale")) { /* 0.x: a nested texture times a constant */
        static const float one[3] = {1, 1, 1};
        float value[3], scale[3];
        const XmlNode *nested;
        if (!mts_find_object(p, n, "texture", 0, &nested) ||
            !mts_color(p, n, "scale", one, scale, &t.input[1].texture, NULL))
            return false;
        if (!nested)
            return mts_fail(p, n, "scale texture without a nested texture");
        if (!texture(p, nested, &t.input[0].texture, value))
            return false;
        t.kind = SG_TEXTURE_SCALE;
        for (int c = 0; c < 3; c++) {
            t.input[0].value[c] = value[c];
            t.input[1].value[c] = scale[c];
            t.mean[c] = value[c] * scale[c];
        }
        varies = t.input[0].texture || t.input[1].texture;
    } else {
        mts_warn(p, n, "texture \"%s\" is not supported: grey 0.5", type);
        t.mean[0] = t.mean[1] = t.mean[2] = 0.5f;
        varies = false;
    }
    if (!MTS_RESERVE(p, p->textures, p->texture_count, p->texture_capacity, 1))
        return false;
    MtsTexture *mt = &p->textures[p->texture_count];
    mt->node = n;
    mt->scene_texture = 0;
    memcpy(mt->mean, t.mean, sizeof mt->mean);
    if (varies) {
        uint32_t id;
        if (!sg_builder_add_texture(&p->core, &t, &id, p->err))
            return false;
        mt->scene_texture = id + 1;
    }
    p->texture_count++;
    *scene_texture = mt->scene_texture;
    memcpy(mean, mt->mean, 3 * sizeof(float));
    return true;
}

bool mts_color(MtsParser *p, const XmlNode *obj, const char *name, const float fallback[3], float out[3],
               uint32_t *texture_out, bool *present)
{
    const XmlNode *n;
    memcpy(out, fallback, 3 * sizeof(float));
    if (texture_out)
        *texture_out = 0;
    if (present)
        *present = false;
    if (!mts_find(p, obj, name, &n))
        return false;
    if (!n)
        return true;
    if (present)
        *present = true;
    if (mts_is_tag(n, "texture")) {
        uint32_t id;
        if (!texture(p, n, &id, out))
            return false;
        if (texture_out)
            *texture_out = id;
        else if (id)
            mts_warn(p, n, "a texture where only a constant is supported (\"%s\") is taken as its mean", name);
        return true;
    }
    return mts_color_of(p, n, out);
}

/* ---- named media and metals ----------------------------------------------- */

/* Mitsuba's named indices of refraction (its documented table). */
static const struct {
    const char *name;
    double ior;
} named_iors[] = {
    {"vacuum", 1.0},          {"helium", 1.00004},        {"hydrogen", 1.00013},
    {"air", 1.000277},        {"carbon dioxide", 1.00045}, {"water", 1.3330},
    {"acetone", 1.36},        {"ethanol", 1.361},         {"carbon tetrachloride", 1.461},
    {"glycerol", 1.4729},     {"benzene", 1.501},         {"silicone oil", 1.52045},
    {"bromine", 1.661},       {"water ice", 1.31},        {"fused quartz", 1.458},
    {"pyrex", 1.470},         {"acrylic glass", 1.49},    {"polypropylene", 1.49},
    {"bk7", 1.5046},          {"sodium chloride", 1.544}, {"amber", 1.55},
    {"pet", 1.5750},          {"diamond", 2.419},
};

/* An index property: a number or a medium's name. */
static bool ior(MtsParser *p, const XmlNode *obj, const char *name, double fallback, double *out)
{
    const XmlNode *n;
    *out = fallback;
    if (!mts_find(p, obj, name, &n))
        return false;
    if (!n)
        return true;
    if (mts_is_tag(n, "float"))
        return mts_float(p, obj, name, fallback, out);
    const char *s;
    if (!mts_string(p, obj, name, NULL, &s))
        return false;
    for (size_t i = 0; i < sizeof named_iors / sizeof *named_iors; i++)
        if (!strcasecmp(s, named_iors[i].name)) {
            *out = named_iors[i].ior;
            return true;
        }
    return mts_fail(p, n, "\"%s\": unknown material \"%.40s\"", name, s);
}

static bool conductor(MtsParser *p, const XmlNode *n, bool rough, SgMaterial *m)
{
    const char *name;
    if (!mts_string(p, n, "material", "Cu", &name))
        return false;
    float tint[3];
    bool tinted;
    static const float one[3] = {1, 1, 1};
    if (!mts_color(p, n, "specular_reflectance", one, tint, NULL, &tinted))
        return false;
    tinted = tinted && (tint[0] != 1 || tint[1] != 1 || tint[2] != 1);
    if (!strcmp(name, "none")) {
        m->type = SG_MATERIAL_MIRROR;
        memcpy(m->specular, tint, sizeof tint);
        m->diffuse[0] = m->diffuse[1] = m->diffuse[2] = 0;
        if (rough)
            mts_warn(p, n, "roughconductor with material \"none\" is taken as a smooth mirror");
        return true;
    }
    const XmlNode *eta_node, *k_node;
    if (!mts_find(p, n, "eta", &eta_node) || !mts_find(p, n, "k", &k_node))
        return false;
    const SgNamedMetal *metal = sg_named_metal(name);
    if (metal) {
        memcpy(m->eta, metal->eta, sizeof m->eta);
        memcpy(m->k, metal->k, sizeof m->k);
    }
    if (!metal && !(eta_node && k_node))
        mts_warn(p, n, "conductor material \"%s\" is not known here: copper instead", name);
    double ext_ior;
    if (!mts_color(p, n, "eta", m->eta, m->eta, NULL, NULL) || !mts_color(p, n, "k", m->k, m->k, NULL, NULL) ||
        !ior(p, n, "ext_eta", 1.0, &ext_ior))
        return false;
    for (int c = 0; c < 3; c++) { /* relative to the outside medium */
        m->eta[c] /= (float)ext_ior;
        m->k[c] /= (float)ext_ior;
    }
    m->type = SG_MATERIAL_CONDUCTOR;
    m->diffuse[0] = m->diffuse[1] = m->diffuse[2] = 0;
    if (tinted) {
        /* Mitsuba multiplies the Fresnel term by the tint; ours cannot, so
         * the tinted reflectance at normal incidence becomes the metal's,
         * as pbrt's conductor given a "reflectance" (eta 1) */
        mts_warn(p, n, "conductor specular_reflectance: the tinted reflectance at normal incidence is kept, with eta 1");
        for (int c = 0; c < 3; c++) {
            double e = m->eta[c], k = m->k[c];
            double f0 = ((e - 1) * (e - 1) + k * k) / ((e + 1) * (e + 1) + k * k);
            float r = (float)(tint[c] * f0);
            m->diffuse[c] = r;
            m->eta[c] = 1;
            m->k[c] = sg_conductor_k_of_reflectance(r);
        }
    }
    return true;
}

/* GGX alphas of a rough bsdf: "alpha", or "alpha_u" and "alpha_v" (a
 * texture: its mean, with a warning). */
static bool alphas(MtsParser *p, const XmlNode *n, float alpha[2])
{
    static const float tenth[3] = {0.1f, 0.1f, 0.1f};
    float a[3], u[3], v[3];
    const char *distribution;
    if (!mts_color(p, n, "alpha", tenth, a, NULL, NULL) || !mts_color(p, n, "alpha_u", a, u, NULL, NULL) ||
        !mts_color(p, n, "alpha_v", a, v, NULL, NULL) || !mts_string(p, n, "distribution", "beckmann", &distribution))
        return false;
    /* Mitsuba 3's default is beckmann too; GGX is all the renderer has */
    if (strcmp(distribution, "ggx"))
        mts_warn(p, n, "microfacet distribution \"%s\" is taken as GGX of the same alpha", distribution);
    if (fabsf(u[0] - v[0]) > 1e-6f * fmaxf(u[0], v[0]))
        mts_warn(p, n, "anisotropic roughness is oriented around the normal arbitrarily");
    alpha[0] = fmaxf(u[0], 0);
    alpha[1] = fmaxf(v[0], 0);
    return true;
}

static void clamp_albedo(MtsParser *p, const XmlNode *n, float c[3])
{
    for (int a = 0; a < 3; a++)
        if (c[a] > 1) {
            mts_warn(p, n, "reflectance above 1 clamped to 1");
            c[a] = 1;
        }
}

/* plastic and roughplastic: the coated diffuse of index int_ior / ext_ior. */
static bool plastic(MtsParser *p, const XmlNode *n, bool rough, SgMaterial *m)
{
    double int_ior, ext_ior;
    float spec[3];
    bool has_spec;
    static const float one[3] = {1, 1, 1}, half[3] = {0.5f, 0.5f, 0.5f};
    if (!mts_color(p, n, "diffuse_reflectance", half, m->diffuse, &m->diffuse_texture, NULL) ||
        !ior(p, n, "int_ior", 1.49, &int_ior) || !ior(p, n, "ext_ior", 1.000277, &ext_ior) ||
        !mts_color(p, n, "specular_reflectance", one, spec, NULL, &has_spec))
        return false;
    if (has_spec && (spec[0] != 1 || spec[1] != 1 || spec[2] != 1))
        mts_warn(p, n, "plastic specular_reflectance is ignored (the coat is clear)");
    clamp_albedo(p, n, m->diffuse);
    m->roughness[0] = m->roughness[1] = 0;
    if (rough && !alphas(p, n, m->roughness))
        return false;
    double eta = int_ior / ext_ior;
    m->type = SG_MATERIAL_COATED_DIFFUSE;
    m->ior = (float)(eta > 1 ? eta : 1.49);
    return true;
}

/* dielectric, roughdielectric, thindielectric: glass of int_ior / ext_ior. */
static bool dielectric(MtsParser *p, const XmlNode *n, const char *type, SgMaterial *m)
{
    double int_ior, ext_ior;
    if (!ior(p, n, "int_ior", 1.5046, &int_ior) || !ior(p, n, "ext_ior", 1.000277, &ext_ior))
        return false;
    double eta = int_ior / ext_ior;
    if (eta < 1 && eta > 0)
        eta = 1 / eta;
    if (!(eta >= 1 && eta <= 10))
        return mts_fail(p, n, "dielectric index %g is out of range", eta);
    if (!strcmp(type, "thindielectric"))
        mts_warn(p, n, "thindielectric is taken as a solid dielectric");
    m->roughness[0] = m->roughness[1] = 0;
    if (!strcmp(type, "roughdielectric") && !alphas(p, n, m->roughness))
        return false;
    m->type = SG_MATERIAL_DIELECTRIC;
    m->ior = (float)eta;
    m->diffuse[0] = m->diffuse[1] = m->diffuse[2] = 0;
    return true;
}

static bool make_material(MtsParser *p, const XmlNode *n, MtsMaterial *out, int depth);

/* The inner bsdf of twosided, mask, bumpmap, normalmap (the first nested one). */
static bool inner(MtsParser *p, const XmlNode *n, size_t index, MtsMaterial *out, int depth)
{
    const XmlNode *child;
    if (!mts_find_object(p, n, "bsdf", index, &child))
        return false;
    if (!child)
        return mts_fail(p, n, "bsdf \"%s\" needs a nested bsdf", sg_xml_attr(n, "type"));
    return make_material(p, child, out, depth + 1);
}

static bool blend(MtsParser *p, const XmlNode *n, MtsMaterial *out, int depth)
{
    MtsMaterial a, b;
    float weight[3];
    static const float half[3] = {0.5f, 0.5f, 0.5f};
    if (!mts_color(p, n, "weight", half, weight, NULL, NULL))
        return false;
    double w = weight[0];
    if (!inner(p, n, 0, &a, depth) || !inner(p, n, 1, &b, depth))
        return false;
    bool plain = a.material.type == SG_MATERIAL_DIFFUSE && b.material.type == SG_MATERIAL_DIFFUSE &&
                 !a.material.diffuse_texture && !b.material.diffuse_texture;
    if (plain) { /* a blend of two Lambertian lobes is the Lambertian of the blend */
        *out = a;
        for (int c = 0; c < 3; c++)
            out->material.diffuse[c] = (float)((1 - w) * a.material.diffuse[c] + w * b.material.diffuse[c]);
        return true;
    }
    mts_warn(p, n, "blendbsdf of other than two plain diffuse bsdfs keeps the one of larger weight");
    *out = w > 0.5 ? b : a;
    return true;
}

static bool make_material_of_type(MtsParser *p, const XmlNode *n, MtsMaterial *out, int depth);

/* bumpmap (its texture a displacement, times "scale") and normalmap (its
 * texture tangent-space normals, to be read raw): the inner bsdf with
 * shading normals (SgMaterial.normal_texture, bump_texture). */
static bool shading_map(MtsParser *p, const XmlNode *n, const char *type, MtsMaterial *out, int depth)
{
    const XmlNode *tex;
    uint32_t id = 0;
    float mean[3];
    double scale = 1;
    bool bump = !strcmp(type, "bumpmap");
    if (!mts_find_object(p, n, "texture", 0, &tex) || (tex && !texture(p, tex, &id, mean)) ||
        (bump && !mts_float(p, n, "scale", 1, &scale)) || !inner(p, n, 0, out, depth))
        return false;
    if (!id) { /* a constant bends nothing */
        if (!tex)
            mts_warn(p, n, "%s without a texture is ignored", type);
        return true;
    }
    if (bump) {
        out->material.bump_texture = id;
        out->material.bump_scale = (float)scale;
    } else {
        out->material.normal_texture = id;
    }
    return true;
}

/* A bsdf with its own id names the material, even where it wraps another. */
static bool make_material(MtsParser *p, const XmlNode *n, MtsMaterial *out, int depth)
{
    if (!make_material_of_type(p, n, out, depth))
        return false;
    const char *id = sg_xml_attr(n, "id");
    if (id)
        snprintf(out->material.name, sizeof out->material.name, "%.63s", id);
    return true;
}

static bool make_material_of_type(MtsParser *p, const XmlNode *n, MtsMaterial *out, int depth)
{
    if (depth > 16)
        return mts_fail(p, n, "bsdfs nested too deeply");
    const char *type = mts_attr(p, n, "type");
    if (!type)
        return p->err->failed ? false : mts_fail(p, n, "<bsdf> without a type");
    SgMaterial *m = &out->material;
    sg_material_default(m, type);
    out->invisible = false;
    static const float half[3] = {0.5f, 0.5f, 0.5f};
    if (!strcmp(type, "twosided"))
        return inner(p, n, 0, out, depth);
    if (!strcmp(type, "bumpmap") || !strcmp(type, "normalmap"))
        return shading_map(p, n, type, out, depth);
    if (!strcmp(type, "mask")) { /* a cut-out: see SgMaterial.cutout */
        float opacity[3];
        uint32_t texture;
        static const float half_opaque[3] = {0.5f, 0.5f, 0.5f};
        if (!mts_color(p, n, "opacity", half_opaque, opacity, &texture, NULL) || !inner(p, n, 0, out, depth))
            return false;
        if (texture || opacity[0] < 1.0f) {
            m->cutout = true;
            m->alpha = texture ? 1.0f : fmaxf(opacity[0], 0.0f);
            m->alpha_texture = texture;
        }
        return true;
    }
    if (!strcmp(type, "blendbsdf"))
        return blend(p, n, out, depth);
    if (!strcmp(type, "null")) {
        out->invisible = true;
        return true;
    }
    if (!strcmp(type, "diffuse") || !strcmp(type, "roughdiffuse")) {
        if (!mts_color(p, n, "reflectance", half, m->diffuse, &m->diffuse_texture, NULL))
            return false;
        if (!strcmp(type, "roughdiffuse"))
            mts_warn(p, n, "roughdiffuse is taken as diffuse");
        clamp_albedo(p, n, m->diffuse);
        m->type = SG_MATERIAL_DIFFUSE;
        return true;
    }
    if (!strcmp(type, "difftrans")) { /* 0.6's diffuse transmitter: it reflects nothing */
        if (!mts_color(p, n, "transmittance", half, m->transmittance, NULL, NULL))
            return false;
        clamp_albedo(p, n, m->transmittance);
        m->diffuse[0] = m->diffuse[1] = m->diffuse[2] = 0;
        m->type = SG_MATERIAL_DIFFUSE_TRANSMISSION;
        return true;
    }
    if (!strcmp(type, "plastic") || !strcmp(type, "roughplastic"))
        return plastic(p, n, !strcmp(type, "roughplastic"), m);
    if (!strcmp(type, "conductor") || !strcmp(type, "roughconductor")) {
        bool rough = !strcmp(type, "roughconductor");
        m->roughness[0] = m->roughness[1] = 0;
        if (!conductor(p, n, rough, m) || (rough && m->type == SG_MATERIAL_CONDUCTOR && !alphas(p, n, m->roughness)))
            return false;
        return true;
    }
    if (!strcmp(type, "dielectric") || !strcmp(type, "roughdielectric") || !strcmp(type, "thindielectric"))
        return dielectric(p, n, type, m);
    if (!strcmp(type, "phong")) {
        double exponent;
        static const float spec_default[3] = {0.2f, 0.2f, 0.2f};
        if (!mts_color(p, n, "diffuse_reflectance", half, m->diffuse, &m->diffuse_texture, NULL) ||
            !mts_color(p, n, "specular_reflectance", spec_default, m->specular, NULL, NULL) ||
            !mts_float(p, n, "exponent", 30, &exponent))
            return false;
        m->type = SG_MATERIAL_GLOSSY;
        m->exponent = (float)fmin(fmax(exponent, 1), 1e4);
        return true;
    }
    if (!strcmp(type, "principled")) {
        mts_warn(p, n, "principled is taken as diffuse of its base_color");
        if (!mts_color(p, n, "base_color", half, m->diffuse, &m->diffuse_texture, NULL))
            return false;
        clamp_albedo(p, n, m->diffuse);
        m->type = SG_MATERIAL_DIFFUSE;
        return true;
    }
    mts_warn(p, n, "bsdf \"%s\" is not supported: grey diffuse instead", type);
    return true;
}

bool mts_material(MtsParser *p, const XmlNode *bsdf, size_t *index)
{
    for (size_t i = 0; i < p->material_count; i++)
        if (p->materials[i].node == bsdf) {
            *index = i;
            return true;
        }
    MtsMaterial m;
    memset(&m, 0, sizeof m);
    if (bsdf) {
        if (!make_material(p, bsdf, &m, 0))
            return false;
    } else {
        sg_material_default(&m.material, "default");
    }
    m.node = bsdf;
    m.scene_id = UINT32_MAX;
    if (!MTS_RESERVE(p, p->materials, p->material_count, p->material_capacity, 1))
        return false;
    *index = p->material_count;
    p->materials[p->material_count++] = m;
    return true;
}

bool mts_scene_material(MtsParser *p, size_t index, const float *radiance, uint32_t *id)
{
    MtsMaterial *m = &p->materials[index];
    if (!radiance) {
        if (m->scene_id == UINT32_MAX && !sg_builder_add_material(&p->core, &m->material, &m->scene_id, p->err))
            return false;
        *id = m->scene_id;
        return true;
    }
    return sg_builder_emissive_material(&p->core, index, &m->material, radiance, id, p->err);
}

/* ---- media ------------------------------------------------------------------ */

/* Mitsuba's homogeneous medium: sigma_t and albedo (Mitsuba 3's defaults 1
 * and 0.75) or, as 0.6 also takes, sigma_a and sigma_s (1 each), all times
 * scale (0.6: densityMultiplier). Absorbing only where what it scatters is 0. */
bool mts_medium_absorption(MtsParser *p, const XmlNode *medium, float sigma_a[3], bool *absorbing)
{
    *absorbing = false;
    memset(sigma_a, 0, 3 * sizeof(float));
    const char *type = mts_attr(p, medium, "type");
    if (!type)
        return p->err->failed ? false : mts_fail(p, medium, "<medium> without a type");
    if (strcmp(type, "homogeneous")) {
        mts_warn(p, medium, "media of type \"%s\" are not supported: left out", type);
        return true;
    }
    static const float one[3] = {1, 1, 1}, three_quarters[3] = {0.75f, 0.75f, 0.75f};
    float a[3], s[3], sigma_t[3], albedo[3];
    bool has_a, has_s;
    double scale, density;
    const XmlNode *preset;
    if (!mts_color(p, medium, "sigma_a", one, a, NULL, &has_a) ||
        !mts_color(p, medium, "sigma_s", one, s, NULL, &has_s) ||
        !mts_color(p, medium, "sigma_t", one, sigma_t, NULL, NULL) ||
        !mts_color(p, medium, "albedo", three_quarters, albedo, NULL, NULL) ||
        !mts_float(p, medium, "scale", 1, &scale) || !mts_float(p, medium, "density_multiplier", 1, &density) ||
        !mts_find(p, medium, "material", &preset))
        return false;
    if (preset) {
        mts_warn(p, medium, "media of a named \"material\" (measured scattering media) are not supported: left out");
        return true;
    }
    bool scatters = false;
    for (int c = 0; c < 3; c++) {
        double k = scale * density;
        double absorb = has_a || has_s ? a[c] : sigma_t[c] * (1 - albedo[c]);
        double scatter = has_a || has_s ? s[c] : sigma_t[c] * albedo[c];
        sigma_a[c] = (float)fmax(absorb * k, 0);
        scatters = scatters || scatter * k > 0;
    }
    if (scatters) {
        memset(sigma_a, 0, 3 * sizeof(float));
        mts_warn(p, medium, "scattering media (albedo above 0) are not supported: left out");
        return true;
    }
    *absorbing = true;
    return true;
}

bool mts_interior_material(MtsParser *p, const XmlNode *shape, uint32_t *id)
{
    const XmlNode *interior, *exterior;
    if (!mts_find(p, shape, "interior", &interior) || !mts_find(p, shape, "exterior", &exterior))
        return false;
    if (exterior)
        mts_warn(p, exterior, "exterior media are ignored (the outside of shapes is clear)");
    if (!interior)
        return true;
    float sigma_a[3];
    bool absorbing;
    if (!mts_medium_absorption(p, interior, sigma_a, &absorbing))
        return false;
    SgScene *scene = p->core.scene;
    if (!absorbing || (sigma_a[0] <= 0 && sigma_a[1] <= 0 && sigma_a[2] <= 0))
        return true;
    if (scene->materials[*id].type != SG_MATERIAL_DIELECTRIC) {
        mts_warn(p, interior, "a medium inside a shape that is not a dielectric is ignored");
        return true;
    }
    SgMaterial copy;
    memcpy(&copy, &scene->materials[*id], sizeof copy);
    memcpy(copy.sigma_a, sigma_a, sizeof copy.sigma_a);
    for (uint32_t i = 0; i < scene->material_count; i++) /* shapes sharing a bsdf and a medium share a copy */
        if (!memcmp(&scene->materials[i], &copy, sizeof copy)) {
            *id = i;
            return true;
        }
    return sg_builder_add_material(&p->core, &copy, id, p->err);
}
