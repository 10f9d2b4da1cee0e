/* Reader of importance.cache, the file that step 3 writes and render maps
 * with mmap and uses in place (layout: docs/cache-format.md). The file is
 * validated once when opened (size, offsets, checksum, version); lookups
 * after that are constant time and never read outside the mapping. */
#ifndef SG_IMPORTANCE_CACHE_H
#define SG_IMPORTANCE_CACHE_H

#include <stdbool.h>
#include <stdint.h>

#include "error.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct SgImportanceCache SgImportanceCache;

SgImportanceCache *sg_cache_open(const char *path, SgError *err);
void sg_cache_close(SgImportanceCache *cache);

/* Identity of the scene geometry the cache was built for (SgScene.geometry_hash):
 * render refuses a cache whose hash differs from its scene's. */
uint64_t sg_cache_geometry_hash(const SgImportanceCache *cache);
uint32_t sg_cache_light_count(const SgImportanceCache *cache);
uint32_t sg_cache_node_count(const SgImportanceCache *cache);

/* The importance point of the skeleton node nearest (geodesically) to the
 * world position p, for light `light`. False when p is outside the medium,
 * or the light cannot be reached from p's part of the skeleton. */
bool sg_cache_importance_point(const SgImportanceCache *cache, const double p[3],
                               uint32_t light, double point[3]);

/* Litmus test (paper 3.3): can light `light` reach the world position p
 * (the camera, typically) through the medium? */
bool sg_cache_light_reaches(const SgImportanceCache *cache, uint32_t light, const double p[3]);

#ifdef __cplusplus
}
#endif
#endif
