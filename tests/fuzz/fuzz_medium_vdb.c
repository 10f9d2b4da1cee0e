/* libFuzzer target: the medium reader (OpenVDB file + our metadata) must
 * refuse or accept any bytes without crashing. */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

#include "medium.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char path[64];
    snprintf(path, sizeof path, "/tmp/sg-fuzz-medium-%ld.vdb", (long)getpid());
    FILE *f = fopen(path, "wb");
    if (!f)
        return 0;
    fwrite(data, 1, size, f);
    fclose(f);
    SgMedium medium;
    SgError err = {0};
    if (sg_medium_read(&medium, path, &err)) {
        const SgGrid *g = &medium.grid;
        if (g->nx <= 0 || g->ny <= 0 || g->nz <= 0 || !(g->voxel_size > 0))
            abort();
        sg_medium_release(&medium);
    } else if (!err.failed) {
        abort();
    }
    unlink(path);
    return 0;
}
