/* Scene loading by file type: a .pbrt file to the pbrt-v4 reader
 * (pbrt_scene.h), a .xml file to the Mitsuba reader
 * (mitsuba/mitsuba_scene.h), anything else to the JSON reader (scene_json.h).
 * All three fill the flat world-space arrays through scene_builder.h. */
#include "scene_load.h"

#include "input_file.h"
#include "mitsuba/mitsuba_scene.h"
#include "pbrt_scene.h"
#include "scene_json.h"

SgScene *sg_scene_load(const char *path, SgError *err)
{
    if (sg_has_extension(path, ".pbrt") || sg_has_extension(path, ".pbrt.gz"))
        return sg_pbrt_scene_load(path, err);
    if (sg_has_extension(path, ".xml"))
        return sg_mitsuba_scene_load(path, err);
    return sg_json_scene_load(path, err);
}
