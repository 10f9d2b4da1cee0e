/* pbrt scene files, parameter lists: the "type name" [values] pairs after a
 * statement, checked against their type, and the lookups by name. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "pbrt_parser.h"

static const char *const known_types[] = {
    "integer", "float", "point2", "vector2", "point3", "vector3", "normal", "normal3", "point",
    "vector", "color", "rgb", "spectrum", "blackbody", "bool", "string", "texture",
};

static bool numeric_type(const char *type)
{
    return strcmp(type, "bool") && strcmp(type, "string") && strcmp(type, "texture") &&
           strcmp(type, "spectrum");
}

static bool add_value(Parser *p, Param *param, const Token *v)
{
    bool is_bool = !v->quoted && (pbrt_token_is(v, "true") || pbrt_token_is(v, "false"));
    if (!strcmp(param->type, "bool")) {
        if (!(is_bool || (v->quoted && (pbrt_string_is(v, "true") || pbrt_string_is(v, "false")))))
            return pbrt_fail_at(p, v, "\"bool %s\": expected true or false", param->name);
        if (!RESERVE(p, p->bools, p->bool_count, p->bool_capacity, 1))
            return false;
        if (param->count == 0)
            param->first = p->bool_count;
        p->bools[p->bool_count++] = v->s[0] == 't';
        param->kind = PARAM_BOOLS;
        param->count++;
        return true;
    }
    if (v->quoted) {
        if (numeric_type(param->type))
            return pbrt_fail_at(p, v, "\"%s %s\": expected numbers, found a string", param->type,
                                param->name);
        if (param->count && param->kind != PARAM_STRINGS)
            return pbrt_fail_at(p, v, "\"%s %s\": mixes numbers and strings", param->type,
                                param->name);
        if (!RESERVE(p, p->strings, p->string_count, p->string_capacity, 1))
            return false;
        if (param->count == 0)
            param->first = p->string_count;
        p->strings[p->string_count++] = *v;
        param->kind = PARAM_STRINGS;
        param->count++;
        return true;
    }
    double x;
    if (!pbrt_token_number(v, &x)) {
        if (pbrt_token_is(v, "["))
            return pbrt_fail_at(p, v, "\"%s %s\": '[' inside '[ ]'", param->type, param->name);
        return pbrt_fail_at(p, v, "\"%s %s\": expected a value, found %.*s", param->type,
                            param->name, (int)(v->len > 40 ? 40 : v->len), v->s);
    }
    if (!strcmp(param->type, "string") || !strcmp(param->type, "texture"))
        return pbrt_fail_at(p, v, "\"%s %s\": expected a quoted string, found a number",
                            param->type, param->name);
    if (param->count && param->kind != PARAM_NUMBERS)
        return pbrt_fail_at(p, v, "\"%s %s\": mixes numbers and strings", param->type, param->name);
    if (!strcmp(param->type, "integer") && x != floor(x))
        return pbrt_fail_at(p, v, "\"integer %s\": %.*s is not a whole number", param->name,
                            (int)v->len, v->s);
    if (!RESERVE(p, p->numbers, p->number_count, p->number_capacity, 1))
        return false;
    if (param->count == 0)
        param->first = p->number_count;
    p->numbers[p->number_count++] = x;
    param->kind = PARAM_NUMBERS;
    param->count++;
    return true;
}

/* "type name" with a known type. */
static bool looks_like_declaration(const Token *t)
{
    for (size_t i = 0; i < sizeof known_types / sizeof known_types[0]; i++) {
        size_t n = strlen(known_types[i]);
        if (t->len > n + 1 && !memcmp(t->s, known_types[i], n) && t->s[n] == ' ')
            return true;
    }
    return false;
}

/* Reads "type name" value-or-[values] pairs until the next statement. */
bool pbrt_parse_params(Parser *p)
{
    p->param_count = p->number_count = p->string_count = p->bool_count = 0;
    for (;;) {
        Token decl;
        if (!pbrt_next_token(p, &decl))
            return !p->err->failed;
        if (!decl.quoted) {
            if (pbrt_token_is(&decl, "["))
                return pbrt_fail_at(p, &decl, "'[' without a parameter name before it");
            if (pbrt_token_is(&decl, "]"))
                return pbrt_fail_at(p, &decl, "']' without a matching '['");
            pbrt_unget_token(p, &decl);
            return true;
        }
        /* "type name": split at blanks */
        char text[256];
        if (decl.len >= sizeof text)
            return pbrt_fail_at(p, &decl, "parameter declaration too long");
        memcpy(text, decl.s, decl.len);
        text[decl.len] = 0;
        char type[64], name[128], extra[8];
        int fields = sscanf(text, "%63s %127s %7s", type, name, extra);
        if (fields != 2)
            return pbrt_fail_at(p, &decl, "\"%s\" is not a parameter declaration (\"type name\")",
                                text);
        if (!strcmp(type, "point"))
            strcpy(type, "point3");
        else if (!strcmp(type, "vector"))
            strcpy(type, "vector3");
        else if (!strcmp(type, "normal"))
            strcpy(type, "normal3");
        else if (!strcmp(type, "color"))
            strcpy(type, "rgb");
        bool known = false;
        for (size_t i = 0; i < sizeof known_types / sizeof known_types[0]; i++)
            known |= !strcmp(type, known_types[i]);
        if (!known)
            return pbrt_fail_at(p, &decl, "unknown parameter type \"%s\" in \"%s\"", type, text);
        if (!RESERVE(p, p->params, p->param_count, p->param_capacity, 1))
            return false;
        Param *param = &p->params[p->param_count++];
        memset(param, 0, sizeof *param);
        snprintf(param->type, sizeof param->type, "%.15s", type); /* a known type: short */
        snprintf(param->name, sizeof param->name, "%s", name);
        param->line = decl.line;
        param->source = decl.source;
        param->kind = numeric_type(type) ? PARAM_NUMBERS : PARAM_STRINGS;
        Token v;
        if (!pbrt_need_token(p, &decl, &v))
            return false;
        if (pbrt_token_is(&v, "[")) {
            Token open = v;
            for (;;) {
                if (!pbrt_next_token(p, &v)) {
                    if (!p->err->failed)
                        pbrt_fail_at(p, &open, "'[' is never closed by ']'");
                    return false;
                }
                if (pbrt_token_is(&v, "]"))
                    break;
                /* A statement name or a parameter declaration: the list ran on. */
                if ((!v.quoted && v.len && v.s[0] >= 'A' && v.s[0] <= 'Z') ||
                    (v.quoted && looks_like_declaration(&v)))
                    return pbrt_fail_at(p, &open,
                                        "'[' is not closed by ']' before \"%.*s\" (line %d)",
                                        (int)(v.len > 40 ? 40 : v.len), v.s, v.line);
                if (!add_value(p, param, &v))
                    return false;
            }
        } else if (pbrt_token_is(&v, "]")) {
            return pbrt_fail_at(p, &v, "']' without a matching '['");
        } else if (!add_value(p, param, &v)) {
            return false;
        }
    }
}

const Param *pbrt_find_param(const Parser *p, const char *name)
{
    for (size_t i = p->param_count; i-- > 0;)
        if (!strcmp(p->params[i].name, name))
            return &p->params[i];
    return NULL;
}

Token pbrt_param_token(const Param *param)
{
    Token t = {0};
    t.line = param->line;
    t.source = param->source;
    return t;
}

/* The parameter `name` when given with a value of `kind`; NULL when absent
 * (*ok true) or of another kind or empty (*ok false: "must be <what>"). */
static const Param *single_param(Parser *p, const char *name, ParamKind kind, const char *what, bool *ok)
{
    const Param *param = pbrt_find_param(p, name);
    *ok = true;
    if (!param)
        return NULL;
    Token at = pbrt_param_token(param);
    if (param->kind != kind || param->count < 1) {
        *ok = pbrt_fail_at(p, &at, "\"%s %s\" must be %s", param->type, name, what);
        return NULL;
    }
    return param;
}

bool pbrt_param_float(Parser *p, const char *name, double fallback, double *out)
{
    bool ok;
    const Param *param = single_param(p, name, PARAM_NUMBERS, "a number", &ok);
    *out = param ? p->numbers[param->first] : fallback;
    return ok;
}

bool pbrt_param_bool(Parser *p, const char *name, bool fallback, bool *out)
{
    bool ok;
    const Param *param = single_param(p, name, PARAM_BOOLS, "true or false", &ok);
    *out = param ? p->bools[param->first] : fallback;
    return ok;
}

/* A string parameter; NULL if absent. */
const Token *pbrt_param_string(Parser *p, const char *name)
{
    const Param *param = pbrt_find_param(p, name);
    if (!param || param->kind != PARAM_STRINGS || param->count < 1)
        return NULL;
    return &p->strings[param->first];
}
