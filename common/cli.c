#include "cli.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>

bool sg_parse_long(const char *text, long lo, long hi, long *out)
{
    char *end;
    errno = 0;
    long v = strtol(text, &end, 10);
    if (errno || end == text || *end || v < lo || v > hi)
        return false;
    *out = v;
    return true;
}

bool sg_parse_int(const char *text, int lo, int hi, int *out)
{
    long v;
    if (!sg_parse_long(text, lo, hi, &v))
        return false;
    *out = (int)v;
    return true;
}

bool sg_parse_double(const char *text, double lo, double hi, double *out)
{
    char *end;
    errno = 0;
    double v = strtod(text, &end);
    if (errno || end == text || *end || !isfinite(v) || v < lo || v > hi)
        return false;
    *out = v;
    return true;
}
