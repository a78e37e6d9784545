/* Aligned allocation: every hot array of the library comes from here. */
#define _DEFAULT_SOURCE /* madvise, MADV_HUGEPAGE */
#include "internal.h"

#include <malloc.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>

#ifdef PSTENCIL_HAVE_PETSC
/* Debian's PETSc links SuperLU_DIST, which sets glibc's M_MMAP_MAX to 0 when it is loaded: no
 * large block would go back to the system, and a run's resident memory would stay at its peak
 * after the whole neighbour list is freed (docs/scale.md). A library's dependencies are set up
 * before it, and a static consumer links this file with its first allocation, so this puts
 * glibc's default back after them, unless the user set the limit through the environment. */
__attribute__((constructor)) static void glibc_mmap_default(void)
{
    const char *tunables = getenv("GLIBC_TUNABLES");
    if (!getenv("MALLOC_MMAP_MAX_") && !(tunables && strstr(tunables, "mmap_max")))
        mallopt(M_MMAP_MAX, 65536);
}
#endif

/* Arrays of at least this size are placed on 2 MiB boundaries and offered to the kernel as
 * transparent huge pages (where THP is in "madvise" mode, Debian's default). The first touch of
 * a 10^6-particle neighbour list or weight store then takes hundreds of faults instead of
 * hundreds of thousands: measured in a VM, where a fault costs several microseconds, the page
 * faults were 12 % of a qsfdi precompute + store with 4 KiB pages. */
#define PST_HUGE_BYTES ((size_t)8 << 20)
#define PST_HUGE_PAGE ((size_t)2 << 20)

void *pst_alloc(size_t bytes)
{
    if (bytes > SIZE_MAX - PST_HUGE_PAGE)
        return NULL;
    size_t align = bytes >= PST_HUGE_BYTES ? PST_HUGE_PAGE : PST_ALIGN;
    size_t rounded = (bytes + align - 1) / align * align;
    if (rounded == 0)
        rounded = PST_ALIGN;
    void *p = aligned_alloc(align, rounded);
#ifdef MADV_HUGEPAGE
    if (p && align == PST_HUGE_PAGE)
        (void)madvise(p, rounded, MADV_HUGEPAGE); /* a hint: refused, the pages stay small */
#endif
    return p;
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
