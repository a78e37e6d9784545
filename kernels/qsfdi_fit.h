/* The QSFDI fit (qsfdi.c's file comment): sizes, pair geometry, the moment pass, the inversions,
 * the functionals and the fallbacks, shared by the operator (qsfdi.c, qsfdi_lanes.c), the
 * one-off derivatives (qsfdi_derivs.c) and the interpolation (qsfdi_points.c). Internal: every
 * function is inlined into the hot loop that calls it. */
#ifndef PSTENCIL_QSFDI_FIT_H
#define PSTENCIL_QSFDI_FIT_H

#include "kernel_common.h"
#include "small_matrix.h"
#include "sph_kernels.h"
#include "wls.h"

#include <math.h>
#include <string.h>

/* The linear-exact fallback row is used only if its correction keeps this fraction of
 * sum w in the normalisation (sum a |r|^2); below it the row would be amplified by more than
 * the inverse (with exactly D neighbours linear exactness forces the row to 0) and the
 * Brookshaw-type row is used instead. */
#define QS_LINEAR_KEEP 0.01
/* Sizes per dimension: quadratic monomials nq = ns + nc, all monomials nm = D + nq, omega2
 * moments n2 (degree 2-4), omega4 moments n4 (degree 3-4), kappa nk = nq + nm. */
#define QS_NQ(D) ((D) == 2 ? 3 : 6)
#define QS_NC(D) ((D) == 2 ? 1 : 3)
#define QS_NM(D) ((D) + QS_NQ(D))
#define QS_N2(D) ((D) == 2 ? 12 : 31)
#define QS_ND2(D) ((D) == 2 ? 3 : 6)
#define QS_N4(D) (QS_N2(D) - QS_ND2(D))
#define QS_NK(D) (QS_NQ(D) + QS_NM(D))
#define QS_NMOM (QS_N2(3) + QS_N4(3)) /* 56, the largest */

/* The monomials of degree 2-4 in graded lexicographic order: by degree, then the x exponent,
 * then y, descending (2D: xx xy yy | xxx xxy xyy yyy | ...). prod[a][b] is the index of
 * m_a m_b, m = (r, r2s, r2c). */
static const unsigned char qs_prod2[5][5] = {
    {0, 1, 3, 5, 4}, {1, 2, 4, 6, 5}, {3, 4, 7, 9, 8}, {5, 6, 9, 11, 10}, {4, 5, 8, 10, 9}};
static const unsigned char qs_prod3[9][9] = {
    {0, 1, 2, 6, 9, 11, 7, 8, 10},      {1, 3, 4, 7, 12, 14, 9, 10, 13},
    {2, 4, 5, 8, 13, 15, 10, 11, 14},   {6, 7, 8, 16, 19, 21, 17, 18, 20},
    {9, 12, 13, 19, 26, 28, 22, 23, 27}, {11, 14, 15, 21, 28, 30, 24, 25, 29},
    {7, 9, 10, 17, 22, 24, 19, 20, 23}, {8, 10, 11, 18, 23, 25, 20, 21, 24},
    {10, 13, 14, 20, 27, 29, 23, 24, 28}};

static inline int qs_prod(int D, int a, int b) { return D == 2 ? qs_prod2[a][b] : qs_prod3[a][b]; }


typedef struct {
    double *kap; /* nk per particle: kappa4 (nq) then kappa2 (nm), with the 1/h^2 (1/h) in */
    /* opts.keep: the kappa of each gradient (D) and Hessian (nq) component per particle, in
     * scaled coordinates (the h factors are applied to the result), or NULL */
    double *gkap, *hkap;
} qs_data;

/* What the pair functions read. */
typedef struct {
    pst_kctx c;
    double supp;
    double cond_max, rank_tol;
} qs_ctx;

static inline qs_ctx make_ctx(const pst_op *op)
{
    return (qs_ctx){.c = pst_kctx_of(op), .supp = pst_kernel_support(op->kernel),
                    .cond_max = op->opts.cond_max, .rank_tol = op->opts.rank_tol};
}

/* omega2 = w / d^2 and 1 / d^2 (omega4 = omega2 / d^2 is their product) of a pair at scaled
 * squared distance d2 for the kernel K; 0 for degenerate pairs and pairs beyond the support.
 * Returns 1 for a live pair, else 0, as a double: arithmetic on it rather than selects of
 * computed values, which GCC turns back into branches (it may not speculate the division).
 * qs_omega_q takes q = sqrt(d2) computed (the matrix-free rows take it a block ahead,
 * kernels/lanes.h). The scalar pair (qs_pair), the vectorised chunk (qs_omegas) and the lanes
 * all call this: their weights are bit-identical. */
PST_KHOT double qs_omega_q(pst_kernel K, int D, double supp, double eps, double d2, double q,
                           double *o2, double *id2)
{
    double in = ((q > eps) & (q < supp)) ? 1.0 : 0.0;
    double w = pst_sph_shape(K, D, q, 0); /* the constant C_D cancels */
    *id2 = in / (d2 + (1.0 - in)); /* 1 / d^2, or 0 / (d^2 + 1) */
    *o2 = w * *id2;
    return in;
}

PST_KHOT double qs_omega(pst_kernel K, int D, double supp, double eps, double d2, double *o2,
                         double *id2)
{
    return qs_omega_q(K, D, supp, eps, d2, sqrt(d2), o2, id2);
}

/* Scaled offset r = (x_j - x_I) / h_I and omega2, 1 / d^2 of a pair; degenerate pairs and
 * pairs beyond the support (possible with per-particle h) get 0 weights. Returns 1 for a live
 * pair. */
PST_KHOT int qs_pair(const qs_ctx *k, int D, const double xi[3], double ih, size_t j, double r[3],
                   double *o2, double *id2)
{
    double d2 = 0;
    for (int a = 0; a < D; ++a) {
        r[a] = pst_offset(&k->c, a, k->c.x[a][j], xi[a]) * ih;
        d2 += r[a] * r[a];
    }
    return qs_omega(k->c.kernel, D, k->supp, k->c.pair_eps, d2, o2, id2) > 0;
}

/* The quadratic monomials (r2s, r2c) of r. */
PST_KHOT void qs_quad(int D, const double r[3], double qm[6])
{
    for (int a = 0; a < D; ++a)
        qm[a] = r[a] * r[a];
    qm[D] = r[0] * r[1];
    if (D == 3) {
        qm[4] = r[0] * r[2];
        qm[5] = r[1] * r[2];
    }
}

/* a_IJ = omega4 kappa4 . (r2s, r2c) + omega2 kappa2 . (r, r2s, r2c), from the components of r
 * as scalars (no arrays: the form that vectorises across neighbours; z is not read in 2D), as
 * omega2 (s4 / d^2 + s2) with the quadratic forms s4 = kappa4 . (r2s, r2c) and s2 in Horner
 * order: 20 multiplications in 3D where the monomials and two dot products take 24 (the
 * multiplications are what the matrix-free apply is bound by, qs_lane_rows), and neither
 * form waits for the division. kappa_m is kap[m * stride]: a row's (stride 1), or one lane
 * of coefficient vectors (pst_lanes_coefs, stride 8), the same arithmetic for both. */
PST_KHOT double qs_weight_strided(int D, double x, double y, double z, double o2, double id2,
                                  const double *kap, int stride)
{
    const int nq = QS_NQ(D);
#define K4(m) kap[(m) * stride]
#define K2(m) kap[(nq + (m)) * stride]
    double s4, s2;
    if (D == 2) {
        s4 = x * (K4(0) * x + K4(2) * y) + y * (K4(1) * y);
        s2 = x * (K2(2) * x + K2(4) * y + K2(0)) + y * (K2(3) * y + K2(1));
    } else {
        s4 = x * (K4(0) * x + K4(3) * y + K4(4) * z) + y * (K4(1) * y + K4(5) * z) +
             z * (K4(2) * z);
        s2 = x * (K2(3) * x + K2(6) * y + K2(7) * z + K2(0)) + y * (K2(4) * y + K2(8) * z + K2(1)) +
             z * (K2(5) * z + K2(2));
    }
#undef K4
#undef K2
    return o2 * (s4 * id2 + s2);
}

PST_KHOT double qs_weight_xyz(int D, double x, double y, double z, double o2, double id2,
                              const double *kap)
{
    return qs_weight_strided(D, x, y, z, o2, id2, kap, 1);
}

PST_KHOT double qs_weight(int D, const double r[3], double o2, double id2, const double *kap)
{
    return qs_weight_xyz(D, r[0], r[1], D == 3 ? r[2] : 0.0, o2, id2, kap);
}

/* ---- moments ---------------------------------------------------------------------------- */

/* The moment pass gathers a row's neighbours, a chunk at a time, into stack arrays (structure
 * of arrays: the scaled offsets and the two weights), then forms the sums as separate
 * reduction loops over them that the compiler vectorises. The order of a vectorised sum is
 * fixed by the code, the same for every row and thread: results do not depend on the thread
 * count. A 3D row (~190 neighbours) is one chunk. */
#define QS_CHUNK 256

/* omega2 and 1 / d^2 (qs_omega) of a chunk of n pairs from their squared distances d2,
 * vectorised; returns the live pairs. */
PST_KHOT int qs_omegas(pst_kernel K, int D, double supp, double eps, int n,
                       const double *restrict d2, double *restrict o2, double *restrict id2)
{
    double live = 0;
#pragma omp simd reduction(+ : live)
    for (int c = 0; c < n; ++c)
        live += qs_omega(K, D, supp, eps, d2[c], &o2[c], &id2[c]);
    return (int)live;
}

/* Scaled offsets r[a][c] = (x_j - x_I) / h_I of the neighbours idx[0..n) and their omega2,
 * 1 / d^2 (qs_pair's values, bit for bit). Returns the live pairs. Vectorised (sqrt too: the
 * library is built without math errno): the gather of x_J, a sqrt, a division and ~25 flops
 * per neighbour. */
PST_KHOT int qs_gather(const qs_ctx *k, int D, const double xi[3], double ih, const uint32_t *idx,
                     int n, double (*r)[QS_CHUNK], double *o2, double *id2)
{
    double d2[QS_CHUNK];
    for (int c = 0; c < n; ++c)
        for (int a = 0; a < D; ++a)
            r[a][c] = pst_offset(&k->c, a, k->c.x[a][idx[c]], xi[a]) * ih;
    for (int c = 0; c < n; ++c)
        d2[c] = r[0][c] * r[0][c] + r[1][c] * r[1][c] + (D == 3 ? r[2][c] * r[2][c] : 0.0);
    switch (k->c.kernel) { /* one vectorised instantiation per kernel */
    case PST_KERNEL_CUBIC: return qs_omegas(PST_KERNEL_CUBIC, D, k->supp, k->c.pair_eps, n, d2, o2, id2);
    case PST_KERNEL_QUINTIC: return qs_omegas(PST_KERNEL_QUINTIC, D, k->supp, k->c.pair_eps, n, d2, o2, id2);
    case PST_KERNEL_WENDLAND_C2: return qs_omegas(PST_KERNEL_WENDLAND_C2, D, k->supp, k->c.pair_eps, n, d2, o2, id2);
    default: return qs_omegas(PST_KERNEL_WENDLAND_C4, D, k->supp, k->c.pair_eps, n, d2, o2, id2);
    }
}

/* One pass over the neighbours idx[e0..e1) of the point xi (smoothing length 1/ih): the omega2
 * moments nu (degree 2-4) and omega4 moments mu (degree 3-4). Returns the live pairs. Per
 * neighbour: the gather, sqrt, division and ~19 flops of kernel, then 12 / 31 omega2 and 9 /
 * 25 omega4 sums in pst_wls_msums' vectorised loops (compute-bound, ~2/3 of the time).
 * Measured (3D, 1 thread): 12.2 ns per neighbour with default flags, 8.0 native (was ~57 ns
 * before the gather and the separate sum loops). The data moments of the derivatives are
 * qsfdi_derivs.c's, in lanes. */
PST_KHOT int qs_moments(const qs_ctx *k, int D, const double xi[3], double ih, const uint32_t *idx,
                      int64_t e0, int64_t e1, double *restrict nu, double *restrict mu)
{
    const int n2 = QS_N2(D), nd2 = QS_ND2(D), nd3 = D == 2 ? 4 : 10;
    int live = 0;
    memset(nu, 0, (size_t)n2 * sizeof *nu);
    memset(mu, 0, (size_t)(n2 - nd2) * sizeof *mu);
    for (int64_t c0 = e0; c0 < e1; c0 += QS_CHUNK) {
        int n = (int)(e1 - c0 < QS_CHUNK ? e1 - c0 : QS_CHUNK);
        double r[3][QS_CHUNK], o2[QS_CHUNK], o4[QS_CHUNK];
        live += qs_gather(k, D, xi, ih, idx + c0, n, r, o2, o4); /* o4 = 1 / d^2 here */
#pragma omp simd
        for (int c = 0; c < n; ++c)
            o4[c] *= o2[c]; /* omega4 = omega2 / d^2 */
        pst_wls_msums(D, 2, n, r[0], QS_CHUNK, o2, nu);
        pst_wls_msums(D, 3, n, r[0], QS_CHUNK, o2, nu + nd2);
        pst_wls_msums(D, 4, n, r[0], QS_CHUNK, o2, nu + nd2 + nd3);
        pst_wls_msums(D, 3, n, r[0], QS_CHUNK, o4, mu);
        pst_wls_msums(D, 4, n, r[0], QS_CHUNK, o4, mu + nd3);
    }
    return live;
}

/* ---- the dense per-particle step ---------------------------------------------------------- */

/* What the functionals need (row-major; ns = D): M2c^-1 (nc x nc), At = M2c^-1 A (nc x D),
 * Bt = M2c^-1 B (nc x ns), M2s^-1, P (ns x D), M1q^-1, Qc (D x nc), Qs (D x ns). */
typedef struct {
    double m2ci[9], at[9], bt[9], m2si[9], p[9], m1qi[9], qc[9], qs[9];
} qs_state;

/* Status from a condition estimate (the enum is ordered by severity). */
static inline uint8_t qs_cond_status(const qs_ctx *k, double cond)
{
    if (!(cond * k->rank_tol < 1.0))
        return PST_ROW_RANK_DEFICIENT;
    return cond > k->cond_max ? PST_ROW_ILL_CONDITIONED : PST_ROW_OK;
}

/* Condition of a Schur complement S of a Gram matrix with diagonal g: the 1-norm condition of
 * S and the largest loss of a diagonal entry in the elimination (g_kk / S_kk), which catches
 * a neighbourhood that is degenerate only in combination with the eliminated block. */
static inline double qs_schur_cond(int n, const double *s, const double *g, int gstride,
                                   double cond1)
{
    double c = cond1;
    for (int a = 0; a < n; ++a) {
        double sk = s[a * n + a], gk = g[a * gstride + a];
        c = sk > 0 ? fmax(c, gk / sk) : INFINITY;
    }
    return c;
}

/* Invert a 1x1, 2x2 or 3x3 symmetric matrix; returns its 1-norm condition (INFINITY when
 * singular or not finite; inv is then untouched). */
static inline double qs_inverse(int n, const double *a, double *inv)
{
    if (n == 1) {
        if (!(a[0] > 0) || !isfinite(a[0]))
            return INFINITY;
        inv[0] = 1.0 / a[0];
        return 1.0;
    }
    return pst_mat_inverse(n, a, inv);
}

/* The moment matrices of a row from its moments: S2 = <m, m>_2 (nm x nm), and the omega4
 * blocks Gq = <q, q>_4 (nq x nq) and Gqr = <q, r>_4 (nq x D), q the quadratic monomials. */
PST_KHOT void qs_moment_blocks(int D, const double *nu, const double *mu, double *S2,
                               double *Gq, double *Gqr)
{
    const int nq = QS_NQ(D), nm = QS_NM(D), nd2 = QS_ND2(D);
    for (int a = 0; a < nm; ++a)
        for (int b = 0; b < nm; ++b)
            S2[a * nm + b] = nu[qs_prod(D, a, b)];
    for (int a = 0; a < nq; ++a) {
        for (int b = 0; b < nq; ++b)
            Gq[a * nq + b] = mu[qs_prod(D, D + a, D + b) - nd2];
        for (int b = 0; b < D; ++b)
            Gqr[a * D + b] = mu[qs_prod(D, D + a, b) - nd2];
    }
}

/* The inversions of docs/schemes/qsfdi.md ("One-pass moment form") from the moments: returns
 * the row status (ok, ill-conditioned or rank-deficient; the state is complete only when not
 * rank-deficient).
 * Roughly 300 (2D) / 1500 (3D) flops, no inter-particle dependencies. */
PST_KHOT uint8_t qs_invert(const qs_ctx *k, int D, const double *nu, const double *mu,
                         qs_state *st)
{
    const int ns = D, nc = QS_NC(D), nq = QS_NQ(D), nm = QS_NM(D);
    double S2[81], Gq[36], Gqr[18];
    memset(st, 0, sizeof *st); /* a singular inverse leaves its block untouched */
    qs_moment_blocks(D, nu, mu, S2, Gq, Gqr);
    /* M2c = <r2c, r2c>_4, A = <r2c, r>_4, B = <r2c, r2s>_4 */
    double M2c[9], A[9], B[9];
    for (int c = 0; c < nc; ++c) {
        for (int e = 0; e < nc; ++e)
            M2c[c * nc + e] = Gq[(ns + c) * nq + ns + e];
        for (int a = 0; a < D; ++a)
            A[c * D + a] = Gqr[(ns + c) * D + a];
        for (int s = 0; s < ns; ++s)
            B[c * ns + s] = Gq[(ns + c) * nq + s];
    }
    double cond = qs_inverse(nc, M2c, st->m2ci);
    double gmax = 0; /* M2c against the scale of the pure squares */
    for (int s = 0; s < ns; ++s)
        gmax = fmax(gmax, Gq[s * nq + s]);
    for (int c = 0; c < nc; ++c)
        cond = M2c[c * nc + c] > 0 ? fmax(cond, gmax / M2c[c * nc + c]) : INFINITY;
    uint8_t status = qs_cond_status(k, cond);
    if (status == PST_ROW_RANK_DEFICIENT)
        return status;
    const double *Mi = st->m2ci;
    for (int c = 0; c < nc; ++c) {
        for (int a = 0; a < D; ++a) {
            double t = 0;
            for (int e = 0; e < nc; ++e)
                t += Mi[c * nc + e] * A[e * D + a];
            st->at[c * D + a] = t;
        }
        for (int s = 0; s < ns; ++s) {
            double t = 0;
            for (int e = 0; e < nc; ++e)
                t += Mi[c * nc + e] * B[e * ns + s];
            st->bt[c * ns + s] = t;
        }
    }
    /* M2s = Nss - B^T Bt (symmetrised), P = Nsr - B^T At */
    double M2s[9];
    for (int s = 0; s < ns; ++s) {
        for (int t = 0; t < ns; ++t) {
            double v = Gq[s * nq + t];
            for (int c = 0; c < nc; ++c)
                v -= B[c * ns + s] * st->bt[c * ns + t];
            M2s[s * ns + t] = v;
        }
        for (int a = 0; a < D; ++a) {
            double v = Gqr[s * D + a];
            for (int c = 0; c < nc; ++c)
                v -= B[c * ns + s] * st->at[c * D + a];
            st->p[s * D + a] = v;
        }
    }
    for (int s = 0; s < ns; ++s)
        for (int t = 0; t < s; ++t)
            M2s[s * ns + t] = M2s[t * ns + s] = 0.5 * (M2s[s * ns + t] + M2s[t * ns + s]);
    cond = qs_schur_cond(ns, M2s, Gq, nq, qs_inverse(ns, M2s, st->m2si));
    uint8_t s2 = qs_cond_status(k, cond);
    status = s2 > status ? s2 : status;
    if (status == PST_ROW_RANK_DEFICIENT)
        return status;
    /* R = P^T M2s^-1; Tq = [I | -R | -At^T + R Bt^T]; Y = Tq S2; M1q = Y Tq^T */
    double R[9], Tq[27], Y[27], M1q[9];
    for (int a = 0; a < D; ++a)
        for (int s = 0; s < ns; ++s) {
            double v = 0;
            for (int t = 0; t < ns; ++t)
                v += st->p[t * D + a] * st->m2si[t * ns + s];
            R[a * ns + s] = v;
        }
    for (int a = 0; a < D; ++a) {
        for (int b = 0; b < D; ++b)
            Tq[a * nm + b] = a == b ? 1.0 : 0.0;
        for (int s = 0; s < ns; ++s)
            Tq[a * nm + D + s] = -R[a * ns + s];
        for (int c = 0; c < nc; ++c) {
            double v = -st->at[c * D + a];
            for (int s = 0; s < ns; ++s)
                v += R[a * ns + s] * st->bt[c * ns + s];
            Tq[a * nm + D + ns + c] = v;
        }
    }
    for (int a = 0; a < D; ++a)
        for (int b = 0; b < nm; ++b) {
            double v = 0;
            for (int t = 0; t < nm; ++t)
                v += Tq[a * nm + t] * S2[t * nm + b];
            Y[a * nm + b] = v;
        }
    for (int a = 0; a < D; ++a)
        for (int b = 0; b <= a; ++b) {
            double v = 0, w = 0;
            for (int t = 0; t < nm; ++t) {
                v += Y[a * nm + t] * Tq[b * nm + t];
                w += Y[b * nm + t] * Tq[a * nm + t];
            }
            M1q[a * D + b] = M1q[b * D + a] = 0.5 * (v + w);
        }
    /* Qc = Y Ec^T, Qs = Y TPi^T = Y_s - Y_c Bt */
    for (int a = 0; a < D; ++a) {
        for (int c = 0; c < nc; ++c)
            st->qc[a * nc + c] = Y[a * nm + D + ns + c];
        for (int s = 0; s < ns; ++s) {
            double v = Y[a * nm + D + s];
            for (int c = 0; c < nc; ++c)
                v -= Y[a * nm + D + ns + c] * st->bt[c * ns + s];
            st->qs[a * ns + s] = v;
        }
    }
    cond = qs_schur_cond(D, M1q, S2, nm, qs_inverse(D, M1q, st->m1qi));
    uint8_t s3 = qs_cond_status(k, cond);
    return s3 > status ? s3 : status;
}

/* kappa of the functional l_g . grad + l_s . d2s + l_c . d2c (scaled coordinates): the
 * adjoint of the weights of eqs. 28-31 (docs/schemes/qsfdi.md derives it; with l_s = 1 it is
 * the Laplacian's kappa). About 150 (2D) / 400 (3D) flops. */
PST_KHOT void qs_functional(int D, const qs_state *st, const double *lg, const double *ls,
                          const double *lc, double *kap)
{
    const int ns = D, nc = QS_NC(D), nq = QS_NQ(D);
    /* rho zeroed: inlined into a dispatched clone, GCC cannot see that ns <= 3 fills it */
    double gc[3], lsp[3], gs[3], lgp[3], gg[3], t[3], ss[3], sc[3], rho[3] = {0, 0, 0};
    for (int c = 0; c < nc; ++c) { /* gamma_c = M2c^-1 l_c */
        gc[c] = 0;
        for (int e = 0; e < nc; ++e)
            gc[c] += st->m2ci[c * nc + e] * lc[e];
    }
    for (int s = 0; s < ns; ++s) { /* l_s' = l_s - 1/2 Bt^T l_c */
        lsp[s] = ls[s];
        for (int c = 0; c < nc; ++c)
            lsp[s] -= 0.5 * st->bt[c * ns + s] * lc[c];
    }
    for (int s = 0; s < ns; ++s) { /* gamma_s = 2 M2s^-1 l_s' */
        gs[s] = 0;
        for (int u = 0; u < ns; ++u)
            gs[s] += 2.0 * st->m2si[s * ns + u] * lsp[u];
    }
    for (int a = 0; a < D; ++a) { /* l_g'' = l_g - At^T l_c - P^T gamma_s */
        lgp[a] = lg[a];
        for (int c = 0; c < nc; ++c)
            lgp[a] -= st->at[c * D + a] * lc[c];
        for (int s = 0; s < ns; ++s)
            lgp[a] -= st->p[s * D + a] * gs[s];
    }
    for (int a = 0; a < D; ++a) { /* gamma_g = M1q^-1 l_g'' */
        gg[a] = 0;
        for (int b = 0; b < D; ++b)
            gg[a] += st->m1qi[a * D + b] * lgp[b];
    }
    for (int s = 0; s < ns; ++s) { /* sigma_s = gamma_s - M2s^-1 Qs^T gamma_g */
        t[s] = 0;
        for (int a = 0; a < D; ++a)
            t[s] += st->qs[a * ns + s] * gg[a];
    }
    for (int s = 0; s < ns; ++s) {
        ss[s] = gs[s];
        for (int u = 0; u < ns; ++u)
            ss[s] -= st->m2si[s * ns + u] * t[u];
    }
    for (int c = 0; c < nc; ++c) { /* sigma_c = M2c^-1 (l_c - Qc^T gamma_g) */
        t[c] = lc[c];
        for (int a = 0; a < D; ++a)
            t[c] -= st->qc[a * nc + c] * gg[a];
    }
    for (int c = 0; c < nc; ++c) {
        sc[c] = 0;
        for (int e = 0; e < nc; ++e)
            sc[c] += st->m2ci[c * nc + e] * t[e];
    }
    for (int s = 0; s < ns; ++s) { /* rho = M2s^-1 P gamma_g */
        t[s] = 0;
        for (int a = 0; a < D; ++a)
            t[s] += st->p[s * D + a] * gg[a];
    }
    for (int s = 0; s < ns; ++s) {
        rho[s] = 0;
        for (int u = 0; u < ns; ++u)
            rho[s] += st->m2si[s * ns + u] * t[u];
    }
    /* kappa4 = (sigma_s, sigma_c - Bt sigma_s); kappa2 = (gamma_g, -rho, -At gamma_g + Bt rho) */
    double *k4 = kap, *k2 = kap + nq;
    for (int s = 0; s < ns; ++s) {
        k4[s] = ss[s];
        k2[D + s] = -rho[s];
    }
    for (int c = 0; c < nc; ++c) {
        double v4 = sc[c], v2 = 0;
        for (int s = 0; s < ns; ++s) {
            v4 -= st->bt[c * ns + s] * ss[s];
            v2 += st->bt[c * ns + s] * rho[s];
        }
        for (int a = 0; a < D; ++a)
            v2 -= st->at[c * D + a] * gg[a];
        k4[ns + c] = v4;
        k2[D + ns + c] = v2;
    }
    for (int a = 0; a < D; ++a)
        k2[a] = gg[a];
}

/* The linear WLS pieces of the fallbacks from the moments: N1 = sum omega2 r r^T (its inverse
 * into n1i) and g1 = sum omega2 r. Returns 0 when N1 is singular. */
PST_KHOT int qs_linear(const qs_ctx *k, int D, const double *nu, const double *mu, double *n1i,
                     double *g1)
{
    double N1[9];
    for (int a = 0; a < D; ++a) {
        for (int b = 0; b < D; ++b)
            N1[a * D + b] = nu[qs_prod(D, a, b)];
        g1[a] = 0; /* omega2 r_a = sum_b omega4 r_b^2 r_a */
        for (int b = 0; b < D; ++b)
            g1[a] += mu[qs_prod(D, D + b, a) - QS_ND2(D)];
    }
    return qs_cond_status(k, pst_mat_inverse(D, N1, n1i)) != PST_ROW_RANK_DEFICIENT;
}

/* The fallback Laplacian row (file comment) as kappa, scaled coordinates. */
PST_KHOT void qs_fallback_laplacian(const qs_ctx *k, int D, const double *nu, const double *mu,
                                  double *kap)
{
    const int nq = QS_NQ(D);
    memset(kap, 0, (size_t)QS_NK(D) * sizeof *kap);
    double sw = 0, swr[3], n1i[9], g1[3], xi[3] = {0, 0, 0};
    for (int a = 0; a < D; ++a) {
        sw += nu[qs_prod(D, a, a)]; /* sum w = sum omega2 d^2 */
        swr[a] = 0;
        for (int b = 0; b < D; ++b)
            swr[a] += nu[qs_prod(D, D + b, a)];
    }
    double den = sw;
    if (qs_linear(k, D, nu, mu, n1i, g1)) {
        double dl = sw;
        for (int a = 0; a < D; ++a) {
            double v = 0;
            for (int b = 0; b < D; ++b)
                v += n1i[a * D + b] * g1[b];
            xi[a] = v;
            dl -= v * swr[a];
        }
        if (dl > QS_LINEAR_KEEP * sw)
            den = dl;
        else
            xi[0] = xi[1] = xi[2] = 0;
    }
    if (!(den > 0))
        return; /* no neighbour: the zero row */
    double c = 2.0 * D / den;
    for (int a = 0; a < D; ++a) {
        kap[a] = c;            /* omega4 c |r|^2 = c omega2 */
        kap[nq + a] = -c * xi[a];
    }
}

/* The fallback gradient functional l . grad: l . N1^-1 sum omega2 r u (linear-exact), or 0. */
PST_KHOT void qs_fallback_gradient(const qs_ctx *k, int D, const double *nu, const double *mu,
                                 const double *l, double *kap)
{
    memset(kap, 0, (size_t)QS_NK(D) * sizeof *kap);
    double n1i[9] = {0}, g1[3]; /* n1i is untouched when N1 is singular */
    if (!qs_linear(k, D, nu, mu, n1i, g1))
        return;
    for (int a = 0; a < D; ++a)
        for (int b = 0; b < D; ++b)
            kap[QS_NQ(D) + a] += n1i[a * D + b] * l[b];
}

static inline int qs_min(int dim) { return dim == 2 ? 5 : 9; } /* choice 6, docs/choices.md */

/* The table [D - 2][K] of the functions prefix_D_name: the rows instantiated per dimension and
 * kernel with PST_FOR_KERNELS (qsfdi.c, qsfdi_derivs.c, qsfdi_lanes.c). */
#define QS_KERNEL_TABLE(prefix)                                                                \
    {{prefix##_2_cubic, prefix##_2_quintic, prefix##_2_wc2, prefix##_2_wc4},                   \
     {prefix##_3_cubic, prefix##_3_quintic, prefix##_3_wc2, prefix##_3_wc4}}

/* The interpolation at points (qsfdi_points.c), the hook of the scheme table (the gradient
 * and Hessian: qsfdi_derivs.h). */
int pst_qsfdi_interpolate(const pst_op *op, const double *const pts[3], size_t m, const double *u,
                          double *value, double *lap, size_t *fallbacks, char *err);

#endif /* PSTENCIL_QSFDI_FIT_H */
