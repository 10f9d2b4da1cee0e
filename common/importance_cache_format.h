/* On-disk layout of importance.cache, shared by the writer (importance/)
 * and the reader (importance_cache.c). Documented in docs/cache-format.md.
 * Everything is little-endian; sections start at multiples of 16 bytes so
 * that a page-aligned mmap gives aligned typed access in place. */
#ifndef SG_IMPORTANCE_CACHE_FORMAT_H
#define SG_IMPORTANCE_CACHE_FORMAT_H

#include <stdint.h>

#include "importance_cache.h" /* SG_CACHE_NONE: no node / no block / no component */

#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "importance.cache is read in place: a little-endian host is required"
#endif

#define SG_CACHE_MAGIC "SGIMPCA\x1a" /* 8 bytes; \x1a stops `type` on a terminal */
#define SG_CACHE_VERSION 1u
#define SG_CACHE_BLOCK 8             /* nearest-node table blocks are 8x8x8 voxels */
#define SG_CACHE_BLOCK_VOXELS 512
#define SG_CACHE_ALIGN 16

typedef enum SgCacheSection {
    SG_CACHE_NODES,       /* SgCacheNode[node_count] */
    SG_CACHE_LIGHTS,      /* SgCacheLight[light_count] */
    SG_CACHE_POINTS,      /* float[node_count][light_count][3] importance points */
    SG_CACHE_BLOCK_INDEX, /* uint32[bx*by*bz]: block record or SG_CACHE_NONE */
    SG_CACHE_BLOCKS,      /* SgCacheBlock[block_count] */
    SG_CACHE_PALETTE,     /* uint32[palette_count]: node ids (SG_CACHE_NONE = not medium) */
    SG_CACHE_VOXEL_BITS,  /* packed per-voxel palette indices */
    SG_CACHE_SECTION_COUNT
} SgCacheSection;

typedef struct SgCacheRange {
    uint64_t offset;
    uint64_t size;
} SgCacheRange;

typedef struct SgCacheHeader {
    char magic[8];
    uint32_t version;
    uint32_t header_size;  /* sizeof(SgCacheHeader) */
    uint64_t file_size;
    uint64_t checksum;     /* FNV-1a 64 of the whole file with this field zero */
    uint64_t geometry_hash; /* SgMedium.geometry_hash (= SgScene.geometry_hash) */
    uint64_t skeleton_hash; /* sg_importance_skeleton_hash() of skeleton.ply's graph */
    uint64_t medium_hash;   /* FNV-1a 64 of the medium's dims and voxel bytes */
    int32_t nx, ny, nz;     /* grid size in voxels */
    int32_t block_size;     /* SG_CACHE_BLOCK */
    double origin[3];       /* world position of voxel (0,0,0)'s min corner */
    double voxel_size;
    uint32_t node_count;
    uint32_t light_count;
    uint32_t component_count; /* connected components of the skeleton graph */
    uint32_t block_count;     /* blocks that hold medium voxels */
    uint64_t medium_voxels;
    uint64_t palette_count;
    SgCacheRange sections[SG_CACHE_SECTION_COUNT];
} SgCacheHeader;

typedef struct SgCacheNode {
    float position[3];
    uint32_t component;
} SgCacheNode;

typedef struct SgCacheLight {
    float position[3];
    uint32_t node;      /* skeleton node of the light, SG_CACHE_NONE if none */
    uint32_t component; /* its skeleton component; SG_CACHE_NONE: reaches nothing */
    uint32_t reserved;
} SgCacheLight;

/* A present block: its node palette and its packed voxel indices. bits is
 * 0 (one palette entry for the whole block), 1, 2, 4, 8 or 16; voxel
 * (x,y,z) of the block, local = x + 8 (y + 8 z), has palette index
 * bits_at(data_offset, local * bits). */
typedef struct SgCacheBlock {
    uint32_t palette_offset; /* first entry in the palette section */
    uint32_t data_offset;    /* byte offset in the voxel-bits section */
    uint16_t palette_size;
    uint8_t bits;
    uint8_t reserved;
    uint32_t reserved2;
} SgCacheBlock;

_Static_assert(sizeof(SgCacheHeader) == 8 + 4 + 4 + 8 * 5 + 16 + 32 + 16 + 16 + 16 * 7,
               "header layout");
_Static_assert(sizeof(SgCacheNode) == 16, "node layout");
_Static_assert(sizeof(SgCacheLight) == 24, "light layout");
_Static_assert(sizeof(SgCacheBlock) == 16, "block layout");

#endif
