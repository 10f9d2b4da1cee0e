/* The PLY scalar types shared by the mesh and skeleton readers: every name,
 * every size, and each type decoded from known bytes in both byte orders. */
#include <criterion/criterion.h>

#include "ply_types.h"

Test(ply_types, names_and_sizes)
{
    const char *names[] = {"char", "int8", "uchar", "uint8", "short", "int16", "ushort", "uint16",
                           "int", "int32", "uint", "uint32", "float", "float32", "double", "float64"};
    const size_t sizes[] = {1, 1, 1, 1, 2, 2, 2, 2, 4, 4, 4, 4, 4, 4, 8, 8};
    for (int i = 0; i < 16; i++) {
        SgPlyType t = sg_ply_type_parse(names[i]);
        cr_assert_neq(t, SG_PLY_NONE, "%s", names[i]);
        cr_assert_eq(sg_ply_type_size(t), sizes[i], "%s", names[i]);
        cr_assert_eq(sg_ply_type_is_float(t), i >= 12, "%s", names[i]);
    }
    cr_assert_eq(sg_ply_type_parse("int64"), SG_PLY_NONE);
    cr_assert_eq(sg_ply_type_parse("Float"), SG_PLY_NONE);
    cr_assert_eq(sg_ply_type_size(SG_PLY_NONE), 0);
    /* the name in messages is the first spelling, and reads back as its type */
    for (SgPlyType t = SG_PLY_I8; t <= SG_PLY_F64; t++)
        cr_assert_eq(sg_ply_type_parse(sg_ply_type_name(t)), t, "%s", sg_ply_type_name(t));
    cr_assert_str_eq(sg_ply_type_name(SG_PLY_U8), "uchar");
    cr_assert_str_eq(sg_ply_type_name(SG_PLY_F64), "double");
    cr_assert_str_eq(sg_ply_type_name(SG_PLY_NONE), "none");
}

Test(ply_types, decodes_both_byte_orders)
{
    struct {
        SgPlyType t;
        unsigned char le[8];
        double want;
    } cases[] = {
        {SG_PLY_I8, {0xfe}, -2},
        {SG_PLY_U8, {0xfe}, 254},
        {SG_PLY_I16, {0x18, 0xfc}, -1000},
        {SG_PLY_U16, {0x18, 0xfc}, 64536},
        {SG_PLY_I32, {0x00, 0x94, 0x35, 0x77}, 2000000000},
        {SG_PLY_I32, {0xff, 0xff, 0xff, 0xff}, -1},
        {SG_PLY_U32, {0xff, 0xff, 0xff, 0xff}, 4294967295.0},
        {SG_PLY_F32, {0x00, 0x00, 0xc0, 0x3f}, 1.5},
        {SG_PLY_F64, {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x04, 0xc0}, -2.5},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        size_t n = sg_ply_type_size(cases[k].t);
        unsigned char be[8];
        for (size_t i = 0; i < n; i++)
            be[i] = cases[k].le[n - 1 - i];
        double le_value = 0, be_value = 0;
        cr_assert(sg_ply_decode(cases[k].le, cases[k].t, false, &le_value));
        cr_assert(sg_ply_decode(be, cases[k].t, true, &be_value));
        cr_assert_eq(le_value, cases[k].want, "case %zu little-endian: %g", k, le_value);
        cr_assert_eq(be_value, cases[k].want, "case %zu big-endian: %g", k, be_value);
    }
    double v;
    unsigned char zero[8] = {0};
    cr_assert_not(sg_ply_decode(zero, SG_PLY_NONE, false, &v));
}
