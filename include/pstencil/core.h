/* pstencil: Status codes, the error convention, version, threads and atomic file writes. Part of the public API; include <pstencil.h>. */
#ifndef PSTENCIL_PUBLIC_CORE_H
#define PSTENCIL_PUBLIC_CORE_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

#define PSTENCIL_VERSION_MAJOR 0
#define PSTENCIL_VERSION_MINOR 1
#define PSTENCIL_VERSION_PATCH 0

/* ------------------------------------------------------------------------------------------ */
/* Status codes                                                                               */
/* ------------------------------------------------------------------------------------------ */

enum {
    PST_OK = 0,
    PST_EINVAL = -1,   /* a bad argument from the caller (wrong dimension, negative size, ...) */
    PST_EINPUT = -2,   /* bad input data: malformed file, NaN, duplicate particles, ...        */
    PST_ENOMEM = -3,   /* an allocation failed, or an estimate exceeds the allowed memory       */
    PST_EIO = -4,      /* a file could not be opened, written or renamed                       */
    PST_ENUMERIC = -5  /* a numerical failure (singular system, no convergence)                 */
};

/* A static, human-readable name of a status code ("ok", "invalid argument", ...). */
const char *pst_strerror(int status);

/* The library version as "MAJOR.MINOR.PATCH". */
const char *pst_version(void);

/* Size of the error-detail buffers (`char *err`, the last argument of every call that can fail
 * for more than one reason; NULL is allowed and then no message is written). */
#define PST_ERRLEN 512

/* Rewrite the control bytes (0x01-0x1f, 0x7f) of the string msg, in its buffer of cap bytes,
 * as \xNN, cutting the end (never inside an escape) when it no longer fits: a message that
 * quotes input stays one printable line. The library's messages are written so. */
void pst_escape_controls(char *msg, size_t cap);

/* ------------------------------------------------------------------------------------------ */
/* Files                                                                                      */
/* ------------------------------------------------------------------------------------------ */

/* Write `path` all or nothing: write(f, job) fills a temporary file in the same directory,
 * which is synced and renamed over `path`, and the directory is synced. A symbolic link is
 * followed (its target is replaced, the link stays a link); a device, FIFO or socket is written
 * into directly (no temporary); a directory is refused. PST_EIO (message in err) on any
 * failure, and then a regular `path` is untouched and no temporary file is left. */
int pst_write_atomic(const char *path, void (*write)(FILE *f, const void *job), const void *job,
                     char *err);

/* Remove the temporary files of the pst_write_atomic calls in progress. Async-signal-safe: for
 * a SIGINT/SIGTERM/SIGHUP handler that then re-raises the signal (the program installs one). */
void pst_write_atomic_cleanup(void);

/* ------------------------------------------------------------------------------------------ */
/* Progress of long calls                                                                     */
/* ------------------------------------------------------------------------------------------ */

/* A progress hook: fn(user, done, total) reports that `done` of the call's `total` units of
 * work (rows, points) are finished. The calls that take one (pst_nlist_build_with,
 * pst_op_create through pst_op_opts.progress, and pst_op_gradient, pst_op_hessian and
 * pst_op_interpolate through the operator's hook) call it at a coarse grain: once per chunk of
 * rows (512 to 8192), from whichever thread finished the chunk, an OpenMP worker thread
 * included. The library guarantees that fn is never entered by two threads at once (a thread
 * that finds it busy skips its report: nobody waits on it), that `done` never decreases
 * within one call, and that a call that succeeds ends with a call where done == total, made
 * from the calling thread. fn must return quickly, must not call the library on the objects
 * of the call in progress and must not jump out. fn == NULL: no hook, which costs one branch
 * per chunk. Results are the same, bit for bit, with and without a hook. docs/cli.md,
 * "Progress". */
typedef void (*pst_progress_fn)(void *user, uint64_t done, uint64_t total);
typedef struct {
    pst_progress_fn fn; /* NULL: none */
    void *user;         /* passed to fn as it is */
} pst_progress;

/* ------------------------------------------------------------------------------------------ */
/* Threads                                                                                    */
/* ------------------------------------------------------------------------------------------ */

/* The number of OpenMP threads the library will use (omp_get_max_threads). */
int pst_threads(void);

/* The instruction set the hot kernels run with (docs/building.md, "Vector instructions"):
 * "x86-64-v4" (AVX-512), "x86-64-v3" (AVX2 + FMA) or "generic", chosen at load time from the
 * CPU; "native" for a -march=native build and "generic" where the build has no dispatch. A
 * static string. */
const char *pst_isa(void);

#ifdef __cplusplus
}
#endif

#endif /* PSTENCIL_PUBLIC_CORE_H */
