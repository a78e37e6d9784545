/* Small dense algebra for the per-particle matrices, inline so that precompute loops keep them
 * in registers (no LAPACK call per particle: its overhead alone is 100-300 ns): closed-form
 * 2x2/3x3 inverses with a 1-norm condition number, LDL^T for SPD moment matrices and LU with
 * partial pivoting for general ones up to 10x10. Row-major storage. */
#ifndef PSTENCIL_SMALL_MATRIX_H
#define PSTENCIL_SMALL_MATRIX_H

#include <math.h>

/* The 1-norm (largest absolute column sum) of a dim x dim matrix. */
static inline double pst_mat_norm1(int dim, const double *a)
{
    double best = 0;
    for (int c = 0; c < dim; ++c) {
        double s = 0;
        for (int r = 0; r < dim; ++r)
            s += fabs(a[r * dim + c]);
        best = s > best ? s : best;
    }
    return best;
}

/* inv = a^-1 for dim 2 or 3 by the adjugate; returns the condition number
 * ||a||_1 ||a^-1||_1, or INFINITY (inv untouched) when a is exactly singular or not finite. */
static inline double pst_mat_inverse(int dim, const double *a, double *inv)
{
    double adj[9], det;
    if (dim == 2) {
        det = a[0] * a[3] - a[1] * a[2];
        adj[0] = a[3];
        adj[1] = -a[1];
        adj[2] = -a[2];
        adj[3] = a[0];
    } else {
        adj[0] = a[4] * a[8] - a[5] * a[7];
        adj[1] = a[2] * a[7] - a[1] * a[8];
        adj[2] = a[1] * a[5] - a[2] * a[4];
        adj[3] = a[5] * a[6] - a[3] * a[8];
        adj[4] = a[0] * a[8] - a[2] * a[6];
        adj[5] = a[2] * a[3] - a[0] * a[5];
        adj[6] = a[3] * a[7] - a[4] * a[6];
        adj[7] = a[1] * a[6] - a[0] * a[7];
        adj[8] = a[0] * a[4] - a[1] * a[3];
        det = a[0] * adj[0] + a[1] * adj[3] + a[2] * adj[6];
    }
    if (det == 0 || !isfinite(det))
        return INFINITY;
    int nn = dim * dim;
    for (int k = 0; k < nn; ++k)
        adj[k] /= det;
    double cond = pst_mat_norm1(dim, a) * pst_mat_norm1(dim, adj);
    if (!isfinite(cond))
        return INFINITY;
    for (int k = 0; k < nn; ++k)
        inv[k] = adj[k];
    return cond;
}

/* Strictly diagonally dominant with a positive diagonal (LV Definition 6 and Lemma 3). */
static inline int pst_mat_sdd_positive(int dim, const double *a)
{
    for (int r = 0; r < dim; ++r) {
        double off = 0;
        for (int c = 0; c < dim; ++c)
            off += c == r ? 0 : fabs(a[r * dim + c]);
        if (!(a[r * dim + r] > off))
            return 0;
    }
    return 1;
}

/* In-place LDL^T of a symmetric n x n matrix (n <= 10; only the lower triangle is read):
 * on return a[r*n + c] (c < r) holds L and a[r*n + r] holds D. No pivoting: the matrices
 * factored this way are weighted moment (Gram) matrices, SPD when the neighbourhood is not
 * degenerate. Returns the pivot ratio min D / max D, a cheap conditioning proxy: <= 0 (or
 * tiny) means singular or indefinite, and the caller falls back. */
static inline double pst_ldlt_factor(int n, double *a)
{
    double dmin = INFINITY, dmax = 0;
    for (int j = 0; j < n; ++j) {
        double d = a[j * n + j];
        for (int k = 0; k < j; ++k)
            d -= a[j * n + k] * a[j * n + k] * a[k * n + k];
        a[j * n + j] = d;
        dmin = d < dmin ? d : dmin;
        dmax = d > dmax ? d : dmax;
        if (!(d > 0))
            return d == 0 ? 0.0 : -1.0;
        for (int i = j + 1; i < n; ++i) {
            double v = a[i * n + j];
            for (int k = 0; k < j; ++k)
                v -= a[i * n + k] * a[j * n + k] * a[k * n + k];
            a[i * n + j] = v / d;
        }
    }
    return dmax > 0 ? dmin / dmax : 0.0;
}

/* Solve (L D L^T) x = b in place with the factor of pst_ldlt_factor. */
static inline void pst_ldlt_solve(int n, const double *f, double *b)
{
    for (int i = 0; i < n; ++i)
        for (int k = 0; k < i; ++k)
            b[i] -= f[i * n + k] * b[k];
    for (int i = 0; i < n; ++i)
        b[i] /= f[i * n + i];
    for (int i = n - 1; i >= 0; --i)
        for (int k = i + 1; k < n; ++k)
            b[i] -= f[k * n + i] * b[k];
}

/* In-place LU with partial pivoting of a general n x n matrix (n <= 10): piv[i] is the row
 * swapped into position i. Returns the pivot ratio min |U_ii| / max |U_ii| (0 when singular). */
static inline double pst_lu_factor(int n, double *a, int *piv)
{
    double umin = INFINITY, umax = 0;
    for (int j = 0; j < n; ++j) {
        int p = j;
        for (int i = j + 1; i < n; ++i)
            if (fabs(a[i * n + j]) > fabs(a[p * n + j]))
                p = i;
        piv[j] = p;
        if (p != j)
            for (int c = 0; c < n; ++c) {
                double t = a[j * n + c];
                a[j * n + c] = a[p * n + c];
                a[p * n + c] = t;
            }
        double d = a[j * n + j], ad = fabs(d);
        umin = ad < umin ? ad : umin;
        umax = ad > umax ? ad : umax;
        if (d == 0 || !isfinite(d))
            return 0.0;
        for (int i = j + 1; i < n; ++i) {
            double l = a[i * n + j] / d;
            a[i * n + j] = l;
            for (int c = j + 1; c < n; ++c)
                a[i * n + c] -= l * a[j * n + c];
        }
    }
    return umax > 0 ? umin / umax : 0.0;
}

/* Solve A x = b in place with the factor and pivots of pst_lu_factor. */
static inline void pst_lu_solve(int n, const double *f, const int *piv, double *b)
{
    for (int i = 0; i < n; ++i) {
        double t = b[i];
        b[i] = b[piv[i]];
        b[piv[i]] = t;
    }
    for (int i = 0; i < n; ++i)
        for (int k = 0; k < i; ++k)
            b[i] -= f[i * n + k] * b[k];
    for (int i = n - 1; i >= 0; --i) {
        for (int k = i + 1; k < n; ++k)
            b[i] -= f[i * n + k] * b[k];
        b[i] /= f[i * n + i];
    }
}

#endif
