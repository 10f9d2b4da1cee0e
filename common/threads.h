/* Minimal fork-join parallelism over pthreads: run body(ctx, index) for
 * index in [0, count) on `threads` workers that take indices in order.
 * Deterministic results are the caller's job: give each index its own
 * output slot. */
#ifndef SG_THREADS_H
#define SG_THREADS_H

#include <stdint.h>

typedef void (*SgParallelBody)(void *ctx, uint64_t index, int thread);

/* threads <= 0 means every core. */
void sg_parallel_for(uint64_t count, int threads, SgParallelBody body, void *ctx);
int sg_thread_count(int requested);

#endif
