#include "output_file.h"

#include <errno.h>
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

bool sg_commit_temp(const char *tmp, const char *path, SgError *err)
{
    int fd = open(tmp, O_RDONLY);
    if (fd >= 0) {
        fsync(fd);
        close(fd);
    }
    if (rename(tmp, path) != 0) {
        int e = errno;
        unlink(tmp);
        return sg_fail(err, "%s: cannot write: %s", path, strerror(e));
    }
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
