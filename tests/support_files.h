/* Test support: temporary directories, files, and running the programs. */
#ifndef SG_TEST_SUPPORT_FILES_H
#define SG_TEST_SUPPORT_FILES_H

#include <stdbool.h>
#include <stddef.h>

/* A fresh directory under $TMPDIR (or /tmp); path valid until exit. */
const char *sg_test_tmpdir(void);
/* Writes text to dir/name and returns the path. Both return storage from a
 * ring of 32 static slots: do not free. */
char *sg_test_write(const char *dir, const char *name, const char *text);
bool sg_test_exists(const char *path);
/* The absolute path of a file of the source tree (relative: "data/..."),
 * whatever the working directory: for scenes written elsewhere that name
 * the repository's meshes. */
const char *sg_test_source_path(const char *relative);
/* Where the programs are: SG_BIN, else bin. */
const char *sg_test_bin_dir(void);
/* Path of a program in sg_test_bin_dir(). */
const char *sg_test_program(const char *name, char *buf, size_t size);
/* Runs a shell command; returns its exit status and stores its stderr
 * (at most size bytes) in err_text if given. */
int sg_test_run(const char *command, char *err_text, size_t size);
/* voxelize, skeletonize and importance on `scene` into dir (the test fails
 * if one does); the importance cache's path, valid until the next call. */
const char *sg_test_precompute(const char *scene, const char *dir);
/* Number of lines in text. */
int sg_test_count_lines(const char *text);
/* True when ../shared/scenes exists (third-party scenes for some tests). */
bool sg_test_have_shared_scenes(void);

/* A growing text (scenes written as JSON by the tests); free data when done. */
typedef struct SgTestText {
    char *data;
    size_t size, cap;
} SgTestText;
/* Appends printf-style; fails the test if memory runs out. */
void sg_test_put(SgTestText *t, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

#endif
