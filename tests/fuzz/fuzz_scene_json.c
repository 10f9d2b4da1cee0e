/* libFuzzer target: the scene loader (JSON front end, inline geometry,
 * materials, lights, camera) must refuse or accept any bytes cleanly. */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

#include "scene.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char path[64];
    snprintf(path, sizeof path, "/tmp/sg-fuzz-scene-%ld.json", (long)getpid());
    FILE *f = fopen(path, "wb");
    if (!f)
        return 0;
    fwrite(data, 1, size, f);
    fclose(f);
    SgError err = {0};
    SgScene *scene = sg_scene_load(path, &err);
    if (scene) {
        /* What the loader hands out must be consistent. */
        for (uint32_t t = 0; t < scene->triangle_count; t++) {
            for (int c = 0; c < 3; c++)
                if (scene->indices[3 * t + c] >= scene->vertex_count)
                    abort();
            if (scene->triangle_material[t] >= scene->material_count)
                abort();
        }
        for (uint32_t k = 0; k < scene->light_count; k++)
            if (scene->lights[k].first_triangle + scene->lights[k].triangle_count >
                scene->triangle_count)
                abort();
        sg_scene_free(scene);
    } else if (!err.failed) {
        abort(); /* a failure must say why */
    }
    unlink(path);
    return 0;
}
