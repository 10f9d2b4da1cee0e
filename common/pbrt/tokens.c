/* pbrt scene files, tokens: reading the files (Include nests them), the
 * lexer, the need_* readers of what a statement must hold, and the errors
 * ("file:line: cause") and warnings (one per kind) of the whole loader. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "input_file.h"
#include "memory.h"
#include "pbrt_parser.h"

/* Grows *array to hold needed items of size item. */
bool pbrt_reserve(Parser *p, void **array, size_t *capacity, size_t needed, size_t item)
{
    if (!sg_reserve(array, capacity, needed, item, 16))
        return sg_fail(p->err, "%s: out of memory", p->core.path);
    return true;
}

/* "file:line" of a place in the sources, or the main file's path when
 * there is none. */
static void write_place(const Parser *p, const Source *src, int line, char *where, size_t size)
{
    if (src)
        snprintf(where, size, "%s:%d", src->path, line);
    else
        snprintf(where, size, "%s", p->core.path);
}

bool pbrt_fail_at(Parser *p, const Token *t, const char *fmt, ...)
{
    /* without a token's place, the error is where reading stopped */
    bool placed = t && t->source;
    char where[4200]; /* as long as a warning's place */
    write_place(p, placed ? t->source : p->last_source, placed ? t->line : p->last_line, where,
                sizeof where);
    char cause[900];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(cause, sizeof cause, fmt, ap);
    va_end(ap);
    return sg_fail(p->err, "%s: %s", where, cause);
}

void pbrt_warn_at(Parser *p, const Token *t, const char *fmt, ...)
{
    char where[4200];
    write_place(p, t ? t->source : NULL, t ? t->line : 0, where, sizeof where);
    va_list ap;
    va_start(ap, fmt);
    sg_builder_warnv(&p->core, where, fmt, ap);
    va_end(ap);
}

bool pbrt_token_is(const Token *t, const char *word)
{
    size_t n = strlen(word);
    return !t->quoted && t->len == n && !memcmp(t->s, word, n);
}

bool pbrt_string_is(const Token *t, const char *word)
{
    size_t n = strlen(word);
    return t->len == n && !memcmp(t->s, word, n);
}

char *pbrt_token_dup(const Token *t)
{
    char *s = malloc(t->len + 1);
    if (s) {
        memcpy(s, t->s, t->len);
        s[t->len] = 0;
    }
    return s;
}

/* ---- reading files ------------------------------------------------------ */

bool pbrt_push_file(Parser *p, const char *path, const Token *from)
{
    if (p->depth >= MAX_INCLUDE_DEPTH)
        return pbrt_fail_at(p, from,
                            "Include nested more than %d deep (does a file include itself?)",
                            MAX_INCLUDE_DEPTH);
    size_t n = strlen(path);
    if (n > 3 && !strcmp(path + n - 3, ".gz")) {
        if (from)
            return pbrt_fail_at(p, from, "%s: compressed files are not read: gunzip it first",
                                path);
        return sg_fail(p->err, "%s: compressed files are not read: gunzip it first", path);
    }
    char *text;
    size_t size;
    SgError read_err = {0};
    if (!sg_read_file(path, NULL, SG_LIMIT_PBRT_TEXT, &text, &size, &read_err)) {
        if (from)
            return pbrt_fail_at(p, from, "%s", read_err.message);
        return sg_fail(p->err, "%s", read_err.message);
    }
    Source *src = calloc(1, sizeof *src);
    if (!src || !RESERVE(p, p->sources, p->source_count, p->source_capacity, 1)) {
        free(src);
        free(text);
        return sg_fail(p->err, "%s: out of memory", path);
    }
    p->sources[p->source_count++] = src;
    sg_builder_add_source(&p->core, text, size);
    snprintf(src->path, sizeof src->path, "%s", path);
    src->line = 1;
    src->text = text;
    src->size = size;
    if (src->size >= 2 && (((unsigned char)src->text[0] == 0xfe &&
                            (unsigned char)src->text[1] == 0xff) ||
                           ((unsigned char)src->text[0] == 0xff &&
                            (unsigned char)src->text[1] == 0xfe)))
        return sg_fail(p->err, "%s: UTF-16 text is not supported (save it as UTF-8)", path);
    p->stack[p->depth++] = src;
    return true;
}

static bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }

/* Next token of the current file; false at its end (t->s == NULL) or on a
 * lexical error (p->err set). */
static bool lex(Parser *p, Source *src, Token *t)
{
    t->s = NULL;
    for (;;) {
        while (src->pos < src->size && is_space(src->text[src->pos])) {
            if (src->text[src->pos] == '\n')
                src->line++;
            src->pos++;
        }
        if (src->pos >= src->size)
            return false;
        if (src->text[src->pos] != '#')
            break;
        while (src->pos < src->size && src->text[src->pos] != '\n')
            src->pos++;
    }
    char *c = src->text + src->pos;
    t->line = src->line;
    t->source = src;
    t->quoted = false;
    if (*c == '"') {
        char *out = c + 1, *in = c + 1;
        for (;; in++) {
            if (in >= src->text + src->size || *in == '\n') {
                Token at = *t;
                pbrt_fail_at(p, &at, "unterminated string");
                return false;
            }
            if (*in == '"')
                break;
            if (*in == '\\') {
                in++;
                static const char from[] = "bfnrt\\'\"", to[] = "\b\f\n\r\t\\'\"";
                const char *k = *in ? strchr(from, *in) : NULL;
                if (!k) {
                    Token at = *t;
                    pbrt_fail_at(p, &at, "unknown escape \\%c in a string", *in ? *in : ' ');
                    return false;
                }
                *out++ = to[k - from];
            } else {
                *out++ = *in;
            }
        }
        t->s = c + 1;
        t->len = (uint32_t)(out - (c + 1));
        t->quoted = true;
        src->pos = (size_t)(in + 1 - src->text);
        return true;
    }
    if (*c == '[' || *c == ']') {
        t->s = c;
        t->len = 1;
        src->pos++;
        return true;
    }
    char *end = c;
    while (end < src->text + src->size && !is_space(*end) && *end != '"' && *end != '[' &&
           *end != ']' && *end != '#')
        end++;
    t->s = c;
    t->len = (uint32_t)(end - c);
    src->pos = (size_t)(end - src->text);
    return true;
}

/* Next token across included files; false at the very end or on error. */
bool pbrt_next_token(Parser *p, Token *t)
{
    if (p->has_pending) {
        *t = p->pending;
        p->has_pending = false;
        return true;
    }
    while (p->depth > 0) {
        Source *src = p->stack[p->depth - 1];
        if (lex(p, src, t)) {
            p->last_source = src;
            p->last_line = t->line;
            return true;
        }
        if (p->err->failed)
            return false;
        p->last_source = src;
        p->last_line = src->line;
        p->depth--;
    }
    t->s = NULL;
    return false;
}

void pbrt_unget_token(Parser *p, const Token *t)
{
    p->pending = *t;
    p->has_pending = true;
}

/* A token that must be there. */
bool pbrt_need_token(Parser *p, const Token *statement, Token *t)
{
    if (pbrt_next_token(p, t))
        return true;
    if (!p->err->failed)
        pbrt_fail_at(p, NULL, "premature end of file after %.*s", (int)statement->len,
                     statement->s);
    return false;
}

bool pbrt_token_number(const Token *t, double *out)
{
    if (t->quoted || t->len == 0 || t->len > 63)
        return false;
    char buf[64];
    memcpy(buf, t->s, t->len);
    buf[t->len] = 0;
    char *end;
    double v = strtod(buf, &end);
    if (*end || !isfinite(v))
        return false;
    *out = v;
    return true;
}

bool pbrt_need_number(Parser *p, const Token *statement, double *out)
{
    Token t;
    if (!pbrt_need_token(p, statement, &t))
        return false;
    if (!pbrt_token_number(&t, out))
        return pbrt_fail_at(p, &t, "%.*s: expected a number, found \"%.*s\"", (int)statement->len,
                            statement->s, (int)(t.len > 40 ? 40 : t.len), t.s);
    return true;
}

bool pbrt_need_string(Parser *p, const Token *statement, Token *out)
{
    if (!pbrt_need_token(p, statement, out))
        return false;
    if (!out->quoted)
        return pbrt_fail_at(p, out, "%.*s: expected a quoted string, found %.*s",
                            (int)statement->len, statement->s, (int)(out->len > 40 ? 40 : out->len),
                            out->s);
    return true;
}

/* "[ n1 ... nN ]" with exactly n numbers. */
bool pbrt_need_bracketed_numbers(Parser *p, const Token *statement, int n, double *out)
{
    Token open;
    if (!pbrt_need_token(p, statement, &open))
        return false;
    bool bracketed = pbrt_token_is(&open, "[");
    if (!bracketed)
        pbrt_unget_token(p, &open);
    for (int i = 0; i < n; i++)
        if (!pbrt_need_number(p, statement, &out[i]))
            return false;
    if (bracketed) {
        Token close;
        if (!pbrt_need_token(p, statement, &close))
            return false;
        if (!pbrt_token_is(&close, "]"))
            return pbrt_fail_at(p, &open,
                                "%.*s: '[' at line %d is not closed by ']' after %d numbers",
                                (int)statement->len, statement->s, open.line, n);
    }
    return true;
}

bool pbrt_resolve_path(Parser *p, const Token *at, const Token *name, char *out, size_t size)
{
    int n = name->len && name->s[0] == '/'
                ? snprintf(out, size, "%.*s", (int)name->len, name->s)
                : snprintf(out, size, "%s%.*s", p->base_dir, (int)name->len, name->s);
    if (n < 0 || (size_t)n >= size)
        return pbrt_fail_at(p, at, "file name too long");
    return true;
}
