/* pbrt scene files, materials: pbrt-v4's (and pbrt-v3's) materials mapped
 * onto ours, named materials with forward references, and area lights. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "pbrt_parser.h"

static void clamp_albedo(Parser *p, const Token *at, float c[3], const char *what)
{
    for (int a = 0; a < 3; a++)
        if (c[a] > 1) {
            pbrt_warn_at(p, at, "%s above 1 clamped to 1", what);
            c[a] = 1;
        }
}

/* pbrt-v3's roughness remapping (a fit in log roughness). */
static double v3_roughness_to_alpha(double rough)
{
    double x = log(fmax(rough, 1e-3));
    return 1.62142 + 0.819955 * x + 0.1734 * x * x + 0.0171201 * x * x * x +
           0.000640711 * x * x * x * x;
}

/* Microfacet roughness to a Phong exponent (alpha^2 = 2 / (n + 2)).
 * fallback: the material's default roughness; v3: pbrt-v3's remapping. */
static bool roughness_exponent_of(Parser *p, double fallback, bool v3, double *exponent,
                                  double *alpha_out)
{
    double rough, u, v;
    bool remap;
    if (!pbrt_param_scalar(p, "uroughness", fallback, &u) ||
        !pbrt_param_scalar(p, "vroughness", fallback, &v) ||
        !pbrt_param_bool(p, "remaproughness", true, &remap) ||
        !pbrt_param_scalar(p, "roughness", 0.5 * (u + v), &rough))
        return false;
    if (!(rough >= 0))
        rough = 0;
    double alpha = !remap ? rough : v3 ? v3_roughness_to_alpha(rough) : sqrt(rough);
    *alpha_out = alpha;
    double n = alpha > 0 ? 2 / (alpha * alpha) - 2 : 1e4;
    *exponent = fmin(fmax(n, 1), 1e4);
    return true;
}

/* pbrt-v4's GGX alphas along u and v: "uroughness" and "vroughness",
 * each defaulting to "roughness", remapped by sqrt unless remaproughness
 * is false (v3: pbrt-v3's fit). A roughness texture counts as its mean. */
static bool ggx_alphas(Parser *p, const Token *at, double fallback, bool v3, float alpha[2])
{
    double rough, uv[2];
    bool remap;
    if (!pbrt_param_scalar(p, "roughness", fallback, &rough) ||
        !pbrt_param_scalar(p, "uroughness", rough, &uv[0]) || !pbrt_param_scalar(p, "vroughness", rough, &uv[1]) ||
        !pbrt_param_bool(p, "remaproughness", true, &remap))
        return false;
    for (int i = 0; i < 2; i++) {
        /* 0 stays smooth (pbrt-v3's fit would give 0.04: its glass tests for 0 first) */
        double r = uv[i] > 0 ? uv[i] : 0;
        alpha[i] = (float)(!remap || r == 0 ? r : v3 ? v3_roughness_to_alpha(r) : sqrt(r));
    }
    if (fabsf(alpha[0] - alpha[1]) > 1e-6f * fmaxf(alpha[0], alpha[1]))
        pbrt_warn_at(p, at, "anisotropic roughness is oriented around the normal arbitrarily, not along the "
                            "mesh's u direction");
    return true;
}

/* An index given as outside over inside (below 1) read the other way. */
static double index_above_1(double ior) { return ior > 0 && ior < 1 ? 1 / ior : ior; }

/* What glass and dielectric end with: index ior, GGX-rough where alpha > 0
 * (render/microfacet.h), smooth below pbrt's 1e-3 (v3: pbrt-v3's
 * roughness remapping). */
static bool dielectric(Parser *p, const Token *at, double ior, bool v3, SgMaterial *m)
{
    if (!ggx_alphas(p, at, 0, v3, m->roughness))
        return false;
    m->type = SG_MATERIAL_DIELECTRIC;
    m->ior = (float)ior;
    m->diffuse[0] = m->diffuse[1] = m->diffuse[2] = 0;
    return true;
}

/* pbrt-v4's diffusetransmission: reflectance and transmittance (0.25 each
 * unless told), both times "scale". A textured transmittance is its mean. */
static bool diffuse_transmission(Parser *p, const Token *at, SgMaterial *m)
{
    static const float quarter[3] = {0.25f, 0.25f, 0.25f};
    double scale;
    if (!pbrt_param_color(p, "reflectance", quarter, m->diffuse, NULL) ||
        !pbrt_param_color(p, "transmittance", quarter, m->transmittance, NULL) ||
        !pbrt_param_scalar(p, "scale", 1, &scale))
        return false;
    if (pbrt_param_texture(p, "transmittance"))
        pbrt_warn_at(p, at, "diffusetransmission: a textured transmittance is taken as its mean");
    m->diffuse_texture = scale == 1 ? pbrt_param_texture(p, "reflectance") : 0;
    if (scale != 1 && pbrt_param_texture(p, "reflectance"))
        pbrt_warn_at(p, at, "diffusetransmission: a scaled reflectance texture is taken as its mean");
    bool above_1 = false;
    for (int a = 0; a < 3; a++) {
        m->diffuse[a] = (float)(m->diffuse[a] * fmax(scale, 0));
        m->transmittance[a] = (float)(m->transmittance[a] * fmax(scale, 0));
        float sum = m->diffuse[a] + m->transmittance[a];
        if (sum > 1) {
            above_1 = true;
            m->diffuse[a] /= sum;
            m->transmittance[a] /= sum;
        }
    }
    if (above_1)
        pbrt_warn_at(p, at, "diffusetransmission: reflectance + transmittance above 1 scaled to 1");
    m->type = SG_MATERIAL_DIFFUSE_TRANSMISSION;
    return true;
}

/* pbrt-v4's shading normals: "displacement", a float texture (a bump map;
 * a constant displaces nothing), and "normalmap", an image file read
 * linear, in tangent space. */
static bool shading_maps(Parser *p, const Token *at, SgMaterial *m)
{
    m->bump_texture = pbrt_param_texture(p, "displacement");
    m->bump_scale = 1;
    const Token *file = pbrt_param_string(p, "normalmap");
    if (!file || !file->len)
        return true;
    char path[8192];
    if (!pbrt_resolve_path(p, at, file, path, sizeof path))
        return false;
    SgTexture st = {.kind = SG_TEXTURE_IMAGE, .uscale = 1, .vscale = 1, .path = path, .gamma = 0, .scale = 1,
                    .wrap = SG_WRAP_REPEAT};
    if (!sg_image_average(&p->core.images, path, 0, st.mean, NULL)) {
        pbrt_warn_at(p, at, "normal maps that cannot be read (missing files) are ignored");
        return true;
    }
    uint32_t id;
    if (!sg_builder_add_texture(&p->core, &st, &id, p->err))
        return false;
    m->normal_texture = id + 1;
    return true;
}

/* A material's constructor: reads the statement's parameters into *out,
 * which holds pbrt's defaults (sg_material_default) named for the
 * statement. `type` is the name it was called by. */
typedef bool MaterialMaker(Parser *p, const Token *at, const Token *type, PbrtMaterial *out);

static const float half[3] = {0.5f, 0.5f, 0.5f};

/* diffuse, and the materials taken as diffuse (with a warning) */
static bool make_diffuse(Parser *p, const Token *at, const Token *type, PbrtMaterial *out)
{
    SgMaterial *m = &out->material;
    if (!pbrt_string_is(type, "diffuse"))
        pbrt_warn_at(p, at, "Material \"%.*s\" is not supported: diffuse instead", (int)type->len, type->s);
    if (!pbrt_param_color(p, "reflectance", half, m->diffuse, NULL))
        return false;
    clamp_albedo(p, at, m->diffuse, "reflectance");
    m->diffuse_texture = pbrt_param_texture(p, "reflectance");
    m->type = SG_MATERIAL_DIFFUSE;
    return true;
}

static bool make_diffuse_transmission(Parser *p, const Token *at, const Token *type, PbrtMaterial *out)
{
    (void)type;
    return diffuse_transmission(p, at, &out->material);
}

static bool make_coated_diffuse(Parser *p, const Token *at, const Token *type, PbrtMaterial *out)
{
    (void)type;
    SgMaterial *m = &out->material;
    double eta, thickness, albedo;
    if (!pbrt_param_color(p, "reflectance", half, m->diffuse, NULL) || !ggx_alphas(p, at, 0, false, m->roughness) ||
        !pbrt_param_scalar(p, "eta", 1.5, &eta) || !pbrt_param_scalar(p, "albedo", 0, &albedo) ||
        !pbrt_param_scalar(p, "thickness", 0.01, &thickness))
        return false;
    clamp_albedo(p, at, m->diffuse, "reflectance");
    m->diffuse_texture = pbrt_param_texture(p, "reflectance");
    if (albedo > 0)
        pbrt_warn_at(p, at, "coateddiffuse: a medium between coat and base (\"albedo\") is ignored");
    if (!(eta > 1))
        eta = 1.5;
    /* the closed form of a GGX coat over a Lambertian base (render/bsdf.c) */
    m->type = SG_MATERIAL_COATED_DIFFUSE;
    m->ior = (float)eta;
    return true;
}

/* conductor, coatedconductor (its conductor) and v3's metal */
static bool make_conductor(Parser *p, const Token *at, const Token *type, PbrtMaterial *out)
{
    SgMaterial *m = &out->material;
    bool coated = pbrt_string_is(type, "coatedconductor"), v3 = pbrt_string_is(type, "metal");
    if (coated)
        pbrt_warn_at(p, at, "Material \"coatedconductor\" is approximated by its conductor");
    float eta[3], k[3], reflectance[3];
    bool has_reflectance;
    /* unless told, copper: sg_material_default's, pbrt's default */
    if (!pbrt_param_color(p, coated ? "conductor.eta" : "eta", m->eta, eta, NULL) ||
        !pbrt_param_color(p, coated ? "conductor.k" : "k", m->k, k, NULL) ||
        !pbrt_param_color(p, "reflectance", half, reflectance, &has_reflectance))
        return false;
    /* GGX with the complex Fresnel of eta + i k; a reflectance in
     * their place is pbrt's eta 1 and the k of that reflectance */
    for (int a = 0; a < 3; a++) {
        if (has_reflectance) {
            eta[a] = 1;
            k[a] = sg_conductor_k_of_reflectance(reflectance[a]);
            m->diffuse[a] = reflectance[a];
        } else {
            m->diffuse[a] = 0;
        }
        m->eta[a] = eta[a];
        m->k[a] = k[a];
    }
    if (has_reflectance)
        m->diffuse_texture = pbrt_param_texture(p, "reflectance");
    if (!ggx_alphas(p, at, v3 ? 0.01 : 0, v3, m->roughness))
        return false;
    m->type = SG_MATERIAL_CONDUCTOR;
    return true;
}

/* pbrt-v3 materials: Bitterli's collection first came in v3 syntax. */
static bool make_matte(Parser *p, const Token *at, const Token *type, PbrtMaterial *out)
{
    SgMaterial *m = &out->material;
    if (pbrt_string_is(type, "translucent"))
        pbrt_warn_at(p, at, "Material \"translucent\" is taken as diffuse (its Kd)");
    if (!pbrt_param_color(p, "Kd", half, m->diffuse, NULL))
        return false;
    clamp_albedo(p, at, m->diffuse, "Kd");
    m->type = SG_MATERIAL_DIFFUSE;
    return true;
}

/* v3's plastic, substrate and uber: a glossy lobe over a diffuse one */
static bool make_plastic(Parser *p, const Token *at, const Token *type, PbrtMaterial *out)
{
    SgMaterial *m = &out->material;
    float d = pbrt_string_is(type, "substrate") ? 0.5f : 0.25f;
    const float kd[3] = {d, d, d};
    double exponent, alpha, opacity;
    if (!pbrt_param_color(p, "Kd", kd, m->diffuse, NULL) || !pbrt_param_color(p, "Ks", kd, m->specular, NULL) ||
        !roughness_exponent_of(p, 0.1, true, &exponent, &alpha) || !pbrt_param_scalar(p, "opacity", 1, &opacity))
        return false;
    if (opacity < 1 || pbrt_find_param(p, "Kr") || pbrt_find_param(p, "Kt"))
        pbrt_warn_at(p, at, "uber opacity, Kr and Kt are ignored");
    for (int a = 0; a < 3; a++) { /* keep energy: scale the pair down */
        float sum = m->diffuse[a] + m->specular[a];
        if (sum > 1) {
            m->diffuse[a] /= sum;
            m->specular[a] /= sum;
        }
    }
    m->type = SG_MATERIAL_GLOSSY;
    m->exponent = (float)exponent;
    return true;
}

static bool make_mirror(Parser *p, const Token *at, const Token *type, PbrtMaterial *out)
{
    (void)type;
    SgMaterial *m = &out->material;
    const float kr[3] = {0.9f, 0.9f, 0.9f};
    if (!pbrt_param_color(p, "Kr", kr, m->specular, NULL))
        return false;
    clamp_albedo(p, at, m->specular, "Kr");
    m->diffuse[0] = m->diffuse[1] = m->diffuse[2] = 0;
    m->type = SG_MATERIAL_MIRROR;
    return true;
}

/* v3's glass */
static bool make_glass(Parser *p, const Token *at, const Token *type, PbrtMaterial *out)
{
    (void)type;
    double ior;
    if (!pbrt_param_scalar(p, "index", 1.5, &ior) ||
        (pbrt_find_param(p, "eta") && !pbrt_param_scalar(p, "eta", 1.5, &ior)))
        return false;
    ior = index_above_1(ior);
    if (!(ior >= 1 && ior <= 10))
        return pbrt_fail_at(p, at, "glass index %g is out of range", ior);
    return dielectric(p, at, ior, true, &out->material);
}

static bool make_dielectric(Parser *p, const Token *at, const Token *type, PbrtMaterial *out)
{
    if (pbrt_string_is(type, "thindielectric"))
        pbrt_warn_at(p, at, "Material \"thindielectric\" is taken as a solid dielectric");
    float eta[3];
    if (!pbrt_param_color(p, "eta", (const float[3]){1.5f, 1.5f, 1.5f}, eta, NULL))
        return false;
    double ior = index_above_1(eta[1]);
    if (!(ior >= 1 && ior <= 10))
        return pbrt_fail_at(p, at, "dielectric eta %g is out of range", (double)eta[1]);
    return dielectric(p, at, ior, false, &out->material);
}

/* interface, none, "": a boundary of media, not a surface */
static bool make_invisible(Parser *p, const Token *at, const Token *type, PbrtMaterial *out)
{
    (void)p, (void)at, (void)type;
    out->invisible = true;
    return true;
}

/* mix: the named material with the larger weight, under this name */
static bool make_mix(Parser *p, const Token *at, const Token *type, PbrtMaterial *out)
{
    (void)type;
    const Param *names = pbrt_find_param(p, "materials");
    double amount;
    if (!pbrt_param_scalar(p, "amount", 0.5, &amount))
        return false;
    pbrt_warn_at(p, at, "Material \"mix\" is replaced by the material with the larger weight");
    if (!names || names->kind != PARAM_STRINGS || names->count != 2)
        return true;
    const Token *pick = &p->strings[names->first + (amount > 0.5 ? 1 : 0)];
    char label[sizeof out->material.name];
    memcpy(label, out->material.name, sizeof label);
    for (size_t i = p->material_count; i-- > 0;)
        if (p->materials[i].name && pbrt_string_is(pick, p->materials[i].name)) {
            *out = p->materials[i];
            out->name = NULL;
            out->scene_id = UINT32_MAX;
            out->pending = false;
            memcpy(out->material.name, label, sizeof label);
            return true;
        }
    return true;
}

static const struct {
    const char *type;
    MaterialMaker *make;
} material_makers[] = {
    {"diffuse", make_diffuse},
    {"diffusetransmission", make_diffuse_transmission},
    {"subsurface", make_diffuse},
    {"measured", make_diffuse},
    {"hair", make_diffuse},
    {"kdsubsurface", make_diffuse},
    {"fourier", make_diffuse},
    {"disney", make_diffuse},
    {"coateddiffuse", make_coated_diffuse},
    {"conductor", make_conductor},
    {"coatedconductor", make_conductor},
    {"metal", make_conductor},
    {"matte", make_matte},
    {"translucent", make_matte},
    {"plastic", make_plastic},
    {"substrate", make_plastic},
    {"uber", make_plastic},
    {"mirror", make_mirror},
    {"glass", make_glass},
    {"dielectric", make_dielectric},
    {"thindielectric", make_dielectric},
    {"interface", make_invisible},
    {"", make_invisible},
    {"none", make_invisible},
    {"mix", make_mix},
};

static bool make_material(Parser *p, const Token *at, const Token *type, const char *label,
                          PbrtMaterial *out)
{
    memset(out, 0, sizeof *out);
    out->scene_id = UINT32_MAX;
    sg_material_default(&out->material, label);
    if (!shading_maps(p, at, &out->material))
        return false;
    for (size_t i = 0; i < sizeof material_makers / sizeof material_makers[0]; i++)
        if (pbrt_string_is(type, material_makers[i].type))
            return material_makers[i].make(p, at, type, out);
    pbrt_warn_at(p, at, "Material \"%.*s\" is not supported: grey diffuse instead", (int)type->len,
                 type->s);
    return true;
}

bool pbrt_add_material(Parser *p, const PbrtMaterial *m, uint32_t *index)
{
    if (!RESERVE(p, p->materials, p->material_count, p->material_capacity, 1))
        return false;
    p->materials[p->material_count] = *m;
    *index = (uint32_t)p->material_count++;
    return true;
}

bool pbrt_material_statement(Parser *p, const Token *statement)
{
    Token type;
    if (!pbrt_need_string(p, statement, &type) || !pbrt_parse_params(p))
        return false;
    char label[64];
    snprintf(label, sizeof label, "%.*s@%d", (int)(type.len > 40 ? 40 : type.len), type.s,
             statement->line);
    PbrtMaterial m;
    return make_material(p, statement, &type, label, &m) &&
           pbrt_add_material(p, &m, &p->state.material);
}

bool pbrt_make_named_material_statement(Parser *p, const Token *statement)
{
    Token name;
    if (!pbrt_need_string(p, statement, &name) || !pbrt_parse_params(p))
        return false;
    const Token *type = pbrt_param_string(p, "type");
    if (!type)
        return pbrt_fail_at(p, statement, "MakeNamedMaterial \"%.*s\" has no \"string type\"",
                            (int)name.len, name.s);
    char label[64];
    snprintf(label, sizeof label, "%.*s", (int)(name.len > 63 ? 63 : name.len), name.s);
    PbrtMaterial m;
    uint32_t index;
    if (!make_material(p, statement, type, label, &m))
        return false;
    for (size_t i = p->material_count; i-- > 0;) {
        PbrtMaterial *old = &p->materials[i];
        if (!old->name || !pbrt_string_is(&name, old->name))
            continue;
        if (!old->pending) {
            pbrt_warn_at(p, statement,
                         "MakeNamedMaterial redefines a name: later uses get the new one");
            break;
        }
        /* Fill in the forward reference, and what shapes already got. */
        old->material = m.material;
        old->invisible = m.invisible;
        old->pending = false;
        SgScene *scene = p->core.scene;
        if (old->scene_id != UINT32_MAX)
            scene->materials[old->scene_id] = m.material;
        for (size_t k = 0; k < p->core.emissive_count; k++)
            if (p->core.emissive[k].material == i) {
                SgMaterial *e = &scene->materials[p->core.emissive[k].scene_id];
                float emission[3];
                memcpy(emission, e->emission, sizeof emission);
                *e = m.material;
                memcpy(e->emission, emission, sizeof emission);
            }
        return true;
    }
    if (!(m.name = pbrt_token_dup(&name)))
        return sg_fail(p->err, "%s: out of memory", p->core.path);
    if (!pbrt_add_material(p, &m, &index)) {
        free(m.name);
        return false;
    }
    return true;
}

bool pbrt_named_material_statement(Parser *p, const Token *statement)
{
    Token name;
    if (!pbrt_need_string(p, statement, &name))
        return false;
    for (size_t i = p->material_count; i-- > 0;)
        if (p->materials[i].name && pbrt_string_is(&name, p->materials[i].name)) {
            p->state.material = (uint32_t)i;
            return true;
        }
    PbrtMaterial m;
    memset(&m, 0, sizeof m);
    char label[64];
    snprintf(label, sizeof label, "%.*s", (int)(name.len > 63 ? 63 : name.len), name.s);
    sg_material_default(&m.material, label);
    m.scene_id = UINT32_MAX;
    m.pending = true;
    m.first_use = name;
    if (!(m.name = pbrt_token_dup(&name)))
        return sg_fail(p->err, "%s: out of memory", p->core.path);
    if (!pbrt_add_material(p, &m, &p->state.material)) {
        free(m.name);
        return false;
    }
    return true;
}

/* The scene material of the current state (emissive copies cached). */
static bool plain_scene_material(Parser *p, bool emissive, uint32_t *id)
{
    PbrtMaterial *m = &p->materials[p->state.material];
    if (!emissive) {
        if (m->scene_id == UINT32_MAX &&
            !sg_builder_add_material(&p->core, &m->material, &m->scene_id, p->err))
            return false;
        *id = m->scene_id;
        return true;
    }
    return sg_builder_emissive_material(&p->core, p->state.material, &m->material, p->state.radiance, id, p->err);
}

/* The scene material of the current state with the current shape's
 * attributes (copies cached by what they were made from). */
bool pbrt_current_scene_material(Parser *p, bool emissive, uint32_t *id)
{
    if (!plain_scene_material(p, emissive, id))
        return false;
    static const ShapeAttributes none;
    ShapeAttributes attr;
    memcpy(&attr, &p->shape, sizeof attr); /* padding too: compared by memcmp */
    if (p->core.scene->materials[*id].type != SG_MATERIAL_DIELECTRIC) /* only glass holds a medium here */
        memset(attr.sigma_a, 0, sizeof attr.sigma_a);
    if (!memcmp(&attr, &none, sizeof none))
        return true;
    for (size_t i = 0; i < p->variant_count; i++)
        if (p->variants[i].base == *id && !memcmp(&p->variants[i].attr, &attr, sizeof attr)) {
            *id = p->variants[i].scene_id;
            return true;
        }
    SgMaterial copy = p->core.scene->materials[*id];
    copy.cutout = attr.cutout;
    copy.alpha = attr.alpha;
    copy.alpha_texture = attr.alpha_texture;
    memcpy(copy.sigma_a, attr.sigma_a, sizeof copy.sigma_a);
    uint32_t base = *id;
    if (!RESERVE(p, p->variants, p->variant_count, p->variant_capacity, 1) ||
        !sg_builder_add_material(&p->core, &copy, id, p->err))
        return false;
    MaterialVariant *v = &p->variants[p->variant_count++];
    v->base = base;
    memcpy(&v->attr, &attr, sizeof attr);
    v->scene_id = *id;
    return true;
}

bool pbrt_area_light_statement(Parser *p, const Token *statement)
{
    Token type;
    if (!pbrt_need_string(p, statement, &type) || !pbrt_parse_params(p))
        return false;
    if (!pbrt_string_is(&type, "diffuse")) {
        pbrt_warn_at(p, statement, "AreaLightSource \"%.*s\" is not supported: shapes not emissive",
                     (int)type.len, type.s);
        p->state.area_light = false;
        return true;
    }
    float L[3];
    double scale;
    bool two_sided;
    if (!pbrt_param_color(p, "L", (const float[3]){1, 1, 1}, L, NULL) ||
        !pbrt_param_float(p, "scale", 1, &scale) ||
        !pbrt_param_bool(p, "twosided", false, &two_sided))
        return false;
    if (!(scale >= 0))
        return pbrt_fail_at(p, statement, "AreaLightSource: \"scale\" must not be negative");
    if (two_sided)
        pbrt_warn_at(p, statement, "two-sided area lights emit on their front side only");
    if (pbrt_find_param(p, "power"))
        pbrt_warn_at(p, statement,
                     "area light \"power\" is ignored (\"L\" and \"scale\" are used)");
    if (pbrt_find_param(p, "filename"))
        pbrt_warn_at(p, statement, "image area lights are taken as uniform");
    for (int a = 0; a < 3; a++)
        L[a] = (float)(L[a] * scale);
    memcpy(p->state.radiance, L, sizeof L);
    p->state.area_light = L[0] > 0 || L[1] > 0 || L[2] > 0;
    return true;
}
