/* All-or-nothing output files: write to a temporary file in the destination's directory, sync,
 * then rename() over the destination, so a reader sees the old file or the whole new one and a
 * failed write never leaves a half-written file. */
#define _POSIX_C_SOURCE 200809L /* mkstemp, fdopen, fchmod, fsync */

#include "check.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* Fill, flush and sync the temporary file; 0 or an errno value. Closes `fd` in every case. */
static int fill(int fd, void (*write)(FILE *, const void *), const void *job)
{
    FILE *f = fdopen(fd, "w");
    if (!f) {
        int e = errno;
        close(fd);
        return e;
    }
    write(f, job);
    int e = 0;
    if (ferror(f) || fflush(f) != 0 || fsync(fileno(f)) != 0)
        e = errno ? errno : EIO;
    if (fclose(f) != 0 && !e)
        e = errno;
    return e;
}

/* The destination's name with a mkstemp template appended (malloc'd; NULL on OOM). */
static char *temp_template(const char *path)
{
    size_t plen = strlen(path);
    char *tmp = malloc(plen + sizeof ".tmp.XXXXXX");
    if (tmp) {
        memcpy(tmp, path, plen);
        memcpy(tmp + plen, ".tmp.XXXXXX", sizeof ".tmp.XXXXXX");
    }
    return tmp;
}

/* Create the temporary file `tmp` (a mkstemp template), fill it and rename it over `path`; on
 * a failure after its creation it is removed. */
static int write_through(const char *path, char *tmp, void (*write)(FILE *, const void *),
                         const void *job, char *err)
{
    int fd = mkstemp(tmp);
    PST_CHECK(fd < 0, PST_EIO, err, "%s: cannot create a temporary file: %s", path,
              strerror(errno));
    /* mkstemp makes the file 0600; keep the mode of a file being replaced, else 0644 */
    struct stat sb;
    (void)fchmod(fd, stat(path, &sb) == 0 ? (sb.st_mode & 07777) : 0644);
    errno = 0;
    int e = fill(fd, write, job);
    if (e)
        unlink(tmp);
    PST_CHECK(e, PST_EIO, err, "%s: cannot write %s: %s", path, tmp, strerror(e));
    int renamed = rename(tmp, path) == 0;
    e = errno;
    if (!renamed)
        unlink(tmp);
    PST_CHECK(!renamed, PST_EIO, err, "%s: cannot rename %s to it: %s", path, tmp, strerror(e));
    return PST_OK;
}

int pst_write_atomic(const char *path, void (*write)(FILE *, const void *), const void *job,
                     char *err)
{
    char *tmp = temp_template(path);
    PST_CHECK_ALLOC(tmp, err, "%s: out of memory", path);
    int st = write_through(path, tmp, write, job, err);
    free(tmp);
    return st;
}
