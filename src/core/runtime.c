/* What the library reports about itself: its version, the threads it will use and the
 * instruction set its dispatched kernels run with. */
#include "internal.h"
#include "isa.h"

#include <omp.h>
#include <stdatomic.h>

#define PST_STR2(x) #x
#define PST_STR(x) PST_STR2(x)
const char *pst_version(void)
{
    return PST_STR(PSTENCIL_VERSION_MAJOR) "." PST_STR(PSTENCIL_VERSION_MINOR) "." PST_STR(
        PSTENCIL_VERSION_PATCH);
}

int pst_threads(void) { return omp_get_max_threads(); }

/* The CPU's level, by the same test as the target_clones resolver of PST_ISA_DISPATCH (isa.h),
 * which picks the widest level the CPU supports; once (the per-level files ask at every apply,
 * and the WLS emission at every row). */
static int cpu_level(void)
{
    static _Atomic int level = -1;
    int l = atomic_load_explicit(&level, memory_order_relaxed);
    if (l >= 0)
        return l;
    l = 0;
#if !defined(PSTENCIL_NO_ISA_DISPATCH) && defined(__x86_64__) && defined(__GNUC__) &&            \
    !defined(__clang__)
    __builtin_cpu_init();
    l = __builtin_cpu_supports("x86-64-v4") ? 2 : __builtin_cpu_supports("x86-64-v3") ? 1 : 0;
#endif
    atomic_store_explicit(&level, l, memory_order_relaxed);
    return l;
}

static _Atomic int level_cap = 2; /* pst_isa_level_cap */

int pst_isa_level(void)
{
    int l = cpu_level(), cap = atomic_load_explicit(&level_cap, memory_order_relaxed);
    return l < cap ? l : cap;
}

int pst_isa_level_cap(int level)
{
    atomic_store_explicit(&level_cap, level < 0 ? 0 : level > 2 ? 2 : level,
                          memory_order_relaxed);
    return pst_isa_level();
}

const char *pst_isa(void)
{
#if defined(PSTENCIL_NATIVE_BUILD)
    return "native";
#else
    static const char *const names[] = {"generic", "x86-64-v3", "x86-64-v4"};
    return names[cpu_level()];
#endif
}
