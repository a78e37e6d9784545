/* pst_write_atomic, the one way the library writes a file: the whole file or none. A new file,
 * a replaced file keeping its mode, a write cut short by a file-size limit, a folder in the
 * way and a missing folder, each with its message and no temporary file left behind; a
 * symbolic link followed, devices and FIFOs written into, the temporaries a signal handler
 * removes and those of killed writers that a later writer sweeps. */
#define _POSIX_C_SOURCE 200809L /* chmod, stat, rmdir, symlink, mkfifo, readlink */

#include "check.h"
#include "support.h"
#include "pstencil.h"

#include <dirent.h>
#include <fcntl.h>
#include <limits.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

static char dir[64];

static void write_text(FILE *f, const void *job) { fputs(job, f); }

/* 64 KiB of text: more than the file-size limit below lets through. */
static void write_big(FILE *f, const void *job)
{
    (void)job;
    for (int k = 0; k < 4096; ++k)
        fputs("0123456789abcde\n", f);
}

static char limit_err[PST_ERRLEN];
static int write_big_to(const void *path)
{
    return pst_write_atomic(path, write_big, NULL, limit_err);
}

static void test_new_and_replaced(void)
{
    char err[PST_ERRLEN] = "", path[256];
    snprintf(path, sizeof path, "%s", test_path_in(dir, "a.txt"));
    CHECK_INT(pst_write_atomic(path, write_text, "first\n", err), PST_OK);
    CHECK(test_file_holds(path, "first\n"));
    struct stat sb;
    CHECK(stat(path, &sb) == 0 && (sb.st_mode & 07777) == 0644);
    /* a replaced file keeps its mode */
    CHECK(chmod(path, 0640) == 0);
    CHECK_INT(pst_write_atomic(path, write_text, "second\n", err), PST_OK);
    CHECK(test_file_holds(path, "second\n"));
    CHECK(stat(path, &sb) == 0 && (sb.st_mode & 07777) == 0640);
    CHECK_INT(test_count_temporaries(dir), 0);
}

static void test_failures(void)
{
    char err[PST_ERRLEN] = "", path[256];
    /* cut short by a file-size limit: the old file stays as it was */
    snprintf(path, sizeof path, "%s", test_path_in(dir, "keep.txt"));
    CHECK(test_write_text(path, "old contents\n") == 0);
    CHECK_INT(test_under_file_limit(4096, write_big_to, path), PST_EIO);
    CHECK(strstr(limit_err, "keep.txt: cannot write") != NULL);
    CHECK(test_file_holds(path, "old contents\n"));
    CHECK_INT(test_count_temporaries(dir), 0);
    CHECK_INT(pst_write_atomic(path, write_big, NULL, err), PST_OK); /* without the limit */
    CHECK(!test_file_holds(path, "old contents\n"));
    /* a folder in the way: refused before anything is written */
    snprintf(path, sizeof path, "%s", test_path_in(dir, "a_dir"));
    CHECK(mkdir(path, 0755) == 0);
    CHECK_INT(pst_write_atomic(path, write_text, "x\n", err), PST_EIO);
    CHECK(strstr(err, "a_dir: is a directory") != NULL);
    CHECK_INT(test_count_temporaries(dir), 0);
    CHECK(rmdir(path) == 0);
    /* no such folder: not even a temporary file */
    snprintf(path, sizeof path, "%s", test_path_in(dir, "no_such_dir/b.txt"));
    CHECK_INT(pst_write_atomic(path, write_text, "x\n", err), PST_EIO);
    CHECK(strstr(err, "no_such_dir/b.txt: cannot create a temporary file") != NULL);
}

/* A link is followed: its target gets the new contents and the link stays a link. */
static void test_symlink(void)
{
    char err[PST_ERRLEN] = "", target[256], link[256], buf[256];
    snprintf(target, sizeof target, "%s", test_path_in(dir, "target.txt"));
    snprintf(link, sizeof link, "%s", test_path_in(dir, "link.txt"));
    CHECK(test_write_text(target, "old\n") == 0);
    CHECK(symlink("target.txt", link) == 0);
    CHECK_INT(pst_write_atomic(link, write_text, "new\n", err), PST_OK);
    struct stat sb;
    CHECK(lstat(link, &sb) == 0 && S_ISLNK(sb.st_mode));
    ssize_t n = readlink(link, buf, sizeof buf - 1);
    CHECK(n == (ssize_t)strlen("target.txt") && memcmp(buf, "target.txt", (size_t)n) == 0);
    CHECK(test_file_holds(target, "new\n"));
    CHECK_INT(test_count_temporaries(dir), 0);
    /* a dangling link: its target is created */
    CHECK(unlink(target) == 0);
    CHECK_INT(pst_write_atomic(link, write_text, "created\n", err), PST_OK);
    CHECK(lstat(link, &sb) == 0 && S_ISLNK(sb.st_mode));
    CHECK(test_file_holds(target, "created\n"));
    CHECK_INT(test_count_temporaries(dir), 0);
    /* a link into a missing folder: the message names the link */
    CHECK(unlink(link) == 0);
    CHECK(symlink("no_such_dir/t.txt", link) == 0);
    CHECK_INT(pst_write_atomic(link, write_text, "x\n", err), PST_EIO);
    CHECK(strstr(err, "link.txt: cannot create a temporary file") != NULL);
    CHECK(unlink(link) == 0);
    CHECK(unlink(target) == 0);
}

/* Devices and FIFOs are written into, never replaced; a full device fails with its reason. */
static void test_devices(void)
{
    char err[PST_ERRLEN] = "", fifo[256];
    struct stat sb;
    CHECK_INT(pst_write_atomic("/dev/null", write_text, "x\n", err), PST_OK);
    CHECK(stat("/dev/null", &sb) == 0 && S_ISCHR(sb.st_mode));
    if (stat("/dev/full", &sb) == 0) {
        CHECK_INT(pst_write_atomic("/dev/full", write_big, NULL, err), PST_EIO);
        CHECK(strstr(err, "/dev/full: write error: ") != NULL);
        CHECK(stat("/dev/full", &sb) == 0 && S_ISCHR(sb.st_mode));
    }
    snprintf(fifo, sizeof fifo, "%s", test_path_in(dir, "pipe"));
    CHECK(mkfifo(fifo, 0600) == 0);
    int rd = open(fifo, O_RDONLY | O_NONBLOCK); /* a reader, so that the writer's open returns */
    CHECK(rd >= 0);
    CHECK_INT(pst_write_atomic(fifo, write_text, "through\n", err), PST_OK);
    char buf[16] = "";
    CHECK(read(rd, buf, sizeof buf - 1) == 8 && strcmp(buf, "through\n") == 0);
    close(rd);
    CHECK(lstat(fifo, &sb) == 0 && S_ISFIFO(sb.st_mode));
    CHECK_INT(test_count_temporaries(dir), 0);
    CHECK(unlink(fifo) == 0);
}

/* What a signal handler does in the middle of a write: the live temporary goes, and the write
 * then fails (its temporary cannot be renamed) leaving the old file as it was. */
static int temps_seen;
static void write_interrupted(FILE *f, const void *job)
{
    (void)job;
    fputs("partial\n", f);
    temps_seen = test_count_temporaries(dir);
    pst_write_atomic_cleanup();
}

static void test_cleanup(void)
{
    char err[PST_ERRLEN] = "", path[256];
    snprintf(path, sizeof path, "%s", test_path_in(dir, "signalled.txt"));
    CHECK(test_write_text(path, "old\n") == 0);
    CHECK_INT(pst_write_atomic(path, write_interrupted, NULL, err), PST_EIO);
    CHECK_INT(temps_seen, 1);
    CHECK_INT(test_count_temporaries(dir), 0);
    CHECK(test_file_holds(path, "old\n"));
    pst_write_atomic_cleanup(); /* nothing live: a no-op */
    CHECK_INT(pst_write_atomic(path, write_text, "new\n", err), PST_OK);
    CHECK(test_file_holds(path, "new\n"));
}

/* The live temporary's name, seen from inside a write: "<host>-" of its writer's tag goes to
 * the job (io_atomic.c: "<path>.tmp.<host>-<pid>.XXXXXX"). */
static void write_seeing_tag(FILE *f, const void *job)
{
    char *tag = (char *)job;
    DIR *d = opendir(dir);
    for (struct dirent *e; d && (e = readdir(d));) {
        const char *t = strstr(e->d_name, ".tmp.");
        const char *dash = t ? strrchr(e->d_name, '-') : NULL;
        if (dash && dash > t + 5)
            snprintf(tag, 48, "%.*s", (int)(dash - (t + 5) + 1), t + 5);
    }
    if (d)
        closedir(d);
    fputs("tagged\n", f);
}

/* Temporaries of a writer that is gone (a child that has exited) are removed by the next write
 * into their directory; those of a live process, of another host and lookalike names stay. */
static void test_stale_sweep(void)
{
    char err[PST_ERRLEN] = "", sub[128], host[48], name[5][320];
    snprintf(sub, sizeof sub, "%s", test_path_in(dir, "stale"));
    CHECK(mkdir(sub, 0755) == 0);
    host[0] = '\0';
    CHECK_INT(pst_write_atomic(test_path_in(dir, "tagged.txt"), write_seeing_tag, host, err),
              PST_OK);
    CHECK(host[0] != '\0');
    pid_t child = fork();
    if (child == 0)
        _exit(0);
    CHECK(child > 0 && waitpid(child, NULL, 0) == child);
    snprintf(name[0], sizeof name[0], "%s/out.csv.tmp.%s%ld.a1B2c3", sub, host, (long)child);
    snprintf(name[1], sizeof name[1], "%s/other.vtu.tmp.%s%ld.zzzzzz", sub, host, (long)child);
    snprintf(name[2], sizeof name[2], "%s/out.csv.tmp.%s%ld.a1B2c3", sub, host, (long)getppid());
    snprintf(name[3], sizeof name[3], "%s/out.csv.tmp.elsewhere-%ld.a1B2c3", sub, (long)child);
    snprintf(name[4], sizeof name[4], "%s/out.csv.tmp.%s%ld.txt", sub, host, (long)child);
    for (int k = 0; k < 5; ++k)
        CHECK(test_write_text(name[k], "left\n") == 0);
    char out[200];
    snprintf(out, sizeof out, "%s/out.csv", sub);
    CHECK_INT(pst_write_atomic(out, write_text, "new\n", err), PST_OK);
    CHECK(test_file_holds(out, "new\n"));
    for (int k = 0; k < 5; ++k) {
        int gone = access(name[k], F_OK) != 0;
        CHECK_INT(gone, k < 2); /* the dead writer's two temporaries, of any output */
        unlink(name[k]);
    }
    unlink(out);
    rmdir(sub);
}

int main(void)
{
    if (test_scratch_dir(dir, sizeof dir, "pst_test_atomic") != 0)
        return 1;
    test_new_and_replaced();
    test_failures();
    test_symlink();
    test_devices();
    test_cleanup();
    test_stale_sweep();
    test_remove_dir(dir);
    return check_summary("test_atomic");
}
