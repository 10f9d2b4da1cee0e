/* Whole files read into memory, for the parsers (scene JSON and MTL, pbrt
 * text, PLY meshes and skeletons): one reader, each format giving its own
 * size limit, with one-line errors naming the file. */
#ifndef SG_INPUT_FILE_H
#define SG_INPUT_FILE_H

#include <stdbool.h>
#include <stddef.h>

#include "error.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The formats' limits: what no real input of theirs comes near, and a
 * corrupt or hostile one is refused at before it is read whole. */
#define SG_LIMIT_SCENE_TEXT ((size_t)256 << 20)  /* JSON, MTL */
#define SG_LIMIT_PBRT_TEXT ((size_t)1 << 30)     /* one pbrt file (each Include its own) */
#define SG_LIMIT_MESH ((size_t)16 << 30)         /* PLY and other meshes: memory decides first */
#define SG_LIMIT_SKELETON ((size_t)1 << 30)      /* skeleton.ply */

/* Reads `path` into *data (malloc'ed, with a NUL after its *size bytes, so
 * text can be parsed in place). `what` names the file in the messages
 * ("mesh": "PATH: cannot open mesh: No such file"; NULL: "PATH: cannot
 * open: ..."). Fails, with *data NULL, when it cannot be opened or read,
 * or holds more than max_bytes. Works on pipes as on files. */
bool sg_read_file(const char *path, const char *what, size_t max_bytes, char **data, size_t *size, SgError *err);

/* A file's type by its name: path ends with ext (".ply"), in any case,
 * after at least one character. */
bool sg_has_extension(const char *path, const char *ext);

/* The folder part of path with its trailing '/' ("" for a bare file
 * name): what a file's relative references are read against. */
void sg_folder_of(const char *path, char *out, size_t size);

#ifdef __cplusplus
}
#endif
#endif
