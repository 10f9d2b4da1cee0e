#include "importance_lookup.h"

#include <stdlib.h>
#include <string.h>

bool importance_lookup_init(ImportanceLookup *g, const SgImportanceSource *source, const double centre[3], float scale,
                         const LightSet *lights, const char *path, SgError *err)
{
    *g = (ImportanceLookup){.source = *source, .min_length = 1e-6f * scale, .lights = lights};
    memcpy(g->centre, centre, sizeof g->centre);
    const SgImportanceCache *c = source->cache;
    if (!c)
        return true;
    uint32_t nodes = sg_cache_node_count(c), n_lights = sg_cache_light_count(c);
    if (n_lights != lights->follow_count)
        return sg_fail(err, "%s: the importance cache has %u lights, the scene %u", path, n_lights,
                       lights->follow_count);
    uint32_t lights_n = n_lights;
    double floats = 3.0 * nodes * lights_n;
    if (!nodes || !lights_n || floats * sizeof(float) > 256.0 * 1024 * 1024)
        return true;
    g->points = malloc((size_t)floats * sizeof(float));
    if (!g->points)
        return true;
    int dims[3];
    double origin[3];
    sg_cache_grid(c, dims, origin);
    g->decoded = sg_cache_decoded(c);
    g->octants = sg_cache_decoded_octants(c);
    for (int a = 0; a < 3; a++)
        g->extent[a] = (float)dims[a];
    g->stride[0] = 1;
    g->stride[1] = dims[0];
    g->stride[2] = (int64_t)dims[0] * dims[1];
    double voxel = sg_cache_voxel_size(c);
    g->cache = c;
    g->origin = v3((float)(origin[0] - centre[0]), (float)(origin[1] - centre[1]), (float)(origin[2] - centre[2]));
    g->inv_voxel = (float)(1.0 / voxel);
    g->offset = (float)source->query_offset;
    g->light_count = lights_n;
    for (uint32_t n = 0; n < nodes; n++)
        for (uint32_t l = 0; l < lights_n; l++) {
            double q[3];
            float *out = g->points + 3 * ((size_t)n * lights_n + l);
            bool ok = sg_cache_node_importance_point(c, n, l, q);
            for (int a = 0; a < 3; a++)
                out[a] = ok ? (float)(q[a] - centre[a]) : NAN;
        }
    return true;
}

void importance_lookup_free(ImportanceLookup *g)
{
    free(g->points);
    g->points = NULL;
}
