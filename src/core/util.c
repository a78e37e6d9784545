/* Aligned allocation, error strings and the version: the small shared helpers. */
#include "internal.h"

#include <omp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

void *pst_alloc(size_t bytes)
{
    if (bytes > SIZE_MAX - PST_ALIGN)
        return NULL;
    size_t rounded = (bytes + PST_ALIGN - 1) / PST_ALIGN * PST_ALIGN;
    if (rounded == 0)
        rounded = PST_ALIGN;
    return aligned_alloc(PST_ALIGN, rounded);
}

void *pst_calloc(size_t count, size_t size)
{
    if (size != 0 && count > SIZE_MAX / size)
        return NULL;
    void *p = pst_alloc(count * size);
    if (p)
        memset(p, 0, count * size);
    return p;
}

void pst_free(void *p) { free(p); }

void pst_set_err(char *err, const char *fmt, ...)
{
    if (!err)
        return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err, PST_ERRLEN, fmt, ap);
    va_end(ap);
}

const char *pst_strerror(int status)
{
    switch (status) {
    case PST_OK: return "ok";
    case PST_EINVAL: return "invalid argument";
    case PST_EINPUT: return "bad input data";
    case PST_ENOMEM: return "out of memory";
    case PST_EIO: return "input/output error";
    case PST_ENUMERIC: return "numerical failure";
    default: return "unknown status";
    }
}

#define PST_STR2(x) #x
#define PST_STR(x) PST_STR2(x)
const char *pst_version(void)
{
    return PST_STR(PSTENCIL_VERSION_MAJOR) "." PST_STR(PSTENCIL_VERSION_MINOR) "." PST_STR(
        PSTENCIL_VERSION_PATCH);
}

int pst_threads(void) { return omp_get_max_threads(); }
