/* libFuzzer target: the skeleton.ply reader must refuse or accept any bytes
 * without reading out of bounds (built by `make fuzz`). */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "skeleton_graph.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    /* An exact-size copy, so that ASan sees any read past the end. */
    uint8_t *copy = malloc(size ? size : 1);
    if (!copy)
        return 0;
    memcpy(copy, data, size);
    SgSkeleton skeleton;
    SgError err = {0};
    if (sg_skeleton_parse_ply(&skeleton, copy, size, "fuzz.ply", &err)) {
        for (uint32_t e = 0; e < skeleton.edge_count; e++)
            if (skeleton.edges[e][0] >= skeleton.node_count ||
                skeleton.edges[e][1] >= skeleton.node_count)
                abort();
        sg_skeleton_release(&skeleton);
    }
    free(copy);
    return 0;
}
