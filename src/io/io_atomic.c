/* All-or-nothing output files: write to a temporary file in the destination's directory, sync,
 * then rename() over the destination, so a reader sees the old file or the whole new one and a
 * failed write never leaves a half-written file. Also the inverse of a cloud's ids, which every
 * writer needs to emit rows in input order. */
#define _POSIX_C_SOURCE 200809L /* mkstemp, fdopen, fchmod, fsync */

#include "internal.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

int pst_cloud_input_inverse(const pst_cloud *c, size_t **inv_out, char *err)
{
    size_t n = c->n, *inv = malloc((n ? n : 1) * sizeof *inv);
    if (!inv) {
        pst_set_err(err, "out of memory for %zu row indices", n);
        return PST_ENOMEM;
    }
    for (size_t r = 0; r < n; ++r)
        inv[r] = SIZE_MAX;
    for (size_t i = 0; i < n; ++i) {
        int64_t id = c->id[i];
        if (id < 0 || (uint64_t)id >= n || inv[id] != SIZE_MAX) {
            pst_set_err(err, "the cloud's ids are not a permutation of 0..%zu (particle %zu "
                             "has id %lld)",
                        n ? n - 1 : 0, i, (long long)id);
            free(inv);
            return PST_EINVAL;
        }
        inv[id] = i;
    }
    *inv_out = inv;
    return PST_OK;
}

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

int pst_write_atomic(const char *path, void (*write)(FILE *, const void *), const void *job,
                     char *err)
{
    size_t plen = strlen(path);
    char *tmp = malloc(plen + sizeof ".tmp.XXXXXX");
    if (!tmp) {
        pst_set_err(err, "%s: out of memory", path);
        return PST_ENOMEM;
    }
    memcpy(tmp, path, plen);
    memcpy(tmp + plen, ".tmp.XXXXXX", sizeof ".tmp.XXXXXX");
    int fd = mkstemp(tmp);
    if (fd < 0) {
        pst_set_err(err, "%s: cannot create a temporary file: %s", path, strerror(errno));
        free(tmp);
        return PST_EIO;
    }
    /* mkstemp makes the file 0600; keep the mode of a file being replaced, else 0644 */
    struct stat sb;
    (void)fchmod(fd, stat(path, &sb) == 0 ? (sb.st_mode & 07777) : 0644);
    errno = 0;
    int st = PST_OK;
    int e = fill(fd, write, job);
    if (e) {
        pst_set_err(err, "%s: cannot write %s: %s", path, tmp, strerror(e));
        unlink(tmp);
        st = PST_EIO;
    } else if (rename(tmp, path) != 0) {
        pst_set_err(err, "%s: cannot rename %s to it: %s", path, tmp, strerror(errno));
        unlink(tmp);
        st = PST_EIO;
    }
    free(tmp);
    return st;
}
