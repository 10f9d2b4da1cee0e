/* bin/merge: the render farm's last step. Shards of one render (render
 * --shard K/N, each an unbiased image of its own passes) become the image
 * the whole render would be: each pixel the spp-weighted mean of the
 * shards'. Merged images merge again (their sg:shards lists the shards they
 * hold), so merging is associative up to float rounding. */
#ifndef SG_MERGE_H
#define SG_MERGE_H

#include <stdbool.h>

#include "error.h"
#include "image_io.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct SgMerged SgMerged;

/* Reads and checks the inputs, then merges them. Refuses (NULL, one line in
 * err naming the files): an unreadable file, one that is not a render shard
 * (no sg:shards, sg:shard_count or sg:recipe), inputs of different sizes,
 * sampling, seed, shard count, scene, cache or recipe, a shard held twice,
 * and, unless `partial`, a shard missing. */
SgMerged *sg_merge_files(const char *const *paths, int count, bool partial, SgError *err);
void sg_merged_free(SgMerged *m);

int sg_merged_width(const SgMerged *m);
int sg_merged_height(const SgMerged *m);
const float *sg_merged_rgb(const SgMerged *m);
long sg_merged_spp(const SgMerged *m);
double sg_merged_seconds(const SgMerged *m);
/* Shards held, of how many; the missing ones as "2,5" ("" none). */
int sg_merged_shards_held(const SgMerged *m);
int sg_merged_shard_count(const SgMerged *m);
const char *sg_merged_missing(const SgMerged *m);
/* The inputs' sg:exposure, or 0 where they do not agree or have none. */
double sg_merged_exposure(const SgMerged *m);

/* The EXR with the merged attributes (and first the PNG at `exposure`, if
 * png is not NULL), each written under a temporary name and renamed. */
bool sg_merged_write(const SgMerged *m, const char *exr, const char *png, double exposure, SgError *err);

#ifdef __cplusplus
}
#endif
#endif
