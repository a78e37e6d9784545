/* QSFDI's matrix-free rows in lanes (docs/operators.md, "Matrix-free rows in lanes"): the
 * whole-list apply and the half-list rows, a block of pairs at a time from the packed rows,
 * each weight the emission's bit for bit. A file compiled once per ISA level (src/core/isa.h),
 * so that its blocks are as wide as the level's vectors (kernels/lanes.h). */
#include "isa.h"
#include "lanes.h"
#include "qsfdi_fit.h"
#include "qsfdi_lanes.h"

/* The weights of a block of pairs (kernels/lanes.h) in the row with coefficients kap, lane
 * by lane through qs_omega_q and qs_weight_xyz: the emission's weights bit for bit. */
PST_KHOT pst_vl qs_lane_weights(pst_kernel K, int D, double supp, double eps,
                                const pst_lanes_block *b, const double *kap)
{
    pst_vl a;
#pragma omp simd
    for (int l = 0; l < PST_LW; ++l) {
        double o2, id2;
        qs_omega_q(K, D, supp, eps, b->d2[l], b->q[l], &o2, &id2);
        a[l] = qs_weight_xyz(D, b->x[l], b->y[l], b->z[l], o2, id2, kap);
    }
    return a;
}

/* Rows [i0, i1) of the matrix-free apply for the constant D and kernel K, a block at a time
 * (kernels/lanes.h). Compute-bound (its multiplications): per pair a sqrt, a division, ~19
 * flops of kernel and ~34 (3D) of the two quadratic forms in vector lanes, against 4 bytes of
 * index and a 32-byte row of the packed array (in cache: the neighbours of Morton-ordered rows
 * overlap). */
PST_KHOT void qs_lane_rows(const qs_ctx *k, const qs_data *d, int D, pst_kernel K, size_t i0,
                           size_t i1, double *y)
{
    const int64_t *off = k->c.off;
    const uint32_t *idx = k->c.idx;
    for (size_t i = i0; i < i1; ++i) {
        if (k->c.kind[i] == PST_DIRICHLET)
            continue;
        const double *kap = d->kap + (size_t)QS_NK(D) * i;
        pst_lanes L = pst_lanes_row(&k->c, i, 1.0 / pst_h(&k->c, i));
        PST_LANES_ROW(L, D, idx, off[i], off[i + 1], b,
                      qs_lane_weights(K, D, k->supp, k->c.pair_eps, b, kap));
        y[i] = pst_lanes_sum(L.acc);
    }
}

/* qs_lane_rows instantiated per dimension and kernel. */
typedef void (*qs_rows_fn)(const qs_ctx *, const qs_data *, size_t, size_t, double *);
#define QS_ROWS(D, K, name)                                                                    \
    static void qs_rows_##D##_##name(const qs_ctx *k, const qs_data *d, size_t i0, size_t i1,   \
                                     double *y)                                                \
    {                                                                                          \
        qs_lane_rows(k, d, D, K, i0, i1, y);                                                   \
    }
PST_FOR_KERNELS(QS_ROWS, 2)
PST_FOR_KERNELS(QS_ROWS, 3)
static const qs_rows_fn qs_rows_table[2][4] = QS_KERNEL_TABLE(qs_rows);

/* Matrix-free apply: each pair's weight recomputed from positions and kappa_I, a block at a
 * time (qs_lane_rows), blocks of rows per thread. */
void PST_LEVEL_NAME(pst_qs_apply)(const pst_op *op, const double *u, double *y)
{
    (void)u; /* read from op->xyzu */
    qs_ctx k = make_ctx(op);
    qs_rows_fn rows = qs_rows_table[k.c.dim - 2][k.c.kernel];
    PST_LANES_ROW_BLOCKS(op->n, i0, i1, rows(&k, op->data, i0, i1, y));
}

/* Both weights of a block of half-list pairs (i, j[l] > i): a_IJ from row i's coefficients
 * kap_i, a_JI from each J's (gathered as vectors, pst_lanes_coefs) at the negated offset. With
 * one h for the cloud r_JI = -r_IJ exactly and the omegas are the same, so one sqrt and one
 * division serve both, and each weight is apply's bit for bit. */
PST_KHOT void qs_lane_half_weights(pst_kernel K, int D, double supp, double eps,
                                   const pst_lanes_block *b, const double *kap_i,
                                   const double *kap, pst_vl *wij, pst_vl *wji)
{
    pst_vl c[16], a, r;
    pst_lanes_coefs(kap, QS_NK(D), b->j, c);
    const double *cj = (const double *)c;
#pragma omp simd
    for (int l = 0; l < PST_LW; ++l) {
        double o2, id2;
        qs_omega_q(K, D, supp, eps, b->d2[l], b->q[l], &o2, &id2);
        a[l] = qs_weight_xyz(D, b->x[l], b->y[l], b->z[l], o2, id2, kap_i);
        r[l] = qs_weight_strided(D, -b->x[l], -b->y[l], -b->z[l], o2, id2, cj + l, PST_LW);
    }
    *wij = a;
    *wji = r;
}

/* Both weights of a block of half-list pairs with h per particle: each direction at its own
 * row's scaled offset (pst_lanes_lane_scaled), with its own sqrt, division and kernel, as each
 * row's whole-list apply forms them: each weight bit for bit. */
PST_KHOT void qs_lane_half_weights_hs(pst_kernel K, int D, double supp, double eps,
                                      const pst_lanes_block *b, double ihi, const double *h,
                                      const double *kap_i, const double *kap, pst_vl *wij,
                                      pst_vl *wji)
{
    pst_vl c[16], a, r, fj = pst_lanes_back_scale(h, b);
    pst_lanes_coefs(kap, QS_NK(D), b->j, c);
    const double *cj = (const double *)c;
#pragma omp simd
    for (int l = 0; l < PST_LW; ++l) {
        double o2, id2, x, y, z, d2 = pst_lanes_lane_scaled(b, D, l, ihi, &x, &y, &z);
        qs_omega_q(K, D, supp, eps, d2, sqrt(d2), &o2, &id2);
        a[l] = qs_weight_xyz(D, x, y, z, o2, id2, kap_i);
        d2 = pst_lanes_lane_scaled(b, D, l, fj[l], &x, &y, &z);
        qs_omega_q(K, D, supp, eps, d2, sqrt(d2), &o2, &id2);
        r[l] = qs_weight_strided(D, x, y, z, o2, id2, cj + l, PST_LW);
    }
    *wij = a;
    *wji = r;
}

/* One block of a half-list row (pst_lanes_half_add); hs: h per particle, the block's offsets
 * unscaled, ihi = 1 / h_I. */
PST_KHOT pst_vl qs_half_block_step(pst_kernel K, int D, const qs_ctx *k, const qs_data *d,
                                   const double *kap_i, int hs, double ihi,
                                   const pst_lanes_block *b, pst_vl acc, double *y)
{
    pst_vl wij, wji;
    if (hs)
        qs_lane_half_weights_hs(K, D, k->supp, k->c.pair_eps, b, ihi, k->c.h, kap_i, d->kap,
                                &wij, &wji);
    else
        qs_lane_half_weights(K, D, k->supp, k->c.pair_eps, b, kap_i, d->kap, &wij, &wji);
    return pst_lanes_half_add(acc, wij, wji, b, k->c.kind, y);
}

/* Half-list row i, a block at a time from the packed rows like qs_lane_rows: y_I += its sum
 * after the scatter of the row's blocks. Compute-bound: per pair both quadratic forms and the
 * transposes of kappa_J (15 doubles in 3D); with one h for the cloud half the sqrts, divisions
 * and kernels of the whole list, with h per particle (hs, a constant: as a run-time flag it
 * made the one-h rows 15-25 % slower) as many, plus a division for 1 / h_J. */
PST_KHOT void qs_half_lane_row(const qs_ctx *k, const qs_data *d, int D, pst_kernel K, int hs,
                               const int64_t *off, const uint32_t *idx, size_t i, double *y)
{
    const double *kap = d->kap + (size_t)QS_NK(D) * i;
    const double ihi = 1.0 / pst_h(&k->c, i);
    pst_lanes L = pst_lanes_row(&k->c, i, hs ? 1.0 : ihi);
    PST_LANES_HALF_ROW(L, D, idx, off[i], off[i + 1], b, k->c.kind, y,
                       qs_half_block_step(K, D, k, d, kap, hs, ihi, b, L.acc[b->s], y));
}

/* Rows [i0, i1) of a half list (qs_half_lane_row) per dimension, kernel and h layout (HS: h
 * per particle). */
typedef void (*qs_half_fn)(const qs_ctx *, const qs_data *, const int64_t *, const uint32_t *,
                           size_t, size_t, double *);
#define QS_HALF_HS(D, K, name, HS)                                                             \
    static void qs_half_##HS##_##D##_##name(const qs_ctx *k, const qs_data *d,                  \
                                            const int64_t *off, const uint32_t *idx, size_t i0, \
                                            size_t i1, double *y)                              \
    {                                                                                          \
        for (size_t i = i0; i < i1; ++i)                                                       \
            qs_half_lane_row(k, d, D, K, HS, off, idx, i, y);                                  \
    }
#define QS_HALF(D, K, name) QS_HALF_HS(D, K, name, 0) QS_HALF_HS(D, K, name, 1)
PST_FOR_KERNELS(QS_HALF, 2)
PST_FOR_KERNELS(QS_HALF, 3)
static const qs_half_fn qs_half_table[2][2][4] = {QS_KERNEL_TABLE(qs_half_0),
                                                  QS_KERNEL_TABLE(qs_half_1)};

/* Rows [i0, i1) of a half list (operator.h, half_rows): in lanes from the packed rows. */
void PST_LEVEL_NAME(pst_qs_half_rows)(const pst_op *op, const int64_t *off, const uint32_t *idx,
                                      size_t i0, size_t i1, const double *u, double *y)
{
    (void)u; /* read from op->xyzu */
    qs_ctx k = make_ctx(op);
    qs_half_table[k.c.h != NULL][k.c.dim - 2][k.c.kernel](&k, op->data, off, idx, i0, i1, y);
}
