/* Triangle meshes from PLY files (ascii, binary little and big endian).
 * Why not Assimp for PLY: Assimp 5.2 (Debian 12) skips whitespace after
 * "end_header", so a binary file whose first data byte is 0x0A is read
 * misaligned and its post-processing faults (4 meshes of Bitterli's
 * bathroom do this). This reader is strict and bounds-checked instead. */
#ifndef SG_PLY_MESH_H
#define SG_PLY_MESH_H

#include <stdbool.h>
#include <stdint.h>

#include "error.h"

typedef struct SgPlyMesh {
    uint32_t vertex_count;
    double *positions;   /* 3 * vertex_count */
    uint32_t triangle_count;
    uint32_t *indices;   /* 3 * triangle_count; polygons are fanned */
    double *normals;     /* 3 * vertex_count from nx ny nz, or NULL if the file has none */
    float *uvs;          /* 2 * vertex_count from u v (or s t), or NULL if the file has none */
} SgPlyMesh;

bool sg_ply_mesh_read(SgPlyMesh *mesh, const char *path, SgError *err);
void sg_ply_mesh_release(SgPlyMesh *mesh);

#endif
