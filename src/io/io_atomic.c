/* All-or-nothing output files: write to a temporary file in the destination's directory, sync,
 * rename() it over the destination, then sync the directory, so a reader sees the old file or
 * the whole new one and a failed write never leaves a half-written file. A symbolic link is
 * followed (its target is replaced, the link stays), a device or FIFO is written through
 * directly, a directory is refused. Live temporaries are listed so that a signal handler can
 * remove them (docs/io.md). */
#define _XOPEN_SOURCE 700 /* mkstemp, fdopen, fchmod, fsync, lstat, realpath */

#include "check.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* ---- the registry of live temporaries, read by pst_write_atomic_cleanup in a handler ---- */

enum { LIVE_SLOTS = 8, LIVE_NAME = 4096 };
static char live_name[LIVE_SLOTS][LIVE_NAME];
static atomic_int live_state[LIVE_SLOTS]; /* 0 free, 1 being filled in, 2 live */

/* Claim a slot for `name`; -1 when all are taken or the name is too long (then a signal
 * leaves that temporary behind, nothing worse). */
static int live_add(const char *name)
{
    size_t n = strlen(name);
    if (n >= LIVE_NAME)
        return -1;
    for (int k = 0; k < LIVE_SLOTS; ++k) {
        int expect = 0;
        if (atomic_compare_exchange_strong(&live_state[k], &expect, 1)) {
            memcpy(live_name[k], name, n + 1);
            atomic_store(&live_state[k], 2);
            return k;
        }
    }
    return -1;
}

static void live_remove(int slot)
{
    if (slot >= 0)
        atomic_store(&live_state[slot], 0);
}

void pst_write_atomic_cleanup(void)
{
    for (int k = 0; k < LIVE_SLOTS; ++k) {
        int expect = 2;
        if (atomic_compare_exchange_strong(&live_state[k], &expect, 1)) {
            unlink(live_name[k]); /* async-signal-safe */
            atomic_store(&live_state[k], 0);
        }
    }
}

/* ---- writing ------------------------------------------------------------------------------ */

/* Fill and flush `fd`, and sync it when `sync`; 0 or an errno value. Closes `fd` in every
 * case. */
static int fill(int fd, void (*write)(FILE *, const void *), const void *job, int sync)
{
    FILE *f = fdopen(fd, "w");
    if (!f) {
        int e = errno;
        close(fd);
        return e;
    }
    errno = 0;
    write(f, job);
    int e = 0;
    if (ferror(f) || fflush(f) != 0 || (sync && fsync(fileno(f)) != 0))
        e = errno ? errno : EIO;
    if (fclose(f) != 0 && !e)
        e = errno ? errno : EIO;
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

/* Sync the directory that holds `path`, so that the rename survives a crash. File systems
 * that cannot sync a directory (EINVAL) are not an error. */
static int sync_dir(const char *path)
{
    const char *slash = strrchr(path, '/');
    char dir[PATH_MAX];
    if (!slash)
        strcpy(dir, ".");
    else if (slash == path)
        strcpy(dir, "/");
    else if ((size_t)(slash - path) < sizeof dir)
        snprintf(dir, sizeof dir, "%.*s", (int)(slash - path), path);
    else
        return ENAMETOOLONG;
    int fd = open(dir, O_RDONLY);
    if (fd < 0)
        return errno;
    int e = fsync(fd) != 0 && errno != EINVAL ? errno : 0;
    close(fd);
    return e;
}

/* Create the temporary file `tmp` (a mkstemp template) beside `path`, fill it, rename it over
 * `path` and sync the directory; on a failure before the rename it is removed. `shown` is the
 * name the caller gave, for messages. */
static int replace(const char *shown, const char *path, char *tmp,
                   void (*write)(FILE *, const void *), const void *job, char *err)
{
    int fd = mkstemp(tmp);
    PST_CHECK(fd < 0, PST_EIO, err, "%s: cannot create a temporary file: %s", shown,
              strerror(errno));
    int slot = live_add(tmp);
    /* mkstemp makes the file 0600; keep the mode of a file being replaced, else 0644 */
    struct stat sb;
    (void)fchmod(fd, stat(path, &sb) == 0 ? (sb.st_mode & 07777) : 0644);
    int e = fill(fd, write, job, 1);
    if (e) {
        unlink(tmp);
        live_remove(slot);
    }
    PST_CHECK(e, PST_EIO, err, "%s: cannot write %s: %s", shown, tmp, strerror(e));
    int renamed = rename(tmp, path) == 0;
    e = errno;
    if (!renamed)
        unlink(tmp);
    live_remove(slot);
    PST_CHECK(!renamed, PST_EIO, err, "%s: cannot rename %s to it: %s", shown, tmp, strerror(e));
    e = sync_dir(path);
    PST_CHECK(e, PST_EIO, err, "%s: written, but its directory cannot be synced: %s", shown,
              strerror(e));
    return PST_OK;
}

/* A device, FIFO or socket: write straight into it (no temporary, no rename). */
static int write_into(const char *path, void (*write)(FILE *, const void *), const void *job,
                      char *err)
{
    int fd = open(path, O_WRONLY | O_NOCTTY);
    PST_CHECK(fd < 0, PST_EIO, err, "%s: cannot open: %s", path, strerror(errno));
    int e = fill(fd, write, job, 0);
    PST_CHECK(e, PST_EIO, err, "%s: write error: %s", path, strerror(e));
    return PST_OK;
}

/* The file a symbolic link ends at, in `out`: its real path, or for a dangling link the name
 * its last link points to (the file to create). 0 or an errno value. */
static int follow_link(const char *path, char out[PATH_MAX])
{
    if (realpath(path, out))
        return 0;
    if (errno != ENOENT)
        return errno;
    char cur[PATH_MAX], t[PATH_MAX];
    snprintf(cur, sizeof cur, "%s", path);
    for (int hops = 0; hops < 40; ++hops) {
        ssize_t n = readlink(cur, t, sizeof t - 1);
        if (n < 0)
            return errno;
        t[n] = '\0';
        const char *slash = strrchr(cur, '/');
        int dlen = t[0] == '/' || !slash ? 0 : (int)(slash - cur) + 1; /* relative: beside it */
        if (snprintf(out, PATH_MAX, "%.*s%s", dlen, cur, t) >= PATH_MAX)
            return ENAMETOOLONG;
        struct stat sb;
        if (lstat(out, &sb) != 0)
            return errno == ENOENT ? 0 : errno;
        if (!S_ISLNK(sb.st_mode))
            return ENOENT; /* realpath failed on a directory part */
        snprintf(cur, sizeof cur, "%s", out);
    }
    return ELOOP;
}

int pst_write_atomic(const char *path, void (*write)(FILE *, const void *), const void *job,
                     char *err)
{
    struct stat sb;
    char resolved[PATH_MAX];
    const char *target = path;
    int exists = 0;
    if (lstat(path, &sb) == 0 && S_ISLNK(sb.st_mode)) {
        /* replace the link's target, not the link */
        int e = follow_link(path, resolved);
        PST_CHECK(e, PST_EIO, err, "%s: cannot follow the symbolic link: %s", path, strerror(e));
        target = resolved;
        exists = stat(target, &sb) == 0;
    } else {
        exists = stat(path, &sb) == 0;
    }
    PST_CHECK(exists && S_ISDIR(sb.st_mode), PST_EIO, err, "%s: is a directory", path);
    if (exists && !S_ISREG(sb.st_mode))
        return write_into(path, write, job, err);
    char *tmp = temp_template(target);
    PST_CHECK_ALLOC(tmp, err, "%s: out of memory", path);
    int st = replace(path, target, tmp, write, job, err);
    free(tmp);
    return st;
}
