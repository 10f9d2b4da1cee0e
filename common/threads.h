/* Minimal fork-join parallelism over pthreads: run body(ctx, index, thread)
 * for index in [0, count) on `threads` workers that take indices in order.
 * Deterministic results are the caller's job: give each index its own
 * output slot (which worker runs an index is not fixed).
 *
 * A program that runs many short jobs (the renderer: one per pass, and
 * its noise estimates) keeps an SgThreadPool, whose workers live across
 * jobs and sleep between them; sg_parallel_for is a one-job pool. */
#ifndef SG_THREADS_H
#define SG_THREADS_H

#include <stdint.h>

typedef void (*SgParallelBody)(void *ctx, uint64_t index, int thread);

typedef struct SgThreadPool SgThreadPool;

/* threads <= 0 means every core. Never fails: a pool whose workers could not
 * be started runs its jobs on fewer threads (on the caller's alone at worst). */
SgThreadPool *sg_thread_pool_create(int threads);
void sg_thread_pool_free(SgThreadPool *pool);
int sg_thread_pool_size(const SgThreadPool *pool);
/* Runs the job on the pool (the caller is its thread 0) and returns when
 * every index is done. One job at a time: not to be called concurrently. */
void sg_thread_pool_run(SgThreadPool *pool, uint64_t count, SgParallelBody body, void *ctx);

/* A pool for one job, threads <= 0 meaning every core. */
void sg_parallel_for(uint64_t count, int threads, SgParallelBody body, void *ctx);
/* requested if > 0, else the cores this process may run on (its CPU affinity). */
int sg_thread_count(int requested);

#endif
