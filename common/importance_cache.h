/* Reader of importance.cache, the file that step 3 writes and render maps
 * with mmap and uses in place (layout: docs/cache-format.md). The file is
 * validated once when opened (size, offsets, checksum, version); lookups
 * after that are constant time and never read outside the mapping. */
#ifndef SG_IMPORTANCE_CACHE_H
#define SG_IMPORTANCE_CACHE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "error.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct SgImportanceCache SgImportanceCache;

/* No node (a voxel that is not medium, in sg_cache_decoded and the file),
 * no block, no component: one value, on disk too. */
#define SG_CACHE_NONE 0xffffffffu
#define SG_CACHE_WALL_BIT 0x80000000u /* marks a wall's entry in sg_cache_decoded */
#define SG_CACHE_MIXED_BIT 0x40000000u /* ... whose octants have their own nodes */
#define SG_CACHE_MIXED_INDEX 0x3fffffffu /* ... at 8 times this part (sg_cache_decoded_octants) */

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

/* ---- additions (step 3 helper) ----------------------------------------
 * Lookups by position accept points in a medium voxel and, because surface
 * points lie in solid voxels under conservative voxelization, points in a
 * non-medium voxel next to the medium: the adjacent medium voxel whose
 * centre is nearest to p is used. Points further from the medium fail. For
 * thin walls, query at p offset by about one voxel (sg_cache_voxel_size)
 * along the normal facing the incoming ray. */

/* Validates bytes in memory (16-byte aligned, kept alive by the caller
 * until sg_cache_close); `name` names them in messages. For tests, fuzzing. */
SgImportanceCache *sg_cache_open_memory(const void *data, size_t size, const char *name,
                                        SgError *err);

/* Unpacks the nearest-node table into memory (4 bytes a voxel), unless
 * that would take more than max_bytes: lookups then read one word instead
 * of a packed block (for render's hot loop). False: not unpacked (too
 * large, or no memory); lookups still work, from the packed blocks. */
bool sg_cache_decode(SgImportanceCache *cache, uint64_t max_bytes);

/* Nearest skeleton node (geodesic) of the voxel at p. */
bool sg_cache_nearest_node(const SgImportanceCache *cache, const double p[3], uint32_t *node);
/* The same for a point given in voxel units, v = (p - origin) / voxel_size
 * (sg_cache_grid): for callers that keep their own frame (render's hot loop). */
bool sg_cache_nearest_node_voxel(const SgImportanceCache *cache, const float v[3], uint32_t *node);
/* The unpacked table (sg_cache_decode; NULL before), entry of voxel
 * (i, j, k) at i + nx (j + ny k): its node where the voxel is medium. Where
 * it is a wall (a surface point's voxel), SG_CACHE_WALL_BIT and:
 * - node, if all its medium neighbours have that node (the answer for any
 *   point in it);
 * - else SG_CACHE_MIXED_BIT and an index e (the entry's SG_CACHE_MIXED_INDEX
 *   bits): a point of the voxel in octant o (bit a set where its coordinate
 *   a is at least the voxel's centre) has node octants[8 e + o];
 * where that is SG_CACHE_NONE, or the entry is, no one node answers for
 * the whole octant: sg_cache_nearest_node_voxel then searches the
 * neighbours. For a hot loop that reads it inline (and prefetches). */
const uint32_t *sg_cache_decoded(const SgImportanceCache *cache);
const uint32_t *sg_cache_decoded_octants(const SgImportanceCache *cache);
/* The node an entry of that table gives a point in octant `octant` of its
 * voxel; SG_CACHE_NONE: search the neighbours. */
static inline uint32_t sg_cache_entry_node(uint32_t entry, const uint32_t *octants, unsigned octant)
{
    if (!(entry & SG_CACHE_WALL_BIT) || entry == SG_CACHE_NONE)
        return entry; /* medium, or no node */
    if (entry & SG_CACHE_MIXED_BIT)
        return octants[8 * (size_t)(entry & SG_CACHE_MIXED_INDEX) + octant];
    return entry & ~SG_CACHE_WALL_BIT; /* a wall whose neighbours agree */
}
/* Importance point of a node for a light; false if the light cannot reach it. */
bool sg_cache_node_importance_point(const SgImportanceCache *cache, uint32_t node,
                                    uint32_t light, double point[3]);
/* The light has a place on the skeleton (false: sealed off, reaches nothing). */
bool sg_cache_light_has_paths(const SgImportanceCache *cache, uint32_t light);

uint64_t sg_cache_skeleton_hash(const SgImportanceCache *cache);
/* The file's checksum (FNV-1a 64 of its bytes, verified on open): its identity. */
uint64_t sg_cache_checksum(const SgImportanceCache *cache);
uint32_t sg_cache_component_count(const SgImportanceCache *cache);
uint64_t sg_cache_medium_voxels(const SgImportanceCache *cache);
uint64_t sg_cache_bytes(const SgImportanceCache *cache);
double sg_cache_voxel_size(const SgImportanceCache *cache);
void sg_cache_grid(const SgImportanceCache *cache, int dims[3], double origin[3]);

#ifdef __cplusplus
}
#endif
#endif
