/* Eight doubles as one value (pst_v8): GCC / Clang vector extensions, not intrinsics, so
 * each ISA clone of a PST_ISA_DISPATCH function (isa.h) compiles them to its own registers
 * (one AVX-512 register, two AVX2 or four SSE2 registers per vector) with the same IEEE
 * operations in every clone: the results do not depend on the ISA. The hot loops that keep
 * 8 partial sums use them (kernels/lanes.h, the stored apply). Internal; the functions are
 * inlined. */
#ifndef PSTENCIL_LANES8_H
#define PSTENCIL_LANES8_H

#include <stdint.h>

#if !defined(__clang__) && defined(__GNUC__) && __GNUC__ < 12
#error "pst_v8 needs __builtin_shufflevector (GCC 12 or later, or Clang)"
#endif
#if !defined(__clang__) && defined(__GNUC__)
/* 64-byte vectors cross no call boundary here (every function is inlined), so the ABI note
 * GCC gives for them without AVX-512 does not apply. */
#pragma GCC diagnostic ignored "-Wpsabi"
#endif

#define PST_LANES 8
#define PST_V8_INLINE static inline __attribute__((always_inline))

typedef double pst_v8 __attribute__((vector_size(64)));
typedef double pst_v4 __attribute__((vector_size(32)));
typedef int64_t pst_v8i __attribute__((vector_size(64))); /* a comparison's lanes: 0 or -1 */

PST_V8_INLINE pst_v8 pst_v8_splat(double a) { return (pst_v8){a, a, a, a, a, a, a, a}; }

/* The lanes' sum in one fixed order (kernels/wls.h's pst_dot_sum has the same). */
PST_V8_INLINE double pst_v8_sum(pst_v8 a)
{
    return ((a[0] + a[4]) + (a[2] + a[6])) + ((a[1] + a[5]) + (a[3] + a[7]));
}

#endif /* PSTENCIL_LANES8_H */
