/* QSFDI, quadric smoothed finite-difference interpolation (Yan, Ma & Wang 2020; spec qsfdi.md
 * §1), in the one-pass moment formulation of spec §1.9-§1.12 with the corrected formulas of
 * §1.4-§1.7 (docs/schemes/qsfdi.md lists the paper's typos avoided).
 *
 * Per particle I, in coordinates scaled by h_I (r = x_IJ / h_I, d = |r|), with the quintic w:
 *   omega2 = w / d^2, omega4 = w / d^4, m = (r, r2s, r2c) (5 in 2D, 9 in 3D);
 *   MOMENTS:   21 (2D) / 56 (3D) sums in one pass over the neighbours: the omega2 moments of
 *              degree 2-4 (S2 = <m, m>_2) and the omega4 moments of degree 3-4, as vectorised
 *              loops over the gathered neighbours (the sum loops are the WLS engine's, wls.c);
 *   INVERSION: the three SPD matrices M2c, M2s (Schur complement of M2c), M1q (spec §1.10-1.11)
 *              and the small products that link them (state below);
 *   WEIGHTS:   kappa (8 / 15 numbers): a_IJ = omega4 kappa4 . (r2s, r2c) + omega2 kappa2 . m.
 * Every linear functional of the derivative estimates, l_g . grad + l_s . d2s + l_c . d2c,
 * has weights of this form (qs_functional: the adjoint of spec §1.6); the Laplacian is
 * l_s = 1, a Neumann row l_g = n, the gradient and Hessian hooks unit vectors, interpolation
 * (§1.7) l = tau. The matrix-free apply and emit_row share qs_pair/qs_weight.
 *
 * Fallback chain (status too-few-neighbours or rank-deficient): the linear-exact row
 * c omega2 (1 - xi . r), xi = (sum omega2 r r^T)^-1 sum omega2 r, c fixing lap |x|^2 = 2D; if
 * that matrix is singular or c <= 0 the Brookshaw-type row c w / d^2, c = 2D / sum w; with no
 * neighbour the row is 0. Neumann rows fall back to n . (linear WLS gradient), else 0. */
#include "check.h"
#include "kernel_common.h"
#include "small_matrix.h"
#include "sph_kernels.h"
#include "wls.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

/* The linear-exact fallback row is used only if its correction keeps this fraction of
 * sum w in the normalisation (sum a |r|^2); below it the row would be amplified by more than
 * the inverse (with exactly D neighbours linear exactness forces the row to 0) and the
 * Brookshaw-type row is used instead. */
#define QS_LINEAR_KEEP 0.01
/* Particles per block of the precompute: each phase is one threaded pass over a block, so
 * the moments and inversion state live in a small scratch (about 5 MB in 3D), not per cloud. */
#define QS_BLOCK 8192
/* Sizes per dimension: quadratic monomials nq = ns + nc, all monomials nm = D + nq, omega2
 * moments n2 (degree 2-4), omega4 moments n4 (degree 3-4), kappa nk = nq + nm. */
#define QS_NQ(D) ((D) == 2 ? 3 : 6)
#define QS_NC(D) ((D) == 2 ? 1 : 3)
#define QS_NM(D) ((D) + QS_NQ(D))
#define QS_N2(D) ((D) == 2 ? 12 : 31)
#define QS_ND2(D) ((D) == 2 ? 3 : 6)
#define QS_N4(D) (QS_N2(D) - QS_ND2(D))
#define QS_NK(D) (QS_NQ(D) + QS_NM(D))
#define QS_NMOM 56 /* n2 + n4 in 3D: the largest */

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
} qs_data;

/* What the pair functions read. */
typedef struct {
    pst_kctx c;
    double supp;
    double cond_max, rank_tol;
} qs_ctx;

static qs_ctx make_ctx(const pst_op *op)
{
    return (qs_ctx){.c = pst_kctx_of(op), .supp = pst_kernel_support(op->kernel),
                    .cond_max = op->opts.cond_max, .rank_tol = op->opts.rank_tol};
}

/* Scaled offset r = (x_j - x_I) / h_I and omega2, omega4 of a pair; degenerate pairs and pairs
 * beyond the support (possible with per-particle h) get 0 weights. Returns 1 for a live pair. */
PST_KHOT int qs_pair(const qs_ctx *k, int D, const double xi[3], double ih, size_t j, double r[3],
                   double *o2, double *o4)
{
    double d2 = 0;
    for (int a = 0; a < D; ++a) {
        r[a] = (k->c.x[a][j] - xi[a]) * ih;
        d2 += r[a] * r[a];
    }
    double q = sqrt(d2);
    int ok = q > k->c.pair_eps && q < k->supp;
    double w = ok ? pst_sph_shape(k->c.kernel, D, q, 0) : 0.0; /* constant C_D cancels */
    double id2 = 1.0 / (ok ? d2 : 1.0);
    *o2 = w * id2;
    *o4 = *o2 * id2;
    return ok;
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

/* a_IJ = omega4 kappa4 . (r2s, r2c) + omega2 kappa2 . (r, r2s, r2c). */
PST_KHOT double qs_weight(int D, const double r[3], double o2, double o4, const double *kap)
{
    double qm[6];
    qs_quad(D, r, qm);
    const int nq = QS_NQ(D);
    double s4 = 0, s2 = 0;
    for (int a = 0; a < nq; ++a) {
        s4 += kap[a] * qm[a];
        s2 += kap[nq + D + a] * qm[a];
    }
    for (int a = 0; a < D; ++a)
        s2 += kap[nq + a] * r[a];
    return o4 * s4 + o2 * s2;
}

/* ---- moments ---------------------------------------------------------------------------- */

/* The moment pass gathers a row's neighbours, a chunk at a time, into stack arrays (structure
 * of arrays: the scaled offsets and the two weights), then forms the sums as separate
 * reduction loops over them that the compiler vectorises. The order of a vectorised sum is
 * fixed by the code, the same for every row and thread: results do not depend on the thread
 * count. A 3D row (~190 neighbours) is one chunk. */
#define QS_CHUNK 256

/* omega2 = w / d^2 and omega4 = w / d^4 for the kernel K from q = d (in o2) and d^2 (in o4),
 * in place; 0 for degenerate pairs and pairs beyond the support. Returns the live pairs.
 * Vectorised (the count is a double: an integer count of double compares does not vectorise
 * with SSE2); bound by the division, ~2 ns per neighbour (3D, 1 thread, default flags). */
PST_KHOT int qs_omegas(pst_kernel K, int D, double supp, double eps, int n, double *restrict o2,
                     double *restrict o4)
{
    double live = 0;
#pragma omp simd reduction(+ : live)
    for (int c = 0; c < n; ++c) {
        double q = o2[c], w = pst_sph_shape(K, D, q, 0); /* the constant C_D cancels */
        /* 1 for a live pair, else 0; arithmetic on it rather than selects of computed values,
         * which GCC turns back into branches (it may not speculate the division) */
        double in = (q > eps) & (q < supp) ? 1.0 : 0.0;
        double id2 = in / (o4[c] + (1.0 - in)); /* 1 / d^2, or 0 / (d^2 + 1) */
        o2[c] = w * id2;
        o4[c] = w * id2 * id2;
        live += in;
    }
    return (int)live;
}

/* Scaled offsets r[a][c] = (x_j - x_I) / h_I of the neighbours idx[0..n) and their omega2,
 * omega4 (qs_pair's values up to rounding). Returns the live pairs. Three loops, so that only
 * the sqrt stays scalar (GCC does not vectorise sqrt while it may set errno, the default
 * -fmath-errno): bound by it and the gather, ~2 ns per neighbour without qs_omegas. */
PST_KHOT int qs_gather(const qs_ctx *k, int D, const double xi[3], double ih, const uint32_t *idx,
                     int n, double (*r)[QS_CHUNK], double *o2, double *o4)
{
    for (int c = 0; c < n; ++c)
        for (int a = 0; a < D; ++a)
            r[a][c] = (k->c.x[a][idx[c]] - xi[a]) * ih;
    for (int c = 0; c < n; ++c)
        o4[c] = r[0][c] * r[0][c] + r[1][c] * r[1][c] + (D == 3 ? r[2][c] * r[2][c] : 0.0);
    for (int c = 0; c < n; ++c)
        o2[c] = sqrt(o4[c]);
    switch (k->c.kernel) { /* one vectorised instantiation per kernel */
    case PST_KERNEL_CUBIC: return qs_omegas(PST_KERNEL_CUBIC, D, k->supp, k->c.pair_eps, n, o2, o4);
    case PST_KERNEL_QUINTIC: return qs_omegas(PST_KERNEL_QUINTIC, D, k->supp, k->c.pair_eps, n, o2, o4);
    case PST_KERNEL_WENDLAND_C2: return qs_omegas(PST_KERNEL_WENDLAND_C2, D, k->supp, k->c.pair_eps, n, o2, o4);
    default: return qs_omegas(PST_KERNEL_WENDLAND_C4, D, k->supp, k->c.pair_eps, n, o2, o4);
    }
}

/* The degree-2 monomials of graded lexicographic order (xx xy yy / xx xy xz yy yz zz) in the
 * order of (r2s, r2c) (xx yy xy / xx yy zz xy xz yz). */
static const unsigned char qs_gl2q[2][6] = {{0, 2, 1}, {0, 3, 5, 1, 2, 4}};

/* One pass over the neighbours idx[e0..e1) of the point xi (smoothing length 1/ih): the omega2
 * moments nu (degree 2-4) and omega4 moments mu (degree 3-4); with u, also the data moments
 * du2 = sum omega2 m (u_j - ui) and du4 = sum omega4 (r2s, r2c)(u_j - ui). Returns the live
 * pairs. Per neighbour: the gather, sqrt, division and ~19 flops of kernel, then 12 / 31
 * omega2 and 9 / 25 omega4 sums in pst_wls_msums' vectorised loops (compute-bound, ~2/3 of
 * the time). Measured (3D, 1 thread): 12.2 ns per neighbour with default flags, 8.0 native
 * (was ~57 ns before the gather and the separate sum loops). */
PST_KHOT int qs_moments(const qs_ctx *k, int D, const double xi[3], double ih, const uint32_t *idx,
                      int64_t e0, int64_t e1, const double *u, double ui, double *restrict nu,
                      double *restrict mu, double *restrict du2, double *restrict du4)
{
    const int n2 = QS_N2(D), nd2 = QS_ND2(D), nq = QS_NQ(D), nd3 = D == 2 ? 4 : 10;
    double g2[2][6] = {{0}};
    int live = 0;
    memset(nu, 0, (size_t)n2 * sizeof *nu);
    memset(mu, 0, (size_t)(n2 - nd2) * sizeof *mu);
    if (u)
        memset(du2, 0, (size_t)QS_NM(D) * sizeof *du2);
    for (int64_t c0 = e0; c0 < e1; c0 += QS_CHUNK) {
        int n = (int)(e1 - c0 < QS_CHUNK ? e1 - c0 : QS_CHUNK);
        double r[3][QS_CHUNK], o2[QS_CHUNK], o4[QS_CHUNK];
        live += qs_gather(k, D, xi, ih, idx + c0, n, r, o2, o4);
        pst_wls_msums(D, 2, n, r[0], QS_CHUNK, o2, nu);
        pst_wls_msums(D, 3, n, r[0], QS_CHUNK, o2, nu + nd2);
        pst_wls_msums(D, 4, n, r[0], QS_CHUNK, o2, nu + nd2 + nd3);
        pst_wls_msums(D, 3, n, r[0], QS_CHUNK, o4, mu);
        pst_wls_msums(D, 4, n, r[0], QS_CHUNK, o4, mu + nd3);
        if (u) {
            double o2u[QS_CHUNK], o4u[QS_CHUNK];
            for (int c = 0; c < n; ++c) {
                double du = u[idx[c0 + c]] - ui;
                o2u[c] = o2[c] * du;
                o4u[c] = o4[c] * du;
            }
            pst_wls_msums(D, 1, n, r[0], QS_CHUNK, o2u, du2);
            pst_wls_msums(D, 2, n, r[0], QS_CHUNK, o2u, g2[0]);
            pst_wls_msums(D, 2, n, r[0], QS_CHUNK, o4u, g2[1]);
        }
    }
    if (u)
        for (int a = 0; a < nq; ++a) {
            du2[D + a] = g2[0][qs_gl2q[D - 2][a]];
            du4[a] = g2[1][qs_gl2q[D - 2][a]];
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

/* The inversions of spec §1.10-1.11 from the moments: returns the row status (ok,
 * ill-conditioned or rank-deficient; the state is complete only when not rank-deficient).
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
 * adjoint of the weights of spec §1.6 (docs/schemes/qsfdi.md derives it; with l_s = 1 it is
 * the kappa of §1.9). About 150 (2D) / 400 (3D) flops. */
PST_KHOT void qs_functional(int D, const qs_state *st, const double *lg, const double *ls,
                          const double *lc, double *kap)
{
    const int ns = D, nc = QS_NC(D), nq = QS_NQ(D);
    double gc[3], lsp[3], gs[3], lgp[3], gg[3], t[3], ss[3], sc[3], rho[3];
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
    double n1i[9], g1[3];
    if (!qs_linear(k, D, nu, mu, n1i, g1))
        return;
    for (int a = 0; a < D; ++a)
        for (int b = 0; b < D; ++b)
            kap[QS_NQ(D) + a] += n1i[a * D + b] * l[b];
}

/* ---- precompute ------------------------------------------------------------------------- */

static int qs_min(int dim) { return dim == 2 ? 5 : 9; } /* spec choice 6 */

static void qs_free(void *p)
{
    qs_data *d = p;
    if (!d)
        return;
    pst_free(d->kap);
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

PST_KHOT int qs_precompute_t(pst_op *op, int D)
{
    qs_ctx k = make_ctx(op);
    qs_data *d = op->data;
    const int64_t *off = op->poff;
    const uint32_t *idx = op->pidx;
    const int n2 = QS_N2(D), nk = QS_NK(D), mn = qs_min(D);
    double *mom = pst_alloc((size_t)QS_BLOCK * QS_NMOM * sizeof *mom);
    qs_state *state = pst_alloc((size_t)QS_BLOCK * sizeof *state);
    int *live = pst_alloc((size_t)QS_BLOCK * sizeof *live);
    if (!mom || !state || !live) {
        pst_free(mom);
        pst_free(state);
        pst_free(live);
        return PST_ENOMEM;
    }
    size_t n = op->n;
    for (size_t b0 = 0; b0 < n; b0 += QS_BLOCK) {
        long nb = (long)(n - b0 < QS_BLOCK ? n - b0 : QS_BLOCK);
        double t0 = omp_get_wtime();
#pragma omp parallel for schedule(dynamic, 64)
        for (long t = 0; t < nb; ++t) {
            size_t i = b0 + (size_t)t;
            if (k.c.kind[i] == PST_DIRICHLET)
                continue;
            double xi[3] = {0, 0, 0};
            for (int a = 0; a < D; ++a)
                xi[a] = k.c.x[a][i];
            double *m = mom + (size_t)t * QS_NMOM;
            live[t] = qs_moments(&k, D, xi, 1.0 / pst_h(&k.c, i), idx, off[i], off[i + 1], NULL,
                                 0.0, m, m + n2, NULL, NULL);
        }
        double t1 = omp_get_wtime();
#pragma omp parallel for schedule(static)
        for (long t = 0; t < nb; ++t) {
            size_t i = b0 + (size_t)t;
            if (k.c.kind[i] == PST_DIRICHLET) {
                op->status[i] = PST_ROW_OK;
                continue;
            }
            const double *m = mom + (size_t)t * QS_NMOM;
            op->status[i] = live[t] < mn ? PST_ROW_TOO_FEW : qs_invert(&k, D, m, m + n2, &state[t]);
        }
        double t2 = omp_get_wtime();
#pragma omp parallel for schedule(static)
        for (long t = 0; t < nb; ++t) {
            size_t i = b0 + (size_t)t;
            double *kap = d->kap + (size_t)nk * i;
            if (k.c.kind[i] == PST_DIRICHLET) {
                memset(kap, 0, (size_t)nk * sizeof *kap);
                continue;
            }
            const double *m = mom + (size_t)t * QS_NMOM;
            qs_row_kappa(&k, D, i, op->status[i], m, m + n2, &state[t], kap);
        }
        double t3 = omp_get_wtime();
        op->phase[PST_PHASE_MOMENTS] += t1 - t0;
        op->phase[PST_PHASE_INVERSION] += t2 - t1;
        op->phase[PST_PHASE_WEIGHTS] += t3 - t2;
    }
    pst_free(mom);
    pst_free(state);
    pst_free(live);
    return PST_OK;
}

static int qs_precompute(pst_op *op, char *err)
{
    qs_data *d = calloc(1, sizeof *d);
    if (!d)
        return PST_ENOMEM;
    op->data = d;
    d->kap = pst_alloc(op->n * (size_t)QS_NK(op->dim) * sizeof *d->kap);
    int st = !d->kap ? PST_ENOMEM : op->dim == 2 ? qs_precompute_t(op, 2) : qs_precompute_t(op, 3);
    PST_CHECK(st != PST_OK, PST_ENOMEM, err,
              "qsfdi: cannot allocate the coefficients of %zu particles", op->n);
    return PST_OK;
}

/* ---- apply and emission ------------------------------------------------------------------ */

/* The weight a_IJ of row i (centre xi, 1/h_I ih, coefficients kap) for neighbour j. */
PST_KHOT double qs_row_weight(const qs_ctx *k, int D, const double xi[3], double ih,
                              const double *kap, size_t j)
{
    double r[3] = {0, 0, 0}, o2, o4;
    qs_pair(k, D, xi, ih, j, r, &o2, &o4);
    return qs_weight(D, r, o2, o4, kap);
}

/* The weight of row j for its neighbour i (the reverse of a pair, from row j's own data). */
PST_KHOT double qs_weight_to(const qs_ctx *k, const qs_data *d, int D, size_t j, size_t i)
{
    double xj[3] = {0, 0, 0};
    for (int a = 0; a < D; ++a)
        xj[a] = k->c.x[a][j];
    return qs_row_weight(k, D, xj, 1.0 / pst_h(&k->c, j), d->kap + (size_t)QS_NK(D) * j, i);
}

/* Row i into y (apply) or its weights into w (emission), for constant D. */
PST_KHOT void qs_row_t(const qs_ctx *k, const qs_data *d, const int64_t *off, const uint32_t *idx,
                     size_t i, const double *u, double *y, double *w, int D)
{
    const int nk = QS_NK(D);
    double kap[15], xi[3] = {0, 0, 0}, ih = 1.0 / pst_h(&k->c, i);
    memcpy(kap, d->kap + (size_t)nk * i, (size_t)nk * sizeof *kap);
    for (int a = 0; a < D; ++a)
        xi[a] = k->c.x[a][i];
    PST_ROW_LOOP(off, idx, i, u, y, w, j, qs_row_weight(k, D, xi, ih, kap, j));
}

/* Matrix-free apply: each pair's weight recomputed from positions and kappa_I. Compute-bound:
 * a sqrt, a division, ~19 flops of kernel and ~30 (2D) / ~45 (3D) of monomials and kappa per
 * neighbour, against 4 bytes of index and a gather of x_J and u_J. */
static void qs_apply(const pst_op *op, const double *u, double *y)
{
    qs_ctx k = make_ctx(op);
    const qs_data *d = op->data;
    const int64_t *off = op->poff;
    const uint32_t *idx = op->pidx;
    if (k.c.dim == 2) {
#pragma omp parallel for schedule(static)
        for (size_t i = 0; i < op->n; ++i)
            if (k.c.kind[i] != PST_DIRICHLET)
                qs_row_t(&k, d, off, idx, i, u, y, NULL, 2);
    } else {
#pragma omp parallel for schedule(static)
        for (size_t i = 0; i < op->n; ++i)
            if (k.c.kind[i] != PST_DIRICHLET)
                qs_row_t(&k, d, off, idx, i, u, y, NULL, 3);
    }
}

/* Rows [i0, i1) of a half list (operator.h, half_rows), for constant D. With one h for the
 * cloud a pair's geometry serves both of its weights (r_JI = -r_IJ exactly, the same omegas):
 * one sqrt and one division for two weights, each bit for bit apply's. With per-particle h each
 * direction is computed as apply computes it. Compute-bound like apply: two kappa dot products
 * per pair, 4 bytes of index, x_J, u_J and kappa_J gathered and y_J written back. */
PST_KHOT void qs_half_t(const qs_ctx *k, const qs_data *d, const int64_t *off,
                        const uint32_t *idx, size_t i0, size_t i1, const double *u, double *y,
                        int D)
{
    const int nk = QS_NK(D);
    const uint8_t *kind = k->c.kind;
    for (size_t i = i0; i < i1; ++i) {
        double xi[3] = {0, 0, 0}, ih = 1.0 / pst_h(&k->c, i);
        const double *kap = d->kap + (size_t)nk * i;
        for (int a = 0; a < D; ++a)
            xi[a] = k->c.x[a][i];
        if (k->c.h) {
            PST_HALF_LOOP(off, idx, kind, i, u, y, j, (void)0,
                          qs_row_weight(k, D, xi, ih, kap, j), qs_weight_to(k, d, D, j, i));
        } else {
            double r[3] = {0, 0, 0}, m[3] = {0, 0, 0}, o2, o4;
            PST_HALF_LOOP(off, idx, kind, i, u, y, j, qs_pair(k, D, xi, ih, j, r, &o2, &o4),
                          qs_weight(D, r, o2, o4, kap),
                          qs_weight(D, pst_negated(D, r, m), o2, o4, d->kap + (size_t)nk * j));
        }
    }
}

static void qs_half_rows(const pst_op *op, const int64_t *off, const uint32_t *idx, size_t i0,
                         size_t i1, const double *u, double *y)
{
    qs_ctx k = make_ctx(op);
    if (k.c.dim == 2)
        qs_half_t(&k, op->data, off, idx, i0, i1, u, y, 2);
    else
        qs_half_t(&k, op->data, off, idx, i0, i1, u, y, 3);
}

static void qs_emit_row(const pst_op *op, size_t i, double *w)
{
    qs_ctx k = make_ctx(op);
    if (k.c.dim == 2)
        qs_row_t(&k, op->data, op->poff, op->pidx, i, NULL, NULL, w, 2);
    else
        qs_row_t(&k, op->data, op->poff, op->pidx, i, NULL, NULL, w, 3);
}

/* ---- one-off derivatives: gradient and Hessian -------------------------------------------- */

/* Gradient (which = 0) or Hessian (1) of u at every particle: one pass of geometry and data
 * moments per particle, the inversions, then one kappa per component dotted with the data
 * moments (spec §1.9: no stored weights needed). Fallback rows: the linear WLS gradient (or 0)
 * and a zero Hessian. */
PST_KHOT void qs_derivs_t(const pst_op *op, const double *u, double *const out[6], int which,
                        int D)
{
    qs_ctx k = make_ctx(op);
    const int64_t *off = pst_nlist_offsets(op->nl);
    const uint32_t *idx = pst_nlist_indices(op->nl);
    const int n2 = QS_N2(D), nq = QS_NQ(D), nk = QS_NK(D), mn = qs_min(D);
    const int ncomp = which ? nq : D;
#pragma omp parallel for schedule(dynamic, 64)
    for (size_t i = 0; i < op->n; ++i) {
        double xi[3] = {0, 0, 0}, mom[QS_NMOM], du2[9], du4[6], h = pst_h(&k.c, i);
        for (int a = 0; a < D; ++a)
            xi[a] = k.c.x[a][i];
        int live = qs_moments(&k, D, xi, 1.0 / h, idx, off[i], off[i + 1], u, u[i], mom,
                              mom + n2, du2, du4);
        qs_state st;
        int fit = live >= mn && qs_invert(&k, D, mom, mom + n2, &st) < PST_ROW_RANK_DEFICIENT;
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
                qs_fallback_gradient(&k, D, mom, mom + n2, lg, kap);
            else
                memset(kap, 0, sizeof kap);
            double v = 0;
            for (int a = 0; a < nq; ++a)
                v += kap[a] * du4[a];
            for (int a = 0; a < nk - nq; ++a)
                v += kap[nq + a] * du2[a];
            out[c][i] = which ? v / (h * h) : v / h;
        }
    }
}

static void qs_gradient(const pst_op *op, const double *u, double *const grad[3])
{
    double *const out[6] = {grad[0], grad[1], grad[2], NULL, NULL, NULL};
    if (op->dim == 2)
        qs_derivs_t(op, u, out, 0, 2);
    else
        qs_derivs_t(op, u, out, 0, 3);
}

static void qs_hessian(const pst_op *op, const double *u, double *const hess[6])
{
    if (op->dim == 2)
        qs_derivs_t(op, u, hess, 1, 2);
    else
        qs_derivs_t(op, u, hess, 1, 3);
}

/* ---- interpolation at points (spec §1.7, eqs. 32-35) ---------------------------------------- */

/* Value and Laplacian at point p with neighbours idx[e0..e1) and smoothing length h:
 * Phi_k = omega1_k - tau^T Phi^all_k, <p> = sum Phi_k u_k / M0, lap = sum a_k (u_k - <p>).
 * Returns 0 (fallback) for too few neighbours, a singular fit or M0 not positive. The data
 * are taken relative to uref (the nearest neighbour's value) to keep rounding small. */
PST_KHOT int qs_point_t(const qs_ctx *k, int D, const double p[3], double h, const uint32_t *idx,
                      int64_t e0, int64_t e1, const double *u, double uref, double *value,
                      double *lap)
{
    const int n2 = QS_N2(D), nq = QS_NQ(D);
    double mom[QS_NMOM], ih = 1.0 / h;
    if (qs_moments(k, D, p, ih, idx, e0, e1, NULL, 0.0, mom, mom + n2, NULL, NULL) < qs_min(D))
        return 0;
    qs_state st;
    if (qs_invert(k, D, mom, mom + n2, &st) >= PST_ROW_RANK_DEFICIENT)
        return 0;
    /* tau = sum omega1 (r; r2s / 2; r2c), omega1 = w / d */
    double tau[9] = {0};
    for (int64_t e = e0; e < e1; ++e) {
        double r[3] = {0, 0, 0}, o2, o4, qm[6];
        qs_pair(k, D, p, ih, idx[e], r, &o2, &o4);
        qs_quad(D, r, qm);
        double o1 = o2 * sqrt(qm[0] + qm[1] + (D == 3 ? qm[2] : 0.0)); /* w/d = omega2 d */
        for (int a = 0; a < D; ++a)
            tau[a] += o1 * r[a];
        for (int a = 0; a < nq; ++a)
            tau[D + a] += o1 * (a < D ? 0.5 : 1.0) * qm[a];
    }
    double kt[15], kl[15], one[3] = {1, 1, 1}, zero[3] = {0, 0, 0};
    qs_functional(D, &st, tau, tau + D, tau + 2 * D, kt);
    qs_functional(D, &st, zero, one, zero, kl);
    double sp = 0, m0 = 0, sphi = 0, sa = 0, sau = 0;
    for (int64_t e = e0; e < e1; ++e) {
        double r[3] = {0, 0, 0}, o2, o4;
        size_t j = idx[e];
        qs_pair(k, D, p, ih, j, r, &o2, &o4);
        double d2 = 0;
        for (int a = 0; a < D; ++a)
            d2 += r[a] * r[a];
        double o1 = o2 * sqrt(d2);
        double phi = o1 - qs_weight(D, r, o2, o4, kt), a = qs_weight(D, r, o2, o4, kl);
        double du = u[j] - uref;
        sp += phi * du;
        m0 += phi;
        sphi += fabs(phi);
        sa += a;
        sau += a * du;
    }
    if (!(fabs(m0) > k->rank_tol * sphi))
        return 0; /* M0 = 0: the value is undetermined (e.g. neighbours on one circle) */
    double v = sp / m0;
    *value = uref + v;
    *lap = (sau - sa * v) * ih * ih;
    return 1;
}

static int qs_interpolate(const pst_op *op, const double *const pts[3], size_t m,
                          const double *u, double *value, double *lap, size_t *fallbacks,
                          char *err)
{
    qs_ctx k = make_ctx(op);
    int D = op->dim;
    for (size_t q = 0; q < m; ++q)
        for (int a = 0; a < D; ++a)
            PST_CHECK(!isfinite(pts[a][q]), PST_EINVAL, err,
                      "interpolation point %zu has a non-finite coordinate", q);
    double h = pst_cloud_h_max(op->cloud);
    int64_t *off;
    uint32_t *idx;
    int st = pst_points_neighbours(op->cloud, pts, m, k.supp * h, &off, &idx, err);
    if (st != PST_OK)
        return st;
    size_t nfb = 0;
#pragma omp parallel for schedule(dynamic, 64) reduction(+ : nfb)
    for (size_t q = 0; q < m; ++q) {
        double p[3] = {0, 0, 0}, v = 0, l = 0;
        for (int a = 0; a < D; ++a)
            p[a] = pts[a][q];
        /* the nearest particle: among the neighbours, else over the whole cloud (rare) */
        size_t near = 0;
        double best = INFINITY;
        int64_t e0 = off[q], e1 = off[q + 1];
        size_t cand = e0 < e1 ? (size_t)(e1 - e0) : op->n;
        for (size_t t = 0; t < cand; ++t) {
            size_t j = e0 < e1 ? idx[e0 + (int64_t)t] : t;
            double d2 = 0;
            for (int a = 0; a < D; ++a)
                d2 += (k.c.x[a][j] - p[a]) * (k.c.x[a][j] - p[a]);
            if (d2 < best) {
                best = d2;
                near = j;
            }
        }
        double uref = op->n ? u[near] : 0.0;
        int ok = D == 2 ? qs_point_t(&k, 2, p, h, idx, e0, e1, u, uref, &v, &l)
                        : qs_point_t(&k, 3, p, h, idx, e0, e1, u, uref, &v, &l);
        if (!ok) {
            v = uref;
            l = 0;
            ++nfb;
        }
        if (value)
            value[q] = v;
        if (lap)
            lap[q] = l;
    }
    pst_free(off);
    pst_free(idx);
    *fallbacks = nfb;
    return PST_OK;
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
    .half_rows = qs_half_rows,
    .amg_radius = 1.3, /* docs/solving.md: 1.6 h's iterations, 60 % of its entries */
    .precompute = qs_precompute,
    .apply = qs_apply,
    .emit_row = qs_emit_row,
    .gradient = qs_gradient,
    .hessian = qs_hessian,
    .interpolate = qs_interpolate,
    .free_data = qs_free,
    .data_bytes = {64, 120}, /* kap: QS_NK = 8 / 15 doubles */
};
