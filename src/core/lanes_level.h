/* Blocks as wide as the level's vectors (pst_vl, PST_LW lanes): what the files compiled once
 * per ISA level (src/core/isa.h) share, so that a loop over a row's pairs keeps its blocks and
 * its 8 partial sums in registers at every level. The 8 partial sums are those of 8-lane blocks
 * at every width (neighbour c of a row into sum c mod 8, PST_LSUMS vectors), combined in
 * pst_v8_sum's order: the same bits for every level. Internal; the functions are inlined. */
#ifndef PSTENCIL_LANES_LEVEL_H
#define PSTENCIL_LANES_LEVEL_H

#include "isa.h"
#include "lanes8.h"

#include <stddef.h>
#include <stdint.h>

/* The block width. A file whose functions are compiled for one target (a per-level copy, or a
 * build without dispatch) takes the width of that target's vectors: 8 with AVX-512, 4 with AVX,
 * 2 without. Without AVX-512 GCC 12 has no register for an 8-lane vector and keeps every one
 * that lives across statements in memory (the blocks taken ahead, the row's centre and sums),
 * copying it between stack slots 16 bytes at a time: the x86-64-v3 copies of the lane rows,
 * in 8-lane blocks, took 2.2-5.6x the time of the AVX-512 ones, in 4-lane blocks 1.4-2.0x
 * (docs/building.md, "Vector instructions"). A file with target_clones functions compiles one
 * source for the three levels and keeps 8. */
#if defined(PST_ISA_CLONES) || defined(__AVX512F__)
#define PST_LW 8
typedef pst_v8 pst_vl;
#elif defined(__AVX__)
#define PST_LW 4
typedef pst_v4 pst_vl;
#else
#define PST_LW 2
typedef pst_v2 pst_vl;
#endif
#define PST_LSUMS (PST_LANES / PST_LW) /* the vectors of a row's 8 partial sums */

/* a in every lane. */
PST_V8_INLINE pst_vl pst_vl_splat(double a)
{
#if PST_LW == 8
    return pst_v8_splat(a);
#elif PST_LW == 4
    return pst_v4_splat(a);
#else
    return (pst_vl){a, a};
#endif
}

/* a[s j[0]], ..., a[s j[PST_LW - 1]] (s: the stride). */
PST_V8_INLINE pst_vl pst_vl_gather_stride(const double *a, size_t s, const uint32_t *j)
{
#if PST_LW == 8
    return pst_v8_gather_stride(a, s, j);
#elif PST_LW == 4
    return pst_v4_gather_stride(a, s, j);
#else
    return (pst_vl){a[s * j[0]], a[s * j[1]]};
#endif
}

/* a[j[0]], ..., a[j[PST_LW - 1]]. */
PST_V8_INLINE pst_vl pst_vl_gather(const double *a, const uint32_t *j)
{
    return pst_vl_gather_stride(a, 1, j);
}

/* pst_v8_add_below for a block of PST_LW lanes: acc + terms in the lanes l < len, acc in the
 * others. */
PST_V8_INLINE pst_vl pst_vl_add_below(pst_vl acc, pst_vl terms, double len)
{
#if PST_LW == 8
    return pst_v8_add_below(acc, terms, 0, pst_v8_splat(len));
#elif PST_LW == 4
    return pst_v4_add_below(acc, terms, 0, pst_v4_splat(len));
#else
    const pst_v2 lane_no = {0, 1};
    pst_v2 sum = acc + terms;
    pst_v2i keep = lane_no < (pst_v2){len, len};
    return (pst_v2)(((pst_v2i)sum & keep) | ((pst_v2i)acc & ~keep));
#endif
}

#if PST_LW < 8
/* rows[l][0..PST_LW) for l < PST_LW as PST_LW vectors, out[c][l] = rows[l][c]. */
PST_V8_INLINE void pst_vl_transpose(const double *const rows[PST_LW], pst_vl out[PST_LW])
{
#if PST_LW == 4
    pst_v4_transpose4(rows, out);
#else
    pst_v2_transpose2(rows, out);
#endif
}
#endif

/* Rows j[0 .. PST_LW) of the packed rows (x, y, z, u) as four vectors, one per column (with 8
 * lanes pst_v8_rows4; with 4, one 4 x 4 transpose; with 2, two 2 x 2 ones). */
PST_V8_INLINE void pst_vl_rows4(const double *rows, const uint32_t *j, pst_vl *x, pst_vl *y,
                                pst_vl *z, pst_vl *u)
{
#if PST_LW == 8
    pst_v8_rows4(rows, j, x, y, z, u);
#else
    const double *p[PST_LW];
    for (int l = 0; l < PST_LW; ++l)
        p[l] = rows + 4 * (size_t)j[l];
    pst_vl c[4];
    pst_vl_transpose(p, c);
    if (PST_LW == 2) {
        for (int l = 0; l < PST_LW; ++l)
            p[l] += 2;
        pst_vl_transpose(p, c + 2);
    }
    *x = c[0];
    *y = c[1];
    *z = c[2];
    *u = c[3];
#endif
}

/* The sum of a row's 8 partial sums (sum c mod 8 in lane c mod PST_LW of acc[(c mod 8) /
 * PST_LW]) in pst_v8_sum's order, ((s0 + s4) + (s2 + s6)) + ((s1 + s5) + (s3 + s7)): the same
 * bits for every width. */
PST_V8_INLINE double pst_lanes_sum(const pst_vl acc[PST_LSUMS])
{
#if PST_LW == 8
    return pst_v8_sum(acc[0]);
#elif PST_LW == 4
    return pst_v4_sum_halves(acc[0], acc[1]);
#else
    pst_v2 t = (acc[0] + acc[2]) + (acc[1] + acc[3]);
    return t[0] + t[1];
#endif
}

#endif /* PSTENCIL_LANES_LEVEL_H */
