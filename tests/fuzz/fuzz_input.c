/* The fuzz harnesses' inputs: text copies, in-memory files, pieces of text. */
#define _GNU_SOURCE /* memfd_create */

#include "fuzz_input.h"

#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

static void die(const char *what)
{
    perror(what);
    abort();
}

char *fuzz_text(const uint8_t *data, size_t size)
{
    char *t = malloc(size + 1);
    if (!t)
        die("fuzz_text");
    memcpy(t, data, size);
    t[size] = '\0';
    return t;
}

int fuzz_memfile(const uint8_t *data, size_t size, char *path, size_t cap)
{
    int fd = memfd_create("fuzz-input", MFD_CLOEXEC);
    if (fd < 0)
        die("memfd_create");
    for (size_t done = 0; done < size;) {
        ssize_t w = write(fd, data + done, size - done);
        if (w <= 0)
            die("write");
        done += (size_t)w;
    }
    snprintf(path, cap, "/proc/self/fd/%d", fd);
    return fd;
}

int fuzz_split(char *text, char sep, char **piece, int max)
{
    int n = 0;
    piece[n++] = text;
    for (char *p = text; *p && n < max; ++p)
        if (*p == sep) {
            *p = '\0';
            piece[n++] = p + 1;
        }
    return n;
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    omp_set_num_threads(1);
    return 0;
}
