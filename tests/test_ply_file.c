/* The PLY header walk and value readers shared by the mesh and skeleton
 * readers (common/ply_file.h): what a header declares, where the data
 * start, each malformed header refused with its message, every truncation
 * refused without a read past the end, and ascii tokens and binary values
 * read to the byte. */
#include <criterion/criterion.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ply_file.h"

/* Parses an exact-size copy of text[0..size), so that ASan sees any read past it. */
static bool parse(SgPlyHeader *h, const char *text, size_t size, bool big_endian, SgError *err)
{
    char *copy = malloc(size ? size : 1);
    memcpy(copy, text, size);
    bool ok = sg_ply_header_parse(h, copy, size, big_endian, "t.ply", err);
    free(copy);
    return ok;
}

static SgPlyHeader *header_of(const char *text, size_t size, bool big_endian)
{
    SgPlyHeader *h = malloc(sizeof *h);
    SgError err = {0};
    cr_assert(parse(h, text, size, big_endian, &err), "%s", err.message);
    return h;
}

Test(ply_file, a_header_declares_elements_properties_and_where_the_data_start)
{
    /* CRLF lines, tabs, a blank line, comments, both spellings of types, a
     * word past what a line needs, and a first data byte that is '\n' (the
     * one Assimp 5.2 skips). */
    const char text[] = "ply\r\n"
                        "format binary_big_endian 1.0\r\n"
                        "comment element fake 3\r\n"
                        "obj_info end_header\r\n"
                        "\r\n"
                        "element vertex 3\r\n"
                        "property\tfloat32 x\r\n"
                        "property double y ignored\r\n"
                        "element face 4294967295\r\n"
                        "  property list uint8 int vertex_indices\r\n"
                        "element empty 0\r\n"
                        "end_header\r\n"
                        "\n\x01\x02";
    SgPlyHeader *h = header_of(text, sizeof text - 1, true);
    cr_assert_eq(h->format, SG_PLY_BINARY_BE);
    cr_assert_eq(h->data_start, sizeof text - 1 - 3, "data start at %zu", h->data_start);
    cr_assert_eq(h->element_count, 3);
    const SgPlyElement *v = &h->elements[0], *f = &h->elements[1], *e = &h->elements[2];
    cr_assert_str_eq(v->name, "vertex");
    cr_assert_eq(v->count, 3);
    cr_assert_eq(v->property_count, 2);
    cr_assert_str_eq(v->properties[0].name, "x");
    cr_assert_eq(v->properties[0].type, SG_PLY_F32);
    cr_assert_eq(v->properties[0].count_type, SG_PLY_NONE);
    cr_assert_str_eq(v->properties[1].name, "y");
    cr_assert_eq(v->properties[1].type, SG_PLY_F64);
    cr_assert_str_eq(f->name, "face");
    cr_assert_eq(f->count, 4294967295u);
    cr_assert_eq(f->property_count, 1);
    cr_assert_str_eq(f->properties[0].name, "vertex_indices");
    cr_assert_eq(f->properties[0].count_type, SG_PLY_U8);
    cr_assert_eq(f->properties[0].type, SG_PLY_I32);
    cr_assert_str_eq(e->name, "empty");
    cr_assert_eq(e->count, 0);
    cr_assert_eq(e->property_count, 0);
    free(h);

    h = header_of("ply\nformat ascii 1.0\nend_header\n", 32, false);
    cr_assert_eq(h->format, SG_PLY_ASCII);
    cr_assert_eq(h->data_start, 32);
    cr_assert_eq(h->element_count, 0);
    free(h);
}

Test(ply_file, long_names_are_cut_and_long_counts_refused)
{
    char text[512];
    snprintf(text, sizeof text, "ply\nformat binary_little_endian 1.0\nelement %0100d 1\nproperty uchar %0100d\nend_header\n", 7, 8);
    SgPlyHeader *h = header_of(text, strlen(text), false);
    cr_assert_eq(h->format, SG_PLY_BINARY_LE);
    cr_assert_eq(strlen(h->elements[0].name), SG_PLY_NAME_CAP - 1);
    cr_assert_eq(strlen(h->elements[0].properties[0].name), SG_PLY_NAME_CAP - 1);
    free(h);
    /* cut to 63 zeros, the count would read as 0 */
    snprintf(text, sizeof text, "ply\nformat ascii 1.0\nelement v %0100d\nend_header\n", 5);
    SgPlyHeader hh;
    SgError err = {0};
    cr_assert_not(parse(&hh, text, strlen(text), false, &err));
    cr_assert(strstr(err.message, "bad count"), "%s", err.message);
}

static void expect_refused(const char *text, bool big_endian, const char *message)
{
    SgPlyHeader *h = malloc(sizeof *h);
    SgError err = {0};
    cr_assert_not(parse(h, text, strlen(text), big_endian, &err), "accepted: %s", text);
    cr_assert_str_eq(err.message, message, "for: %s", text);
    free(h);
}

#define FMT "ply\nformat ascii 1.0\n"

Test(ply_file, malformed_headers_are_refused_with_what_is_wrong)
{
    expect_refused("", true, "t.ply: not a PLY file (no 'ply' magic line)");
    expect_refused("ply \nformat ascii 1.0\nend_header\n", true, "t.ply: not a PLY file (no 'ply' magic line)");
    expect_refused("PLY\nformat ascii 1.0\nend_header\n", true, "t.ply: not a PLY file (no 'ply' magic line)");
    expect_refused(FMT "element v 1\n", true, "t.ply: PLY header is truncated or malformed (no end_header)");
    expect_refused(FMT "comment a\0b\nend_header\n", true, "t.ply: PLY header is truncated or malformed (no end_header)");
    expect_refused(FMT "end_header", true, "t.ply: PLY header is truncated or malformed (no end_header)");
    expect_refused("ply\nend_header\n", true, "t.ply: PLY header has no format line");
    expect_refused("ply\nformat ascii\nend_header\n", true, "t.ply: malformed PLY format line");
    expect_refused("ply\nformat ascii 2.0\nend_header\n", true, "t.ply: malformed PLY format line");
    expect_refused("ply\nformat text 1.0\nend_header\n", true,
                   "t.ply: unsupported PLY format 'text' (ascii, binary_little_endian or binary_big_endian expected)");
    expect_refused("ply\nformat binary_big_endian 1.0\nend_header\n", false,
                   "t.ply: unsupported PLY format 'binary_big_endian' (ascii or binary_little_endian expected)");
    expect_refused(FMT "element v\nend_header\n", true, "t.ply: malformed PLY element line");
    expect_refused(FMT "element v -1\nend_header\n", true, "t.ply: bad count '-1' for element v");
    expect_refused(FMT "element v 4294967296\nend_header\n", true, "t.ply: bad count '4294967296' for element v");
    expect_refused(FMT "element v 12x\nend_header\n", true, "t.ply: bad count '12x' for element v");
    expect_refused(FMT "property float x\nend_header\n", true, "t.ply: PLY property before any element");
    expect_refused(FMT "element v 1\nproperty int64 x\nend_header\n", true,
                   "t.ply: malformed property line in element v");
    expect_refused(FMT "element v 1\nproperty float\nend_header\n", true,
                   "t.ply: malformed property line in element v");
    expect_refused(FMT "element v 1\nproperty list float int x\nend_header\n", true,
                   "t.ply: bad list count type in element v");
    expect_refused(FMT "element v 1\nproperty list uchar\nend_header\n", true,
                   "t.ply: malformed property line in element v");
    expect_refused(FMT "element v 1\nproperty list uchar int\nend_header\n", true,
                   "t.ply: malformed property line in element v");
    expect_refused(FMT "elements v 1\nend_header\n", true, "t.ply: unknown PLY header keyword 'elements'");

    char text[4096] = FMT;
    for (int e = 0; e < SG_PLY_MAX_ELEMENTS + 1; e++)
        strcat(text, "element e 1\n");
    strcat(text, "end_header\n");
    expect_refused(text, true, "t.ply: too many PLY elements");
    strcpy(text, FMT "element e 1\n");
    for (int p = 0; p < SG_PLY_MAX_PROPERTIES + 1; p++)
        strcat(text, "property int p\n");
    strcat(text, "end_header\n");
    expect_refused(text, true, "t.ply: too many properties in element e");
}

Test(ply_file, every_truncation_of_a_header_is_refused)
{
    const char text[] = "ply\nformat binary_little_endian 1.0\ncomment c\nelement vertex 2\nproperty float x\n"
                        "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
    SgPlyHeader *h = malloc(sizeof *h);
    for (size_t n = 0; n < sizeof text - 1; n++) {
        SgError err = {0};
        cr_assert_not(parse(h, text, n, true, &err), "prefix %zu", n);
        cr_assert(strncmp(err.message, "t.ply: ", 7) == 0, "%s", err.message);
    }
    SgError err = {0};
    cr_assert(parse(h, text, sizeof text - 1, true, &err), "%s", err.message);
    cr_assert_eq(h->data_start, sizeof text - 1);
    free(h);
}

Test(ply_file, ascii_tokens)
{
    const unsigned char data[] = " \t-1.5e3\r\n42 \n  \x0b" "7 x";
    size_t pos = 0;
    char token[8];
    cr_assert_eq(sg_ply_read_token(data, 11, &pos, token, sizeof token), SG_PLY_TOKEN_OK);
    cr_assert_str_eq(token, "-1.5e3");
    cr_assert_eq(pos, 8);
    cr_assert_eq(sg_ply_read_token(data, 11, &pos, token, sizeof token), SG_PLY_TOKEN_OK);
    cr_assert_str_eq(token, "4", "the data end after its first digit");
    cr_assert_eq(sg_ply_read_token(data, 11, &pos, token, sizeof token), SG_PLY_TOKEN_END);
    pos = 8;
    cr_assert_eq(sg_ply_read_token(data, sizeof data - 1, &pos, token, sizeof token), SG_PLY_TOKEN_OK);
    cr_assert_str_eq(token, "42");
    /* a vertical tab is not a separator: no number may start with it */
    cr_assert_eq(sg_ply_read_token(data, sizeof data - 1, &pos, token, sizeof token), SG_PLY_TOKEN_BAD);
    const unsigned char blanks[] = " \n\r\t ";
    pos = 0;
    cr_assert_eq(sg_ply_read_token(blanks, sizeof blanks - 1, &pos, token, sizeof token), SG_PLY_TOKEN_END);
    const unsigned char longer[] = "1234567 12345678";
    pos = 0;
    cr_assert_eq(sg_ply_read_token(longer, sizeof longer - 1, &pos, token, sizeof token), SG_PLY_TOKEN_OK);
    cr_assert_str_eq(token, "1234567");
    cr_assert_eq(sg_ply_read_token(longer, sizeof longer - 1, &pos, token, sizeof token), SG_PLY_TOKEN_BAD,
                 "8 characters do not fit 8 bytes with the NUL");
}

Test(ply_file, binary_values_in_either_byte_order)
{
    const unsigned char le[] = {0x01, 0x02, 0x00, 0x00, 0x80, 0x3f, 0xff};
    size_t pos = 0;
    double v;
    cr_assert(sg_ply_read_binary(le, sizeof le, &pos, SG_PLY_I16, false, &v));
    cr_assert_eq(v, 0x0201);
    cr_assert(sg_ply_read_binary(le, sizeof le, &pos, SG_PLY_F32, false, &v));
    cr_assert_eq(v, 1.0);
    cr_assert_eq(pos, 6);
    cr_assert_not(sg_ply_read_binary(le, sizeof le, &pos, SG_PLY_U16, false, &v), "one byte left");
    cr_assert_eq(pos, 6);
    cr_assert(sg_ply_read_binary(le, sizeof le, &pos, SG_PLY_I8, false, &v));
    cr_assert_eq(v, -1);
    pos = 0;
    cr_assert(sg_ply_read_binary(le, sizeof le, &pos, SG_PLY_U16, true, &v));
    cr_assert_eq(v, 0x0102);
}
