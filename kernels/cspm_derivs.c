/* The CSPM family's gradient and Hessian (kernels/cspm_family.c): refitted per row from its
 * moments and the data sums through the precompute's fallback chain (not stored). */
#include "cspm_family.h"

/* Gradient and packed second derivatives of row i, refitted from the moments and the data
 * sums with the same chain as the precompute: ICSPM (47) on its level, the CSPM gradient (40)
 * elsewhere (the kernel gradient where M1 is singular); second derivatives from X (ICSPM's
 * Schur complement, or CSPM's M2 on that level; 0 on the others). */
static void refit(const pst_op *op, const cs_ctx *k, size_t i, const double *u, double *g,
                  double *hs)
{
    const int D = k->c.dim, n2 = cs_n2(D);
    double m[3 * CS_NM_MAX], S1[3], S2[6];
    int count = pst_cs_moments(k, k->which, i, m, u, S1, S2);
    cs_inv v;
    pst_cs_invert(op, k, i, k->c.kind[i] == PST_NEUMANN, count, m, &v);
    double H[6] = {0, 0, 0, 0, 0, 0}, t[6], gs[3];
    if (v.level == CS_ICSPM || v.level == CS_CSPM) {
        /* H = 2 X^-1 (S2 - N21 M1^-1 S1) */
        for (int a = 0; a < D; ++a) {
            gs[a] = 0;
            for (int c = 0; c < D; ++c)
                gs[a] += v.M1inv[a * D + c] * S1[c];
        }
        for (int p = 0; p < n2; ++p) {
            t[p] = S2[p];
            for (int c = 0; c < D; ++c)
                t[p] -= v.N21[p * D + c] * gs[c];
        }
        for (int p = 0; p < n2; ++p) {
            for (int q = 0; q < n2; ++q)
                H[p] += v.Xinv[p * n2 + q] * t[q];
            H[p] *= 2.0;
        }
    }
    double s[3];
    for (int a = 0; a < D; ++a)
        s[a] = S1[a];
    if (v.level == CS_ICSPM) /* (47): S1 - N12 H / 2 */
        for (int a = 0; a < D; ++a)
            for (int q = 0; q < n2; ++q)
                s[a] -= 0.5 * v.N12[a * n2 + q] * H[q];
    for (int a = 0; a < D; ++a) {
        g[a] = 0;
        for (int c = 0; c < D; ++c)
            g[a] += v.M1inv[a * D + c] * s[c];
    }
    if (hs)
        for (int p = 0; p < n2; ++p)
            hs[p] = H[p];
}

void pst_cs_gradient(const pst_op *op, const double *u, double *const grad[3])
{
    cs_ctx k = make_ctx(op);
#pragma omp parallel for schedule(dynamic, 1)
    for (size_t b = 0; b < pst_chunks(op->n, PST_CHUNK); ++b)
        PST_CHUNK_ROWS(op->tally, b, op->n, PST_CHUNK, i) {
            double g[3];
            refit(op, &k, i, u, g, NULL);
            for (int a = 0; a < k.c.dim; ++a)
                grad[a][i] = g[a];
        }
}

/* pst_op_hessian's layout: 2D xx, yy, xy; 3D xx, yy, zz, xy, xz, yz (from the packed order). */
void pst_cs_hessian(const pst_op *op, const double *u, double *const hess[6])
{
    static const int out2[3] = {0, 2, 1}, out3[6] = {0, 3, 4, 1, 5, 2};
    cs_ctx k = make_ctx(op);
    int n2 = cs_n2(k.c.dim);
#pragma omp parallel for schedule(dynamic, 1)
    for (size_t b = 0; b < pst_chunks(op->n, PST_CHUNK); ++b)
        PST_CHUNK_ROWS(op->tally, b, op->n, PST_CHUNK, i) {
            double g[3], hs[6];
            refit(op, &k, i, u, g, hs);
            for (int p = 0; p < n2; ++p)
                hess[k.c.dim == 2 ? out2[p] : out3[p]][i] = hs[p];
        }
}
