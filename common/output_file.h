/* Outputs are written under a temporary name beside the target and renamed
 * over it only when complete, so that an interrupted or failed run never
 * leaves a partial file that make or a later step would take as finished. */
#ifndef SG_OUTPUT_FILE_H
#define SG_OUTPUT_FILE_H

#include <stdbool.h>
#include <stdio.h>

#include "error.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Temporary name for `path` in the same directory ("dir/.name.tmp.PID"). */
void sg_temp_path(const char *path, char *out, size_t out_size);
/* Renames tmp over path (fsync'ed first); removes tmp on failure. */
bool sg_commit_temp(const char *tmp, const char *path, SgError *err);

typedef struct SgOutputFile {
    FILE *file;
    char path[4096];
    char tmp[4096];
} SgOutputFile;

bool sg_output_open(SgOutputFile *out, const char *path, SgError *err);
/* Flushes, checks for write errors (a full disk), renames into place. */
bool sg_output_commit(SgOutputFile *out, SgError *err);
/* Drops the temporary file; the target is untouched. */
void sg_output_abort(SgOutputFile *out);

#ifdef __cplusplus
}
#endif
#endif
