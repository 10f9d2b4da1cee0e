/* The disjoint sets of common/union_find.h against a brute-force labelling:
 * after random unions every element's root is the smallest index of its
 * component, and sg_set_union says whether it joined two sets. */
#include <criterion/criterion.h>
#include <stdlib.h>

#include "rng.h"
#include "union_find.h"

#define N 2000

/* label[i] = smallest index connected to i by the edges so far (brute force). */
static void relabel(uint32_t *label, uint32_t a, uint32_t b)
{
    uint32_t from = label[a] > label[b] ? label[a] : label[b], to = label[a] < label[b] ? label[a] : label[b];
    for (uint32_t i = 0; i < N; i++)
        if (label[i] == from)
            label[i] = to;
}

Test(union_find, roots_are_the_smallest_index_of_each_component)
{
    uint32_t *parent = malloc(N * sizeof *parent), *label = malloc(N * sizeof *label);
    for (uint32_t i = 0; i < N; i++)
        parent[i] = label[i] = i;
    SgRng rng;
    sg_rng_seed(&rng, 7, 1);
    uint32_t sets = N;
    for (int e = 0; e < 1500; e++) {
        uint32_t a = sg_rng_next(&rng) % N, b = sg_rng_next(&rng) % N;
        bool joined = label[a] != label[b];
        cr_assert_eq(sg_set_union(parent, a, b), joined, "edge %d (%u, %u)", e, a, b);
        if (joined) {
            relabel(label, a, b);
            sets--;
        }
        if (e % 100 == 0)
            for (uint32_t i = 0; i < N; i++)
                cr_assert_eq(sg_set_find(parent, i), label[i], "after %d edges, %u", e, i);
    }
    uint32_t roots = 0;
    for (uint32_t i = 0; i < N; i++) {
        cr_assert_eq(sg_set_find(parent, i), label[i]);
        roots += sg_set_find(parent, i) == i;
    }
    cr_assert_eq(roots, sets);
    cr_assert(sets > 1 && sets < N - 1000, "the random graph should be partly joined: %u sets", sets);
    free(parent);
    free(label);
}

Test(union_find, a_chain_is_found_from_either_end)
{
    uint32_t parent[64];
    for (uint32_t i = 0; i < 64; i++)
        parent[i] = i;
    for (uint32_t i = 63; i > 0; i--) /* each union hangs the larger root under the smaller */
        cr_assert(sg_set_union(parent, i, i - 1));
    for (uint32_t i = 0; i < 64; i++)
        cr_assert_eq(sg_set_find(parent, i), 0);
    cr_assert_not(sg_set_union(parent, 5, 60));
}
