#include "shard_format.h"

bool sg_shard_valid(long shard, long shard_count)
{
    return shard_count >= 1 && shard_count <= SG_SHARDS_MAX && shard >= 0 && shard < shard_count;
}

uint64_t sg_shard_pass(int shard, int shard_count, uint64_t p)
{
    return (uint64_t)shard + p * (uint64_t)shard_count;
}

int sg_shard_pass_count(int shard, int shard_count, int total_passes)
{
    return total_passes / shard_count + (shard < total_passes % shard_count);
}
