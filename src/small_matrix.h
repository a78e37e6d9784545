/* Closed-form inverses of the 2x2 and 3x3 per-particle matrices, with a 1-norm condition
 * number, inline so that precompute loops keep them in registers (no LAPACK call per particle:
 * its overhead alone is 100-300 ns). Row-major storage. */
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

#endif
