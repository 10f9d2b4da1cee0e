/* Mitsuba scene files (.xml): Mitsuba 3's dialect and the 0.5/0.6 one
 * (told apart by the scene's version), mapped onto the scene builder as the
 * pbrt-v4 reader is (docs/scene-format.md). sg_scene_load (scene.c)
 * dispatches here on the ".xml" extension. */
#ifndef SG_MITSUBA_SCENE_H
#define SG_MITSUBA_SCENE_H

#include "error.h"
#include "scene.h"

/* Loads a Mitsuba XML file. Malformed or meaningless input (no light, a
 * missing mesh, an unknown reference, a cyclic include) fails with
 * "file:line: cause"; what is understood but not supported becomes one
 * scene warning per kind. */
SgScene *sg_mitsuba_scene_load(const char *path, SgError *err);

#endif
