/* QSFDI, quadric smoothed finite-difference interpolation (Yan, Ma & Wang 2020, §2 and
 * Appendix 1), in the one-pass moment formulation of docs/schemes/qsfdi.md ("Equations") with
 * the corrected formulas of eqs. 16-35 (docs/schemes/qsfdi.md lists the paper's typos avoided).
 *
 * Per particle I, in coordinates scaled by h_I (r = x_IJ / h_I, d = |r|), with the quintic w:
 *   omega2 = w / d^2, omega4 = w / d^4, m = (r, r2s, r2c) (5 in 2D, 9 in 3D);
 *   MOMENTS:   21 (2D) / 56 (3D) sums in one pass over the neighbours: the omega2 moments of
 *              degree 2-4 (S2 = <m, m>_2) and the omega4 moments of degree 3-4, as vectorised
 *              loops over the gathered neighbours (the sum loops are the WLS engine's, wls.c);
 *   INVERSION: the three SPD matrices M2c, M2s (Schur complement of M2c), M1q
 *              (docs/schemes/qsfdi.md) and the small products that link them (state below);
 *   WEIGHTS:   kappa (8 / 15 numbers): a_IJ = omega4 kappa4 . (r2s, r2c) + omega2 kappa2 . m.
 * Every linear functional of the derivative estimates, l_g . grad + l_s . d2s + l_c . d2c,
 * has weights of this form (qs_functional: the adjoint of eqs. 28-31); the Laplacian is
 * l_s = 1, a Neumann row l_g = n, the gradient and Hessian hooks unit vectors, interpolation
 * (eqs. 32-35) l = tau. The matrix-free apply and emit_row share qs_pair/qs_weight.
 *
 * Fallback chain (status too-few-neighbours or rank-deficient): the linear-exact row
 * c omega2 (1 - xi . r), xi = (sum omega2 r r^T)^-1 sum omega2 r, c fixing lap |x|^2 = 2D; if
 * that matrix is singular or c <= 0 the Brookshaw-type row c w / d^2, c = 2D / sum w; with no
 * neighbour the row is 0. Neumann rows fall back to n . (linear WLS gradient), else 0. */
#include "check.h"
#include "isa.h"
#include "qsfdi_derivs.h"
#include "qsfdi_fit.h"
#include "qsfdi_lanes.h"

#include <omp.h>
#include <stdlib.h>

/* Particles per block of the precompute: each phase is one threaded pass over a block, so
 * the moments and inversion state live in a small scratch (about 5 MB in 3D), not per cloud. */
#define QS_BLOCK 8192

/* ---- precompute ------------------------------------------------------------------------- */


static void qs_free(void *p)
{
    qs_data *d = p;
    if (!d)
        return;
    pst_free(d->kap);
    pst_free(d->gkap);
    pst_free(d->hkap);
    free(d);
}

/* kappa of row i from its moments and state (WEIGHTS phase), with the h factors. */
PST_KHOT void qs_row_kappa(const qs_ctx *k, int D, size_t i, uint8_t status, const double *nu,
                         const double *mu, const qs_state *st, double *kap)
{
    const int nk = QS_NK(D);
    double ih = 1.0 / pst_h(&k->c, i), zero[3] = {0, 0, 0}, scale;
    int neumann = k->c.kind[i] == PST_NEUMANN, fit = status < PST_ROW_RANK_DEFICIENT;
    if (neumann) {
        double n[3];
        for (int a = 0; a < D; ++a)
            n[a] = k->c.normal[a][i];
        if (fit)
            qs_functional(D, st, n, zero, zero, kap);
        else
            qs_fallback_gradient(k, D, nu, mu, n, kap);
        scale = ih;
    } else {
        double one[3] = {1, 1, 1};
        if (fit)
            qs_functional(D, st, zero, one, zero, kap);
        else
            qs_fallback_laplacian(k, D, nu, mu, kap);
        scale = ih * ih;
    }
    for (int a = 0; a < nk; ++a)
        kap[a] *= scale;
}

/* The geometry moments of row i into m (qs_moments), in the widest vector ISA; returns the
 * live pairs. */
PST_ISA_DISPATCH static int qs_row_moments(const qs_ctx *k, int D, size_t i, const int64_t *off,
                                           const uint32_t *idx, double *m)
{
    double xi[3] = {0, 0, 0}, ih = 1.0 / pst_h(&k->c, i);
    for (int a = 0; a < D; ++a)
        xi[a] = k->c.x[a][i];
    return D == 2 ? qs_moments(k, 2, xi, ih, idx, off[i], off[i + 1], m, m + QS_N2(2))
                  : qs_moments(k, 3, xi, ih, idx, off[i], off[i + 1], m, m + QS_N2(3));
}

/* The kept derivative kappas of row i (opts.keep), as qs_deriv_row_t (qsfdi_derivs.c) forms
 * them: the gradient's fallback is the linear WLS gradient, the Hessian's 0. */
PST_KHOT void qs_keep_row(const qs_ctx *k, const qs_data *d, int D, size_t i, int fit,
                          const double *nu, const double *mu, const qs_state *st)
{
    const int nq = QS_NQ(D), nk = QS_NK(D);
    for (int c = 0; d->gkap && c < D; ++c) {
        double lg[3] = {0, 0, 0}, zero[3] = {0, 0, 0}, *kap = d->gkap + ((size_t)D * i + c) * nk;
        lg[c] = 1;
        if (fit)
            qs_functional(D, st, lg, zero, zero, kap);
        else
            qs_fallback_gradient(k, D, nu, mu, lg, kap);
    }
    for (int c = 0; d->hkap && c < nq; ++c) {
        double ls[3] = {0, 0, 0}, lc[3] = {0, 0, 0}, zero[3] = {0, 0, 0};
        double *kap = d->hkap + ((size_t)nq * i + c) * nk;
        if (c < D)
            ls[c] = 1;
        else
            lc[c - D] = 1;
        if (fit)
            qs_functional(D, st, zero, ls, lc, kap);
        else
            memset(kap, 0, (size_t)nk * sizeof *kap);
    }
}

/* One row's inversions in the widest vector ISA (called from the OpenMP region, which the
 * clones do not reach). */
PST_ISA_DISPATCH static uint8_t qs_invert_row(const qs_ctx *k, int D, const double *m,
                                              qs_state *st)
{
    return qs_invert(k, D, m, m + QS_N2(D), st);
}

/* One row's WEIGHTS phase in the widest vector ISA: its kappa and its kept kappas, in the
 * ISA that qs_deriv_row (qsfdi_derivs.c) computes them in, so that the two agree bit for bit. */
PST_ISA_DISPATCH static void qs_weights_row(const qs_ctx *k, const qs_data *d, int D, size_t i,
                                            uint8_t status, int fit, const double *m,
                                            const qs_state *st)
{
    double *kap = d->kap + (size_t)QS_NK(D) * i;
    if (k->c.kind[i] == PST_DIRICHLET)
        memset(kap, 0, (size_t)QS_NK(D) * sizeof *kap);
    else
        qs_row_kappa(k, D, i, status, m, m + QS_N2(D), st, kap);
    if (d->gkap || d->hkap)
        qs_keep_row(k, d, D, i, fit, m, m + QS_N2(D), st);
}

PST_KHOT int qs_precompute_t(pst_op *op, int D)
{
    qs_ctx k = make_ctx(op);
    qs_data *d = op->data;
    const int64_t *off = op->poff;
    const uint32_t *idx = op->pidx;
    const int mn = qs_min(D);
    /* kept derivatives are needed at Dirichlet rows too, whose Laplacian row is the identity */
    const int keep = d->gkap || d->hkap;
    double *mom = pst_alloc((size_t)QS_BLOCK * QS_NMOM * sizeof *mom);
    qs_state *state = pst_alloc((size_t)QS_BLOCK * sizeof *state);
    int *live = pst_alloc((size_t)QS_BLOCK * sizeof *live);
    uint8_t *fit = pst_alloc(QS_BLOCK);
    if (!mom || !state || !live || !fit) {
        pst_free(mom);
        pst_free(state);
        pst_free(live);
        pst_free(fit);
        return PST_ENOMEM;
    }
    size_t n = op->n;
    for (size_t b0 = 0; b0 < n; b0 += QS_BLOCK) {
        long nb = (long)(n - b0 < QS_BLOCK ? n - b0 : QS_BLOCK);
        double t0 = omp_get_wtime();
#pragma omp parallel for schedule(dynamic, 64)
        for (long t = 0; t < nb; ++t) {
            size_t i = b0 + (size_t)t;
            if (keep || k.c.kind[i] != PST_DIRICHLET)
                live[t] = qs_row_moments(&k, D, i, off, idx, mom + (size_t)t * QS_NMOM);
        }
        double t1 = omp_get_wtime();
#pragma omp parallel for schedule(static)
        for (long t = 0; t < nb; ++t) {
            size_t i = b0 + (size_t)t;
            uint8_t st = PST_ROW_OK;
            if (keep || k.c.kind[i] != PST_DIRICHLET) {
                const double *m = mom + (size_t)t * QS_NMOM;
                st = live[t] < mn ? PST_ROW_TOO_FEW : qs_invert_row(&k, D, m, &state[t]);
            }
            fit[t] = st < PST_ROW_RANK_DEFICIENT;
            op->status[i] = k.c.kind[i] == PST_DIRICHLET ? PST_ROW_OK : st;
        }
        double t2 = omp_get_wtime();
#pragma omp parallel for schedule(static)
        for (long t = 0; t < nb; ++t) {
            size_t i = b0 + (size_t)t;
            qs_weights_row(&k, d, D, i, op->status[i], fit[t], mom + (size_t)t * QS_NMOM,
                           &state[t]);
        }
        double t3 = omp_get_wtime();
        op->phase[PST_PHASE_MOMENTS] += t1 - t0;
        op->phase[PST_PHASE_INVERSION] += t2 - t1;
        op->phase[PST_PHASE_WEIGHTS] += t3 - t2;
        pst_tally_add(op->tally, (uint64_t)nb); /* the block's rows are done */
    }
    pst_free(mom);
    pst_free(state);
    pst_free(live);
    pst_free(fit);
    return PST_OK;
}

static int qs_precompute(pst_op *op, char *err)
{
    qs_data *d = pst_op_data(op, sizeof *d);
    if (!d)
        return PST_ENOMEM;
    const int D = op->dim, nk = QS_NK(D);
    int ok = PST_DATA_ARRAY(d->kap, op->n * (size_t)nk * sizeof *d->kap) != NULL;
    if (op->opts.keep & PST_KEEP_GRADIENT)
        ok = ok && PST_DATA_ARRAY(d->gkap, op->n * (size_t)(D * nk) * sizeof *d->gkap);
    if (op->opts.keep & PST_KEEP_HESSIAN)
        ok = ok && PST_DATA_ARRAY(d->hkap, op->n * (size_t)(QS_NQ(D) * nk) * sizeof *d->hkap);
    int st = !ok ? PST_ENOMEM : D == 2 ? qs_precompute_t(op, 2) : qs_precompute_t(op, 3);
    PST_CHECK(st != PST_OK, PST_ENOMEM, err,
              "qsfdi: cannot allocate the coefficients of %zu particles", op->n);
    return PST_OK;
}

/* ---- apply and emission ------------------------------------------------------------------ */

/* The weights a_IJ of row i's neighbours idx[0..n) (one chunk) into a: the gather of
 * qs_gather, then qs_weight per pair in one loop the compiler vectorises across neighbours. */
PST_KHOT void qs_chunk_weights(const qs_ctx *k, int D, const double xi[3], double ih,
                               const double *kap, const uint32_t *idx, int n, double *a)
{
    double r[3][QS_CHUNK], o2[QS_CHUNK], id2[QS_CHUNK];
    qs_gather(k, D, xi, ih, idx, n, r, o2, id2);
#pragma omp simd
    for (int c = 0; c < n; ++c)
        a[c] = qs_weight_xyz(D, r[0][c], r[1][c], D == 3 ? r[2][c] : 0.0, o2[c], id2[c], kap);
}

/* Row i's weights into w (emission, pst_op_store), in the widest vector ISA: chunk by chunk
 * through qs_chunk_weights. */
PST_ISA_DISPATCH static void qs_emit(const qs_ctx *k, const qs_data *d, int D, const int64_t *off,
                                     const uint32_t *idx, size_t i, double *w)
{
    const double *kap = d->kap + (size_t)QS_NK(D) * i;
    double xi[3] = {0, 0, 0}, ih = 1.0 / pst_h(&k->c, i);
    for (int a = 0; a < D; ++a)
        xi[a] = k->c.x[a][i];
    for (int64_t c0 = off[i]; c0 < off[i + 1]; c0 += QS_CHUNK) {
        int n = (int)(off[i + 1] - c0 < QS_CHUNK ? off[i + 1] - c0 : QS_CHUNK);
        if (D == 2)
            qs_chunk_weights(k, 2, xi, ih, kap, idx + c0, n, w + (c0 - off[i]));
        else
            qs_chunk_weights(k, 3, xi, ih, kap, idx + c0, n, w + (c0 - off[i]));
    }
}

static void qs_emit_row(const pst_op *op, size_t i, double *w)
{
    qs_ctx k = make_ctx(op);
    qs_emit(&k, op->data, k.c.dim, op->poff, op->pidx, i, w);
}

const pst_scheme pst_scheme_qsfdi = {
    .name = "qsfdi",
    .derivatives_standalone = 1,
    .description = "quadric SFDI, Yan-Ma-Wang 2020 (eqs. 2, 3, 20-35), one-pass moments",
    .fallback = "quadric fit: too few neighbours or singular -> linear-exact row -> "
                "Brookshaw-type row -> zero row",
    .default_kernel = PST_KERNEL_QUINTIC,
    .degree = 2,
    .degree_lattice = 2,
    .min_neighbours = qs_min,
    .half_rows = pst_qs_half_rows,
    .amg_radius = 1.3, /* docs/solving.md: 1.6 h's iterations, 60 % of its entries */
    .precompute = qs_precompute,
    .apply = pst_qs_apply,
    .lanes = 1,
    .emit_row = qs_emit_row,
    .gradient = pst_qsfdi_gradient,
    .hessian = pst_qsfdi_hessian,
    .interpolate = pst_qsfdi_interpolate,
    .free_data = qs_free,
    .data_bytes = {64, 120}, /* kap: QS_NK = 8 / 15 doubles */
    .keep_bytes = {{2 * 64, 3 * 64}, {3 * 120, 6 * 120}}, /* D and QS_NQ kappas per particle */
};
