#include "output_file.h"

#include <dirent.h>
#include <errno.h>
#include <signal.h>
#include <stdlib.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

void sg_temp_path(const char *path, char *out, size_t out_size)
{
    const char *slash = strrchr(path, '/');
    int dir_len = slash ? (int)(slash - path + 1) : 0;
    snprintf(out, out_size, "%.*s.%s.tmp.%ld", dir_len, path, slash ? slash + 1 : path,
             (long)getpid());
}

/* Removes the temporaries "dir/.name.tmp.PID" of `path` left by processes
 * that no longer exist (killed mid-write). A live writer's file is kept. */
static void remove_stale_temps(const char *path)
{
    const char *slash = strrchr(path, '/');
    const char *name = slash ? slash + 1 : path;
    char dir_path[4096], prefix[512];
    snprintf(dir_path, sizeof dir_path, "%.*s", slash ? (int)(slash - path) : 1, slash ? path : ".");
    if (slash == path)
        snprintf(dir_path, sizeof dir_path, "/");
    int n = snprintf(prefix, sizeof prefix, ".%s.tmp.", name);
    if (n <= 0 || (size_t)n >= sizeof prefix)
        return;
    DIR *dir = opendir(dir_path);
    if (!dir)
        return;
    struct dirent *ent;
    while ((ent = readdir(dir))) {
        if (strncmp(ent->d_name, prefix, (size_t)n) != 0)
            continue;
        char *end;
        long pid = strtol(ent->d_name + n, &end, 10);
        if (*end || pid <= 0 || pid == (long)getpid())
            continue;
        if (kill((pid_t)pid, 0) == 0 || errno != ESRCH)
            continue; /* alive (or not ours to judge) */
        char stale[4600];
        snprintf(stale, sizeof stale, "%s/%s", dir_path, ent->d_name);
        unlink(stale);
    }
    closedir(dir);
}

bool sg_commit_temp(const char *tmp, const char *path, SgError *err)
{
    /* A full disk may only show when the data reaches it. */
    int fd = open(tmp, O_RDONLY);
    if (fd >= 0) {
        int rc = fsync(fd);
        int e = errno;
        close(fd);
        if (rc != 0 && e != EINVAL && e != EROFS) {
            unlink(tmp);
            return sg_fail(err, "%s: write failed: %s", path, strerror(e));
        }
    }
    if (rename(tmp, path) != 0) {
        int e = errno;
        unlink(tmp);
        return sg_fail(err, "%s: cannot write: %s", path, strerror(e));
    }
    remove_stale_temps(path);
    return true;
}

bool sg_output_open(SgOutputFile *out, const char *path, SgError *err)
{
    memset(out, 0, sizeof *out);
    snprintf(out->path, sizeof out->path, "%s", path);
    sg_temp_path(path, out->tmp, sizeof out->tmp);
    out->file = fopen(out->tmp, "wb");
    if (!out->file)
        return sg_fail(err, "%s: cannot create: %s", path, strerror(errno));
    return true;
}

bool sg_output_commit(SgOutputFile *out, SgError *err)
{
    if (!out->file)
        return sg_fail(err, "%s: output was not open", out->path);
    bool bad = fflush(out->file) != 0 || ferror(out->file);
    int e = errno;
    if (fclose(out->file) != 0)
        bad = true;
    out->file = NULL;
    if (bad) {
        unlink(out->tmp);
        return sg_fail(err, "%s: write failed: %s", out->path, strerror(e ? e : EIO));
    }
    return sg_commit_temp(out->tmp, out->path, err);
}

void sg_output_abort(SgOutputFile *out)
{
    if (out->file) {
        fclose(out->file);
        out->file = NULL;
    }
    if (out->tmp[0])
        unlink(out->tmp);
}
