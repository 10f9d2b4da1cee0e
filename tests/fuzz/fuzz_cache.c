/* libFuzzer target: the importance.cache reader must refuse or accept any
 * bytes without reading out of bounds, and lookups in an accepted file stay
 * in bounds (built by `make fuzz`). A first input byte with bit 0 set asks
 * the target to repair the checksum first, so that the fuzzer also reaches
 * the structural checks behind it. */
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "hash.h"
#include "importance_cache.h"
#include "importance_cache_format.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1)
        return 0;
    bool fix = data[0] & 1;
    data++;
    size--;
    /* Exact size (rounded to the alignment the reader asks for). */
    uint8_t *copy = aligned_alloc(16, (size + 16) & ~(size_t)15);
    if (!copy)
        return 0;
    memcpy(copy, data, size);
    if (fix && size >= sizeof(SgCacheHeader)) {
        SgCacheHeader h;
        memcpy(&h, copy, sizeof h);
        h.checksum = 0;
        memcpy(copy, &h, sizeof h);
        h.checksum = sg_hash_bytes(SG_HASH_INIT, copy, size);
        memcpy(copy, &h, sizeof h);
    }
    SgError err = {0};
    SgImportanceCache *c = sg_cache_open_memory(copy, size, "fuzz.cache", &err);
    if (c) {
        int dims[3];
        double origin[3], h = sg_cache_voxel_size(c);
        sg_cache_grid(c, dims, origin);
        for (int i = 0; i < 64; i++) {
            double p[3] = {origin[0] + h * (dims[0] * (i % 4) / 3.0),
                           origin[1] + h * (dims[1] * ((i / 4) % 4) / 3.0),
                           origin[2] + h * (dims[2] * (i / 16) / 3.0)};
            double q[3];
            uint32_t n;
            for (uint32_t k = 0; k < sg_cache_light_count(c) && k < 4; k++) {
                sg_cache_importance_point(c, p, k, q);
                sg_cache_light_reaches(c, k, p);
            }
            if (sg_cache_nearest_node(c, p, &n) && n >= sg_cache_node_count(c))
                abort();
        }
        /* the unpacked table (and its walls' octants) answers as the blocks */
        bool found[64];
        uint32_t node[64];
        double at[64][3];
        for (int i = 0; i < 64; i++) {
            for (int a = 0; a < 3; a++) /* points in and around the grid, off the voxel centres */
                at[i][a] = origin[a] + h * (dims[a] + 2.0) * (((i * 37 + a * 11) % 64) / 63.0) - h * 0.93;
            found[i] = sg_cache_nearest_node(c, at[i], &node[i]);
        }
        if (sg_cache_decode(c, 64u << 20))
            for (int i = 0; i < 64; i++) {
                uint32_t n = SG_CACHE_NONE;
                if (sg_cache_nearest_node(c, at[i], &n) != found[i] || (found[i] && n != node[i]))
                    abort();
            }
        sg_cache_close(c);
    }
    free(copy);
    return 0;
}
