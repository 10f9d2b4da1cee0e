#include "threads.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <unistd.h>

typedef struct Job {
    uint64_t count;
    _Atomic uint64_t next;
    SgParallelBody body;
    void *ctx;
} Job;

typedef struct Worker {
    Job *job;
    int thread;
} Worker;

int sg_thread_count(int requested)
{
    if (requested > 0)
        return requested;
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n > 0 ? (int)n : 1;
}

static void *run_worker(void *arg)
{
    Worker *w = arg;
    Job *job = w->job;
    for (;;) {
        uint64_t i = atomic_fetch_add(&job->next, 1);
        if (i >= job->count)
            break;
        job->body(job->ctx, i, w->thread);
    }
    return NULL;
}

void sg_parallel_for(uint64_t count, int threads, SgParallelBody body, void *ctx)
{
    threads = sg_thread_count(threads);
    if ((uint64_t)threads > count)
        threads = (int)(count ? count : 1);
    Job job = {.count = count, .body = body, .ctx = ctx};
    atomic_init(&job.next, 0);
    if (threads <= 1) {
        Worker w = {&job, 0};
        run_worker(&w);
        return;
    }
    pthread_t *ids = calloc((size_t)threads, sizeof *ids);
    Worker *workers = calloc((size_t)threads, sizeof *workers);
    int started = 0;
    if (ids && workers) {
        for (int t = 1; t < threads; t++) {
            workers[t] = (Worker){&job, t};
            if (pthread_create(&ids[t], NULL, run_worker, &workers[t]) != 0)
                break; /* fewer threads is still correct */
            started = t;
        }
    }
    Worker self = {&job, 0};
    run_worker(&self);
    for (int t = 1; t <= started; t++)
        pthread_join(ids[t], NULL);
    free(ids);
    free(workers);
}
