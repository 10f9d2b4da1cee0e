#include "pbrt_scene.h"
SgScene *sg_pbrt_scene_load(const char *path, SgError *err)
{
    sg_fail(err, "%s: not yet", path);
    return 0;
}
