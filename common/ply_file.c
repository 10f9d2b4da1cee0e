#include "ply_file.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A header line split into words. Words past what a line needs are
 * ignored. Each word is cut at SG_PLY_NAME_CAP - 1 characters: a cut
 * keyword, type or format matches nothing and a cut name matches no name a
 * reader looks for, but a cut number would read as another, so an element
 * count refuses it. */
enum { MAX_WORDS = 5 };
typedef struct Line {
    int count; /* all words, also those past MAX_WORDS */
    bool cut[MAX_WORDS];
    char word[MAX_WORDS][SG_PLY_NAME_CAP];
} Line;

/* Splits the line at data[*pos] and moves *pos past its '\n'; false when
 * the data end before a '\n' or hold a NUL (a header is text). */
static bool next_line(const unsigned char *data, size_t size, size_t *pos, Line *line)
{
    line->count = 0;
    size_t length = 0; /* of the current word; 0 between words */
    for (size_t i = *pos; i < size; i++) {
        unsigned char c = data[i];
        if (c == '\n') {
            *pos = i + 1;
            return true;
        }
        if (c == 0)
            return false;
        if (c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f') {
            length = 0;
            continue;
        }
        if (length == 0 && ++line->count <= MAX_WORDS) {
            line->word[line->count - 1][0] = 0;
            line->cut[line->count - 1] = false;
        }
        if (line->count <= MAX_WORDS) {
            char *w = line->word[line->count - 1];
            if (length + 1 < SG_PLY_NAME_CAP) {
                w[length] = (char)c;
                w[length + 1] = 0;
            } else {
                line->cut[line->count - 1] = true;
            }
        }
        length++;
    }
    return false;
}

static bool parse_format(SgPlyHeader *h, const Line *l, bool big_endian, const char *path, SgError *err)
{
    if (l->count < 3 || strcmp(l->word[2], "1.0") != 0)
        return sg_fail(err, "%s: malformed PLY format line", path);
    if (!strcmp(l->word[1], "ascii"))
        h->format = SG_PLY_ASCII;
    else if (!strcmp(l->word[1], "binary_little_endian"))
        h->format = SG_PLY_BINARY_LE;
    else if (big_endian && !strcmp(l->word[1], "binary_big_endian"))
        h->format = SG_PLY_BINARY_BE;
    else
        return sg_fail(err, "%s: unsupported PLY format '%s' (ascii%s binary_little_endian%s expected)",
                       path, l->word[1], big_endian ? "," : " or",
                       big_endian ? " or binary_big_endian" : "");
    return true;
}

static bool parse_element(SgPlyHeader *h, const Line *l, const char *path, SgError *err)
{
    if (l->count < 3)
        return sg_fail(err, "%s: malformed PLY element line", path);
    if (h->element_count >= SG_PLY_MAX_ELEMENTS)
        return sg_fail(err, "%s: too many PLY elements", path);
    const char *name = l->word[1], *count = l->word[2];
    char *end;
    errno = 0;
    unsigned long long n = strtoull(count, &end, 10);
    if (*end || count[0] == '-' || errno || n > UINT32_MAX || l->cut[2])
        return sg_fail(err, "%s: bad count '%s' for element %s", path, count, name);
    SgPlyElement *e = &h->elements[h->element_count++];
    memset(e, 0, sizeof *e);
    memcpy(e->name, name, strlen(name) + 1);
    e->count = n;
    return true;
}

static bool parse_property(SgPlyHeader *h, const Line *l, const char *path, SgError *err)
{
    if (h->element_count == 0)
        return sg_fail(err, "%s: PLY property before any element", path);
    SgPlyElement *e = &h->elements[h->element_count - 1];
    if (e->property_count >= SG_PLY_MAX_PROPERTIES)
        return sg_fail(err, "%s: too many properties in element %s", path, e->name);
    SgPlyProperty *p = &e->properties[e->property_count++];
    memset(p, 0, sizeof *p);
    const char *name;
    int words; /* that the line needs */
    if (l->count >= 2 && !strcmp(l->word[1], "list")) {
        /* the length of a list is a whole number */
        p->count_type = l->count >= 3 ? sg_ply_type_parse(l->word[2]) : SG_PLY_NONE;
        if (p->count_type == SG_PLY_NONE || sg_ply_type_is_float(p->count_type))
            return sg_fail(err, "%s: bad list count type in element %s", path, e->name);
        p->type = l->count >= 4 ? sg_ply_type_parse(l->word[3]) : SG_PLY_NONE;
        name = l->word[4];
        words = 5;
    } else {
        p->type = l->count >= 2 ? sg_ply_type_parse(l->word[1]) : SG_PLY_NONE;
        name = l->word[2];
        words = 3;
    }
    if (p->type == SG_PLY_NONE || l->count < words)
        return sg_fail(err, "%s: malformed property line in element %s", path, e->name);
    memcpy(p->name, name, strlen(name) + 1);
    return true;
}

bool sg_ply_header_parse(SgPlyHeader *h, const void *bytes, size_t size, bool big_endian, const char *path,
                         SgError *err)
{
    memset(h, 0, sizeof *h);
    const unsigned char *data = bytes;
    /* the magic line exactly, as a mistaken text file rarely starts */
    size_t pos = size >= 4 && !memcmp(data, "ply\n", 4)                    ? 4
                 : size >= 5 && !memcmp(data, "ply\r\n", 5)                ? 5
                                                                           : 0;
    if (pos == 0)
        return sg_fail(err, "%s: not a PLY file (no 'ply' magic line)", path);
    bool have_format = false;
    Line l;
    for (;;) {
        if (!next_line(data, size, &pos, &l))
            return sg_fail(err, "%s: PLY header is truncated or malformed (no end_header)", path);
        const char *key = l.word[0];
        if (l.count == 0 || !strcmp(key, "comment") || !strcmp(key, "obj_info"))
            continue;
        bool ok = true;
        if (!strcmp(key, "end_header")) {
            /* the data start right after this line, whatever their first byte */
            break;
        } else if (!strcmp(key, "format")) {
            ok = parse_format(h, &l, big_endian, path, err);
            have_format = true;
        } else if (!strcmp(key, "element")) {
            ok = parse_element(h, &l, path, err);
        } else if (!strcmp(key, "property")) {
            ok = parse_property(h, &l, path, err);
        } else {
            return sg_fail(err, "%s: unknown PLY header keyword '%s'", path, key);
        }
        if (!ok)
            return false;
    }
    if (!have_format)
        return sg_fail(err, "%s: PLY header has no format line", path);
    h->data_start = pos;
    return true;
}

SgPlyToken sg_ply_read_token(const unsigned char *data, size_t size, size_t *pos, char *token, size_t cap)
{
    size_t i = *pos;
    while (i < size && (data[i] == ' ' || data[i] == '\t' || data[i] == '\n' || data[i] == '\r'))
        i++;
    *pos = i;
    if (i >= size)
        return SG_PLY_TOKEN_END;
    size_t n = 0;
    while (i < size && data[i] > ' ') {
        if (n + 1 >= cap)
            return SG_PLY_TOKEN_BAD;
        token[n++] = (char)data[i++];
    }
    token[n] = 0;
    *pos = i;
    return n > 0 ? SG_PLY_TOKEN_OK : SG_PLY_TOKEN_BAD;
}

bool sg_ply_write_begin(SgOutputFile *out, const char *path, const char *comment, SgError *err)
{
    if (!sg_output_open(out, path, err))
        return false;
    fprintf(out->file, "ply\nformat binary_little_endian 1.0\ncomment %s\n", comment);
    return true;
}
