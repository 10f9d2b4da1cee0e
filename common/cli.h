/* Command-line number parsing shared by the programs: the whole argument
 * must be a number within [lo, hi]. */
#ifndef SG_CLI_H
#define SG_CLI_H

#include <stdbool.h>

bool sg_parse_long(const char *text, long lo, long hi, long *out);
bool sg_parse_int(const char *text, int lo, int hi, int *out);
bool sg_parse_double(const char *text, double lo, double hi, double *out);

#endif
