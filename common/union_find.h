/* Disjoint sets over indices 0..n-1 in a caller's array, parent[i] = i to
 * start. Union hangs the larger root under the smaller, so a set's root is
 * always its smallest index: its name does not depend on the order of the
 * unions, and callers may key, sort or keep sets by it deterministically.
 * Finding halves the path as it goes. */
#ifndef SG_UNION_FIND_H
#define SG_UNION_FIND_H

#include <stdbool.h>
#include <stdint.h>

static inline uint32_t sg_set_find(uint32_t *parent, uint32_t x)
{
    while (parent[x] != x) {
        parent[x] = parent[parent[x]];
        x = parent[x];
    }
    return x;
}

/* Joins the sets of a and b; false when they were one already. */
static inline bool sg_set_union(uint32_t *parent, uint32_t a, uint32_t b)
{
    a = sg_set_find(parent, a);
    b = sg_set_find(parent, b);
    if (a == b)
        return false;
    if (a < b)
        parent[b] = a;
    else
        parent[a] = b;
    return true;
}

#endif
