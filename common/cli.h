/* Command-line number parsing shared by the programs: the whole argument
 * must be a number within [lo, hi]. */
#ifndef SG_CLI_H
#define SG_CLI_H

#include <stdbool.h>

bool sg_parse_long(const char *text, long lo, long hi, long *out);
bool sg_parse_int(const char *text, int lo, int hi, int *out);
bool sg_parse_double(const char *text, double lo, double hi, double *out);

/* The options every step's program reads alike: --threads N (into
 * *threads) and -q/--quiet (into *quiet); anything else beginning with '-'
 * is an unknown option. argv[*i] is the argument at hand; a value taken
 * moves *i on. Returns SG_CLI_TAKEN, SG_CLI_POSITIONAL (not an option:
 * the program's own input), or SG_CLI_BAD after a one-line message from
 * `program` (exit 2). */
typedef enum SgCliArg { SG_CLI_TAKEN, SG_CLI_POSITIONAL, SG_CLI_BAD } SgCliArg;
SgCliArg sg_cli_step_option(const char *program, int argc, char **argv, int *i, int *threads, bool *quiet);

#endif
