/* libFuzzer target: the scene loader's JSON front end (inline geometry,
 * materials, lights, camera) must refuse or accept any bytes cleanly. */
#include "fuzz_scene_common.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return sg_fuzz_scene_bytes(data, size, "json");
}
