/* Runtime ISA dispatch of the hot kernels. A function marked PST_ISA_DISPATCH is compiled three
 * times, for generic x86-64, x86-64-v3 (AVX2, FMA) and x86-64-v4 (AVX-512), and the loader picks
 * the widest one the CPU has (GCC's target_clones). The default build thus uses the vector units
 * it finds without -march; pst_isa() names the choice.
 *
 * Mark the function that holds a hot loop, not its always_inline helpers (they are inlined into
 * each clone) and not an OpenMP region (GCC outlines the region into a function the clones do
 * not reach): the region calls the marked function per row or per block. The call costs an
 * indirect jump, a few ns against the hundreds of a row.
 *
 * The build takes one path only when it is told to (-march=native, PSTENCIL_NATIVE) or when the
 * compiler has no target_clones for this target (PSTENCIL_NO_ISA_DISPATCH, set by CMake). */
#ifndef PSTENCIL_ISA_H
#define PSTENCIL_ISA_H

#if !defined(PSTENCIL_NO_ISA_DISPATCH) && defined(__x86_64__) && defined(__GNUC__) &&            \
    !defined(__clang__)
#define PST_ISA_DISPATCH __attribute__((target_clones("default", "arch=x86-64-v3", "arch=x86-64-v4")))
#else
#define PST_ISA_DISPATCH
#endif

#endif /* PSTENCIL_ISA_H */
