/* QSFDI's one-off derivatives (gradient and Hessian at the particles, eqs. 20-27) from the fit
 * of qsfdi_fit.h. A file compiled once per ISA level (src/core/isa.h), so that the blocks of
 * its data-moment loop, and the 15 x 8 partial sums it carries from block to block, are as wide
 * as the level's vectors (src/core/lanes_level.h): as target_clones functions in 8-lane
 * vectors their x86-64-v3 copies kept them in memory, and the kept-kappa gradient took 2.4x
 * the time of 4-lane blocks (3D, 132 651 particles, 1 thread). */
#include "lanes.h"
#include "qsfdi_derivs.h"
#include "qsfdi_fit.h"

/* Component c of the gradient (which = 0) or Hessian (1) at row i from its kappa and the data
 * moments, with the h factors. */
PST_KHOT double qs_deriv_dot(int D, const double *kap, const double *du2, const double *du4,
                             double h, int which)
{
    const int nq = QS_NQ(D), nk = QS_NK(D);
    double v = 0;
    for (int a = 0; a < nq; ++a)
        v += kap[a] * du4[a];
    for (int a = 0; a < nk - nq; ++a)
        v += kap[nq + a] * du2[a];
    return which ? v / (h * h) : v / h;
}

/* The 15 (3D; 2D: 8) sums of the data moments, as named vectors so that they stay in
 * registers (an array of them was kept on the stack: a load and a store per update). In
 * (r2s, r2c) order: xx yy zz xy xz yz (2D: xx yy xy, in the xx, yy, zz slots). A row keeps
 * PST_LSUMS of them, one per block of each group of 8 pairs (kernels/lanes.h). */
typedef struct {
    pst_vl x, y, z, xx2, yy2, zz2, xy2, xz2, yz2, xx4, yy4, zz4, xy4, xz4, yz4;
} qs_dsums;

/* The data moments of a block of pairs (kernels/lanes.h) added to *s: qs_data_moments'
 * terms. */
PST_KHOT void qs_data_block(const qs_ctx *k, int D, pst_kernel K, const pst_lanes_block *b,
                            qs_dsums *s)
{
    const pst_vl x = b->x, y = b->y, z = b->z, du = b->du;
    pst_vl o2 = pst_vl_splat(0.0), o4 = o2;
#pragma omp simd
    for (int l = 0; l < PST_LW; ++l) {
        double a2, id2;
        qs_omega_q(K, D, k->supp, k->c.pair_eps, b->d2[l], b->q[l], &a2, &id2);
        o2[l] = a2;
        o4[l] = a2 * id2;
    }
    const pst_vl o2u = o2 * du, o4u = o4 * du, xx = x * x, yy = y * y, xy = x * y;
    s->x += o2u * x;
    s->y += o2u * y;
    s->xx2 += o2u * xx;
    s->yy2 += o2u * yy;
    s->xx4 += o4u * xx;
    s->yy4 += o4u * yy;
    if (D == 2) {
        s->zz2 += o2u * xy;
        s->zz4 += o4u * xy;
        return;
    }
    const pst_vl zz = z * z, xz = x * z, yz = y * z;
    s->z += o2u * z;
    s->zz2 += o2u * zz;
    s->xy2 += o2u * xy;
    s->xz2 += o2u * xz;
    s->yz2 += o2u * yz;
    s->zz4 += o4u * zz;
    s->xy4 += o4u * xy;
    s->xz4 += o4u * xz;
    s->yz4 += o4u * yz;
}

/* The data moments of row i for u (op->xyzu holds it, pst_op_gradient / _hessian wrote it):
 * du2 = sum omega2 m (u_j - u_i) (the D linear then the quadratic monomials, in the order of
 * (r, r2s, r2c)) and du4 = sum omega4 (r2s, r2c) (u_j - u_i), a block of neighbours at a time
 * from the packed rows (kernels/lanes.h, each block taken one ahead) with qs_omega_q lane by
 * lane, into 8 partial sums per sum: the same sums for every ISA level, block width and thread
 * count. Per neighbour a sqrt, a division, ~19 flops of kernel and 2 per each of the 15 (3D)
 * sums, in vector lanes. */
PST_KHOT void qs_data_moments(const qs_ctx *k, int D, pst_kernel K, size_t i, double ih,
                              const int64_t *off, const uint32_t *idx, double *du2, double *du4)
{
    const pst_vl zero = pst_vl_splat(0.0);
    qs_dsums s[PST_LSUMS];
    for (int p = 0; p < PST_LSUMS; ++p)
        s[p] = (qs_dsums){zero, zero, zero, zero, zero, zero, zero, zero,
                          zero, zero, zero, zero, zero, zero, zero};
    pst_lanes L = pst_lanes_row(&k->c, i, ih);
    PST_LANES_EACH(L, D, idx, off[i], off[i + 1], b, qs_data_block(k, D, K, b, &s[b->s]));
    pst_vl v2[9][PST_LSUMS], v4[6][PST_LSUMS];
    for (int p = 0; p < PST_LSUMS; ++p) {
        const qs_dsums *t = &s[p];
        const pst_vl s2[9] = {t->x, t->y, t->z, t->xx2, t->yy2, t->zz2, t->xy2, t->xz2, t->yz2};
        const pst_vl s4[6] = {t->xx4, t->yy4, t->zz4, t->xy4, t->xz4, t->yz4};
        for (int a = 0; a < 9; ++a)
            v2[a][p] = s2[a];
        for (int a = 0; a < 6; ++a)
            v4[a][p] = s4[a];
    }
    for (int a = 0; a < D; ++a)
        du2[a] = pst_lanes_sum(v2[a]);
    for (int a = 0; a < QS_NQ(D); ++a) {
        du2[D + a] = pst_lanes_sum(v2[3 + a]);
        du4[a] = pst_lanes_sum(v4[a]);
    }
}

/* Gradient or Hessian at row i for the constant D and kernel K. With the kappas kept by the
 * precompute (with_kept, a constant: opts.keep): the data moments dotted with them (bit for
 * bit the computed result: the same sums, the same kappa). Otherwise one pass of geometry
 * moments, the inversions, then one kappa per component (no stored weights needed:
 * docs/schemes/qsfdi.md); fallback rows take the linear WLS gradient (or 0) and a zero
 * Hessian, as the kept kappas do (qs_keep_row). */
PST_KHOT void qs_deriv_row_t(const qs_ctx *k, const double *kept, int D, pst_kernel K, size_t i,
                             const int64_t *off, const uint32_t *idx, double *const out[6],
                             int which, int with_kept)
{
    const int n2 = QS_N2(D), nq = QS_NQ(D), nk = QS_NK(D), ncomp = which ? nq : D;
    double xi[3] = {0, 0, 0}, mom[QS_NMOM], du2[9], du4[6], h = pst_h(&k->c, i);
    for (int a = 0; a < D; ++a)
        xi[a] = k->c.x[a][i];
    qs_data_moments(k, D, K, i, 1.0 / h, off, idx, du2, du4);
    if (with_kept) {
        for (int c = 0; c < ncomp; ++c)
            out[c][i] = qs_deriv_dot(D, kept + ((size_t)ncomp * i + c) * nk, du2, du4, h, which);
        return;
    }
    int live = qs_moments(k, D, xi, 1.0 / h, idx, off[i], off[i + 1], mom, mom + n2);
    qs_state st;
    int fit = live >= qs_min(D) && qs_invert(k, D, mom, mom + n2, &st) < PST_ROW_RANK_DEFICIENT;
    for (int c = 0; c < ncomp; ++c) {
        double lg[3] = {0, 0, 0}, ls[3] = {0, 0, 0}, lc[3] = {0, 0, 0}, kap[15];
        if (!which)
            lg[c] = 1;
        else if (c < D)
            ls[c] = 1;
        else
            lc[c - D] = 1;
        if (fit)
            qs_functional(D, &st, lg, ls, lc, kap);
        else if (!which)
            qs_fallback_gradient(k, D, mom, mom + n2, lg, kap);
        else
            memset(kap, 0, sizeof kap);
        out[c][i] = qs_deriv_dot(D, kap, du2, du4, h, which);
    }
}

/* qs_deriv_row_t per dimension and kernel; the rows with kept kappas in a function of their
 * own (noinline), so that the inversions inlined into the others do not crowd the registers of
 * their data-moment loop. */
typedef void (*qs_deriv_fn)(const qs_ctx *, const double *, size_t, const int64_t *,
                            const uint32_t *, double *const[6], int);
#define QS_DERIV(D, K, name)                                                                   \
    __attribute__((noinline)) static void qs_kept_##D##_##name(                                \
        const qs_ctx *k, const double *kept, size_t i, const int64_t *off, const uint32_t *idx, \
        double *const out[6], int which)                                                       \
    {                                                                                          \
        qs_deriv_row_t(k, kept, D, K, i, off, idx, out, which, 1);                             \
    }                                                                                          \
    static void qs_deriv_##D##_##name(const qs_ctx *k, const double *kept, size_t i,           \
                                      const int64_t *off, const uint32_t *idx,                 \
                                      double *const out[6], int which)                         \
    {                                                                                          \
        if (kept)                                                                              \
            qs_kept_##D##_##name(k, kept, i, off, idx, out, which);                            \
        else                                                                                   \
            qs_deriv_row_t(k, NULL, D, K, i, off, idx, out, which, 0);                         \
    }
PST_FOR_KERNELS(QS_DERIV, 2)
PST_FOR_KERNELS(QS_DERIV, 3)
static const qs_deriv_fn qs_deriv_table[2][4] = QS_KERNEL_TABLE(qs_deriv);

/* Gradient (which = 0) or Hessian (1) of u at every particle (qs_deriv_row_t); u is read from
 * op->xyzu. */
static void qs_derivs(const pst_op *op, double *const out[6], int which)
{
    qs_ctx k = make_ctx(op);
    const qs_data *d = op->data;
    const double *kept = !d ? NULL : which ? d->hkap : d->gkap;
    const int64_t *off = pst_nlist_offsets(op->nl);
    const uint32_t *idx = pst_nlist_indices(op->nl);
    qs_deriv_fn row = qs_deriv_table[op->dim - 2][k.c.kernel];
#pragma omp parallel for schedule(dynamic, 1)
    for (size_t b = 0; b < pst_chunks(op->n, PST_CHUNK); ++b)
        PST_CHUNK_ROWS(op->tally, b, op->n, PST_CHUNK, i)
            row(&k, kept, i, off, idx, out, which);
}

void PST_LEVEL_NAME(pst_qsfdi_gradient)(const pst_op *op, const double *u, double *const grad[3])
{
    (void)u; /* read from op->xyzu */
    double *const out[6] = {grad[0], grad[1], grad[2], NULL, NULL, NULL};
    qs_derivs(op, out, 0);
}

void PST_LEVEL_NAME(pst_qsfdi_hessian)(const pst_op *op, const double *u, double *const hess[6])
{
    (void)u; /* read from op->xyzu */
    qs_derivs(op, hess, 1);
}
