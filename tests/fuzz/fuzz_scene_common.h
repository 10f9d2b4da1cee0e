/* Shared by the scene fuzz targets: write the bytes to a file with the
 * front end's extension, load it, and check that what the loader hands out
 * is consistent, or that a refusal says why in one line. */
#ifndef SG_FUZZ_SCENE_COMMON_H
#define SG_FUZZ_SCENE_COMMON_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "scene_load.h"

static inline int sg_fuzz_scene_bytes(const uint8_t *data, size_t size, const char *extension)
{
    char path[64];
    snprintf(path, sizeof path, "/tmp/sg-fuzz-scene-%ld.%s", (long)getpid(), extension);
    FILE *f = fopen(path, "wb");
    if (!f)
        return 0;
    fwrite(data, 1, size, f);
    fclose(f);
    SgError err = {0};
    SgScene *scene = sg_scene_load(path, &err);
    if (scene) {
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
        for (uint32_t i = 0; i < scene->warning_count; i++)
            if (strchr(scene->warnings[i], '\n'))
                abort();
        sg_scene_free(scene);
    } else if (!err.failed || strchr(err.message, '\n')) {
        abort(); /* a refusal must say why, on one line */
    }
    unlink(path);
    return 0;
}

#endif
