/* The library's private base: aligned allocation and the error-message helper (check.h builds
 * the check macros on it). Not installed. */
#ifndef PSTENCIL_INTERNAL_H
#define PSTENCIL_INTERNAL_H

#include "pstencil.h"

#include <stdarg.h>
#include <stdio.h>

/* Every hot array is 64-byte aligned (one cache line, one AVX-512 vector). */
#define PST_ALIGN 64

/* Allocate `bytes` (rounded up to PST_ALIGN) aligned to PST_ALIGN; NULL on failure or when the
 * size overflows. Free with pst_free. A zero-byte request returns a valid, freeable pointer. */
void *pst_alloc(size_t bytes);
/* Same, zero-filled. */
void *pst_calloc(size_t count, size_t size);
void pst_free(void *p);

/* Write a formatted message into an error buffer of PST_ERRLEN bytes (NULL is ignored). */
void pst_set_err(char *err, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

#endif
