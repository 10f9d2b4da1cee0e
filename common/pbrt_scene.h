/* pbrt-v4 scene files (.pbrt): the subset that shared research scenes use
 * (docs/scene-format.md, "pbrt-v4 scenes"). sg_scene_load (scene_load.c)
 * dispatches here on the ".pbrt" and ".pbrt.gz" extensions. */
#ifndef SG_PBRT_SCENE_H
#define SG_PBRT_SCENE_H

#include "error.h"
#include "scene.h"

/* Loads a pbrt-v4 file. Malformed input fails with "file:line: cause";
 * what is understood but not supported becomes a scene warning. */
SgScene *sg_pbrt_scene_load(const char *path, SgError *err);

#endif
