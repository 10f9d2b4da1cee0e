/* Progress of long work on a terminal: one line on stderr rewritten in
 * place, at most ~10 times a second; silent when stderr is not a terminal
 * (logs and CI stay clean). */
#ifndef SG_PROGRESS_H
#define SG_PROGRESS_H

#include <stdbool.h>
#include <stdint.h>

typedef struct SgProgress {
    const char *label;
    uint64_t total;
    bool enabled;
    double started;
    double last_print;
} SgProgress;

void sg_progress_begin(SgProgress *p, const char *label, uint64_t total);
void sg_progress_update(SgProgress *p, uint64_t done);
void sg_progress_end(SgProgress *p);

/* Monotonic wall-clock seconds. */
double sg_seconds(void);

#endif
