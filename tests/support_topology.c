#include "support_topology.h"

#include <stdlib.h>
#include <string.h>

#include "../skeletonize/complex.h"
#include "union_find.h"

/* Components of the voxels whose value (as "inside") is wanted, over a
 * grid optionally padded by one layer of background, with 6 or 26
 * neighbours; union-find over the half neighbourhood already scanned. */
static bool count_components(const SgGrid *g, bool want_inside, int pad, bool full_26,
                             int64_t *count, SgError *err)
{
    int nx = g->nx + 2 * pad, ny = g->ny + 2 * pad, nz = g->nz + 2 * pad;
    size_t n = (size_t)nx * (size_t)ny * (size_t)nz;
    if (n >= UINT32_MAX)
        return sg_fail(err, "topology: grid too large");
    uint32_t *parent = malloc(n * sizeof *parent);
    if (!parent)
        return sg_fail(err, "topology: out of memory");
    int64_t components = 0;
    size_t i = 0;
    for (int z = 0; z < nz; z++)
        for (int y = 0; y < ny; y++)
            for (int x = 0; x < nx; x++, i++) {
                bool in = sg_grid_get(g, x - pad, y - pad, z - pad) != 0;
                if (in != want_inside) {
                    parent[i] = UINT32_MAX;
                    continue;
                }
                parent[i] = (uint32_t)i;
                components++;
                for (int dz = -1; dz <= 0; dz++)
                    for (int dy = -1; dy <= 1; dy++)
                        for (int dx = -1; dx <= 1; dx++) {
                            if (dz == 0 && (dy > 0 || (dy == 0 && dx >= 0)))
                                continue; /* only neighbours already visited */
                            if (!full_26 && abs(dx) + abs(dy) + abs(dz) != 1)
                                continue;
                            int qx = x + dx, qy = y + dy, qz = z + dz;
                            if (qx < 0 || qy < 0 || qz < 0 || qx >= nx || qy >= ny)
                                continue;
                            size_t j = (size_t)qx + (size_t)nx * ((size_t)qy + (size_t)ny * (size_t)qz);
                            if (parent[j] == UINT32_MAX)
                                continue;
                            if (sg_set_union(parent, (uint32_t)i, (uint32_t)j))
                                components--;
                        }
            }
    free(parent);
    *count = components;
    return true;
}

bool sg_voxel_betti(const SgGrid *g, SgBetti *out, SgError *err)
{
    memset(out, 0, sizeof *out);
    int64_t background = 0;
    if (!count_components(g, true, 0, true, &out->b0, err) ||
        !count_components(g, false, 1, false, &background, err))
        return false;
    out->b2 = background - 1;
    out->chi = sg_complex_euler(g);
    out->b1 = out->b0 + out->b2 - out->chi;
    return true;
}

bool sg_graph_betti(const SgSkeleton *s, SgBetti *out, SgError *err)
{
    memset(out, 0, sizeof *out);
    uint32_t *parent = malloc((s->node_count ? s->node_count : 1) * sizeof *parent);
    if (!parent)
        return sg_fail(err, "topology: out of memory");
    for (uint32_t i = 0; i < s->node_count; i++)
        parent[i] = i;
    int64_t components = s->node_count;
    for (uint32_t e = 0; e < s->edge_count; e++) {
        uint32_t a = s->edges[e][0], b = s->edges[e][1];
        if (a >= s->node_count || b >= s->node_count) {
            free(parent);
            return sg_fail(err, "topology: edge %u has a node index out of range", e);
        }
        if (sg_set_union(parent, a, b))
            components--;
    }
    free(parent);
    out->b0 = components;
    out->b1 = (int64_t)s->edge_count - (int64_t)s->node_count + components;
    out->chi = (int64_t)s->node_count - (int64_t)s->edge_count;
    return true;
}
