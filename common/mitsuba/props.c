/* Mitsuba scene files, properties: messages, "$name" substitution, ids,
 * typed property lookup in both dialects, colours and spectra, transforms
 * and file names. */
#include <ctype.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

#include "color.h"
#include "input_file.h"
#include "mitsuba_parser.h"
#include "vecmath.h"

bool mts_reserve(MtsParser *p, void **array, size_t *capacity, size_t needed, size_t item)
{
    if (needed <= *capacity)
        return true;
    size_t cap = *capacity ? *capacity : 8;
    while (cap < needed)
        cap *= 2;
    void *grown = realloc(*array, cap * item);
    if (!grown)
        return sg_fail(p->err, "%s: out of memory", p->core.path);
    *array = grown;
    *capacity = cap;
    return true;
}

bool mts_fail(MtsParser *p, const XmlNode *at, const char *fmt, ...)
{
    char cause[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(cause, sizeof cause, fmt, ap);
    va_end(ap);
    if (at)
        return sg_fail(p->err, "%s:%d: %s", at->doc->path, at->line, cause);
    return sg_fail(p->err, "%s: %s", p->core.path, cause);
}

void mts_warn(MtsParser *p, const XmlNode *at, const char *fmt, ...)
{
    char where[4200];
    if (at)
        snprintf(where, sizeof where, "%s:%d", at->doc->path, at->line);
    else
        snprintf(where, sizeof where, "%s", p->core.path);
    va_list ap;
    va_start(ap, fmt);
    sg_builder_warnv(&p->core, where, fmt, ap);
    va_end(ap);
}

/* ---- substitution and ids ----------------------------------------------- */

static const char *default_value(const MtsParser *p, const char *name, size_t len)
{
    for (size_t i = 0; i < p->default_count; i++)
        if (strlen(p->defaults[i].name) == len && !memcmp(p->defaults[i].name, name, len))
            return p->defaults[i].value;
    return NULL;
}

bool mts_substitute(MtsParser *p, XmlNode *n)
{
    if (n->substituted)
        return true;
    n->substituted = true;
    for (size_t i = 0; i < n->attr_count; i++) {
        char *v = n->attrs[2 * i + 1];
        if (!strchr(v, '$'))
            continue;
        size_t cap = strlen(v) + 1, len = 0;
        char *out = malloc(cap);
        if (!out)
            return sg_fail(p->err, "%s: out of memory", p->core.path);
        for (const char *s = v; *s;) {
            const char *value = NULL;
            size_t skip = 1;
            if (*s == '$') {
                size_t k = 1;
                while (isalnum((unsigned char)s[k]) || s[k] == '_')
                    k++;
                if (k > 1) {
                    value = default_value(p, s + 1, k - 1);
                    if (!value) {
                        free(out);
                        return mts_fail(p, n, "\"$%.*s\" has no <default> before it", (int)(k - 1), s + 1);
                    }
                    skip = k;
                }
            }
            size_t add = value ? strlen(value) : 1;
            if (len + add + 1 > cap) {
                cap = 2 * (len + add + 1);
                char *grown = realloc(out, cap);
                if (!grown) {
                    free(out);
                    return sg_fail(p->err, "%s: out of memory", p->core.path);
                }
                out = grown;
            }
            memcpy(out + len, value ? value : s, add);
            len += add;
            s += skip;
        }
        out[len] = 0;
        free(v);
        n->attrs[2 * i + 1] = out;
    }
    return true;
}

const char *mts_attr(MtsParser *p, const XmlNode *n, const char *name)
{
    if (!mts_substitute(p, (XmlNode *)n))
        return NULL;
    return sg_xml_attr(n, name);
}

const XmlNode *mts_lookup_id(const MtsParser *p, const char *id)
{
    for (size_t i = p->id_count; i-- > 0;)
        if (!strcmp(p->ids[i].id, id))
            return p->ids[i].node;
    return NULL;
}

bool mts_register_id(MtsParser *p, const XmlNode *n)
{
    const char *id = mts_attr(p, n, "id");
    if (p->err->failed)
        return false;
    if (!id)
        return true;
    const XmlNode *old = mts_lookup_id(p, id);
    if (old == n)
        return true;
    if (old)
        mts_warn(p, n, "an id given twice: references name the later element");
    if (!MTS_RESERVE(p, p->ids, p->id_count, p->id_capacity, 1))
        return false;
    p->ids[p->id_count++] = (MtsId){id, n};
    return true;
}

bool mts_is_tag(const XmlNode *n, const char *tag) { return !strcasecmp(n->tag, tag); }

/* ---- names and lookup --------------------------------------------------- */

/* Mitsuba 3's upgrade of 0.x names: an upper-case letter after a lower-case
 * one (or a digit) starts a new word (toWorld -> to_world, intIOR ->
 * int_ior). */
static void snake_case(const char *in, char *out, size_t size)
{
    size_t k = 0;
    for (size_t i = 0; in[i] && k + 2 < size; i++) {
        unsigned char c = (unsigned char)in[i];
        if (isupper(c) && i > 0 && (islower((unsigned char)in[i - 1]) || isdigit((unsigned char)in[i - 1])))
            out[k++] = '_';
        out[k++] = (char)tolower(c);
    }
    out[k] = 0;
}

void mts_child_name(MtsParser *p, const XmlNode *child, char *out, size_t size)
{
    const char *name = mts_attr(p, child, "name");
    if (!name) {
        out[0] = 0;
        return;
    }
    if (child->doc->old_dialect)
        snake_case(name, out, size);
    else
        snprintf(out, size, "%s", name);
}

static bool resolve_ref(MtsParser *p, const XmlNode *ref, const XmlNode **out)
{
    const char *id = mts_attr(p, ref, "id");
    if (!id)
        return p->err->failed ? false : mts_fail(p, ref, "<ref> without an id");
    if (!(*out = mts_lookup_id(p, id)))
        return mts_fail(p, ref, "reference to an unknown id \"%s\"", id);
    return true;
}

bool mts_find(MtsParser *p, const XmlNode *obj, const char *name, const XmlNode **out)
{
    *out = NULL;
    char child_name[128];
    for (size_t i = obj->child_count; i-- > 0;) { /* the last one given wins */
        const XmlNode *c = obj->children[i];
        mts_child_name(p, c, child_name, sizeof child_name);
        if (p->err->failed)
            return false;
        if (strcmp(child_name, name))
            continue;
        if (mts_is_tag(c, "ref"))
            return resolve_ref(p, c, out);
        *out = c;
        return true;
    }
    return true;
}

bool mts_find_object(MtsParser *p, const XmlNode *obj, const char *tag, size_t index, const XmlNode **out)
{
    *out = NULL;
    for (size_t i = 0; i < obj->child_count; i++) {
        const XmlNode *c = obj->children[i];
        if (mts_is_tag(c, "ref")) {
            const XmlNode *target;
            if (!resolve_ref(p, c, &target))
                return false;
            c = target;
        }
        if (mts_is_tag(c, tag) && index-- == 0) {
            *out = c;
            return true;
        }
    }
    return true;
}

/* ---- typed properties --------------------------------------------------- */

static bool parse_double(const char *s, double *out)
{
    char *end;
    double v = strtod(s, &end);
    while (isspace((unsigned char)*end))
        end++;
    if (end == s || *end || !isfinite(v))
        return false;
    *out = v;
    return true;
}

bool mts_numbers(MtsParser *p, const XmlNode *at, const char *text, double *out, size_t max, size_t *count)
{
    *count = 0;
    const char *s = text;
    for (;;) {
        while (isspace((unsigned char)*s) || *s == ',')
            s++;
        if (!*s)
            return true;
        char *end;
        double v = strtod(s, &end);
        if (end == s || !isfinite(v))
            return mts_fail(p, at, "\"%.60s\" is not a list of numbers", text);
        if (*count == max)
            return mts_fail(p, at, "\"%.60s\" holds more than %zu numbers", text, max);
        out[(*count)++] = v;
        s = end;
    }
}

/* The value attribute of a property found by name, of one of the tags. */
static bool property_value(MtsParser *p, const XmlNode *obj, const char *name, const char *tag,
                           const XmlNode **node, const char **value)
{
    *value = NULL;
    if (!mts_find(p, obj, name, node))
        return false;
    if (!*node)
        return true;
    if (!mts_is_tag(*node, tag) && !(mts_is_tag(*node, "integer") && !strcmp(tag, "float")) &&
        !(mts_is_tag(*node, "float") && !strcmp(tag, "integer")))
        return mts_fail(p, *node, "\"%s\" must be <%s>, not <%s>", name, tag, (*node)->tag);
    if (!(*value = mts_attr(p, *node, "value")))
        return p->err->failed ? false : mts_fail(p, *node, "<%s name=\"%s\"> has no value", tag, name);
    return true;
}

bool mts_float(MtsParser *p, const XmlNode *obj, const char *name, double fallback, double *out)
{
    const XmlNode *n;
    const char *v;
    *out = fallback;
    if (!property_value(p, obj, name, "float", &n, &v))
        return false;
    if (v && !parse_double(v, out))
        return mts_fail(p, n, "\"%s\": \"%.40s\" is not a number", name, v);
    return true;
}

bool mts_int(MtsParser *p, const XmlNode *obj, const char *name, long fallback, long *out)
{
    double d;
    if (!mts_float(p, obj, name, (double)fallback, &d))
        return false;
    if (!(d >= -2147483648.0 && d <= 2147483647.0 && d == floor(d)))
        return mts_fail(p, obj, "\"%s\" = %g is not an integer", name, d);
    *out = (long)d;
    return true;
}

bool mts_bool(MtsParser *p, const XmlNode *obj, const char *name, bool fallback, bool *out)
{
    const XmlNode *n;
    const char *v;
    *out = fallback;
    if (!property_value(p, obj, name, "boolean", &n, &v))
        return false;
    if (!v)
        return true;
    if (!strcasecmp(v, "true") || !strcmp(v, "1"))
        *out = true;
    else if (!strcasecmp(v, "false") || !strcmp(v, "0"))
        *out = false;
    else
        return mts_fail(p, n, "\"%s\": \"%.40s\" is not true or false", name, v);
    return true;
}

bool mts_string(MtsParser *p, const XmlNode *obj, const char *name, const char *fallback, const char **out)
{
    const XmlNode *n;
    const char *v;
    *out = fallback;
    if (!property_value(p, obj, name, "string", &n, &v))
        return false;
    if (v)
        *out = v;
    return true;
}

/* x, y, z attributes (each defaulting to fallback) or a "value" list. */
static bool xyz(MtsParser *p, const XmlNode *n, double fallback, double out[3])
{
    const char *value = mts_attr(p, n, "value");
    if (p->err->failed)
        return false;
    if (value) {
        size_t count;
        if (!mts_numbers(p, n, value, out, 3, &count))
            return false;
        if (count == 1)
            out[1] = out[2] = out[0];
        else if (count != 3)
            return mts_fail(p, n, "<%s> wants 1 or 3 numbers", n->tag);
        return true;
    }
    static const char *axes[3] = {"x", "y", "z"};
    for (int a = 0; a < 3; a++) {
        const char *s = mts_attr(p, n, axes[a]);
        out[a] = fallback;
        if (s && !parse_double(s, &out[a]))
            return mts_fail(p, n, "<%s %s=\"%.40s\">: not a number", n->tag, axes[a], s);
    }
    return true;
}

bool mts_point(MtsParser *p, const XmlNode *obj, const char *name, const double fallback[3], double out[3],
               bool *present)
{
    const XmlNode *n;
    memcpy(out, fallback, 3 * sizeof(double));
    if (present)
        *present = false;
    if (!mts_find(p, obj, name, &n))
        return false;
    if (!n)
        return true;
    if (!mts_is_tag(n, "point") && !mts_is_tag(n, "vector"))
        return mts_fail(p, n, "\"%s\" must be <point> or <vector>", name);
    if (present)
        *present = true;
    return xyz(p, n, 0, out);
}

/* "x, y, z" of a lookat attribute. */
static bool vector_attr(MtsParser *p, const XmlNode *n, const char *name, const double *fallback, double out[3])
{
    const char *s = mts_attr(p, n, name);
    if (p->err->failed)
        return false;
    if (!s) {
        if (fallback) {
            memcpy(out, fallback, 3 * sizeof(double));
            return true;
        }
        return mts_fail(p, n, "<lookat> needs \"%s\"", name);
    }
    size_t count;
    if (!mts_numbers(p, n, s, out, 3, &count))
        return false;
    if (count != 3)
        return mts_fail(p, n, "<lookat %s=...> wants 3 numbers", name);
    return true;
}

static bool lookat(MtsParser *p, const XmlNode *n, SgTransform *m)
{
    double origin[3], target[3], up[3], dir[3], left[3], new_up[3];
    static const double y_up[3] = {0, 1, 0};
    if (!vector_attr(p, n, "origin", NULL, origin) || !vector_attr(p, n, "target", NULL, target) ||
        !vector_attr(p, n, "up", y_up, up))
        return false;
    d3_sub(target, origin, dir);
    double len = d3_length(dir);
    if (!(len > 0))
        return mts_fail(p, n, "<lookat>: origin and target are the same point");
    for (int a = 0; a < 3; a++)
        dir[a] /= len;
    d3_cross(up, dir, left);
    len = d3_length(left);
    if (!(len > 1e-12))
        return mts_fail(p, n, "<lookat>: up is parallel to the view direction");
    for (int a = 0; a < 3; a++)
        left[a] /= len;
    d3_cross(dir, left, new_up);
    sg_transform_identity(m);
    for (int r = 0; r < 3; r++) {
        m->m[r][0] = left[r];
        m->m[r][1] = new_up[r];
        m->m[r][2] = dir[r];
        m->m[r][3] = origin[r];
    }
    return true;
}

/* One step of a <transform>: the matrix it applies. */
static bool transform_step(MtsParser *p, const XmlNode *n, SgTransform *m)
{
    sg_transform_identity(m);
    if (mts_is_tag(n, "translate")) {
        double t[3];
        if (!xyz(p, n, 0, t))
            return false;
        for (int a = 0; a < 3; a++)
            m->m[a][3] = t[a];
        return true;
    }
    if (mts_is_tag(n, "scale")) {
        double s[3];
        if (!xyz(p, n, 1, s))
            return false;
        for (int a = 0; a < 3; a++)
            m->m[a][a] = s[a];
        return true;
    }
    if (mts_is_tag(n, "rotate")) {
        double axis[3], angle = 0;
        const char *a = mts_attr(p, n, "angle");
        if (!xyz(p, n, 0, axis))
            return false;
        if (a && !parse_double(a, &angle))
            return mts_fail(p, n, "<rotate angle=\"%.40s\">: not a number", a);
        if (!sg_transform_rotation(m, angle, axis))
            return mts_fail(p, n, "<rotate> needs a non-zero axis");
        return true;
    }
    if (mts_is_tag(n, "matrix")) {
        const char *v = mts_attr(p, n, "value");
        double values[16];
        size_t count;
        if (!v)
            return p->err->failed ? false : mts_fail(p, n, "<matrix> without a value");
        if (!mts_numbers(p, n, v, values, 16, &count))
            return false;
        if (count == 16) {
            for (int r = 0; r < 4; r++)
                for (int c = 0; c < 4; c++)
                    m->m[r][c] = values[4 * r + c];
        } else if (count == 9) {
            for (int r = 0; r < 3; r++)
                for (int c = 0; c < 3; c++)
                    m->m[r][c] = values[3 * r + c];
        } else {
            return mts_fail(p, n, "<matrix> wants 16 (or 9) numbers, row by row");
        }
        return true;
    }
    if (mts_is_tag(n, "lookat"))
        return lookat(p, n, m);
    return mts_fail(p, n, "<%s> is not a transform step (translate, rotate, scale, matrix, lookat)", n->tag);
}

bool mts_transform(MtsParser *p, const XmlNode *obj, const char *name, SgTransform *out, bool *present)
{
    const XmlNode *n;
    sg_transform_identity(out);
    if (present)
        *present = false;
    if (!mts_find(p, obj, name, &n))
        return false;
    if (!n)
        return true;
    if (mts_is_tag(n, "animation")) { /* motion: where it starts */
        mts_warn(p, n, "animated transforms are taken at their first key");
        const XmlNode *first = NULL;
        for (size_t i = 0; !first && i < n->child_count; i++)
            if (mts_is_tag(n->children[i], "transform"))
                first = n->children[i];
        if (!first)
            return mts_fail(p, n, "<animation> without a <transform>");
        n = first;
    }
    if (!mts_is_tag(n, "transform"))
        return mts_fail(p, n, "\"%s\" must be a <transform>", name);
    if (present)
        *present = true;
    /* each step applies after the ones before it */
    for (size_t i = 0; i < n->child_count; i++) {
        SgTransform step;
        if (!transform_step(p, n->children[i], &step))
            return false;
        sg_transform_multiply(&step, out, out);
    }
    return true;
}

/* ---- colours and spectra ------------------------------------------------ */

/* CIE 1931 matching functions by the multi-lobe Gaussian fit of Wyman,
 * Sloan and Shirley (JCGT 2013): within a few percent of the tables, which
 * is closer than an RGB rendering of a spectrum needs. */
static double lobe(double x, double mu, double s1, double s2)
{
    double t = (x - mu) / (x < mu ? s1 : s2);
    return exp(-0.5 * t * t);
}

static void cie_xyz(double lambda, double xyz_out[3])
{
    xyz_out[0] = 1.056 * lobe(lambda, 599.8, 37.9, 31.0) + 0.362 * lobe(lambda, 442.0, 16.0, 26.7) -
                 0.065 * lobe(lambda, 501.1, 20.4, 26.2);
    xyz_out[1] = 0.821 * lobe(lambda, 568.8, 46.9, 40.5) + 0.286 * lobe(lambda, 530.9, 16.3, 31.1);
    xyz_out[2] = 1.217 * lobe(lambda, 437.0, 11.8, 36.0) + 0.681 * lobe(lambda, 459.0, 26.0, 13.8);
}

static void xyz_to_linear_srgb(const double xyz[3], double rgb[3])
{
    rgb[0] = 3.2404542 * xyz[0] - 1.5371385 * xyz[1] - 0.4985314 * xyz[2];
    rgb[1] = -0.9692660 * xyz[0] + 1.8760108 * xyz[1] + 0.0415560 * xyz[2];
    rgb[2] = 0.0556434 * xyz[0] - 0.2040259 * xyz[1] + 1.0572252 * xyz[2];
}

/* A sampled spectrum (wavelengths ascending, 0 outside them, as Mitsuba's
 * irregular spectrum) to linear sRGB, each channel divided by what a
 * constant 1 gives: a flat spectrum is grey of its value. */
static void spectrum_to_rgb(const double *lambda, const double *value, size_t n, float out[3])
{
    double sum[3] = {0, 0, 0}, white[3] = {0, 0, 0};
    for (double l = 360; l <= 830; l += 1) {
        double v = 0;
        if (n == 1) {
            v = value[0];
        } else if (l >= lambda[0] && l <= lambda[n - 1]) {
            size_t k = 0;
            while (k + 2 < n && l > lambda[k + 1])
                k++;
            double span = lambda[k + 1] - lambda[k];
            double t = span > 0 ? (l - lambda[k]) / span : 0;
            v = value[k] + t * (value[k + 1] - value[k]);
        }
        double xyz[3], rgb[3], rgb_white[3];
        cie_xyz(l, xyz);
        xyz_to_linear_srgb(xyz, rgb_white);
        for (int c = 0; c < 3; c++) {
            rgb[c] = rgb_white[c] * v;
            sum[c] += rgb[c];
            white[c] += rgb_white[c];
        }
    }
    for (int c = 0; c < 3; c++)
        out[c] = (float)fmax(sum[c] / white[c], 0.0);
}

#define MAX_SPECTRUM_SAMPLES 1024

bool mts_spectrum_text(MtsParser *p, const XmlNode *at, const char *text, float out[3])
{
    if (!strchr(text, ':')) {
        double v;
        if (!parse_double(text, &v))
            return mts_fail(p, at, "spectrum \"%.40s\" is neither a number nor wavelength:value pairs", text);
        out[0] = out[1] = out[2] = (float)v;
        return true;
    }
    double *lambda = malloc(2 * MAX_SPECTRUM_SAMPLES * sizeof(double));
    if (!lambda)
        return sg_fail(p->err, "%s: out of memory", p->core.path);
    double *value = lambda + MAX_SPECTRUM_SAMPLES;
    size_t n = 0;
    const char *s = text;
    bool ok = true;
    while (ok) {
        while (isspace((unsigned char)*s) || *s == ',')
            s++;
        if (!*s)
            break;
        char *end;
        double l = strtod(s, &end);
        if (end == s || *end != ':' || n == MAX_SPECTRUM_SAMPLES) {
            ok = mts_fail(p, at, "spectrum: \"%.40s\" is not wavelength:value pairs (at most %d)", text,
                          MAX_SPECTRUM_SAMPLES);
            break;
        }
        s = end + 1;
        double v = strtod(s, &end);
        if (end == s || !isfinite(l) || !isfinite(v) || (n && l <= lambda[n - 1])) {
            ok = mts_fail(p, at, "spectrum: \"%.40s\": want ascending wavelengths with a value each", text);
            break;
        }
        lambda[n] = l;
        value[n++] = v;
        s = end;
    }
    if (ok && n == 0)
        ok = mts_fail(p, at, "spectrum without values");
    if (ok)
        spectrum_to_rgb(lambda, value, n, out);
    free(lambda);
    return ok;
}

static float srgb_to_linear(double v)
{
    return (float)(v <= 0.04045 ? v / 12.92 : pow((v + 0.055) / 1.055, 2.4));
}

/* "#rrggbb" to 0..1 values; false if it is not one. */
static bool hex_color(const char *s, double out[3])
{
    unsigned r, g, b;
    if (s[0] != '#' || strlen(s) != 7 || sscanf(s + 1, "%2x%2x%2x", &r, &g, &b) != 3)
        return false;
    out[0] = r / 255.0;
    out[1] = g / 255.0;
    out[2] = b / 255.0;
    return true;
}

/* Planck's law, relative: the colour of a black body, luminance 1. */
static void blackbody_rgb(double kelvin, float out[3])
{
    double lambda[471], value[471];
    for (int i = 0; i < 471; i++) {
        double l = (360 + i) * 1e-9;
        lambda[i] = 360 + i;
        value[i] = 1.0 / (pow(l, 5) * (exp(1.4387769e-2 / (l * kelvin)) - 1));
    }
    spectrum_to_rgb(lambda, value, 471, out);
    double y = sg_luminance(out[0], out[1], out[2]);
    for (int c = 0; c < 3; c++)
        out[c] = y > 0 ? (float)(out[c] / y) : 1.0f;
}

bool mts_color_of(MtsParser *p, const XmlNode *n, float out[3])
{
    const char *v = mts_attr(p, n, "value");
    if (p->err->failed)
        return false;
    if (mts_is_tag(n, "blackbody")) {
        const char *t = mts_attr(p, n, "temperature");
        double kelvin, scale = 1;
        const char *s = mts_attr(p, n, "scale");
        if (!t || !parse_double(t, &kelvin) || !(kelvin > 0) || (s && !parse_double(s, &scale)))
            return mts_fail(p, n, "<blackbody> needs a positive temperature");
        mts_warn(p, n, "blackbody spectra are taken as their colour at luminance \"scale\", not in absolute units");
        blackbody_rgb(kelvin, out);
        for (int c = 0; c < 3; c++)
            out[c] = (float)(out[c] * scale);
        return true;
    }
    if (!v) {
        if (mts_is_tag(n, "spectrum") && sg_xml_attr(n, "filename"))
            return mts_fail(p, n, "spectra from files (\"filename\") are not supported");
        return mts_fail(p, n, "<%s> has no value", n->tag);
    }
    if (mts_is_tag(n, "spectrum"))
        return mts_spectrum_text(p, n, v, out);
    double c[3];
    size_t count = 0;
    bool hex = hex_color(v, c);
    if (!hex && !mts_numbers(p, n, v, c, 3, &count))
        return false;
    if (!hex && count == 1)
        c[1] = c[2] = c[0];
    else if (!hex && count != 3)
        return mts_fail(p, n, "<%s> wants 1 or 3 numbers", n->tag);
    if (mts_is_tag(n, "float") || mts_is_tag(n, "integer")) {
        if (count != 1)
            return mts_fail(p, n, "<float> holds one number");
    } else if (!mts_is_tag(n, "rgb") && !mts_is_tag(n, "srgb") && !mts_is_tag(n, "color")) {
        return mts_fail(p, n, "<%s> is not a colour", n->tag);
    }
    bool encoded = mts_is_tag(n, "srgb") || hex;
    for (int a = 0; a < 3; a++)
        out[a] = encoded ? srgb_to_linear(c[a]) : (float)c[a];
    return true;
}

/* ---- files -------------------------------------------------------------- */

void mts_resolve(MtsParser *p, const XmlNode *at, const char *name, char *out, size_t size)
{
    if (name[0] == '/') {
        snprintf(out, size, "%s", name);
        return;
    }
    char dir[4096];
    sg_folder_of(at->doc->path, dir, sizeof dir);
    snprintf(out, size, "%s%s", dir, name);
    if (access(out, F_OK) == 0)
        return;
    char candidate[8192];
    snprintf(candidate, sizeof candidate, "%s%s", p->base_dir, name);
    if (access(candidate, F_OK) == 0) {
        snprintf(out, size, "%s", candidate);
        return;
    }
    for (size_t i = 0; i < p->search_dir_count; i++) {
        snprintf(candidate, sizeof candidate, "%s/%s", p->search_dirs[i], name);
        if (access(candidate, F_OK) == 0) {
            snprintf(out, size, "%s", candidate);
            return;
        }
    }
}
