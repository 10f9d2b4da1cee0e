/* Scene files in JSON (README.md, "Scene format"); sg_scene_load
 * dispatches here for every file that is not pbrt. */
#ifndef SG_SCENE_JSON_H
#define SG_SCENE_JSON_H

#include "error.h"
#include "scene.h"

/* Malformed input fails with "file: cause" (JSON syntax: "near line N"). */
SgScene *sg_json_scene_load(const char *path, SgError *err);

#endif
