/* All-or-nothing output files: write to a temporary file in the destination's directory, sync,
 * rename() it over the destination, then sync the directory, so a reader sees the old file or
 * the whole new one and a failed write never leaves a half-written file. A symbolic link is
 * followed (its target is replaced, the link stays), a device or FIFO is written through
 * directly, a directory is refused. Live temporaries are listed so that a signal handler can
 * remove them, and those of killed writers are swept by later ones (docs/io.md). */
#define _XOPEN_SOURCE 700 /* mkstemp, fdopen, fchmod, fsync, lstat, realpath, dirfd, kill */

#include "check.h"

#include <ctype.h>
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <signal.h>
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

/* ---- temporaries left by killed writers --------------------------------------------------- */

/* The temporary's name records its writer, `<path>.tmp.<host>-<pid>.XXXXXX`, so that a later
 * writer on the same host can tell a temporary whose process is gone (SIGKILL, power cut) from
 * one being written now. The host name is kept to [A-Za-z0-9-] and 32 characters. */
enum { WRITER_TAG = 64 }; /* 32 of host, '-', 20 digits of pid */
static void writer_tag(char tag[WRITER_TAG])
{
    char host[64] = "";
    if (gethostname(host, sizeof host - 1) != 0)
        host[0] = '\0';
    host[32] = '\0';
    for (char *c = host; *c; ++c)
        if (!(isalnum((unsigned char)*c) || *c == '-'))
            *c = '-';
    snprintf(tag, WRITER_TAG, "%.32s-%ld", host[0] ? host : "host", (long)getpid());
}

/* The pid of `name` when it is a temporary of this host's writers (`*.tmp.<host>-<pid>.` and
 * six characters), else 0. `host` is ".tmp.<host>-". */
static long temp_owner(const char *name, const char *host)
{
    size_t n = strlen(name), hl = strlen(host);
    if (n < hl + 9 || name[n - 7] != '.')
        return 0;
    for (const char *p = name; (p = strstr(p, host)) != NULL; ++p) {
        const char *q = p + hl;
        long pid = 0;
        while (*q >= '0' && *q <= '9' && pid < 100000000)
            pid = 10 * pid + (*q++ - '0');
        if (q == name + n - 7 && pid > 0)
            return pid;
    }
    return 0;
}

/* Remove the temporaries in `dir` whose writer on this host is no longer running. Each
 * directory is swept once per process (the first SWEPT_DIRS of them), so that a sweep
 * writing thousands of files into one directory reads it once. */
enum { SWEPT_DIRS = 16 };
static void sweep_stale(const char *dir)
{
    static char swept[SWEPT_DIRS][PATH_MAX];
    static int nswept;
    int fresh = 1;
#pragma omp critical(pst_sweep_stale)
    {
        for (int k = 0; k < nswept && fresh; ++k)
            fresh = strcmp(swept[k], dir) != 0;
        fresh = fresh && nswept < SWEPT_DIRS;
        if (fresh)
            strcpy(swept[nswept++], dir); /* dir_of keeps it below PATH_MAX */
    }
    if (!fresh)
        return;
    char tag[WRITER_TAG], host[WRITER_TAG + 8];
    writer_tag(tag);
    snprintf(host, sizeof host, ".tmp.%.*s", (int)(strrchr(tag, '-') - tag + 1), tag);
    DIR *d = opendir(dir);
    if (!d)
        return;
    for (struct dirent *e; (e = readdir(d)) != NULL;) {
        long pid = temp_owner(e->d_name, host);
        if (pid > 0 && pid != (long)getpid() && kill((pid_t)pid, 0) != 0 && errno == ESRCH)
            (void)unlinkat(dirfd(d), e->d_name, 0);
    }
    closedir(d);
}

/* The directory part of `path` into dir ("." without one); 0 or ENAMETOOLONG. */
static int dir_of(const char *path, char dir[PATH_MAX])
{
    const char *slash = strrchr(path, '/');
    if (!slash)
        strcpy(dir, ".");
    else if (slash == path)
        strcpy(dir, "/");
    else if ((size_t)(slash - path) < PATH_MAX)
        snprintf(dir, PATH_MAX, "%.*s", (int)(slash - path), path);
    else
        return ENAMETOOLONG;
    return 0;
}

/* The destination's name with the writer's tag and a mkstemp template appended (malloc'd;
 * NULL on OOM). */
static char *temp_template(const char *path)
{
    char tag[WRITER_TAG];
    writer_tag(tag);
    size_t plen = strlen(path), n = plen + strlen(tag) + sizeof ".tmp..XXXXXX";
    char *tmp = malloc(n);
    if (tmp)
        snprintf(tmp, n, "%s.tmp.%s.XXXXXX", path, tag);
    return tmp;
}

/* Sync the directory that holds `path`, so that the rename survives a crash. File systems
 * that cannot sync a directory (EINVAL) are not an error. */
static int sync_dir(const char *path)
{
    char dir[PATH_MAX];
    if (dir_of(path, dir) != 0)
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
    char dir[PATH_MAX];
    if (dir_of(target, dir) == 0)
        sweep_stale(dir);
    char *tmp = temp_template(target);
    PST_CHECK_ALLOC(tmp, err, "%s: out of memory", path);
    int st = replace(path, target, tmp, write, job, err);
    free(tmp);
    return st;
}
