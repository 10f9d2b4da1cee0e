/* The windows of a scene lit from outside, found in its precompute: where
 * the medium (the air light reaches) crosses the faces of the scene's
 * bounding box into the margin of outside air voxelize adds. Each 4-connected
 * patch of such crossings on a face becomes a portal (its bounding rectangle
 * on the face, grown by a voxel each way), through which next-event estimation looks at the sky. */
#ifndef SG_RENDER_OPENINGS_H
#define SG_RENDER_OPENINGS_H

#include <stdbool.h>
#include <stdint.h>

#include "importance_cache.h"
#include "vecmath.h"

/* At most this many portals, the largest kept. */
#define OPENINGS_MAX 64

/* The openings of the medium the cache was built on, as rectangles (four
 * corners each, round the window) in local coordinates (world minus
 * `centre`), for a scene whose triangles span [bounds_min, bounds_max]
 * (world). *corners is allocated (free it); *count 0: none found (no
 * margin, or a cache too large to have been unpacked). False: out of memory. */
bool openings_find(const SgImportanceCache *cache, const double bounds_min[3], const double bounds_max[3],
                   const double centre[3], Vec3 (**corners)[4], uint32_t *count);

#endif
