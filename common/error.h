/* Explicit errors: every fallible function takes an SgError* and returns
 * false/NULL on failure with a one-line message "file: cause" in it.
 * No globals, no errno juggling at call sites. */
#ifndef SG_ERROR_H
#define SG_ERROR_H

#include <stdbool.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct SgError {
    bool failed;
    char message[1024];
} SgError;

/* Records a printf-style message (first failure wins: the root cause is
 * more useful than what it caused). err may be NULL. Always returns false
 * so that `return sg_fail(err, ...)` reads naturally. */
bool sg_fail(SgError *err, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

/* Prints "program: message" on stderr as one line. */
void sg_error_print(const char *program, const SgError *err);

#ifdef __cplusplus
}
#endif
#endif
