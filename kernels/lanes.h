/* Pairs a block at a time: the matrix-free rows (docs/operators.md, "Matrix-free rows in
 * lanes").
 *
 * A row's neighbours are taken PST_LW at a time, as many as the vectors of the level the file
 * is compiled for hold (src/core/lanes_level.h). Their positions and values come from the
 * packed array op->xyzu, (x, y, z, u) per particle (pst_op_apply fills u): one 32-byte load per
 * neighbour and a transpose in vector shuffles give one vector per component, where
 * per-element gathers of four separate arrays cost about four times the instructions
 * (pst_lanes_pairs, src/operator/operator_lanes.h, which the flatness check shares). The
 * scheme's pair arithmetic then runs once per lane over these vectors (its own scalar inline
 * functions in a loop over the lanes, which the compiler turns into vector instructions), so a
 * weight is bit for bit the one its emission computes pair by pair; and the products
 * w (u_J - u_I) go into 8 partial sums, neighbour c into sum c mod 8 (8 / PST_LW vectors,
 * pst_lanes_sum), combined in pst_v8_sum's order: the apply's row sum is the same for every
 * level, block width and thread count.
 *
 * The vectors are those of src/core/lanes_level.h and lanes8.h. Internal; every function is
 * inlined into the row that calls it. */
#ifndef PSTENCIL_LANES_H
#define PSTENCIL_LANES_H

#include "kernel_common.h"
#include "lanes_level.h"
#include "operator_lanes.h"

#include <math.h>
#include <string.h>

/* Row i of the kernel context k's packed rows, scaled by ih. */
PST_KHOT pst_lanes pst_lanes_row(const pst_kctx *k, size_t i, double ih)
{
    const double *p = k->xyzu + 4 * i;
    pst_lanes L = {.xyzu = k->xyzu, .i = i, .xi = pst_vl_splat(p[0]), .yi = pst_vl_splat(p[1]),
                   .zi = pst_vl_splat(p[2]), .ui = pst_vl_splat(p[3]), .ih = pst_vl_splat(ih),
                   .im = k->im};
    for (int s = 0; s < PST_LSUMS; ++s)
        L.acc[s] = pst_vl_splat(0.0);
    return L;
}

/* The neighbours idx[0..n) of row L into arrays, for the rows that work a chunk at a time:
 * the scaled offsets at x[a * stride + c] (a < 3) and u_J - u_I at du[c]. Writes up to n
 * rounded up to a multiple of 8 (the padded lanes), whatever the block width. */
PST_KHOT void pst_lanes_gather(const pst_lanes *L, const uint32_t *idx, int n, double *x,
                               int stride, double *du)
{
    for (int c = 0; c < (n + PST_LANES - 1) / PST_LANES * PST_LANES; c += PST_LW) {
        uint32_t pad[PST_LW];
        pst_vl X, Y, Z, U;
        pst_lanes_pairs(L, idx, c, n, pad, &X, &Y, &Z, &U);
        memcpy(x + c, &X, sizeof X);
        memcpy(x + stride + c, &Y, sizeof Y);
        memcpy(x + 2 * stride + c, &Z, sizeof Z);
        memcpy(du + c, &U, sizeof U);
    }
}

/* acc + terms in the block's first n lanes (all for n >= PST_LW, none for n <= 0): the lanes
 * past a row's end are kept out by a select (pst_vl_add_below). */
PST_KHOT pst_vl pst_lanes_add(pst_vl acc, pst_vl terms, int64_t n)
{
    return n >= PST_LW ? acc + terms : pst_vl_add_below(acc, terms, (double)n);
}

/* acc[c mod 8] += t[c] du[c] for c < n (du: u_J - u_I), neighbour c in lane c mod 8 across
 * consecutive calls of one row (every call but the last takes a multiple of 8), then
 * pst_v8_sum: the lanes of the rows that work a chunk at a time. t and du are read in whole
 * blocks of 8 (up to n rounded up; the lanes past n may hold any value, finite or not): the
 * last block adds through a select, so its lanes past n add nothing and no loop runs a scalar
 * tail. The loop carries the sums as two halves (src/core/lanes8.h, "Half vectors": as one
 * pst_v8 they stayed in memory in the AVX2 clones), the same bits. */
PST_KHOT pst_v8 pst_lanes_dot_blocks(int n, const double *t, const double *du, pst_v8 acc)
{
    pst_v4 lo = __builtin_shufflevector(acc, acc, 0, 1, 2, 3);
    pst_v4 hi = __builtin_shufflevector(acc, acc, 4, 5, 6, 7);
    for (int c = 0; c < n; c += PST_LANES) {
        pst_v4 t0, t1, d0, d1;
        memcpy(&t0, t + c, sizeof t0);
        memcpy(&t1, t + c + 4, sizeof t1);
        memcpy(&d0, du + c, sizeof d0);
        memcpy(&d1, du + c + 4, sizeof d1);
        if (n - c >= PST_LANES) {
            lo += t0 * d0;
            hi += t1 * d1;
        } else {
            const pst_v4 len = pst_v4_splat((double)(n - c));
            lo = pst_v4_add_below(lo, t0 * d0, 0, len);
            hi = pst_v4_add_below(hi, t1 * d1, 4, len);
        }
    }
    return __builtin_shufflevector(lo, hi, 0, 1, 2, 3, 4, 5, 6, 7);
}

/* A block of PST_LW pairs as the matrix-free rows (and qsfdi's data moments) take it: the
 * scaled offsets x, y, z, u_J - u_I, the squared scaled distance d2 (x x + y y [+ z z], the
 * schemes' own order) and its square root q; j, its neighbours (for gathers of per-particle
 * values); n, how many of them are the row's (PST_LW but in a row's last blocks; 0 or less
 * past its end); and s, which of the row's partial sums its lanes go to (acc[s]). */
typedef struct {
    pst_vl x, y, z, du, d2, q;
    const uint32_t *j;
    int n, s;
} pst_lanes_block;

/* The block of row L's pairs from idx[e] (dimension D; the row ends at e1; s its partial
 * sums): idx[e .. e + PST_LW) where the list has them (e + PST_LW <= lim), the lanes past e1
 * then the next row's neighbours; else padded as pst_lanes_pairs pads (pad is its scratch).
 * Then d2 and q. */
PST_KHOT void pst_lanes_take(const pst_lanes *L, int D, const uint32_t *idx, int64_t e,
                             int64_t e1, int64_t lim, int s, uint32_t pad[PST_LW],
                             pst_lanes_block *b)
{
    b->n = e1 - e < PST_LW ? (int)(e1 - e) : PST_LW;
    b->s = s;
    b->j = pst_lanes_pairs(L, idx, e, e + PST_LW <= lim ? e + PST_LW : e1, pad, &b->x, &b->y,
                           &b->z, &b->du);
    b->d2 = b->x * b->x + b->y * b->y + (D == 3 ? b->z * b->z : pst_vl_splat(0.0));
#pragma omp simd
    for (int l = 0; l < PST_LW; ++l)
        b->q[l] = sqrt(b->d2[l]);
}

/* The half-list rows on a cloud with h per particle take their blocks unscaled (pst_lanes_row
 * with 1/h = 1: b->x = x_J - x_I) and scale each direction by its own row's 1/h, so that each
 * weight is bit for bit what its row's whole-list apply computes for the pair. These two give
 * the scale factors and one lane's scaled offset. */

/* -1/h_J for the block's neighbours, J's factor: (x_I - x_J) / h_J is (x_J - x_I) (-1/h_J)
 * exactly, and 1/h_J the same IEEE quotient as row J's scalar 1.0 / h_J. */
PST_KHOT pst_vl pst_lanes_back_scale(const double *h, const pst_lanes_block *b)
{
    return -(pst_vl_splat(1.0) / pst_vl_gather(h, b->j));
}

/* Lane l of the unscaled block b seen from a row of factor f (1/h_I, or J's -1/h_J): the
 * scaled offset into x, y, z and its d2, returned, in pst_lanes_take's order. */
PST_KHOT double pst_lanes_lane_scaled(const pst_lanes_block *b, int D, int l, double f,
                                      double *x, double *y, double *z)
{
    *x = b->x[l] * f;
    *y = b->y[l] * f;
    *z = b->z[l] * f;
    return *x * *x + *y * *y + (D == 3 ? *z * *z : 0.0);
}

/* The nk coefficients of the block's neighbours, rows of nk doubles in coef (row J at
 * coef + nk J), as vectors: c[m][l] = coef[nk j[l] + m] for m < nk <= 16. With 8 lanes by 8 x 8
 * transposes (8 < nk: two, the second of the row's last 8 coefficients; nk <= 8: one, of 8
 * doubles from each row's start, so coef must extend 8 - nk doubles past its last row); with
 * 4 or 2 lanes by transposes of PST_LW x PST_LW pieces, the last one ending at the row's end
 * (nk >= PST_LW). The half-list rows read the other row's coefficients this way: with 8 lanes
 * 16 loads and 48 shuffles per block, where per-element gathers took 15 x 8 loads and GCC left
 * the loop scalar. */
PST_KHOT void pst_lanes_coefs(const double *coef, int nk, const uint32_t *j, pst_vl c[16])
{
    const double *p[PST_LW];
    for (int l = 0; l < PST_LW; ++l)
        p[l] = coef + (size_t)nk * j[l];
#if PST_LW == 8
    const double *q[PST_LANES];
    for (int l = 0; l < PST_LANES; ++l)
        q[l] = p[l] + (nk - PST_LANES);
    pst_v8_transpose8(p, c);
    if (nk > PST_LANES)
        pst_v8_transpose8(q, c + (nk - PST_LANES));
#else
    for (int m0 = 0; m0 < nk; m0 += PST_LW) {
        const int m = m0 + PST_LW <= nk ? m0 : nk - PST_LW;
        const double *q[PST_LW];
        for (int l = 0; l < PST_LW; ++l)
            q[l] = p[l] + m;
        pst_vl_transpose(q, c + m);
    }
#endif
}

/* One block of a half-list row (pairs (I, J > I)) with both of its weights: y_J -= a_JI
 * (u_J - u_I) for the block's pairs whose J is not a Dirichlet row, one at a time (the lanes
 * hold different J), and acc + a_IJ (u_J - u_I) returned for row I's sum. */
PST_KHOT pst_vl pst_lanes_half_add(pst_vl acc, pst_vl wij, pst_vl wji, const pst_lanes_block *b,
                                   const uint8_t *kind, double *y)
{
    pst_vl t = wji * b->du;
    for (int l = 0; l < b->n; ++l)
        if (kind[b->j[l]] != PST_DIRICHLET)
            y[b->j[l]] -= t[l];
    return pst_lanes_add(acc, wij * b->du, b->n);
}

/* The pairs idx[e0 .. e1) of row L (dimension D), PST_LW at a time: `step`, a statement in b
 * (a const pst_lanes_block *), for each block in order, over whole groups of 8 (the blocks of
 * a row's last group past e1 have b->n <= 0), so that the lanes are those of 8-lane blocks
 * whatever the width. The blocks read idx up to lim (pst_lanes_take): e1 pads a row's last
 * blocks with the row's own particle, a degenerate pair that adds exactly 0; a farther lim (the
 * list's length) takes the next row's neighbours there, which the step keeps out of its sums
 * (pst_lanes_add with b->n). Each block is taken (its loads, transposes and sqrt) one block
 * ahead of the step that uses it: the latency of the loads and of the sqrt then overlaps the
 * previous block's arithmetic, where in program order the core's scheduler did not reach that
 * far (3D 10^6, 1 and 2 threads: 13-21 % off the qsfdi, lpmps and lsmps applies; two blocks
 * ahead gained nothing more). The same operations in the same order as one block at a time:
 * the same bits. */
#define PST_LANES_EACH_TO(L, D, idx, e0, e1, lim, b, step)                                     \
    do {                                                                                       \
        const int64_t pst_0_ = (e0), pst_n_ = (e1), pst_l_ = (lim);                            \
        const int64_t pst_end_ =                                                               \
            pst_0_ + (pst_n_ - pst_0_ + PST_LANES - 1) / PST_LANES * PST_LANES;                \
        uint32_t pst_pa_[PST_LW], pst_pb_[PST_LW];                                             \
        pst_lanes_block pst_a_, pst_b_;                                                        \
        int64_t pst_e_ = pst_0_;                                                               \
        if (pst_e_ < pst_end_)                                                                 \
            pst_lanes_take(&(L), D, idx, pst_e_, pst_n_, pst_l_, 0, pst_pa_, &pst_a_);         \
        for (; pst_e_ < pst_end_; pst_e_ += 2 * PST_LW) {                                      \
            const int pst_s_ = (int)((pst_e_ - pst_0_) / PST_LW % PST_LSUMS);                  \
            if (pst_e_ + PST_LW < pst_end_)                                                    \
                pst_lanes_take(&(L), D, idx, pst_e_ + PST_LW, pst_n_, pst_l_,                  \
                               (pst_s_ + 1) % PST_LSUMS, pst_pb_, &pst_b_);                    \
            {                                                                                  \
                const pst_lanes_block *b = &pst_a_;                                            \
                step;                                                                          \
            }                                                                                  \
            if (pst_e_ + PST_LW >= pst_end_)                                                   \
                break;                                                                         \
            if (pst_e_ + 2 * PST_LW < pst_end_)                                                \
                pst_lanes_take(&(L), D, idx, pst_e_ + 2 * PST_LW, pst_n_, pst_l_,              \
                               (pst_s_ + 2) % PST_LSUMS, pst_pa_, &pst_a_);                    \
            {                                                                                  \
                const pst_lanes_block *b = &pst_b_;                                            \
                step;                                                                          \
            }                                                                                  \
        }                                                                                      \
    } while (0)

/* PST_LANES_EACH_TO with the row's last blocks padded. */
#define PST_LANES_EACH(L, D, idx, e0, e1, b, step) PST_LANES_EACH_TO(L, D, idx, e0, e1, e1, b, step)

/* The pairs idx[e0 .. e1) of row L (dimension D) into L.acc: for each block (b), `weights`,
 * an expression in b, times u_J - u_I (PST_LANES_EACH). */
#define PST_LANES_ROW(L, D, idx, e0, e1, b, weights)                                           \
    PST_LANES_EACH(L, D, idx, e0, e1, b, (L).acc[b->s] += (weights) * b->du)

/* The pairs idx[e0 .. e1) of half-list row L (pairs (I, J > I); dimension D): for each block
 * (b), L.acc[b->s] = `step`, an expression in b and L.acc[b->s] that writes the block's y_J
 * and returns row I's sums so far (pst_lanes_half_add); then y_I += their sum unless I is a
 * Dirichlet row. */
#define PST_LANES_HALF_ROW(L, D, idx, e0, e1, b, kind, y, step)                                \
    do {                                                                                       \
        PST_LANES_EACH(L, D, idx, e0, e1, b, (L).acc[b->s] = (step));                          \
        if ((kind)[(L).i] != PST_DIRICHLET)                                                    \
            (y)[(L).i] += pst_lanes_sum((L).acc);                                              \
    } while (0)

/* The rows [0, n) of a whole-list apply in blocks of PST_LANES_BLOCK rows, the blocks shared out
 * statically among the threads: `rows`, a statement in i0 and i1 (a block's first and past-last
 * rows), for each block. Rows are independent, so the split does not change a bit. */
#define PST_LANES_BLOCK 256
#define PST_LANES_ROW_BLOCKS(n, i0, i1, rows)                                                  \
    do {                                                                                       \
        const size_t pst_rn_ = (n);                                                            \
        const size_t pst_nb_ = (pst_rn_ + PST_LANES_BLOCK - 1) / PST_LANES_BLOCK;              \
        _Pragma("omp parallel for schedule(static)")                                           \
        for (size_t pst_rb_ = 0; pst_rb_ < pst_nb_; ++pst_rb_) {                               \
            const size_t i0 = pst_rb_ * PST_LANES_BLOCK;                                       \
            const size_t i1 = i0 + PST_LANES_BLOCK < pst_rn_ ? i0 + PST_LANES_BLOCK : pst_rn_; \
            rows;                                                                              \
        }                                                                                      \
    } while (0)

#endif /* PSTENCIL_LANES_H */
