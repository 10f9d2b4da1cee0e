/* Every input the fuzzers found (tests/fuzz/regressions/NAME/) and every
 * seed (tests/fuzz/corpus/NAME/) goes through the fuzz target NAME itself
 * (its own consistency checks abort) and through the reader's file entry
 * point: each must be accepted or refused with one line naming the file,
 * within a few seconds (some regressions were timeouts). */
#include <criterion/criterion.h>
#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "importance_cache.h"
#include "medium.h"
#include "scene_load.h"
#include "skeleton_graph.h"

/* The fuzz targets, each under its own name. */
#define LLVMFuzzerTestOneInput fuzz_scene_json_one
#include "fuzz/fuzz_scene_json.c"
#undef LLVMFuzzerTestOneInput
#define LLVMFuzzerTestOneInput fuzz_medium_vdb_one
#include "fuzz/fuzz_medium_vdb.c"
#undef LLVMFuzzerTestOneInput
#define LLVMFuzzerTestOneInput fuzz_skeleton_ply_one
#include "fuzz/fuzz_skeleton_ply.c"
#undef LLVMFuzzerTestOneInput
#define LLVMFuzzerTestOneInput fuzz_scene_pbrt_one
#include "fuzz/fuzz_scene_pbrt.c"
#undef LLVMFuzzerTestOneInput
#define LLVMFuzzerTestOneInput fuzz_cache_one
#include "fuzz/fuzz_cache.c"
#undef LLVMFuzzerTestOneInput

typedef int (*FuzzTarget)(const uint8_t *data, size_t size);
/* The reader's own file entry point: true = accepted. */
typedef bool (*FileReader)(const char *path, SgError *err);

static bool read_scene(const char *path, SgError *err)
{
    SgScene *s = sg_scene_load(path, err);
    sg_scene_free(s);
    return s != NULL;
}

static bool read_medium(const char *path, SgError *err)
{
    SgMedium m;
    if (!sg_medium_read(&m, path, err))
        return false;
    sg_medium_release(&m);
    return true;
}

static bool read_skeleton(const char *path, SgError *err)
{
    SgSkeleton s;
    if (!sg_skeleton_read_ply(&s, path, err))
        return false;
    sg_skeleton_release(&s);
    return true;
}

static bool read_cache(const char *path, SgError *err)
{
    SgImportanceCache *c = sg_cache_open(path, err);
    sg_cache_close(c);
    return c != NULL;
}

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static uint8_t *slurp(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    cr_assert_not_null(f, "%s", path);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    uint8_t *data = malloc(n > 0 ? (size_t)n : 1);
    cr_assert_not_null(data);
    cr_assert_eq(fread(data, 1, (size_t)n, f), (size_t)n);
    fclose(f);
    *size = (size_t)n;
    return data;
}

/* Feeds every file of tests/fuzz/{regressions,corpus}/name/; returns how
 * many there were. */
static int feed_folder(const char *name, FuzzTarget target, FileReader reader)
{
    /* sanitized builds run some 10x slower */
    const double limit = getenv("SG_SANITIZED") ? 20.0 : 3.0;
    const char *kinds[] = {"regressions", "corpus"};
    int files = 0;
    for (int k = 0; k < 2; k++) {
        char dir_path[512];
        snprintf(dir_path, sizeof dir_path, "tests/fuzz/%s/%s", kinds[k], name);
        DIR *dir = opendir(dir_path);
        if (!dir)
            continue;
        struct dirent *ent;
        while ((ent = readdir(dir))) {
            if (ent->d_name[0] == '.')
                continue;
            char path[1024];
            snprintf(path, sizeof path, "%s/%s", dir_path, ent->d_name);
            size_t size;
            uint8_t *data = slurp(path, &size);
            double t0 = now();
            target(data, size);
            double t1 = now();
            free(data);
            SgError err = {0};
            bool accepted = reader(path, &err);
            double t2 = now();
            if (!accepted) {
                cr_assert(err.failed, "%s: refused without a message", path);
                cr_assert(strchr(err.message, '\n') == NULL, "%s: message on several lines: %s",
                          path, err.message);
                /* the file itself, or one it refers to beside it */
                cr_assert(strncmp(err.message, dir_path, strlen(dir_path)) == 0,
                          "%s: message does not name the file: %s", path, err.message);
            }
            cr_assert_lt(t1 - t0, limit, "%s: the fuzz target took %.1f s", path, t1 - t0);
            cr_assert_lt(t2 - t1, limit, "%s: the reader took %.1f s", path, t2 - t1);
            files++;
        }
        closedir(dir);
    }
    return files;
}

Test(fuzz_regressions, scene_json, .timeout = 300)
{
    cr_assert_gt(feed_folder("fuzz_scene_json", fuzz_scene_json_one, read_scene), 0);
}

Test(fuzz_regressions, scene_pbrt, .timeout = 300)
{
    cr_assert_gt(feed_folder("fuzz_scene_pbrt", fuzz_scene_pbrt_one, read_scene), 0);
}

Test(fuzz_regressions, medium_vdb, .timeout = 300)
{
    cr_assert_gt(feed_folder("fuzz_medium_vdb", fuzz_medium_vdb_one, read_medium), 0);
}

Test(fuzz_regressions, skeleton_ply, .timeout = 300)
{
    cr_assert_gt(feed_folder("fuzz_skeleton_ply", fuzz_skeleton_ply_one, read_skeleton), 0);
}

Test(fuzz_regressions, cache, .timeout = 300)
{
    cr_assert_gt(feed_folder("fuzz_cache", fuzz_cache_one, read_cache), 0);
}
