/* pst_write_atomic, the one way the library writes a file: the whole file or none. A new file,
 * a replaced file keeping its mode, a write cut short by a file-size limit, a rename onto a
 * folder and a missing folder, each with its message and no temporary file left behind. */
#define _POSIX_C_SOURCE 200809L /* chmod, stat, rmdir */

#include "check.h"
#include "support.h"
#include "pstencil.h"

#include <limits.h>
#include <string.h>
#include <sys/stat.h>
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
    /* a folder in the way: the rename fails after the write */
    snprintf(path, sizeof path, "%s", test_path_in(dir, "a_dir"));
    CHECK(mkdir(path, 0755) == 0);
    CHECK_INT(pst_write_atomic(path, write_text, "x\n", err), PST_EIO);
    CHECK(strstr(err, "a_dir: cannot rename") != NULL);
    CHECK_INT(test_count_temporaries(dir), 0);
    CHECK(rmdir(path) == 0);
    /* no such folder: not even a temporary file */
    snprintf(path, sizeof path, "%s", test_path_in(dir, "no_such_dir/b.txt"));
    CHECK_INT(pst_write_atomic(path, write_text, "x\n", err), PST_EIO);
    CHECK(strstr(err, "no_such_dir/b.txt: cannot create a temporary file") != NULL);
}

int main(void)
{
    if (test_scratch_dir(dir, sizeof dir, "pst_test_atomic") != 0)
        return 1;
    test_new_and_replaced();
    test_failures();
    test_remove_dir(dir);
    return check_summary("test_atomic");
}
