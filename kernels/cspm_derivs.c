/* The CSPM family's gradient and Hessian (kernels/cspm_family.c): both are linear in a row's
 * data sums S = (S1, S2) (cspm_family.h), g = G S and H = Hm S, with G and Hm folded from the
 * row's inverses; kept by the precompute (opts.keep) or refitted per call. */
#include "cspm_family.h"
#include "isa.h"

#include <string.h>

/* A row's derivatives from its inverses: H = 2 X^-1 (S2 - N21 M1^-1 S1) on the ICSPM and CSPM
 * levels (ICSPM's Schur complement, or CSPM's M2; 0 on the others), the gradient M1^-1 S1,
 * less M1^-1 N12 H / 2 on the ICSPM level (47) (the kernel gradient where M1 is singular). As
 * matrices on S = (S1, S2), with R = 2 X^-1 and T = N21 M1^-1:
 *     Hm = (-R T, R),   G = (M1^-1, 0) - (M1^-1 N12 / 2) Hm   (the last term ICSPM only).
 * G has ng columns: cs_ns for icspm, D (M1^-1) for the schemes without the ICSPM level. About
 * 800 flops per row in 3D on the ICSPM level, a few % of the precompute. */
PST_KHOT void fold_t(int D, int ng, const cs_inv *v, double *G, double *Hm)
{
    const int n2 = cs_n2(D), ns = cs_ns(D);
    double H[6 * 9];
    memset(H, 0, sizeof H);
    if (v->level == CS_ICSPM || v->level == CS_CSPM) {
        double T[6 * 3];
        cs_n21_m1inv(D, v, T);
        for (int p = 0; p < n2; ++p) {
            for (int q = 0; q < n2; ++q)
                H[p * ns + D + q] = 2.0 * v->Xinv[p * n2 + q];
            for (int b = 0; b < D; ++b) {
                double s = 0;
                for (int q = 0; q < n2; ++q)
                    s += H[p * ns + D + q] * T[q * D + b];
                H[p * ns + b] = -s;
            }
        }
    }
    if (Hm)
        memcpy(Hm, H, (size_t)(n2 * ns) * sizeof *Hm);
    if (!G)
        return;
    for (int a = 0; a < D; ++a)
        for (int b = 0; b < ng; ++b)
            G[a * ng + b] = b < D ? v->M1inv[a * D + b] : 0.0;
    if (v->level != CS_ICSPM)
        return;
    double U[3 * 6]; /* M1^-1 N12 / 2 */
    for (int a = 0; a < D; ++a)
        for (int q = 0; q < n2; ++q) {
            double s = 0;
            for (int c = 0; c < D; ++c)
                s += v->M1inv[a * D + c] * v->N12[c * n2 + q];
            U[a * n2 + q] = 0.5 * s;
        }
    for (int a = 0; a < D; ++a)
        for (int b = 0; b < ng; ++b) { /* ng = ns: only icspm rows reach the ICSPM level */
            double s = 0;
            for (int q = 0; q < n2; ++q)
                s += U[a * n2 + q] * H[q * ns + b];
            G[a * ng + b] -= s;
        }
}

/* Per dimension, so that the loops unroll, compiled per ISA: the precompute and the refit call
 * the same code, so the kept and the refitted matrices have the same bits. */
PST_ISA_DISPATCH void pst_cs_fold(int D, int ng, const cs_inv *v, double *G, double *Hm)
{
    if (D == 2)
        ng == 2 ? fold_t(2, 2, v, G, Hm) : fold_t(2, 5, v, G, Hm);
    else
        ng == 3 ? fold_t(3, 3, v, G, Hm) : fold_t(3, 9, v, G, Hm);
}

/* The matrices of row i: the kept ones, or refitted into G and Hm (moments, the precompute's
 * fallback chain, the fold). Returns the one asked for (hessian or not). */
static const double *matrices(const pst_op *op, const cs_ctx *k, size_t i, int hessian,
                              double *G, double *Hm)
{
    const cs_data *d = op->data;
    const int D = k->c.dim, ng = cs_ng(D, k->which);
    if (!hessian && d->G)
        return d->G + (size_t)(D * ng) * i;
    if (hessian && d->Hm)
        return d->Hm + (size_t)(cs_n2(D) * cs_ns(D)) * i;
    double m[3 * CS_NM_MAX];
    int count = pst_cs_moments(k, k->which, i, m);
    cs_inv v;
    pst_cs_invert(op, k, i, k->c.kind[i] == PST_NEUMANN, count, m, &v);
    pst_cs_fold(D, ng, &v, hessian ? NULL : G, hessian ? Hm : NULL);
    return hessian ? Hm : G;
}

/* out[r] = sum_b A[r][b] S[b] for the rows r < nr of the row-major nr x ns matrix A. */
static void times(int nr, int ns, const double *A, const double *S, double *out)
{
    for (int r = 0; r < nr; ++r) {
        double s = 0;
        for (int b = 0; b < ns; ++b)
            s += A[r * ns + b] * S[b];
        out[r] = s;
    }
}

void pst_cs_gradient(const pst_op *op, const double *u, double *const grad[3])
{
    cs_ctx k = make_ctx(op);
    const int D = k.c.dim, ng = cs_ng(D, k.which);
#pragma omp parallel for schedule(dynamic, 1)
    for (size_t b = 0; b < pst_chunks(op->n, PST_CHUNK); ++b)
        PST_CHUNK_ROWS(op->tally, b, op->n, PST_CHUNK, i) {
            double G[3 * 9], S[9], g[3];
            const double *A = matrices(op, &k, i, 0, G, NULL);
            pst_cs_data_sums(&k, i, u, ng, S);
            times(D, ng, A, S, g);
            for (int a = 0; a < D; ++a)
                grad[a][i] = g[a];
        }
}

/* pst_op_hessian's layout: 2D xx, yy, xy; 3D xx, yy, zz, xy, xz, yz (from the packed order). */
void pst_cs_hessian(const pst_op *op, const double *u, double *const hess[6])
{
    static const int out2[3] = {0, 2, 1}, out3[6] = {0, 3, 4, 1, 5, 2};
    cs_ctx k = make_ctx(op);
    const int D = k.c.dim, n2 = cs_n2(D), ns = cs_ns(D);
#pragma omp parallel for schedule(dynamic, 1)
    for (size_t b = 0; b < pst_chunks(op->n, PST_CHUNK); ++b)
        PST_CHUNK_ROWS(op->tally, b, op->n, PST_CHUNK, i) {
            double Hm[6 * 9], S[9], hs[6];
            const double *A = matrices(op, &k, i, 1, NULL, Hm);
            pst_cs_data_sums(&k, i, u, ns, S);
            times(n2, ns, A, S, hs);
            for (int p = 0; p < n2; ++p)
                hess[D == 2 ? out2[p] : out3[p]][i] = hs[p];
        }
}
