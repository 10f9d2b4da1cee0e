/* The importance cache as a renderer's guide, set up as bin/render does:
 * refused when built for other geometry or another light count, its node
 * table unpacked, each light followed in proportion to its power but never
 * one that cannot reach the camera (the paper's litmus test). For
 * bin/render and the benchmarks that render as it does. */
#ifndef SG_RENDER_IMPORTANCE_FILE_H
#define SG_RENDER_IMPORTANCE_FILE_H

#include <stdbool.h>
#include <stdint.h>

#include "error.h"
#include "importance_cache.h"
#include "../renderer.h"
#include "scene.h"

typedef struct SgImportanceFile {
    SgImportanceCache *cache;
    double *follow;   /* per light: its weight in the choice of the light to follow */
    uint32_t dropped; /* lights that cannot reach the camera */
} SgImportanceFile;

/* Opens the cache at `path` for `scene` (read from scene_path, for the
 * errors) and fills `guide`, which points into g until sg_importance_file_close. */
bool sg_importance_file_open(SgImportanceFile *g, const char *path, const SgScene *scene, const char *scene_path,
                         SgImportanceSource *guide, SgError *err);
void sg_importance_file_close(SgImportanceFile *g);

#endif
