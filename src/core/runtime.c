/* What the library reports about itself: its version and the threads it will use. */
#include "internal.h"

#include <omp.h>

#define PST_STR2(x) #x
#define PST_STR(x) PST_STR2(x)
const char *pst_version(void)
{
    return PST_STR(PSTENCIL_VERSION_MAJOR) "." PST_STR(PSTENCIL_VERSION_MINOR) "." PST_STR(
        PSTENCIL_VERSION_PATCH);
}

int pst_threads(void) { return omp_get_max_threads(); }
