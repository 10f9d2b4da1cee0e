/* The thread pool: every index of every job runs exactly once, on a
 * thread index within the pool, job after job on the same workers. */
#include <criterion/criterion.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdlib.h>

#include "threads.h"

typedef struct Count {
    _Atomic int *hits;
    int threads;
    _Atomic int bad_thread;
} Count;

static void count_index(void *vctx, uint64_t index, int thread)
{
    Count *c = vctx;
    atomic_fetch_add(&c->hits[index], 1);
    if (thread < 0 || thread >= c->threads)
        atomic_fetch_add(&c->bad_thread, 1);
}

static void run_jobs(SgThreadPool *pool, int jobs, uint64_t max_count)
{
    _Atomic int *hits = calloc(max_count ? max_count : 1, sizeof *hits);
    cr_assert_not_null(hits);
    Count c = {hits, sg_thread_pool_size(pool), 0};
    for (int j = 0; j < jobs; j++) {
        uint64_t count = (uint64_t)(j * 7919) % (max_count + 1); /* 0, 1 and more than the threads */
        for (uint64_t i = 0; i < count; i++)
            atomic_store(&hits[i], 0);
        sg_thread_pool_run(pool, count, count_index, &c);
        for (uint64_t i = 0; i < count; i++)
            cr_assert_eq(atomic_load(&hits[i]), 1, "job %d: index %lu ran %d times", j, (unsigned long)i,
                         atomic_load(&hits[i]));
    }
    cr_assert_eq(atomic_load(&c.bad_thread), 0, "a thread index outside [0, %d)", c.threads);
    free(hits);
}

Test(threads, a_pool_runs_every_index_once_job_after_job)
{
    SgThreadPool *pool = sg_thread_pool_create(4);
    cr_assert_not_null(pool);
    cr_assert_eq(sg_thread_pool_size(pool), 4);
    run_jobs(pool, 2000, 300);
    sg_thread_pool_free(pool);
}

Test(threads, a_pool_of_one_runs_on_the_caller)
{
    SgThreadPool *pool = sg_thread_pool_create(1);
    cr_assert_eq(sg_thread_pool_size(pool), 1);
    run_jobs(pool, 50, 100);
    sg_thread_pool_free(pool);
    sg_thread_pool_free(NULL); /* as free() */
}

static void sum_index(void *vctx, uint64_t index, int thread)
{
    (void)thread;
    atomic_fetch_add((_Atomic uint64_t *)vctx, index + 1);
}

Test(threads, parallel_for_is_a_one_job_pool)
{
    for (int threads = 0; threads <= 5; threads++) {
        _Atomic uint64_t sum = 0;
        sg_parallel_for(1000, threads, sum_index, &sum);
        cr_assert_eq(atomic_load(&sum), 1000 * 1001 / 2, "%d threads", threads);
        atomic_store(&sum, 0);
        sg_parallel_for(0, threads, sum_index, &sum);
        cr_assert_eq(atomic_load(&sum), 0);
    }
}

/* "Every core" means the cores the process may run on: a job confined to
 * one core (taskset, a Slurm allocation) gets one thread, not the machine's. */
Test(threads, every_core_means_the_allowed_cores)
{
    cpu_set_t allowed;
    cr_assert_eq(sched_getaffinity(0, sizeof allowed, &allowed), 0);
    cr_expect_eq(sg_thread_count(0), CPU_COUNT(&allowed));
    cr_expect_eq(sg_thread_count(3), 3);
    int first = 0;
    while (!CPU_ISSET(first, &allowed))
        first++;
    cpu_set_t one;
    CPU_ZERO(&one);
    CPU_SET(first, &one);
    cr_assert_eq(sched_setaffinity(0, sizeof one, &one), 0);
    cr_expect_eq(sg_thread_count(0), 1);
    cr_expect_eq(sg_thread_count(-1), 1);
    sched_setaffinity(0, sizeof allowed, &allowed);
}
