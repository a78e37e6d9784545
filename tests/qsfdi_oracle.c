/* The literal QSFDI: four passes over the neighbours, as the paper derives it (Appendix 1),
 * with the corrected definitions (Eqs. 16-19) and the corrected weights (Eqs. 28-31) of
 * docs/schemes/qsfdi.md:
 *   pass 1: M2c, A, B;   per j: G_j, Pi_j (Eq. 17)
 *   pass 2: M2s, P;      per j: Gamma_j (Eq. 18), q_j (Eq. 19)
 *   pass 3: M1q, Qc, Qs
 *   pass 4: Phi^g_j, Phi^s_j (Eqs. 28-29), a_j = 1^T Phi^s_j.
 * Deliberately independent of kernels/qsfdi.c: unscaled coordinates, explicit per-neighbour
 * vectors, and its own Gauss-Jordan inverse. */
#include "qsfdi_oracle.h"

#include "pstencil.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* inv = a^-1 (n x n, n <= 3) by Gauss-Jordan with partial pivoting; 0 when singular. */
static int invert(int n, const double *a, double *inv)
{
    double m[3][6];
    for (int r = 0; r < n; ++r)
        for (int c = 0; c < 2 * n; ++c)
            m[r][c] = c < n ? a[r * n + c] : (c - n == r);
    for (int c = 0; c < n; ++c) {
        int p = c;
        for (int r = c + 1; r < n; ++r)
            if (fabs(m[r][c]) > fabs(m[p][c]))
                p = r;
        if (m[p][c] == 0)
            return 0;
        for (int k = 0; k < 2 * n; ++k) {
            double t = m[c][k];
            m[c][k] = m[p][k];
            m[p][k] = t;
        }
        double d = m[c][c];
        for (int k = 0; k < 2 * n; ++k)
            m[c][k] /= d;
        for (int r = 0; r < n; ++r)
            if (r != c) {
                double f = m[r][c];
                for (int k = 0; k < 2 * n; ++k)
                    m[r][k] -= f * m[c][k];
            }
    }
    for (int r = 0; r < n; ++r)
        for (int c = 0; c < n; ++c)
            inv[r * n + c] = m[r][n + c];
    return 1;
}

/* y = M v for M rows x cols (row-major); with trans, y = M^T v. */
static void mv(int rows, int cols, const double *M, const double *v, double *y, int trans)
{
    int ny = trans ? cols : rows;
    for (int i = 0; i < ny; ++i) {
        y[i] = 0;
        for (int k = 0; k < (trans ? rows : cols); ++k)
            y[i] += (trans ? M[k * cols + i] : M[i * cols + k]) * v[k];
    }
}

int qsfdi_oracle_weights(int dim, const double *const x[3], const double xi[3],
                         const uint32_t *nb, size_t n, double h, int flags, double *lap,
                         double *grad)
{
    int D = dim, nc = D == 2 ? 1 : 3;
    double *r = calloc(n * 3, sizeof *r), *r2s = calloc(n * 3, sizeof *r2s),
           *r2c = calloc(n * 3, sizeof *r2c), *w4 = calloc(n, sizeof *w4),
           *w2 = calloc(n, sizeof *w2), *G = calloc(n * 3, sizeof *G),
           *Pi = calloc(n * 3, sizeof *Pi), *Ga = calloc(n * 3, sizeof *Ga),
           *q = calloc(n * 3, sizeof *q);
    int ok = r && r2s && r2c && w4 && w2 && G && Pi && Ga && q;
    for (size_t j = 0; ok && j < n; ++j) {
        double d2 = 0;
        for (int a = 0; a < D; ++a) {
            r[j * 3 + a] = x[a][nb[j]] - xi[a];
            d2 += r[j * 3 + a] * r[j * 3 + a];
        }
        double d = sqrt(d2);
        if (d > 1e-8 * h) {
            double w = pst_kernel_w(PST_KERNEL_QUINTIC, D, d, h);
            w2[j] = w / d2;
            w4[j] = w / (d2 * d2);
        }
        const double *v = r + j * 3;
        for (int a = 0; a < D; ++a)
            r2s[j * 3 + a] = v[a] * v[a];
        r2c[j * 3] = v[0] * v[1];
        if (D == 3) {
            r2c[j * 3 + 1] = v[0] * v[2];
            r2c[j * 3 + 2] = v[1] * v[2];
        }
    }
    /* pass 1 */
    double M2c[9] = {0}, A[9] = {0}, B[9] = {0}, M2ci[9], sw4c[3] = {0};
    for (size_t j = 0; ok && j < n; ++j)
        for (int c = 0; c < nc; ++c) {
            sw4c[c] += w4[j] * r2c[j * 3 + c];
            for (int e = 0; e < nc; ++e)
                M2c[c * nc + e] += w4[j] * r2c[j * 3 + c] * r2c[j * 3 + e];
            for (int a = 0; a < D; ++a) {
                A[c * D + a] += w4[j] * r2c[j * 3 + c] * r[j * 3 + a];
                B[c * D + a] += w4[j] * r2c[j * 3 + c] * r2s[j * 3 + a];
            }
        }
    ok = ok && invert(nc, M2c, M2ci);
    for (size_t j = 0; ok && j < n; ++j) { /* Eq. 17 */
        double t[3], tA[3], tB[3];
        mv(nc, nc, M2ci, r2c + j * 3, t, 0);
        mv(nc, D, A, t, tA, 1);
        mv(nc, D, B, t, tB, 1);
        for (int a = 0; a < D; ++a) {
            G[j * 3 + a] = r[j * 3 + a] - tA[a];
            Pi[j * 3 + a] = r2s[j * 3 + a] - tB[a];
        }
    }
    /* pass 2 */
    double M2s[9] = {0}, P[9] = {0}, M2si[9];
    for (size_t j = 0; ok && j < n; ++j)
        for (int s = 0; s < D; ++s)
            for (int a = 0; a < D; ++a) {
                M2s[s * D + a] += w4[j] * Pi[j * 3 + s] * Pi[j * 3 + a];
                P[s * D + a] += w4[j] * Pi[j * 3 + s] * G[j * 3 + a];
            }
    ok = ok && invert(D, M2s, M2si);
    double cs = 0, t[3];
    if (ok) { /* the printed Gamma's scalar r2c_j^T M2c^-1 sum_k omega4 r2c_k needs t */
        mv(nc, nc, M2ci, sw4c, t, 0);
    }
    for (size_t j = 0; ok && j < n; ++j) {
        if (flags & QSFDI_ORACLE_PRINTED_GAMMA) {
            cs = 0;
            for (int c = 0; c < nc; ++c)
                cs += r2c[j * 3 + c] * t[c];
        }
        double u[3], v[3];
        for (int s = 0; s < D; ++s) /* Eq. 18: corrected omega4 Pi_j; printed minus Pi_j cs */
            Ga[j * 3 + s] = w4[j] * Pi[j * 3 + s] - Pi[j * 3 + s] * cs;
        mv(D, D, M2si, Pi + j * 3, u, 0); /* Eq. 19: q = G - P^T M2s^-1 Pi */
        mv(D, D, P, u, v, 1);
        for (int a = 0; a < D; ++a)
            q[j * 3 + a] = G[j * 3 + a] - v[a];
    }
    /* pass 3 */
    double M1q[9] = {0}, Qc[9] = {0}, Qs[9] = {0}, M1qi[9];
    for (size_t j = 0; ok && j < n; ++j)
        for (int a = 0; a < D; ++a) {
            for (int b = 0; b < D; ++b) {
                M1q[a * D + b] += w2[j] * q[j * 3 + a] * q[j * 3 + b];
                Qs[a * D + b] += w2[j] * q[j * 3 + a] * Pi[j * 3 + b];
            }
            for (int c = 0; c < nc; ++c)
                Qc[a * nc + c] += w2[j] * q[j * 3 + a] * r2c[j * 3 + c];
        }
    ok = ok && invert(D, M1q, M1qi);
    /* pass 4: Eqs. 28-29 (corrected) */
    for (size_t j = 0; ok && j < n; ++j) {
        double t1[3], t2[3], t3[3], t4[3], br[3], phig[3], phis[3];
        mv(nc, nc, M2ci, r2c + j * 3, t1, 0);
        mv(D, nc, Qc, t1, t2, 0);
        mv(D, D, M2si, Ga + j * 3, t3, 0);
        mv(D, D, Qs, t3, t4, 0);
        for (int a = 0; a < D; ++a)
            br[a] = w2[j] * q[j * 3 + a] - w4[j] * t2[a] - t4[a];
        mv(D, D, M1qi, br, phig, 0);
        mv(D, D, P, phig, t1, 0);
        for (int s = 0; s < D; ++s)
            t2[s] = Ga[j * 3 + s] - t1[s];
        mv(D, D, M2si, t2, phis, 0);
        lap[j] = 0;
        for (int s = 0; s < D; ++s)
            lap[j] += 2.0 * phis[s];
        if (grad)
            for (int a = 0; a < D; ++a)
                grad[j * D + a] = phig[a];
    }
    free(r);
    free(r2s);
    free(r2c);
    free(w4);
    free(w2);
    free(G);
    free(Pi);
    free(Ga);
    free(q);
    return ok;
}
