/* The weighted-least-squares engine's rows (kernels/wls.c has the fit): the matrix-free apply
 * and the half-list rows a block of pairs at a time from the packed rows (docs/operators.md,
 * "Matrix-free rows in lanes"), and the emission a chunk of neighbours at a time, each weight
 * w_j lam_I . p_j from the row's coefficients, bit for bit alike. A file of its own, compiled
 * once per ISA level (src/core/isa.h) so that its blocks are as wide as the level's vectors
 * (kernels/lanes.h), and so that its instantiations (dimension, type, kernel) compile beside
 * the moment pass's. */
#include "isa.h"
#include "lanes.h"
#include "wls_common.h"

/* Both weights of a block of half-list pairs (i, j[l] > i) with one h for the cloud: a_IJ
 * from row i's coefficients lam, a_JI from each J's (pst_lanes_coefs) at the negated offset
 * (x^_JI = -x^_IJ exactly, the same kernel weight): one sqrt and one kernel for both, each
 * weight lane_weights' bit for bit. */
PST_KHOT void lane_half_weights(const wls_ctx *k, int D, int B, pst_kernel K,
                                const pst_lanes_block *b, const double *lam, pst_vl *wij,
                                pst_vl *wji)
{
    const double supp = pst_sph_support[K], eps = k->c.pair_eps;
    pst_vl c[16], a, r;
    pst_lanes_coefs(k->d->lam, k->d->nb, b->j, c);
    const double *cj = (const double *)c;
#pragma omp simd
    for (int l = 0; l < PST_LW; ++l) {
        double q = b->q[l], w = cut_weight(D, K, q, supp, eps);
        a[l] = basis_weight_xyz(D, B, w, b->x[l], b->y[l], b->z[l], lam);
        r[l] = basis_weight_strided(D, B, w, -b->x[l], -b->y[l], -b->z[l], cj + l, PST_LW);
    }
    *wij = a;
    *wji = r;
}

/* The same with h per particle: each direction at its own row's scaled offset
 * (pst_lanes_lane_scaled), with its own sqrt and kernel weight, as each row's lane_weights
 * forms them: each weight bit for bit. */
PST_KHOT void lane_half_weights_hs(const wls_ctx *k, int D, int B, pst_kernel K,
                                   const pst_lanes_block *b, double ihi, const double *lam,
                                   pst_vl *wij, pst_vl *wji)
{
    const double supp = pst_sph_support[K], eps = k->c.pair_eps;
    pst_vl c[16], a, r, fj = pst_lanes_back_scale(k->c.h, b);
    pst_lanes_coefs(k->d->lam, k->d->nb, b->j, c);
    const double *cj = (const double *)c;
#pragma omp simd
    for (int l = 0; l < PST_LW; ++l) {
        double x, y, z, q = sqrt(pst_lanes_lane_scaled(b, D, l, ihi, &x, &y, &z));
        double w = cut_weight(D, K, q, supp, eps);
        a[l] = basis_weight_xyz(D, B, w, x, y, z, lam);
        q = sqrt(pst_lanes_lane_scaled(b, D, l, fj[l], &x, &y, &z));
        w = cut_weight(D, K, q, supp, eps);
        r[l] = basis_weight_strided(D, B, w, x, y, z, cj + l, PST_LW);
    }
    *wij = a;
    *wji = r;
}

/* One block of a half-list row (pst_lanes_half_add); HS: h per particle (ihi = 1 / h_I). */
PST_KHOT pst_vl half_block_step(const wls_ctx *k, int D, int B, pst_kernel K, int HS,
                                const double *lam, double ihi, const pst_lanes_block *b,
                                pst_vl acc, double *y)
{
    pst_vl wij, wji;
    if (HS)
        lane_half_weights_hs(k, D, B, K, b, ihi, lam, &wij, &wji);
    else
        lane_half_weights(k, D, B, K, b, lam, &wij, &wji);
    return pst_lanes_half_add(acc, wij, wji, b, k->c.kind, y);
}

/* Row i of a half list (operator.h, half_rows), a block at a time from the packed rows; with
 * h per particle (a separate loop: a flag inside one loop made qsfdi's one-h rows 15-25 %
 * slower) the blocks are taken unscaled and each direction has its own sqrt and kernel. */
PST_KHOT void half_row_t(const wls_ctx *k, const int64_t *off, const uint32_t *idx, size_t i,
                         double *y, int D, int B, pst_kernel K)
{
    const int nb = D + D * (D + 1) / 2 + B;
    const uint8_t *kind = k->c.kind;
    double ih = 1.0 / pst_h(&k->c, i);
    const double *lam = k->d->lam + (size_t)nb * i;
    if (k->c.h) {
        pst_lanes L = pst_lanes_row(&k->c, i, 1.0);
        PST_LANES_HALF_ROW(L, D, idx, off[i], off[i + 1], b, kind, y,
                           half_block_step(k, D, B, K, 1, lam, ih, b, L.acc[b->s], y));
        return;
    }
    pst_lanes L = pst_lanes_row(&k->c, i, ih);
    PST_LANES_HALF_ROW(L, D, idx, off[i], off[i + 1], b, kind, y,
                       half_block_step(k, D, B, K, 0, lam, ih, b, L.acc[b->s], y));
}

/* The weights a_Ij of row i for its neighbours idx[0..n) into t: the chunk's gather, then
 * w_c lam . p(r_c) in one loop over the chunk that the compiler vectorises (basis_weight_xyz,
 * as the lane rows: the emitted weights are the applies' bit for bit). */
PST_KHOT void chunk_weights(const wls_ctx *k, int D, int B, pst_kernel K, const double *xc,
                            double ih, const double *lam, const uint32_t *idx, int n, double *t)
{
    double r[3][WLS_CHUNK];
    gather(k, D, K, xc, ih, idx, n, r, t);
#pragma omp simd
    for (int c = 0; c < n; ++c)
        t[c] = basis_weight_xyz(D, B, t[c], r[0][c], r[1][c], D == 3 ? r[2][c] : 0.0, lam);
}

/* Row i's weights into w (emission), a chunk of neighbours at a time (chunk_weights). */
PST_KHOT void emit_t(const wls_ctx *k, size_t i, double *w, int D, int B, pst_kernel K)
{
    const int nb = D + D * (D + 1) / 2 + B;
    double xc[3], ih = 1.0 / pst_h(&k->c, i);
    const double *lam = k->d->lam + (size_t)nb * i;
    const int64_t e0 = k->c.off[i], e1 = k->c.off[i + 1];
    centre_of(k, D, i, xc);
    for (int64_t c0 = e0; c0 < e1; c0 += WLS_CHUNK) {
        int n = (int)(e1 - c0 < WLS_CHUNK ? e1 - c0 : WLS_CHUNK);
        chunk_weights(k, D, B, K, xc, ih, lam, k->c.idx + c0, n, w + (c0 - e0));
    }
}

/* The weights of a block of pairs (kernels/lanes.h) in the row with coefficients lam, lane
 * by lane with gather's kernel, cut and basis_weight_xyz: the emission's weights bit for bit. */
PST_KHOT pst_vl lane_weights(const wls_ctx *k, int D, int B, pst_kernel K,
                             const pst_lanes_block *b, const double *lam)
{
    const double supp = pst_sph_support[K], eps = k->c.pair_eps;
    pst_vl a;
#pragma omp simd
    for (int l = 0; l < PST_LW; ++l) {
        double q = b->q[l], w = cut_weight(D, K, q, supp, eps);
        a[l] = basis_weight_xyz(D, B, w, b->x[l], b->y[l], b->z[l], lam);
    }
    return a;
}

/* Rows [i0, i1) of the matrix-free apply, a block at a time (kernels/lanes.h). Per pair: one
 * sqrt and ~50 flops (3D) in vector lanes against 4 bytes of index and a 32-byte row of the
 * packed array (in cache): compute-bound. */
PST_KHOT void lane_rows_t(const wls_ctx *k, size_t i0, size_t i1, double *y, int D, int B,
                          pst_kernel K)
{
    const int nb = D + D * (D + 1) / 2 + B;
    for (size_t i = i0; i < i1; ++i) {
        if (k->c.kind[i] == PST_DIRICHLET)
            continue;
        const double *lam = k->d->lam + (size_t)nb * i;
        pst_lanes L = pst_lanes_row(&k->c, i, 1.0 / pst_h(&k->c, i));
        PST_LANES_ROW(L, D, k->c.idx, k->c.off[i], k->c.off[i + 1], b,
                      lane_weights(k, D, B, K, b, lam));
        y[i] = pst_lanes_sum(L.acc);
    }
}

/* ---- apply and emission ------------------------------------------------------------------- */

/* Row i: its weights into w (emission), or with off != NULL the half-list row of (off, idx);
 * and rows [i0, i1) of the matrix-free apply (lane_rows_t). */
typedef void (*row_fn)(const wls_ctx *, size_t, double *, double *, const int64_t *off,
                       const uint32_t *idx);
typedef void (*rows_fn)(const wls_ctx *, size_t, size_t, double *);
#define WLS_ROW(D, B, K)                                                                       \
    static void row_##D##_##B##_##K(const wls_ctx *k, size_t i, double *y, double *w,           \
                                    const int64_t *off, const uint32_t *idx)                   \
    {                                                                                          \
        if (off)                                                                               \
            half_row_t(k, off, idx, i, y, D, B, (pst_kernel)K);                                \
        else                                                                                   \
            emit_t(k, i, w, D, B, (pst_kernel)K);                                              \
    }                                                                                          \
    static void rows_##D##_##B##_##K(const wls_ctx *k, size_t i0, size_t i1, double *y)         \
    {                                                                                          \
        lane_rows_t(k, i0, i1, y, D, B, (pst_kernel)K);                                        \
    }
#define WLS_ROW_K(D, B) WLS_ROW(D, B, 0) WLS_ROW(D, B, 1) WLS_ROW(D, B, 2) WLS_ROW(D, B, 3)
WLS_ROW_K(2, 0)
WLS_ROW_K(2, 1)
WLS_ROW_K(3, 0)
WLS_ROW_K(3, 1)
static const row_fn row_table[2][2][4] = {
    {{row_2_0_0, row_2_0_1, row_2_0_2, row_2_0_3}, {row_2_1_0, row_2_1_1, row_2_1_2, row_2_1_3}},
    {{row_3_0_0, row_3_0_1, row_3_0_2, row_3_0_3},
     {row_3_1_0, row_3_1_1, row_3_1_2, row_3_1_3}}};
static const rows_fn rows_table[2][2][4] = {
    {{rows_2_0_0, rows_2_0_1, rows_2_0_2, rows_2_0_3},
     {rows_2_1_0, rows_2_1_1, rows_2_1_2, rows_2_1_3}},
    {{rows_3_0_0, rows_3_0_1, rows_3_0_2, rows_3_0_3},
     {rows_3_1_0, rows_3_1_1, rows_3_1_2, rows_3_1_3}}};

static row_fn row_for(const wls_ctx *k)
{
    return row_table[k->c.dim - 2][k->d->typeB][k->d->kernel];
}

/* Matrix-free apply: blocks of rows per thread, each a block of pairs at a time (lane_rows_t). */
void PST_LEVEL_NAME(pst_wls_apply)(const pst_op *op, const double *u, double *y)
{
    (void)u; /* read from op->xyzu */
    wls_ctx k = make_ctx(op);
    rows_fn rows = rows_table[k.c.dim - 2][k.d->typeB][k.d->kernel];
    PST_LANES_ROW_BLOCKS(op->n, i0, i1, rows(&k, i0, i1, y));
}

void PST_LEVEL_NAME(pst_wls_half_rows)(const pst_op *op, const int64_t *off, const uint32_t *idx,
                                       size_t i0, size_t i1, const double *u, double *y)
{
    (void)u; /* read from op->xyzu */
    wls_ctx k = make_ctx(op);
    row_fn row = row_for(&k);
    for (size_t i = i0; i < i1; ++i)
        row(&k, i, y, NULL, off, idx);
}

void PST_LEVEL_NAME(pst_wls_emit_row)(const pst_op *op, size_t i, double *w)
{
    wls_ctx k = make_ctx(op);
    row_for(&k)(&k, i, NULL, w, NULL, NULL);
}

