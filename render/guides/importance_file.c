#include "importance_file.h"

#include <inttypes.h>
#include <stdlib.h>

static bool cache_importance_point(void *ctx, const double p[3], uint32_t light, double point[3])
{
    return sg_cache_importance_point(ctx, p, light, point);
}

bool sg_importance_file_open(SgImportanceFile *g, const char *path, const SgScene *scene, const char *scene_path,
                         SgImportanceSource *guide, SgError *err)
{
    *g = (SgImportanceFile){0};
    g->cache = sg_cache_open(path, err);
    if (!g->cache)
        return false;
    if (sg_cache_geometry_hash(g->cache) != scene->geometry_hash) {
        sg_fail(err,
                "%s: built for other geometry (hash %016" PRIx64 ", %s has %016" PRIx64
                "): rebuild it with bin/importance",
                path, sg_cache_geometry_hash(g->cache), scene_path, scene->geometry_hash);
        goto fail;
    }
    uint32_t lights = sg_scene_guide_light_count(scene);
    if (sg_cache_light_count(g->cache) != lights) {
        sg_fail(err, "%s: has %u lights, %s has %u: rebuild it with bin/importance", path,
                sg_cache_light_count(g->cache), scene_path, lights);
        goto fail;
    }
    g->follow = calloc(lights ? lights : 1, sizeof *g->follow);
    if (!g->follow) {
        sg_fail(err, "%s: out of memory", scene_path);
        goto fail;
    }
    /* The litmus test needs the camera inside the voxel grid: one outside
     * the scene's box (in front of an open box, say) cannot be tested,
     * so every light is followed. Inside the box but outside the medium,
     * the camera is in air no light reaches: nothing is followed. */
    int dims[3];
    double origin[3], h = sg_cache_voxel_size(g->cache);
    sg_cache_grid(g->cache, dims, origin);
    bool testable = true;
    for (int a = 0; a < 3; a++)
        if (!(scene->camera.position[a] >= origin[a] && scene->camera.position[a] <= origin[a] + dims[a] * h))
            testable = false;
    for (uint32_t l = 0; l < lights; l++) {
        if (!testable || sg_cache_light_reaches(g->cache, l, scene->camera.position))
            g->follow[l] = sg_scene_guide_light(scene, l).power;
        else
            g->dropped++;
    }
    guide->importance_point = cache_importance_point;
    guide->ctx = g->cache;
    guide->cache = g->cache;
    /* the node table unpacked: one read a query (Sponza: 1.8 MB; beyond
     * 256 MB the packed blocks answer) */
    sg_cache_decode(g->cache, 256u << 20);
    guide->light_weight = g->follow;
    /* 1.5 voxels: a wall on a voxel boundary makes both voxels beside it solid */
    guide->query_offset = 1.5 * h;
    return true;
fail:
    sg_importance_file_close(g);
    return false;
}

void sg_importance_file_close(SgImportanceFile *g)
{
    free(g->follow);
    if (g->cache)
        sg_cache_close(g->cache);
    *g = (SgImportanceFile){0};
}
