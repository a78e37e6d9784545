/* The CSPM family's rows (kernels/cspm_family.c): each pair's weight a_Ij from the positions,
 * V_j and the row's coefficients, summed (the matrix-free apply) or written out (the emission of
 * a stored row), a chunk of neighbours at a time. */
#include "cspm_family.h"
#include "isa.h"

/* a_Ij of cspm_family.c's head comment for the chunk (V_j in g->b, d in g->c) into w; 0 for a
 * dead pair. Shared by apply and emit_row, so that the two apply paths agree bit for bit
 * (elementwise IEEE arithmetic: every ISA clone gives the same weights). */
PST_KHOT void cs_weights(pst_kernel K, int D, const cs_kc *kc, const double *Ki, int n,
                         const cs_chunk *g, double *restrict w)
{
    const int n2 = cs_n2(D);
    const double *lam = Ki, *sig = Ki + n2, *mu = Ki + 2 * n2, c0 = Ki[2 * n2 + D];
#pragma omp simd
    for (int c = 0; c < n; ++c) {
        const double d = g->c[c], q = d * kc->ih;
        CS_LIVE(kc, d, in, id);
        double w1 = kc->s1 * pst_sph_shape(K, D, q, 1), w2 = kc->s2 * pst_sph_shape(K, D, q, 2);
        double ql = 0, qs = 0, mr = 0;
        for (int p = 0; p < n2; ++p) {
            double m = g->r[cs_pa(D, p)][c] * g->r[cs_pb(D, p)][c];
            ql += lam[p] * m;
            qs += sig[p] * m;
        }
        for (int a = 0; a < D; ++a)
            mr += mu[a] * g->r[a][c];
        double id2 = id * id, a1 = w1 * id;
        w[c] = g->b[c] * ((w2 * ql + a1 * qs) * id2 + a1 * (c0 - mr));
    }
}

/* Row i into y (apply) or its weights into w (emission), a chunk at a time. */
PST_KHOT void row_t(const cs_ctx *k, int D, size_t i, const double *u, double *y, double *w)
{
    const double *Ki = k->K + (size_t)cs_ncoef(D) * i;
    const double xi[3] = {k->c.x[0][i], k->c.x[1][i], D == 3 ? k->c.x[2][i] : 0.0};
    const cs_kc kc = kc_of(k, D, pst_h(&k->c, i));
    const int64_t e0 = k->c.off[i], e1 = k->c.off[i + 1];
    double s = 0, ui = u ? u[i] : 0, wb[CS_CHUNK];
    for (int64_t c0 = e0; c0 < e1; c0 += CS_CHUNK) {
        const int n = (int)(e1 - c0 < CS_CHUNK ? e1 - c0 : CS_CHUNK);
        const uint32_t *idx = k->c.idx + c0;
        cs_chunk g;
        cs_gather(k, D, 1, xi, idx, n, &g);
        double *wc = w ? w + (c0 - e0) : wb;
        CS_BY_KERNEL(k->c.kernel, cs_weights, D, &kc, Ki, n, &g, wc);
        if (!w) {
#pragma omp simd reduction(+ : s)
            for (int c = 0; c < n; ++c)
                s += wb[c] * (u[idx[c]] - ui);
        }
    }
    if (!w)
        y[i] = s;
}

PST_ISA_DISPATCH static void row(const cs_ctx *k, size_t i, const double *u, double *y, double *w)
{
    if (k->c.dim == 2)
        row_t(k, 2, i, u, y, w);
    else
        row_t(k, 3, i, u, y, w);
}

/* Matrix-free apply: each pair's weight from the positions, V_j and the row's coefficients.
 * Compute-bound: a sqrt, one division and ~70 flops (2D) / ~90 (3D) per pair against 4 bytes
 * of list, 8 of V_j and 8 of u_J gathered; 3D 10^6 at 2 threads 6 ns per pair and thread (was
 * 19; qsfdi's apply 13). */
void pst_cs_apply(const pst_op *op, const double *u, double *y)
{
    cs_ctx k = make_ctx(op);
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < op->n; ++i)
        if (k.c.kind[i] != PST_DIRICHLET)
            row(&k, i, u, y, NULL);
}

void pst_cs_emit_row(const pst_op *op, size_t i, double *w)
{
    cs_ctx k = make_ctx(op);
    row(&k, i, NULL, NULL, w);
}
