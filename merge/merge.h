/* bin/merge: the render farm's last step. Shards of one render (render
 * --shard K/N, each an unbiased image of its own passes) become the image
 * the whole render would be: each pixel the spp-weighted mean of the
 * shards', sum_i spp_i x_i / sum_i spp_i in double, summed in ascending
 * order of each file's first shard (so the given order does not matter)
 * and rounded to float. Merged images merge again (their sg:shards lists
 * the shards they hold), so merging is associative up to float rounding. */
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
 * err naming the file or files and the cause): a file that cannot be read;
 * one that is not a render shard (no sg:shards, sg:shard_count, sg:recipe,
 * sampling, seed, sg:scene_hash, sg:cache_hash or spp); a shard index not
 * below sg:shard_count; spp not above 0; inputs that differ in size,
 * sampling, seed, sg:shard_count, sg:scene_hash, sg:cache_hash or
 * sg:recipe; a shard held by two inputs; and, unless `partial`, a shard
 * that no input holds.
 *
 * The merged attributes: spp, seconds and sg:nonfinite_samples summed,
 * sg:shards the union, sg:guide_share the spp-weighted mean (where every
 * input has one), and every other attribute of ours (the sg: ones) that
 * all inputs have with one value, as it is; those that differ are dropped.
 * The file format's own header fields (compression, DateTime...) are the
 * writer's, not copied. */
SgMerged *sg_merge_files(const char *const *paths, int count, bool partial, SgError *err);
void sg_merged_free(SgMerged *m);

int sg_merged_width(const SgMerged *m);
int sg_merged_height(const SgMerged *m);
const float *sg_merged_rgb(const SgMerged *m);
long sg_merged_spp(const SgMerged *m);
double sg_merged_seconds(const SgMerged *m);
/* The attributes sg_merged_write puts in the EXR (valid until freed). */
const SgImageAttribute *sg_merged_attributes(const SgMerged *m, int *count);
/* Shards held, of how many; the missing ones as "2,5" ("" none). */
int sg_merged_shards_held(const SgMerged *m);
int sg_merged_shard_count(const SgMerged *m);
const char *sg_merged_missing(const SgMerged *m);
/* The inputs' sg:exposure, or 0 where they do not agree or have none. */
double sg_merged_exposure(const SgMerged *m);

/* The EXR with the merged attributes, and the PNG at `exposure` if png is
 * not NULL. Both are written under temporary names before either takes its
 * name (the EXR last: make and the farm wait for it), so a failed write
 * leaves neither and an existing file untouched. exr and png must differ. */
bool sg_merged_write(const SgMerged *m, const char *exr, const char *png, double exposure, SgError *err);

#ifdef __cplusplus
}
#endif
#endif
