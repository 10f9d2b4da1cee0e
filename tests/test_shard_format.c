/* The shard format's pass rule (common/shard_format.h): the shards of a
 * render hold its passes once each, and a shard's passes are the ones its
 * count says. */
#include <criterion/criterion.h>
#include <stdlib.h>

#include "shard_format.h"

Test(shard_format, the_shards_hold_every_pass_of_the_render_once)
{
    for (int count = 1; count <= 9; count++)
        for (int total = 0; total <= 40; total++) {
            int *owner = calloc((size_t)total + 1, sizeof *owner);
            int held = 0;
            for (int k = 0; k < count; k++) {
                int passes = sg_shard_pass_count(k, count, total);
                cr_assert(passes >= total / count && passes <= total / count + 1, "shard %d of %d: %d of %d passes", k,
                          count, passes, total);
                for (int p = 0; p < passes; p++) {
                    uint64_t whole = sg_shard_pass(k, count, (uint64_t)p);
                    cr_assert_lt(whole, (uint64_t)total, "shard %d of %d: its pass %d is pass %llu of %d", k, count,
                                 p, (unsigned long long)whole, total);
                    cr_assert_eq(owner[whole], 0, "pass %llu of %d is held twice (shards %d and %d of %d)",
                                 (unsigned long long)whole, total, owner[whole] - 1, k, count);
                    owner[whole] = k + 1;
                }
                /* the next pass of the shard is past the render */
                cr_assert_geq(sg_shard_pass(k, count, (uint64_t)passes), (uint64_t)total);
                held += passes;
            }
            cr_assert_eq(held, total, "%d shards hold %d passes of %d", count, held, total);
            free(owner);
        }
}

Test(shard_format, one_shard_is_the_whole_render)
{
    for (uint64_t p = 0; p < 100; p++)
        cr_assert_eq(sg_shard_pass(0, 1, p), p);
    cr_assert_eq(sg_shard_pass_count(0, 1, 77), 77);
    /* shard 2 of 4 of a 10-pass render: passes 2 and 6 */
    cr_assert_eq(sg_shard_pass_count(2, 4, 10), 2);
    cr_assert_eq(sg_shard_pass(2, 4, 1), 6);
    /* the largest render: no overflow in the whole render's pass index */
    cr_assert_eq(sg_shard_pass(SG_SHARDS_MAX - 1, SG_SHARDS_MAX, (uint64_t)1 << 31),
                 (uint64_t)(SG_SHARDS_MAX - 1) + ((uint64_t)1 << 31) * SG_SHARDS_MAX);
}

Test(shard_format, valid_shards)
{
    cr_assert(sg_shard_valid(0, 1));
    cr_assert(sg_shard_valid(3, 4));
    cr_assert(sg_shard_valid(SG_SHARDS_MAX - 1, SG_SHARDS_MAX));
    cr_assert_not(sg_shard_valid(4, 4));
    cr_assert_not(sg_shard_valid(-1, 4));
    cr_assert_not(sg_shard_valid(0, 0));
    cr_assert_not(sg_shard_valid(0, SG_SHARDS_MAX + 1L));
}
