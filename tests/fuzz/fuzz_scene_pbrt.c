/* libFuzzer target: the pbrt-v4 front end of the scene loader (tokenizer,
 * parameter lists, transforms, materials, lights, instancing) must refuse
 * or accept any bytes cleanly, with a one-line message when it refuses. */
#include "fuzz_scene_common.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return sg_fuzz_scene_bytes(data, size, "pbrt");
}
