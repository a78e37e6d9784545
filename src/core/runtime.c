/* What the library reports about itself: its version, the threads it will use and the
 * instruction set its dispatched kernels run with. */
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

/* The same test as the target_clones resolver of PST_ISA_DISPATCH (isa.h), which picks the
 * widest level the CPU supports. */
const char *pst_isa(void)
{
#if defined(PSTENCIL_NATIVE_BUILD)
    return "native";
#elif !defined(PSTENCIL_NO_ISA_DISPATCH) && defined(__x86_64__) && defined(__GNUC__) &&          \
    !defined(__clang__)
    __builtin_cpu_init();
    if (__builtin_cpu_supports("x86-64-v4"))
        return "x86-64-v4";
    if (__builtin_cpu_supports("x86-64-v3"))
        return "x86-64-v3";
    return "generic";
#else
    return "generic";
#endif
}
