/* The guard against hostile .vdb files (common/vdb_read_guard.h) is in
 * effect in a program that reads media: its operator new and OpenVDB's
 * checked chunk readers are the ones the process uses. An OpenVDB upgrade
 * (other mangled names) or a static link would drop them silently; this
 * fails loudly instead. (test_fuzz_regressions feeds it the files it
 * refuses.) */
#include <criterion/criterion.h>

#include "vdb_read_guard.h"

Test(vdb_read_guard, both_interpositions_are_in_effect)
{
    SgError err = {0};
    cr_assert(sg_vdb_read_guard_check(&err), "%s", err.message);
}

Test(vdb_read_guard, the_cap_is_per_read_and_restored)
{
    size_t previous = sg_vdb_read_cap_set(12345);
    cr_assert_eq(sg_vdb_read_cap_set(previous), 12345);
    cr_assert_eq(sg_vdb_read_cap_set(previous), previous);
}
