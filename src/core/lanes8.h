/* Eight doubles as one value (pst_v8): GCC / Clang vector extensions, not intrinsics, so
 * each ISA clone of a PST_ISA_DISPATCH function (isa.h) compiles them to its own registers
 * (one AVX-512 register, two AVX2 or four SSE2 registers per vector; without AVX-512 not for
 * a variable a loop carries, which stays in memory: "Half vectors" below) with the same IEEE
 * operations in every clone: the results do not depend on the ISA. The hot loops that keep
 * 8 partial sums use them (src/core/lanes_level.h, kernels/lanes.h; the stored apply in halves,
 * below). Internal; the functions are inlined. */
#ifndef PSTENCIL_LANES8_H
#define PSTENCIL_LANES8_H

#include <stdint.h>
#include <string.h>

#if !defined(__clang__) && defined(__GNUC__) && __GNUC__ < 12
#error "pst_v8 needs __builtin_shufflevector (GCC 12 or later, or Clang)"
#endif
/* Every function taking or returning a pst_v8 is inlined: the library builds with -Wno-psabi
 * (CMakeLists.txt), since GCC's notes on the ABI of 64-byte vectors do not apply. */

#define PST_LANES 8
#define PST_V8_INLINE static inline __attribute__((always_inline))

typedef double pst_v8 __attribute__((vector_size(64)));
typedef double pst_v4 __attribute__((vector_size(32)));
typedef double pst_v2 __attribute__((vector_size(16)));
typedef int64_t pst_v8i __attribute__((vector_size(64))); /* a comparison's lanes: 0 or -1 */
typedef float pst_v8f __attribute__((vector_size(32)));
typedef int64_t pst_v4i __attribute__((vector_size(32)));
typedef int64_t pst_v2i __attribute__((vector_size(16)));

/* Vectors of run-time values are built as shuffles of short initialisers, never as an
 * initialiser of 8 elements: in the AVX-512 clones of a target_clones function
 * (src/core/isa.h) GCC 12 compiles that to a chain of 8 dependent masked broadcasts, one per
 * lane, a splat included (a constant initialiser is one load). */

/* a in every lane: one broadcast (a shuffle of {a, a} went through the stack). */
PST_V8_INLINE pst_v8 pst_v8_splat(double a)
{
    pst_v4 v = {a};
    return __builtin_shufflevector(v, v, 0, 0, 0, 0, 0, 0, 0, 0);
}

/* The lanes' sum in one fixed order, ((a0 + a4) + (a2 + a6)) + ((a1 + a5) + (a3 + a7)), as
 * halves added in registers: element reads had GCC store the vector and load its lanes back, a
 * stalled store-to-load forwarding per row (a fifth of a 17-pair row's stored apply). */
PST_V8_INLINE double pst_v8_sum(pst_v8 a)
{
    pst_v4 s =
        __builtin_shufflevector(a, a, 0, 1, 2, 3) + __builtin_shufflevector(a, a, 4, 5, 6, 7);
    pst_v2 t = __builtin_shufflevector(s, s, 0, 1) + __builtin_shufflevector(s, s, 2, 3);
    return t[0] + t[1];
}

/* acc + terms in the lanes l with from + l < len (len in every lane), acc in the others: by a
 * select, so the lanes past a row's end add nothing, not even a zero (the same bits as adding
 * the row's last terms one by one). */
PST_V8_INLINE pst_v8 pst_v8_add_below(pst_v8 acc, pst_v8 terms, double from, pst_v8 len)
{
    const pst_v8 lane_no = {0, 1, 2, 3, 4, 5, 6, 7};
    pst_v8 sum = acc + terms;
    pst_v8i keep = lane_no + pst_v8_splat(from) < len;
    return (pst_v8)(((pst_v8i)sum & keep) | ((pst_v8i)acc & ~keep));
}

/* a[s j[0]], ..., a[s j[7]] (s: the stride), as a tree of pairs (a loop of element stores
 * also became a chain of masked merges). */
PST_V8_INLINE pst_v8 pst_v8_gather_stride(const double *a, size_t s, const uint32_t *j)
{
    pst_v2 p0 = {a[s * j[0]], a[s * j[1]]}, p1 = {a[s * j[2]], a[s * j[3]]},
           p2 = {a[s * j[4]], a[s * j[5]]}, p3 = {a[s * j[6]], a[s * j[7]]};
    return __builtin_shufflevector(__builtin_shufflevector(p0, p1, 0, 1, 2, 3),
                                   __builtin_shufflevector(p2, p3, 0, 1, 2, 3), 0, 1, 2, 3, 4, 5,
                                   6, 7);
}

/* a[j[0]], ..., a[j[7]]. */
PST_V8_INLINE pst_v8 pst_v8_gather(const double *a, const uint32_t *j)
{
    return pst_v8_gather_stride(a, 1, j);
}

/* Half vectors (pst_v4: lanes 0-3 or 4-7 of an 8-lane block), for values that a loop carries
 * from one block to the next, such as a row's partial sums: without AVX-512 (the x86-64-v3 and
 * generic clones) GCC 12 keeps a pst_v8 variable in memory and loads and stores it around every
 * operation, where two pst_v4 stay in registers (with AVX2; the generic SSE2 clone keeps them in
 * memory too); with AVX-512 the two halves cost what one pst_v8 does. The stored apply
 * (src/operator/operator_store.c) ran 3-7x faster in an x86-64-v3 build with its partial sums
 * as halves (docs/building.md, "Vector instructions"). */

/* a in every lane of a half. */
PST_V8_INLINE pst_v4 pst_v4_splat(double a)
{
    pst_v2 v = {a};
    return __builtin_shufflevector(v, v, 0, 0, 0, 0);
}

/* a[s j[0]], ..., a[s j[3]] (s: the stride). */
PST_V8_INLINE pst_v4 pst_v4_gather_stride(const double *a, size_t s, const uint32_t *j)
{
    pst_v2 p0 = {a[s * j[0]], a[s * j[1]]}, p1 = {a[s * j[2]], a[s * j[3]]};
    return __builtin_shufflevector(p0, p1, 0, 1, 2, 3);
}

/* a[j[0]], ..., a[j[3]]. */
PST_V8_INLINE pst_v4 pst_v4_gather(const double *a, const uint32_t *j)
{
    return pst_v4_gather_stride(a, 1, j);
}

/* rows[l][0..4) for l < 4 as four vectors, out[c][l] = rows[l][c]: four 32-byte loads and two
 * rounds of 4 shuffles (pairs of elements, then of 128-bit pieces). The loads' loop is unrolled:
 * as a loop, GCC 12's x86-64-v3 code copied the rows to the stack 16 bytes at a time and loaded
 * them back 32 at a time, a failed store-to-load forwarding per row, and the AVX2 matrix-free
 * applies took twice as long (docs/building.md, "Vector instructions"). */
PST_V8_INLINE void pst_v4_transpose4(const double *const rows[4], pst_v4 out[4])
{
    pst_v4 r[4];
#pragma GCC unroll 4
    for (int l = 0; l < 4; ++l)
        memcpy(&r[l], rows[l], sizeof r[l]);
    pst_v4 e01 = __builtin_shufflevector(r[0], r[1], 0, 4, 2, 6);
    pst_v4 o01 = __builtin_shufflevector(r[0], r[1], 1, 5, 3, 7);
    pst_v4 e23 = __builtin_shufflevector(r[2], r[3], 0, 4, 2, 6);
    pst_v4 o23 = __builtin_shufflevector(r[2], r[3], 1, 5, 3, 7);
    out[0] = __builtin_shufflevector(e01, e23, 0, 1, 4, 5);
    out[1] = __builtin_shufflevector(o01, o23, 0, 1, 4, 5);
    out[2] = __builtin_shufflevector(e01, e23, 2, 3, 6, 7);
    out[3] = __builtin_shufflevector(o01, o23, 2, 3, 6, 7);
}

/* rows[l][0..2) for l < 2 as two vectors, out[c][l] = rows[l][c]. */
PST_V8_INLINE void pst_v2_transpose2(const double *const rows[2], pst_v2 out[2])
{
    pst_v2 r0, r1;
    memcpy(&r0, rows[0], sizeof r0);
    memcpy(&r1, rows[1], sizeof r1);
    out[0] = __builtin_shufflevector(r0, r1, 0, 2);
    out[1] = __builtin_shufflevector(r0, r1, 1, 3);
}

/* f[0..8) widened to double (exactly) as two halves: one load and one conversion with AVX-512
 * (two conversions of halves took 10 % longer in the float store's apply; a loop of element
 * conversions became element loads and inserts). */
PST_V8_INLINE void pst_v4_widen_halves(const float *f, pst_v4 *lo, pst_v4 *hi)
{
    pst_v8f v;
    memcpy(&v, f, sizeof v);
    pst_v8 w = __builtin_convertvector(v, pst_v8);
    *lo = __builtin_shufflevector(w, w, 0, 1, 2, 3);
    *hi = __builtin_shufflevector(w, w, 4, 5, 6, 7);
}

/* pst_v8_add_below for the half whose first lane is block lane `from`. */
PST_V8_INLINE pst_v4 pst_v4_add_below(pst_v4 acc, pst_v4 terms, double from, pst_v4 len)
{
    const pst_v4 lane_no = {0, 1, 2, 3};
    pst_v4 sum = acc + terms;
    pst_v4i keep = lane_no + pst_v4_splat(from) < len;
    return (pst_v4)(((pst_v4i)sum & keep) | ((pst_v4i)acc & ~keep));
}

/* pst_v8_sum of the block whose lanes 0-3 are lo and 4-7 are hi: the same order, so the
 * same bits. */
PST_V8_INLINE double pst_v4_sum_halves(pst_v4 lo, pst_v4 hi)
{
    pst_v4 s = lo + hi;
    pst_v2 t = __builtin_shufflevector(s, s, 0, 1) + __builtin_shufflevector(s, s, 2, 3);
    return t[0] + t[1];
}

/* Row j of an array of rows of 4 doubles (32 bytes each). */
PST_V8_INLINE pst_v4 pst_v8_row4(const double *rows, uint32_t j)
{
    pst_v4 p;
    memcpy(&p, rows + 4 * (size_t)j, sizeof p);
    return p;
}

/* Rows j[0..8) of an array of rows of 4 doubles (the packed positions and values of the lane
 * rows, (x, y, z, u)) as four vectors, one per column: each pair of rows (l, l + 4) in one
 * 64-byte register, then interleaves of pairs of registers (x0 x1 z0 z1 x4 x5 z4 z5 and
 * y0 y1 u0 u1 ...) and a last shuffle into lane order: four 32-byte loads and 12 shuffles where
 * element loads would take 32 loads and as many merges. */
PST_V8_INLINE void pst_v8_rows4(const double *rows, const uint32_t *j, pst_v8 *c0, pst_v8 *c1,
                                pst_v8 *c2, pst_v8 *c3)
{
    pst_v8 p04 = __builtin_shufflevector(pst_v8_row4(rows, j[0]), pst_v8_row4(rows, j[4]), 0, 1,
                                         2, 3, 4, 5, 6, 7);
    pst_v8 p15 = __builtin_shufflevector(pst_v8_row4(rows, j[1]), pst_v8_row4(rows, j[5]), 0, 1,
                                         2, 3, 4, 5, 6, 7);
    pst_v8 p26 = __builtin_shufflevector(pst_v8_row4(rows, j[2]), pst_v8_row4(rows, j[6]), 0, 1,
                                         2, 3, 4, 5, 6, 7);
    pst_v8 p37 = __builtin_shufflevector(pst_v8_row4(rows, j[3]), pst_v8_row4(rows, j[7]), 0, 1,
                                         2, 3, 4, 5, 6, 7);
    pst_v8 l01 = __builtin_shufflevector(p04, p15, 0, 8, 2, 10, 4, 12, 6, 14);
    pst_v8 h01 = __builtin_shufflevector(p04, p15, 1, 9, 3, 11, 5, 13, 7, 15);
    pst_v8 l23 = __builtin_shufflevector(p26, p37, 0, 8, 2, 10, 4, 12, 6, 14);
    pst_v8 h23 = __builtin_shufflevector(p26, p37, 1, 9, 3, 11, 5, 13, 7, 15);
    *c0 = __builtin_shufflevector(l01, l23, 0, 1, 8, 9, 4, 5, 12, 13);
    *c2 = __builtin_shufflevector(l01, l23, 2, 3, 10, 11, 6, 7, 14, 15);
    *c1 = __builtin_shufflevector(h01, h23, 0, 1, 8, 9, 4, 5, 12, 13);
    *c3 = __builtin_shufflevector(h01, h23, 2, 3, 10, 11, 6, 7, 14, 15);
}

/* rows[l][0..8) for l < 8 as eight vectors, out[c][l] = rows[l][c]: eight 64-byte loads and
 * three rounds of 8 shuffles (pairs of elements, of 128-bit and of 256-bit pieces), where
 * element loads would take 64 loads and 56 merges. */
PST_V8_INLINE void pst_v8_transpose8(const double *const rows[8], pst_v8 out[8])
{
    pst_v8 r[8];
    for (int l = 0; l < 8; ++l)
        memcpy(&r[l], rows[l], sizeof r[l]);
    pst_v8 e01 = __builtin_shufflevector(r[0], r[1], 0, 8, 2, 10, 4, 12, 6, 14);
    pst_v8 o01 = __builtin_shufflevector(r[0], r[1], 1, 9, 3, 11, 5, 13, 7, 15);
    pst_v8 e23 = __builtin_shufflevector(r[2], r[3], 0, 8, 2, 10, 4, 12, 6, 14);
    pst_v8 o23 = __builtin_shufflevector(r[2], r[3], 1, 9, 3, 11, 5, 13, 7, 15);
    pst_v8 e45 = __builtin_shufflevector(r[4], r[5], 0, 8, 2, 10, 4, 12, 6, 14);
    pst_v8 o45 = __builtin_shufflevector(r[4], r[5], 1, 9, 3, 11, 5, 13, 7, 15);
    pst_v8 e67 = __builtin_shufflevector(r[6], r[7], 0, 8, 2, 10, 4, 12, 6, 14);
    pst_v8 o67 = __builtin_shufflevector(r[6], r[7], 1, 9, 3, 11, 5, 13, 7, 15);
    /* columns (0, 4), (2, 6), (1, 5), (3, 7) of rows 0-3, then of rows 4-7 */
    pst_v8 a04 = __builtin_shufflevector(e01, e23, 0, 1, 8, 9, 4, 5, 12, 13);
    pst_v8 a26 = __builtin_shufflevector(e01, e23, 2, 3, 10, 11, 6, 7, 14, 15);
    pst_v8 a15 = __builtin_shufflevector(o01, o23, 0, 1, 8, 9, 4, 5, 12, 13);
    pst_v8 a37 = __builtin_shufflevector(o01, o23, 2, 3, 10, 11, 6, 7, 14, 15);
    pst_v8 b04 = __builtin_shufflevector(e45, e67, 0, 1, 8, 9, 4, 5, 12, 13);
    pst_v8 b26 = __builtin_shufflevector(e45, e67, 2, 3, 10, 11, 6, 7, 14, 15);
    pst_v8 b15 = __builtin_shufflevector(o45, o67, 0, 1, 8, 9, 4, 5, 12, 13);
    pst_v8 b37 = __builtin_shufflevector(o45, o67, 2, 3, 10, 11, 6, 7, 14, 15);
    out[0] = __builtin_shufflevector(a04, b04, 0, 1, 2, 3, 8, 9, 10, 11);
    out[4] = __builtin_shufflevector(a04, b04, 4, 5, 6, 7, 12, 13, 14, 15);
    out[2] = __builtin_shufflevector(a26, b26, 0, 1, 2, 3, 8, 9, 10, 11);
    out[6] = __builtin_shufflevector(a26, b26, 4, 5, 6, 7, 12, 13, 14, 15);
    out[1] = __builtin_shufflevector(a15, b15, 0, 1, 2, 3, 8, 9, 10, 11);
    out[5] = __builtin_shufflevector(a15, b15, 4, 5, 6, 7, 12, 13, 14, 15);
    out[3] = __builtin_shufflevector(a37, b37, 0, 1, 2, 3, 8, 9, 10, 11);
    out[7] = __builtin_shufflevector(a37, b37, 4, 5, 6, 7, 12, 13, 14, 15);
}

#endif /* PSTENCIL_LANES8_H */
