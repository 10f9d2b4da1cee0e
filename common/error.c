#include "error.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

bool sg_fail(SgError *err, const char *fmt, ...)
{
    if (!err || err->failed)
        return false;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err->message, sizeof err->message, fmt, ap);
    va_end(ap);
    /* Keep the message on one line whatever a library told us. */
    for (char *c = err->message; *c; c++)
        if (*c == '\n' || *c == '\r')
            *c = ' ';
    err->failed = true;
    return false;
}

void sg_error_print(const char *program, const SgError *err)
{
    fprintf(stderr, "%s: %s\n", program,
            err && err->failed ? err->message : "unknown error");
}
