/* The CSPM family's stored rows (kernels/cspm_family.c): each pair's weight a_Ij from the
 * positions, V_j and the row's coefficients, written out a chunk of neighbours at a time (the
 * emission of a stored row; the matrix-free apply is in cspm_lanes.c). */
#include "cspm_family.h"
#include "isa.h"

/* cs_weight_xyz for the chunk (V_j in g->b, d in g->c) into w: the emission's weights. */
PST_KHOT void cs_weights(pst_kernel K, int D, const cs_kc *kc, const double *Ki, int n,
                         const cs_chunk *g, double *restrict w)
{
    for (int c = 0; c < n; ++c)
        w[c] = cs_weight_xyz(K, D, kc, Ki, g->r[0][c], g->r[1][c], D == 3 ? g->r[2][c] : 0.0,
                             g->c[c], g->b[c]);
}

/* The weights of row i into w, a chunk at a time (the emission). */
PST_KHOT void row_t(const cs_ctx *k, int D, size_t i, double *w)
{
    const double *Ki = k->K + (size_t)cs_ncoef(D) * i;
    const double xi[3] = {k->c.x[0][i], k->c.x[1][i], D == 3 ? k->c.x[2][i] : 0.0};
    const cs_kc kc = kc_of(k, D, pst_h(&k->c, i));
    const int64_t e0 = k->c.off[i], e1 = k->c.off[i + 1];
    for (int64_t c0 = e0; c0 < e1; c0 += CS_CHUNK) {
        const int n = (int)(e1 - c0 < CS_CHUNK ? e1 - c0 : CS_CHUNK);
        cs_chunk g;
        cs_gather(k, D, 1, xi, k->c.idx + c0, n, &g);
        CS_BY_KERNEL(k->c.kernel, cs_weights, D, &kc, Ki, n, &g, w + (c0 - e0));
    }
}

PST_ISA_DISPATCH static void row(const cs_ctx *k, size_t i, double *w)
{
    if (k->c.dim == 2)
        row_t(k, 2, i, w);
    else
        row_t(k, 3, i, w);
}

/* The emission of a stored row: the lane rows' weights (cs_weight_xyz), so the stored and the
 * matrix-free apply (cspm_lanes.c) sum the same numbers in the same lanes. */
void pst_cs_emit_row(const pst_op *op, size_t i, double *w)
{
    cs_ctx k = make_ctx(op);
    row(&k, i, w);
}
