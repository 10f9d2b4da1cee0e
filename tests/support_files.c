#include "support_files.h"

#include <criterion/criterion.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

/* Results live in small static rings: no heap, so nothing for the leak
 * checker to report, and a test may use a few at once. */
#define RING 32
static char *ring_slot(void)
{
    static char slots[RING][4096];
    static int next;
    return slots[next++ % RING];
}

const char *sg_test_tmpdir(void)
{
    char *path = ring_slot();
    const char *base = getenv("TMPDIR");
    snprintf(path, 4096, "%s/sg-test-XXXXXX", base && *base ? base : "/tmp");
    if (!mkdtemp(path)) {
        perror("mkdtemp");
        abort();
    }
    return path;
}

char *sg_test_write(const char *dir, const char *name, const char *text)
{
    char *path = ring_slot();
    snprintf(path, 4096, "%s/%s", dir, name);
    FILE *f = fopen(path, "wb");
    if (!f) {
        perror(path);
        abort();
    }
    fputs(text, f);
    fclose(f);
    return path;
}

bool sg_test_exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

const char *sg_test_source_path(const char *relative)
{
    char *path = ring_slot();
    snprintf(path, 4096, "%s/%s", SG_SOURCE_ROOT, relative);
    return path;
}

const char *sg_test_bin_dir(void)
{
    const char *bin = getenv("SG_BIN");
    return bin && *bin ? bin : "bin";
}

const char *sg_test_program(const char *name, char *buf, size_t size)
{
    snprintf(buf, size, "%s/%s", sg_test_bin_dir(), name);
    return buf;
}

int sg_test_run(const char *command, char *err_text, size_t size)
{
    char errfile[] = "/tmp/sg-test-stderr-XXXXXX";
    int fd = mkstemp(errfile);
    if (fd < 0)
        abort();
    close(fd);
    char full[16384];
    snprintf(full, sizeof full, "%s 2>%s", command, errfile);
    int status = system(full);
    if (err_text && size) {
        FILE *f = fopen(errfile, "rb");
        size_t n = f ? fread(err_text, 1, size - 1, f) : 0;
        err_text[n] = 0;
        if (f)
            fclose(f);
    }
    unlink(errfile);
    if (status == -1)
        return -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

int sg_test_count_lines(const char *text)
{
    int n = 0;
    for (const char *c = text; *c; c++)
        n += *c == '\n';
    return n;
}

bool sg_test_have_shared_scenes(void)
{
    return sg_test_exists("../shared/scenes/README.md");
}

void sg_test_put(SgTestText *t, const char *fmt, ...)
{
    va_list ap;
    for (;;) {
        va_start(ap, fmt);
        int n = vsnprintf(t->data ? t->data + t->size : NULL, t->data ? t->cap - t->size : 0, fmt, ap);
        va_end(ap);
        if (t->data && (size_t)n < t->cap - t->size) {
            t->size += (size_t)n;
            return;
        }
        t->cap = t->cap ? 2 * t->cap + (size_t)n : 4096 + (size_t)n;
        t->data = realloc(t->data, t->cap);
        cr_assert_not_null(t->data);
    }
}

const char *sg_test_precompute(const char *scene, const char *dir)
{
    static char cache[4200];
    char vox[4096], skel[4096], imp[4096], cmd[16384], err[4096];
    snprintf(cmd, sizeof cmd,
             "%s %s -o %s/medium.vdb >/dev/null && %s %s/medium.vdb -o %s/skeleton.ply >/dev/null && "
             "%s %s/medium.vdb %s/skeleton.ply -o %s/importance.cache >/dev/null",
             sg_test_program("voxelize", vox, sizeof vox), scene, dir, sg_test_program("skeletonize", skel, sizeof skel),
             dir, dir, sg_test_program("importance", imp, sizeof imp), dir, dir, dir);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 0, "precompute of %s: %s", scene, err);
    snprintf(cache, sizeof cache, "%s/importance.cache", dir);
    return cache;
}
