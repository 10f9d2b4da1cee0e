/* Scene files in JSON (docs/scene-format.md, "JSON scenes"); sg_scene_load
 * dispatches here for every file that is neither pbrt nor Mitsuba XML. */
#ifndef SG_SCENE_JSON_H
#define SG_SCENE_JSON_H

#include "error.h"
#include "scene.h"

/* Malformed input fails with "file: cause" (JSON syntax: "near line N"). */
SgScene *sg_json_scene_load(const char *path, SgError *err);

#endif
