/* The render farm's shard format, shared by the side that writes shards
 * (render --shard K/N) and the side that reads them (bin/merge): which
 * passes of the whole render shard K of N holds, how many shards there may
 * be, and the EXR attributes that make an image a shard (docs/merge.md);
 * and the names of everything else bin/render writes beside its pixels. */
#ifndef SG_SHARD_FORMAT_H
#define SG_SHARD_FORMAT_H

#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* At most this many shards to a render (render --shard K/N: N). */
#define SG_SHARDS_MAX 65536

/* 0 <= shard < shard_count <= SG_SHARDS_MAX. */
bool sg_shard_valid(long shard, long shard_count);

/* The pass rule. Shard `shard` of `shard_count` holds the whole render's
 * passes shard, shard + shard_count, shard + 2 shard_count...: its own
 * pass p (0, 1, 2...) is the whole render's pass sg_shard_pass(shard,
 * shard_count, p), whose random numbers and pixel positions it takes. So
 * the shards' passes are disjoint and together are the whole render's. */
uint64_t sg_shard_pass(int shard, int shard_count, uint64_t p);

/* How many of the first `total_passes` passes of the whole render
 * (render --spp) shard `shard` of `shard_count` holds: total / count, one
 * more for the first total % count shards. 0 when the shard has none. */
int sg_shard_pass_count(int shard, int shard_count, int total_passes);

/* ---- the EXR attributes of a shard ---------------------------------------
 * Ours all begin with SG_ATTR_PREFIX; "spp", "seconds", "sampling" and
 * "seed" are plain names, older than the farm. */
#define SG_ATTR_PREFIX "sg:"
#define SG_ATTR_SPP "spp"
#define SG_ATTR_SECONDS "seconds"
/* seconds from the program's start to its first pass (the scene read, the
 * cache opened, the renderer made): with "seconds", the wall time a user waits */
#define SG_ATTR_SETUP_SECONDS "sg:setup_seconds"
#define SG_ATTR_SAMPLING "sampling"
#define SG_ATTR_SEED "seed"
/* the shard indices the image holds, ascending, comma-separated ("0,1,3") */
#define SG_ATTR_SHARDS "sg:shards"
/* N of render --shard K/N */
#define SG_ATTR_SHARD_COUNT "sg:shard_count"
/* the identities shards of one render agree on (16 hex digits each) */
#define SG_ATTR_SCENE_HASH "sg:scene_hash"
#define SG_ATTR_CACHE_HASH "sg:cache_hash"
#define SG_ATTR_RECIPE "sg:recipe"
/* summed, weighted by spp, and copied by bin/merge */
#define SG_ATTR_NONFINITE_SAMPLES "sg:nonfinite_samples"
#define SG_ATTR_GUIDE_SHARE "sg:guide_share"
#define SG_ATTR_EXPOSURE "sg:exposure"

/* ---- the rest of bin/render's EXR attributes ----------------------------- */
#define SG_ATTR_MAX_DEPTH "sg:max_depth"
#define SG_ATTR_LOBE_EXPONENT "sg:lobe_exponent"
#define SG_ATTR_ALPHA "sg:alpha"
#define SG_ATTR_ROULETTE "sg:roulette"
#define SG_ATTR_BRANCHES_PER_PATH "sg:branches_per_path"
#define SG_ATTR_EDGE_RAYS_PER_SAMPLE "sg:edge_rays_per_sample"
#define SG_ATTR_TRAINING_PASSES "sg:training_passes"
#define SG_ATTR_TRAINING_SECONDS "sg:training_seconds"
#define SG_ATTR_CLAMPING "sg:clamping"
#define SG_ATTR_SCENE "sg:scene"
#define SG_ATTR_CACHE "sg:cache"
#define SG_ATTR_FIELD "sg:field"
#define SG_ATTR_TRAINING "sg:training"
/* the passes a render that learned within itself learned from (0: none) */
#define SG_ATTR_LEARNED_PASSES "sg:learned_passes"
/* the benchmarks' reference images say how they were made */
#define SG_ATTR_REFERENCE "sg:reference"

/* render --reference --log: the error curve's CSV header, one row a pass
 * (relmse_trimmed: the worst 0.1 % of pixels left out, error_metrics.h) */
#define SG_ERROR_LOG_HEADER "seconds,spp,mse,relmse,mse8,relmse_trimmed"

#ifdef __cplusplus
}
#endif
#endif
