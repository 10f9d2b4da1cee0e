/* Scene loading by file type: the one door every program opens a scene
 * description through. It picks the reader from the file name and hands
 * back the data model of scene.h. */
#ifndef SG_SCENE_LOAD_H
#define SG_SCENE_LOAD_H

#include "error.h"
#include "scene.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Loads a scene description: a pbrt-v4 file when the name ends in ".pbrt"
 * or ".pbrt.gz", a Mitsuba file when it ends in ".xml", else a JSON file.
 * On failure returns NULL with "file: cause" (pbrt and Mitsuba:
 * "file:line: cause"). */
SgScene *sg_scene_load(const char *path, SgError *err);

#ifdef __cplusplus
}
#endif
#endif
