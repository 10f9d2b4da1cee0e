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
 * arguments that are no option (at least min_inputs, at most max_inputs;
 * -o required when out_required); anything else beginning with '-' is an
 * unknown option. */
typedef struct SgStepArguments {
    const char *program;
    void (*usage)(FILE *out);
    const char *out_path;
    int threads;
    bool quiet;
    const char *inputs[2];
    int min_inputs, max_inputs, input_count;
    bool out_required;
} SgStepArguments;

/* What became of argv[*i], the argument at hand (a value taken moves *i
 * on): SG_CLI_TAKEN, SG_CLI_HELP (the usage printed: exit 0), SG_CLI_BAD (a
 * one-line message from `program` printed: exit 2) or, from a program's
 * own reader, SG_CLI_OTHER (not one of its options). */
typedef enum SgCliArg { SG_CLI_TAKEN, SG_CLI_HELP, SG_CLI_BAD, SG_CLI_OTHER } SgCliArg;
SgCliArg sg_cli_step_argument(SgStepArguments *s, int argc, char **argv, int *i);

/* A program's own options: ctx is the program's (where they go). */
typedef SgCliArg (*SgCliOwnOption)(void *ctx, int argc, char **argv, int *i);

/* Reads the whole command line: each argument goes to `own` first (NULL:
 * the program has none), then to sg_cli_step_argument; at the end, too few
 * inputs or a missing -o print the usage on stderr (SG_CLI_BAD). Returns
 * SG_CLI_TAKEN when everything was read, else SG_CLI_HELP or SG_CLI_BAD. */
SgCliArg sg_cli_step_arguments(SgStepArguments *s, int argc, char **argv, SgCliOwnOption own, void *ctx);

#endif
