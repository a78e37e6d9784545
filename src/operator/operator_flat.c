/* Flat neighbourhoods (docs/operators.md, "Flat neighbourhoods"): an interior row whose live
 * neighbours all lie on one line (2D) or plane (3D) that misses the particle cannot be exact
 * for linear fields with a non-zero diagonal (linear exactness, sum_J w_IJ (x_J - x_I) = 0,
 * makes x_I an affine combination of the x_J unless sum_J w_IJ = 0). The moment matrices the
 * schemes invert can still be regular there, so this is checked here, on the geometry alone,
 * for the schemes with a `degrade` hook. */
#include "operator.h"

#include "internal.h"
#include "operator_flat_sums.h"
#include "small_matrix.h"

#include <math.h>

/* Eigenvalues w and eigenvectors (columns of v) of the symmetric dim x dim matrix a (row-major,
 * destroyed) by cyclic Jacobi rotations: a few sweeps for 2 x 2 and 3 x 3. */
static void sym_eigen(int dim, double *a, double *w, double *v)
{
    for (int r = 0; r < dim; ++r)
        for (int c = 0; c < dim; ++c)
            v[r * dim + c] = r == c;
    for (int sweep = 0; sweep < 32; ++sweep) {
        double off = 0;
        for (int p = 0; p < dim; ++p)
            for (int q = p + 1; q < dim; ++q)
                off += a[p * dim + q] * a[p * dim + q];
        if (!(off > 0))
            break;
        for (int p = 0; p < dim; ++p)
            for (int q = p + 1; q < dim; ++q) {
                double apq = a[p * dim + q];
                if (apq == 0)
                    continue;
                double th = (a[q * dim + q] - a[p * dim + p]) / (2 * apq);
                double t = (th >= 0 ? 1.0 : -1.0) / (fabs(th) + sqrt(th * th + 1));
                double cs = 1 / sqrt(t * t + 1), sn = t * cs;
                for (int k = 0; k < dim; ++k) { /* a <- J^T a J, v <- v J */
                    double akp = a[k * dim + p], akq = a[k * dim + q];
                    a[k * dim + p] = cs * akp - sn * akq;
                    a[k * dim + q] = sn * akp + cs * akq;
                }
                for (int k = 0; k < dim; ++k) {
                    double apk = a[p * dim + k], aqk = a[q * dim + k];
                    a[p * dim + k] = cs * apk - sn * aqk;
                    a[q * dim + k] = sn * apk + cs * aqk;
                }
                for (int k = 0; k < dim; ++k) {
                    double vkp = v[k * dim + p], vkq = v[k * dim + q];
                    v[k * dim + p] = cs * vkp - sn * vkq;
                    v[k * dim + q] = sn * vkp + cs * vkq;
                }
            }
    }
    for (int k = 0; k < dim; ++k)
        w[k] = a[k * dim + k];
}

typedef struct {
    double cond; /* 1-norm condition of the centred second moment (INFINITY: fewer than
                    dim + 1 live neighbours, or exactly flat)                                */
    double miss; /* distance (in h_I) from I to the flat set's affine hull: the part of the
                    centroid offset along the moment's near-null directions (those below
                    1/cond_max of the largest); 0 when the set is not near-flat            */
} spread;

/* The spread of row i's live neighbours; the eigenvectors only for near-flat rows. */
static spread row_spread(const pst_op *op, size_t i)
{
    const int D = op->dim;
    double m[PST_FLAT_SUMS];
    pst_flat_sums(op, i, m);
    const double s0 = m[0], s1[3] = {m[1], m[2], m[3]};
    const double s2[3][3] = {{m[4], m[5], m[6]}, {m[5], m[7], m[8]}, {m[6], m[8], m[9]}};
    spread sp = {INFINITY, 0};
    if (s0 == 0)
        return sp;
    double cov[9], inv[9], w[3], v[9], mean[3];
    for (int a = 0; a < D; ++a)
        mean[a] = s1[a] / s0;
    for (int a = 0; a < D; ++a)
        for (int b = 0; b < D; ++b)
            cov[a * D + b] = s2[a][b] - s1[a] * mean[b];
    sp.cond = s0 < D + 1 ? INFINITY : pst_mat_inverse(D, cov, inv);
    if (!(sp.cond > op->opts.cond_max))
        return sp;
    sym_eigen(D, cov, w, v);
    double wmax = 0, miss2 = 0;
    for (int k = 0; k < D; ++k)
        wmax = fmax(wmax, w[k]);
    for (int k = 0; k < D; ++k)
        if (!(w[k] > wmax / op->opts.cond_max)) {
            double p = 0;
            for (int a = 0; a < D; ++a)
                p += mean[a] * v[a * D + k];
            miss2 += p * p;
        }
    sp.miss = sqrt(miss2);
    return sp;
}

void pst_op_check_flat_rows(pst_op *op)
{
    if (!op->scheme->degrade)
        return;
#pragma omp parallel for schedule(dynamic, 256)
    for (size_t i = 0; i < op->n; ++i) {
        if (op->kind[i] != PST_INTERIOR || op->status[i] >= PST_ROW_TOO_FEW)
            continue;
        spread sp = row_spread(op, i);
        /* a (near-)flat set through I is the schemes' own business: their moment matrices are
         * singular there and their fallback chains handle it */
        if (!(sp.miss > op->opts.min_pair_distance))
            continue;
        if (!(sp.cond * op->opts.rank_tol < 1.0)) {
            op->scheme->degrade(op, i);
            op->status[i] = PST_ROW_RANK_DEFICIENT;
        } else if (op->status[i] < PST_ROW_ILL_CONDITIONED) {
            op->status[i] = PST_ROW_ILL_CONDITIONED;
        }
    }
}
