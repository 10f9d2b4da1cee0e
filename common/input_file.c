#include "input_file.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

bool sg_read_file(const char *path, const char *what, size_t max_bytes, char **data, size_t *size, SgError *err)
{
    *data = NULL;
    *size = 0;
    const char *space = what ? " " : "", *name = what ? what : "";
    FILE *f = fopen(path, "rb");
    if (!f)
        return sg_fail(err, "%s: cannot open%s%s: %s", path, space, name, strerror(errno));
    /* a regular file's size is known: one allocation; a pipe grows */
    struct stat st;
    size_t cap = fstat(fileno(f), &st) == 0 && S_ISREG(st.st_mode) && st.st_size >= 0 ? (size_t)st.st_size + 1
                                                                                      : (size_t)1 << 16;
    if (cap - 1 > max_bytes) {
        fclose(f);
        return sg_fail(err, "%s: larger than %zu MB: not a%s%s this program reads", path, max_bytes >> 20,
                       what ? " " : "n input", name);
    }
    char *buf = malloc(cap);
    size_t n = 0;
    bool ok = buf != NULL;
    if (!ok)
        sg_fail(err, "%s: out of memory", path);
    while (ok) {
        if (n + 1 == cap) { /* full: more to come (a pipe, or a file that grew)? */
            int c = fgetc(f);
            if (c == EOF) {
                if (ferror(f))
                    ok = sg_fail(err, "%s: read error: %s", path, strerror(errno));
                break;
            }
            if (cap - 1 >= max_bytes) {
                ok = sg_fail(err, "%s: larger than %zu MB: not a%s%s this program reads", path, max_bytes >> 20,
                             what ? " " : "n input", name);
                break;
            }
            size_t next = cap * 2 > max_bytes + 1 ? max_bytes + 1 : cap * 2;
            char *grown = realloc(buf, next);
            if (!grown) {
                ok = sg_fail(err, "%s: out of memory", path);
                break;
            }
            buf = grown;
            cap = next;
            buf[n++] = (char)c;
        }
        size_t got = fread(buf + n, 1, cap - 1 - n, f);
        n += got;
        if (got == 0) {
            if (ferror(f))
                ok = sg_fail(err, "%s: read error: %s", path, strerror(errno));
            break;
        }
    }
    fclose(f);
    if (!ok) {
        free(buf);
        return false;
    }
    buf[n] = 0;
    *data = buf;
    *size = n;
    return true;
}

bool sg_has_extension(const char *path, const char *ext)
{
    size_t n = strlen(path), e = strlen(ext);
    return n > e && !strcasecmp(path + n - e, ext);
}

void sg_folder_of(const char *path, char *out, size_t size)
{
    const char *slash = strrchr(path, '/');
    snprintf(out, size, "%.*s", slash ? (int)(slash - path + 1) : 0, path);
}
