/* Aligned allocation: every hot array of the library comes from here. */
#include "internal.h"

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
