/* pbrt scene files, participating media: MakeNamedMedium and
 * MediumInterface. What the renderer takes is a homogeneous medium that
 * absorbs only, inside a dielectric (tinted glass, liquids): its sigma_a
 * goes to the shape's glass material, and the path is attenuated by
 * exp(-sigma_a d) along each segment inside it. Scattering media and the
 * grid kinds are left out with a warning. */
#include <math.h>
#include <string.h>

#include "pbrt_parser.h"

/* Reads a homogeneous medium's coefficients as pbrt-v4 does: sigma_a and
 * sigma_s (1 each unless given), both times "scale". */
static bool homogeneous(Parser *p, const Token *statement, NamedMedium *m)
{
    static const float one[3] = {1, 1, 1};
    float sigma_s[3];
    double scale;
    if (!pbrt_param_color(p, "sigma_a", one, m->sigma_a, NULL) ||
        !pbrt_param_color(p, "sigma_s", one, sigma_s, NULL) || !pbrt_param_float(p, "scale", 1, &scale))
        return false;
    if (pbrt_param_string(p, "preset")) {
        pbrt_warn_at(p, statement, "media with a \"preset\" (measured scattering media) are not supported: "
                                   "left out");
        return true;
    }
    if (!(scale >= 0))
        return pbrt_fail_at(p, statement, "MakeNamedMedium: \"scale\" must not be negative");
    bool scatters = false;
    for (int c = 0; c < 3; c++) {
        m->sigma_a[c] = (float)fmax(m->sigma_a[c] * scale, 0);
        scatters = scatters || sigma_s[c] * scale > 0;
    }
    if (scatters) {
        pbrt_warn_at(p, statement, "scattering media (sigma_s > 0) are not supported: left out");
        return true;
    }
    m->supported = true;
    return true;
}

bool pbrt_make_named_medium_statement(Parser *p, const Token *statement)
{
    Token name;
    if (!pbrt_need_string(p, statement, &name) || !pbrt_parse_params(p))
        return false;
    NamedMedium m = {0};
    const Token *type = pbrt_param_string(p, "type");
    if (!type)
        return pbrt_fail_at(p, statement, "MakeNamedMedium \"%.*s\" has no \"string type\"", (int)name.len,
                            name.s);
    if (pbrt_string_is(type, "homogeneous")) {
        if (!homogeneous(p, statement, &m))
            return false;
    } else {
        pbrt_warn_at(p, statement, "media of type \"%.*s\" are not supported: left out", (int)type->len, type->s);
    }
    if (!RESERVE(p, p->media, p->medium_count, p->medium_capacity, 1))
        return false;
    if (!(m.name = pbrt_token_dup(&name)))
        return sg_fail(p->err, "%s: out of memory", p->core.path);
    p->media[p->medium_count++] = m;
    return true;
}

/* MediumInterface "inside" ["outside"]: the shapes that follow hold
 * `inside` (the outside is taken as clear air). */
bool pbrt_medium_interface_statement(Parser *p, const Token *statement)
{
    Token inside, outside;
    if (!pbrt_need_string(p, statement, &inside))
        return false;
    if (pbrt_next_token(p, &outside) && !outside.quoted)
        pbrt_unget_token(p, &outside);
    if (p->err->failed)
        return false;
    memset(p->state.inside_sigma_a, 0, sizeof p->state.inside_sigma_a);
    if (!inside.len)
        return true;
    for (size_t i = p->medium_count; i-- > 0;)
        if (pbrt_string_is(&inside, p->media[i].name)) {
            if (p->media[i].supported)
                memcpy(p->state.inside_sigma_a, p->media[i].sigma_a, sizeof p->state.inside_sigma_a);
            return true;
        }
    pbrt_warn_at(p, statement, "MediumInterface names a medium not defined before: left out");
    return true;
}
