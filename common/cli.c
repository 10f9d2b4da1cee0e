#include "cli.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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

SgCliArg sg_cli_step_argument(SgStepArguments *s, int argc, char **argv, int *i)
{
    const char *a = argv[*i];
    if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
        s->usage(stdout);
        return SG_CLI_HELP;
    }
    if (!strcmp(a, "-o") && *i + 1 < argc) {
        s->out_path = argv[++*i];
        return SG_CLI_TAKEN;
    }
    if (!strcmp(a, "--threads") && *i + 1 < argc) {
        if (sg_parse_int(argv[++*i], 1, 1024, &s->threads))
            return SG_CLI_TAKEN;
        fprintf(stderr, "%s: --threads takes a whole number in [1, 1024]\n", s->program);
        return SG_CLI_BAD;
    }
    if (!strcmp(a, "-q") || !strcmp(a, "--quiet")) {
        s->quiet = true;
        return SG_CLI_TAKEN;
    }
    if (a[0] == '-' && a[1]) {
        fprintf(stderr, "%s: unknown or incomplete option '%s' (see --help)\n", s->program, a);
        return SG_CLI_BAD;
    }
    if (s->input_count == s->max_inputs) {
        fprintf(stderr, "%s: more inputs than the %d it takes (%s; see --help)\n", s->program, s->max_inputs, a);
        return SG_CLI_BAD;
    }
    s->inputs[s->input_count++] = a;
    return SG_CLI_TAKEN;
}

SgCliArg sg_cli_step_arguments(SgStepArguments *s, int argc, char **argv, SgCliOwnOption own, void *ctx)
{
    for (int i = 1; i < argc; i++) {
        SgCliArg got = own ? own(ctx, argc, argv, &i) : SG_CLI_OTHER;
        if (got == SG_CLI_OTHER)
            got = sg_cli_step_argument(s, argc, argv, &i);
        if (got != SG_CLI_TAKEN)
            return got;
    }
    if (s->input_count < s->min_inputs || (s->out_required && !s->out_path)) {
        s->usage(stderr);
        return SG_CLI_BAD;
    }
    return SG_CLI_TAKEN;
}
