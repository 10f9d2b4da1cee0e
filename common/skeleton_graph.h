/* The curvilinear skeleton as a graph, and its PLY file (skeleton.ply):
 *   element vertex: float x y z (world), int i j k (voxel), uchar kind
 *                   (0 node, 1 light, 2 camera), float radius (opening
 *                   value, world units), int lifespan, int light (index of
 *                   the light in the medium's light table, -1 otherwise)
 *   element edge:   int vertex1, int vertex2
 * MeshLab and Blender open it; readers must accept ascii and
 * binary_little_endian and ignore properties they do not know. */
#ifndef SG_SKELETON_GRAPH_H
#define SG_SKELETON_GRAPH_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "error.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum SgNodeKind {
    SG_NODE_PLAIN = 0,
    SG_NODE_LIGHT = 1,
    SG_NODE_CAMERA = 2,
} SgNodeKind;

typedef struct SgSkeletonNode {
    float position[3]; /* world */
    int voxel[3];      /* the medium voxel the node stands for */
    uint8_t kind;      /* SgNodeKind */
    float radius;      /* opening value, world units */
    int lifespan;      /* collapse steps the node's cell survived */
    int light;         /* light index for SG_NODE_LIGHT, else -1 */
} SgSkeletonNode;

typedef struct SgSkeleton {
    uint32_t node_count;
    SgSkeletonNode *nodes;
    uint32_t edge_count;
    uint32_t (*edges)[2];
} SgSkeleton;

/* Binary little-endian PLY, written atomically. */
bool sg_skeleton_write_ply(const SgSkeleton *skeleton, const char *path, SgError *err);
/* Validates counts, indices and values; never reads out of bounds. */
bool sg_skeleton_read_ply(SgSkeleton *skeleton, const char *path, SgError *err);
/* The same from bytes in memory (`path` names them in messages); for tests
 * and fuzzing. The file's `light` property is optional (light = -1). */
bool sg_skeleton_parse_ply(SgSkeleton *skeleton, const void *data, size_t size,
                           const char *path, SgError *err);
void sg_skeleton_release(SgSkeleton *skeleton);

#ifdef __cplusplus
}
#endif
#endif
