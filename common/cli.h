/* Command-line number parsing shared by the programs: the whole argument
 * must be a number within [lo, hi]. */
#ifndef SG_CLI_H
#define SG_CLI_H

#include <stdbool.h>
#include <stdio.h>

bool sg_parse_long(const char *text, long lo, long hi, long *out);
bool sg_parse_int(const char *text, int lo, int hi, int *out);
bool sg_parse_double(const char *text, double lo, double hi, double *out);

/* The arguments every step's program reads alike: -h/--help (its usage
 * on stdout), -o FILE, --threads N, -q/--quiet, and its inputs, the
 * arguments that are no option (at most max_inputs); anything else
 * beginning with '-' is an unknown option. */
typedef struct SgStepArguments {
    const char *program;
    void (*usage)(FILE *out);
    const char *out_path;
    int threads;
    bool quiet;
    const char *inputs[2];
    int max_inputs, input_count;
} SgStepArguments;

/* argv[*i], the argument at hand (a value taken moves *i on): SG_CLI_TAKEN,
 * SG_CLI_HELP (the usage printed: exit 0) or SG_CLI_BAD (a one-line message
 * from `program` printed: exit 2). */
typedef enum SgCliArg { SG_CLI_TAKEN, SG_CLI_HELP, SG_CLI_BAD } SgCliArg;
SgCliArg sg_cli_step_argument(SgStepArguments *s, int argc, char **argv, int *i);

#endif
