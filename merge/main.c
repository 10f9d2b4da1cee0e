/* bin/merge: shards of one render (render --shard K/N) into its image. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "merge.h"

static const char *usage =
    "usage: merge SHARD.exr... -o IMAGE.exr [--png IMAGE.png] [--exposure STOPS] [--partial] [--quiet]\n"
    "\n"
    "Merges the EXRs of the shards of one render (render --shard K/N) into the image of the\n"
    "whole render: each pixel the spp-weighted mean of the shards'. Inputs may be merged\n"
    "images themselves. Refuses shards of different renders (size, sampling, seed, scene,\n"
    "cache, options), a shard given twice, and missing shards.\n"
    "  -o FILE.exr       the merged image, with spp and seconds summed, sg:shards the union\n"
    "  --png FILE.png    8-bit sRGB image times 2^exposure\n"
    "  --exposure STOPS  PNG exposure (default: the shards' sg:exposure, else 0)\n"
    "  --partial         merge the shards that are there (saying which are missing)\n"
    "  --quiet           no summary line\n";

int main(int argc, char **argv)
{
    const char *output = NULL, *png = NULL;
    double exposure = 0;
    bool has_exposure = false, partial = false, quiet = false;
    const char **inputs = calloc((size_t)argc, sizeof *inputs);
    int count = 0;
    if (!inputs)
        return 1;
    for (int i = 1; i < argc; i++) {
        const char *s = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(s, "--help") || !strcmp(s, "-h")) {
            fputs(usage, stdout);
            free(inputs);
            return 0;
        } else if (!strcmp(s, "-o") || !strcmp(s, "--png") || !strcmp(s, "--exposure")) {
            if (!v) {
                fprintf(stderr, "merge: %s: needs a value (see --help)\n", s);
                free(inputs);
                return 2;
            }
            i++;
            if (!strcmp(s, "-o"))
                output = v;
            else if (!strcmp(s, "--png"))
                png = v;
            else if (!sg_parse_double(v, -100, 100, &exposure)) {
                fprintf(stderr, "merge: --exposure: '%s' is not a number of stops\n", v);
                free(inputs);
                return 2;
            } else
                has_exposure = true;
        } else if (!strcmp(s, "--partial")) {
            partial = true;
        } else if (!strcmp(s, "--quiet")) {
            quiet = true;
        } else if (s[0] == '-' && s[1]) {
            fprintf(stderr, "merge: %s: unknown option (see --help)\n", s);
            free(inputs);
            return 2;
        } else {
            inputs[count++] = s;
        }
    }
    if (!output || !count) {
        fprintf(stderr, "merge: %s (see --help)\n", !count ? "no shard given" : "no output given: -o IMAGE.exr");
        free(inputs);
        return 2;
    }
    if (png && !strcmp(png, output)) {
        fprintf(stderr, "merge: -o and --png both name %s\n", output);
        free(inputs);
        return 2;
    }
    SgError err = {0};
    SgMerged *m = sg_merge_files(inputs, count, partial, &err);
    int status = 1;
    if (!m)
        goto done;
    if (!sg_merged_write(m, output, png, has_exposure ? exposure : sg_merged_exposure(m), &err))
        goto done;
    if (sg_merged_missing(m)[0]) /* a warning: said even with --quiet */
        fprintf(stderr, "merge: merged %d of %d shards (missing %s)\n", sg_merged_shards_held(m),
                sg_merged_shard_count(m), sg_merged_missing(m));
    if (!quiet)
        fprintf(stderr, "merge: %d file%s, %d of %d shards, %dx%d, %ld spp, %.1f s of rendering -> %s\n", count,
                count == 1 ? "" : "s", sg_merged_shards_held(m), sg_merged_shard_count(m), sg_merged_width(m),
                sg_merged_height(m), sg_merged_spp(m), sg_merged_seconds(m), output);
    status = 0;
done:
    if (status)
        sg_error_print("merge", &err);
    sg_merged_free(m);
    free(inputs);
    return status;
}
