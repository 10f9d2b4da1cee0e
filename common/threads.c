#include "threads.h"

#include <pthread.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdlib.h>
#include <unistd.h>

typedef struct Job {
    uint64_t count;
    _Atomic uint64_t next;
    SgParallelBody body;
    void *ctx;
} Job;

typedef struct Worker {
    SgThreadPool *pool;
    int thread;
} Worker;

struct SgThreadPool {
    int threads;            /* the caller and the workers started */
    pthread_t *ids;         /* [1, threads) */
    Worker *workers;
    pthread_mutex_t lock;
    pthread_cond_t start;   /* a job is posted, or quit */
    pthread_cond_t done;    /* the last worker left the job */
    uint64_t generation;    /* counts the jobs posted: a worker runs each once */
    int busy;               /* workers still in the current job */
    bool quit;
    Job *job;
};

int sg_thread_count(int requested)
{
    if (requested > 0)
        return requested;
    /* the cores this process may run on (a Slurm job or taskset gets fewer
     * than the machine has: more threads would only take turns) */
    cpu_set_t allowed;
    if (sched_getaffinity(0, sizeof allowed, &allowed) == 0 && CPU_COUNT(&allowed) > 0)
        return CPU_COUNT(&allowed);
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n > 0 ? (int)n : 1;
}

static void run_job(Job *job, int thread)
{
    for (;;) {
        uint64_t i = atomic_fetch_add(&job->next, 1);
        if (i >= job->count)
            break;
        job->body(job->ctx, i, thread);
    }
}

static void *worker_main(void *arg)
{
    Worker *w = arg;
    SgThreadPool *p = w->pool;
    uint64_t seen = 0;
    pthread_mutex_lock(&p->lock);
    for (;;) {
        while (p->generation == seen && !p->quit)
            pthread_cond_wait(&p->start, &p->lock);
        if (p->quit)
            break;
        seen = p->generation;
        Job *job = p->job;
        pthread_mutex_unlock(&p->lock);
        run_job(job, w->thread);
        pthread_mutex_lock(&p->lock);
        if (--p->busy == 0)
            pthread_cond_signal(&p->done);
    }
    pthread_mutex_unlock(&p->lock);
    return NULL;
}

SgThreadPool *sg_thread_pool_create(int threads)
{
    SgThreadPool *p = calloc(1, sizeof *p);
    if (!p)
        return NULL;
    int wanted = sg_thread_count(threads);
    p->threads = 1;
    pthread_mutex_init(&p->lock, NULL);
    pthread_cond_init(&p->start, NULL);
    pthread_cond_init(&p->done, NULL);
    if (wanted > 1) {
        p->ids = calloc((size_t)wanted, sizeof *p->ids);
        p->workers = calloc((size_t)wanted, sizeof *p->workers);
        if (p->ids && p->workers)
            for (int t = 1; t < wanted; t++) {
                p->workers[t] = (Worker){p, t};
                if (pthread_create(&p->ids[t], NULL, worker_main, &p->workers[t]) != 0)
                    break; /* fewer threads is still correct */
                p->threads = t + 1;
            }
    }
    return p;
}

void sg_thread_pool_free(SgThreadPool *p)
{
    if (!p)
        return;
    pthread_mutex_lock(&p->lock);
    p->quit = true;
    pthread_cond_broadcast(&p->start);
    pthread_mutex_unlock(&p->lock);
    for (int t = 1; t < p->threads; t++)
        pthread_join(p->ids[t], NULL);
    pthread_cond_destroy(&p->start);
    pthread_cond_destroy(&p->done);
    pthread_mutex_destroy(&p->lock);
    free(p->ids);
    free(p->workers);
    free(p);
}

int sg_thread_pool_size(const SgThreadPool *p) { return p ? p->threads : 1; }

void sg_thread_pool_run(SgThreadPool *p, uint64_t count, SgParallelBody body, void *ctx)
{
    Job job = {.count = count, .body = body, .ctx = ctx};
    atomic_init(&job.next, 0);
    /* a job of one index, or a pool of one thread: no one to wake */
    if (!p || p->threads <= 1 || count <= 1) {
        run_job(&job, 0);
        return;
    }
    pthread_mutex_lock(&p->lock);
    p->job = &job;
    p->busy = p->threads - 1;
    p->generation++;
    pthread_cond_broadcast(&p->start);
    pthread_mutex_unlock(&p->lock);
    run_job(&job, 0);
    pthread_mutex_lock(&p->lock);
    while (p->busy > 0)
        pthread_cond_wait(&p->done, &p->lock);
    pthread_mutex_unlock(&p->lock);
}

void sg_parallel_for(uint64_t count, int threads, SgParallelBody body, void *ctx)
{
    threads = sg_thread_count(threads);
    if ((uint64_t)threads > count)
        threads = (int)(count ? count : 1);
    SgThreadPool *p = sg_thread_pool_create(threads);
    sg_thread_pool_run(p, count, body, ctx); /* a NULL pool runs on this thread */
    sg_thread_pool_free(p);
}
