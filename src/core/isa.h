/* Runtime ISA dispatch of the hot kernels, in two forms.
 *
 * A function marked PST_ISA_DISPATCH is compiled three times, for generic x86-64, x86-64-v3
 * (AVX2, FMA) and x86-64-v4 (AVX-512), and the loader picks the widest one the CPU has (GCC's
 * target_clones). The default build thus uses the vector units it finds without -march;
 * pst_isa() names the choice. Mark the function that holds a hot loop, not its always_inline
 * helpers (they are inlined into each clone) and not an OpenMP region (GCC outlines the region
 * into a function the clones do not reach): the region calls the marked function per row or per
 * block. The call costs an indirect jump, a few ns against the hundreds of a row.
 *
 * The files whose code should differ between the levels, not only its instructions (the
 * matrix-free rows in lanes: kernels/lanes.h takes blocks as wide as the level's vectors), are
 * compiled once per level instead (PSTENCIL_LEVEL_SOURCES in CMakeLists.txt): CMake defines
 * PST_LEVEL (v4, v3 or generic) and passes the level's -march to each copy. Such a file names
 * its entry points PST_LEVEL_NAME(f), and its header declares them with PST_LEVEL_ENTRY, which
 * gives the callers an f that calls the copy of the CPU's level.
 *
 * The build takes one path only when it is told to (-march=native, PSTENCIL_NATIVE) or when the
 * compiler has no target_clones for this target (PSTENCIL_NO_ISA_DISPATCH, set by CMake): then
 * the per-level files are compiled once, for the build's target, with their plain names. */
#ifndef PSTENCIL_ISA_H
#define PSTENCIL_ISA_H

#if defined(PST_LEVEL)
#define PST_ISA_DISPATCH /* a per-level copy is compiled for its level alone */
#elif !defined(PSTENCIL_NO_ISA_DISPATCH) && defined(__x86_64__) && defined(__GNUC__) &&          \
    !defined(__clang__)
#define PST_ISA_CLONES 1 /* this file's PST_ISA_DISPATCH functions are compiled three times */
#define PST_ISA_DISPATCH                                                                       \
    __attribute__((target_clones("default", "arch=x86-64-v3", "arch=x86-64-v4")))
#else
#define PST_ISA_DISPATCH
#endif

#define PST_LEVEL_CAT2(f, level) f##_##level
#define PST_LEVEL_CAT(f, level) PST_LEVEL_CAT2(f, level)
#if defined(PST_LEVEL)
#define PST_LEVEL_NAME(f) PST_LEVEL_CAT(f, PST_LEVEL)
#else
#define PST_LEVEL_NAME(f) f
#endif

/* The level the per-level files run at on this CPU: 2 for x86-64-v4, 1 for x86-64-v3, 0 for
 * generic x86-64 (the target_clones resolver's choice; runtime.c), or lower when capped. */
int pst_isa_level(void);

/* For tests and benchmarks: the per-level files run the copy of the lower of level (clamped to
 * 0..2) and the CPU's level from now on; 2 lifts the cap. Returns the level in effect. The
 * target_clones functions keep the loader's choice, and pst_isa() still names the CPU's level.
 * Call it between operations, not while another thread runs the library's kernels. */
int pst_isa_level_cap(int level);

/* Declares the entry point f (returning ret, parameters params, called with args) of a file
 * compiled per level: with dispatch, its three copies and a static inline f that calls the
 * CPU's; without, f itself. PST_LEVEL_ENTRY_VOID for an f that returns nothing. */
#if !defined(PSTENCIL_NO_ISA_DISPATCH) && defined(__x86_64__) && defined(__GNUC__) &&            \
    !defined(__clang__)
#define PST_LEVEL_COPIES(ret, f, params)                                                       \
    ret f##_v4 params;                                                                         \
    ret f##_v3 params;                                                                         \
    ret f##_generic params;
#define PST_LEVEL_PICK(level, f, args)                                                         \
    ((level) == 2 ? f##_v4 args : (level) == 1 ? f##_v3 args : f##_generic args)
#define PST_LEVEL_ENTRY(ret, f, params, args)                                                  \
    PST_LEVEL_COPIES(ret, f, params)                                                           \
    static inline ret f params                                                                 \
    {                                                                                          \
        const int pst_level_ = pst_isa_level();                                                \
        return PST_LEVEL_PICK(pst_level_, f, args);                                            \
    }
#define PST_LEVEL_ENTRY_VOID(f, params, args)                                                  \
    PST_LEVEL_COPIES(void, f, params)                                                          \
    static inline void f params                                                                \
    {                                                                                          \
        const int pst_level_ = pst_isa_level();                                                \
        PST_LEVEL_PICK(pst_level_, f, args);                                                   \
    }
#else
#define PST_LEVEL_ENTRY(ret, f, params, args) ret f params;
#define PST_LEVEL_ENTRY_VOID(f, params, args) void f params;
#endif

#endif /* PSTENCIL_ISA_H */
