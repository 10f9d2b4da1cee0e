#include "progress.h"

#include <stdio.h>
#include <time.h>
#include <unistd.h>

double sg_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void sg_progress_begin(SgProgress *p, const char *label, uint64_t total)
{
    p->label = label;
    p->total = total;
    p->enabled = isatty(STDERR_FILENO); /* a log or a pipe gets the summary alone */
    p->started = sg_seconds();
    p->last_print = 0;
}

void sg_progress_update(SgProgress *p, uint64_t done)
{
    if (!p->enabled)
        return;
    double now = sg_seconds();
    if (now - p->last_print < 0.1)
        return;
    p->last_print = now;
    if (p->total)
        fprintf(stderr, "\r%s: %5.1f%%  %.1f s", p->label,
                100.0 * (double)done / (double)p->total, now - p->started);
    else
        fprintf(stderr, "\r%s: %llu  %.1f s", p->label, (unsigned long long)done,
                now - p->started);
    fflush(stderr);
}

void sg_progress_end(SgProgress *p)
{
    if (!p->enabled)
        return;
    /* Clear the line so that the summary that follows starts clean. */
    fprintf(stderr, "\r\033[K");
    fflush(stderr);
}
