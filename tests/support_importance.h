/* Synthetic media and hand-made skeletons for the step 3 tests. */
#ifndef SG_TESTS_SUPPORT_IMPORTANCE_H
#define SG_TESTS_SUPPORT_IMPORTANCE_H

#include <stddef.h>
#include <stdint.h>

#include "medium.h"
#include "skeleton_graph.h"

/* An all-solid grid of nx*ny*nz unit voxels at the origin, no lights. */
void sgt_medium_init(SgMedium *m, int nx, int ny, int nz);
/* Sets voxels [lo, hi] (inclusive) to value. */
void sgt_box(SgMedium *m, int i0, int j0, int k0, int i1, int j1, int k1, uint8_t value);
/* Adds a light at world position p with seed voxel (seed may be NULL: sealed). */
uint32_t sgt_add_light(SgMedium *m, const double p[3], const int seed[3]);
/* sgt_medium_init, then sgt_box for each {i0, j0, k0, i1, j1, k1, value} in turn. */
void sgt_medium_boxes(SgMedium *m, int nx, int ny, int nz, const int (*boxes)[7], int count);
/* A grid of nx*ny*nz voxels, all medium. */
void sgt_medium_open(SgMedium *m, int nx, int ny, int nz);
void sgt_medium_free(SgMedium *m);

/* Skeleton built node by node: nodes at voxel centres. */
uint32_t sgt_node(SgSkeleton *s, int i, int j, int k, SgNodeKind kind, int light);
void sgt_edge(SgSkeleton *s, uint32_t a, uint32_t b);
/* Nodes on every voxel of the straight 3D line from a to b (inclusive),
 * chained to `from` (SG_CACHE_NONE: no link); returns the last node. */
uint32_t sgt_line(SgSkeleton *s, uint32_t from, const int a[3], const int b[3]);

/* The sealed rooms: two rooms with no opening between them, a light and a
 * skeleton line in each, a third light sealed inside the wall (no seed). */
void sgt_sealed_rooms(SgMedium *m, SgSkeleton *s);

/* Recomputes the checksum of cache bytes in place (to forge files that
 * pass the checksum but are wrong in another way). */
void sgt_cache_fix_checksum(uint8_t *data, size_t size);
/* Reads a whole file into 16-byte aligned memory. */
uint8_t *sgt_read_file(const char *path, size_t *size);
void sgt_temp_path(char *out, size_t cap, const char *tag);

#endif
