/* sg_read_file: a file's bytes exactly (and a NUL after them), a pipe's as
 * a file's, the limit enforced, one-line errors naming the file. */
#include <criterion/criterion.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "input_file.h"
#include "support_files.h"

static const char *make_file(const char *dir, const char *name, size_t bytes, char **content)
{
    static char path[4200];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    char *c = malloc(bytes + 1);
    for (size_t i = 0; i < bytes; i++)
        c[i] = (char)(i * 131 + 7); /* NULs and high bytes included */
    FILE *f = fopen(path, "wb");
    cr_assert(f && fwrite(c, 1, bytes, f) == bytes && fclose(f) == 0);
    *content = c;
    return path;
}

Test(input_file, reads_every_byte_and_a_nul_after)
{
    const char *dir = sg_test_tmpdir();
    const size_t sizes[] = {0, 1, 65535, 65536, 65537, 300001};
    for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; k++) {
        char name[32], *want, *got;
        snprintf(name, sizeof name, "f%zu", k);
        const char *path = make_file(dir, name, sizes[k], &want);
        size_t size = 99;
        SgError err = {0};
        cr_assert(sg_read_file(path, NULL, (size_t)1 << 20, &got, &size, &err), "%s", err.message);
        cr_assert_eq(size, sizes[k]);
        cr_assert(memcmp(got, want, size) == 0, "%zu bytes differ", size);
        cr_assert_eq(got[size], 0);
        free(got);
        free(want);
    }
}

Test(input_file, a_pipe_is_read_like_a_file)
{
    const char *dir = sg_test_tmpdir();
    char *want;
    const char *path = make_file(dir, "source", 200000, &want);
    char fifo[4200], cmd[8800];
    snprintf(fifo, sizeof fifo, "%s/pipe", dir);
    cr_assert_eq(mkfifo(fifo, 0600), 0);
    snprintf(cmd, sizeof cmd, "cat %s > %s &", path, fifo); /* the writer: a shell in the background */
    cr_assert_eq(system(cmd), 0);
    char *got;
    size_t size;
    SgError err = {0};
    cr_assert(sg_read_file(fifo, NULL, (size_t)1 << 20, &got, &size, &err), "%s", err.message);
    cr_assert_eq(size, 200000);
    cr_assert(memcmp(got, want, size) == 0);
    free(got);
    free(want);
}

Test(input_file, refuses_what_it_cannot_or_must_not_read)
{
    const char *dir = sg_test_tmpdir();
    char *want, *got = (char *)1;
    size_t size;
    const char *path = make_file(dir, "big", 5000, &want);
    SgError err = {0};
    cr_assert_not(sg_read_file(path, "mesh", 4999, &got, &size, &err)); /* one byte over */
    cr_assert_null(got);
    cr_assert(strstr(err.message, path) && strstr(err.message, "larger than"), "%s", err.message);
    err = (SgError){0};
    cr_assert(sg_read_file(path, "mesh", 5000, &got, &size, &err), "exactly the limit: %s", err.message);
    free(got);
    char missing[4200];
    snprintf(missing, sizeof missing, "%s/none.ply", dir);
    err = (SgError){0};
    cr_assert_not(sg_read_file(missing, "mesh", 5000, &got, &size, &err));
    cr_assert(strstr(err.message, "none.ply: cannot open mesh: No such file"), "%s", err.message);
    cr_assert_null(strchr(err.message, '\n'));
    free(want);
}
