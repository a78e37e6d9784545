/* The Lukyanov-Vuik family's whole-list rows in chunks: the matrix-free apply's rows that the
 * lanes (lv_lanes.c) do not serve (G2-G4, and every Neumann row), the emission of every row
 * (pst_op_store) and the gradient's rows, a chunk of up to LV_CHUNK neighbours at a time in
 * vector lanes (docs/operators.md). A file of its own so that its 32 instantiations (dimension, gradient
 * variant, tensor, pair mean) compile beside the precompute (lv_family.c) and the half-list
 * rows (lv_half_rows.c). */
#include "isa.h"
#include "lv_chunks.h"

/* The weights of row i for its neighbours idx[0..n) into t (with L: chunk_geometry's). */
PST_KHOT void chunk_weights(const lv_ctx *k, int D, int G, int T, int H, size_t i,
                            const uint32_t *idx, int n, double *t, const pst_lanes *L,
                            double *du)
{
    lv_chunk ch;
    chunk_geometry(k, D, needs_w(G), i, idx, n, &ch, L, du);
    chunk_weights_of(k, D, G, T, H, i, idx, n, &ch, t);
}

/* Row i into y (apply, from the packed rows: pst_lanes_gather) or its weights into w
 * (emission, from the positions), a chunk of neighbours at a time: the chunk's geometry and
 * weights in vector lanes (chunk_weights), then their dot product with u_J - u_I in the lanes
 * of pst_lanes_dot_blocks. The apply runs every loop of a chunk over whole blocks of 8, so
 * that none has a scalar tail (19-20 % of the 3D apply; bench/README.md): the lanes past the
 * row take the next row's neighbours, whose weights are computed and never summed; the list's
 * last row, with nothing after it, computes its own pairs only and zeros the rest. */
PST_KHOT void row_t(const lv_ctx *k, const int64_t *off, const uint32_t *idx, size_t i,
                    double *y, double *w, int D, int G, int T, int H)
{
    double t[LV_CHUNK], du[LV_CHUNK];
    pst_v8 acc = pst_v8_splat(0.0);
    for (int64_t c0 = off[i]; c0 < off[i + 1]; c0 += LV_CHUNK) {
        int n = (int)(off[i + 1] - c0 < LV_CHUNK ? off[i + 1] - c0 : LV_CHUNK);
        if (w) {
            chunk_weights(k, D, G, T, H, i, idx + c0, n, w + (c0 - off[i]), NULL, NULL);
        } else {
            int m = (n + PST_LANES - 1) / PST_LANES * PST_LANES, whole = c0 + m <= k->list_end;
            pst_lanes L = pst_lanes_row(&k->c, i, 1.0);
            chunk_weights(k, D, G, T, H, i, idx + c0, whole ? m : n, t, &L, du);
            for (int c = whole ? m : n; c < m; ++c)
                t[c] = 0.0;
            acc = pst_lanes_dot_blocks(n, t, du, acc);
        }
    }
    if (!w)
        y[i] = pst_v8_sum(acc);
}

/* row_t instantiated per dimension, gradient variant, mobility (T) and pair mean (H), in the
 * widest vector ISA. */
#define LV_ROW(D, G, T, H)                                                                     \
    PST_ISA_DISPATCH static void row_##D##_##G##_##T##_##H(const lv_ctx *k, const int64_t *off, \
                                                           const uint32_t *idx, size_t i,      \
                                                           double *y, double *w)               \
    {                                                                                          \
        row_t(k, off, idx, i, y, w, D, G, T, H);                                               \
    }
#define LV_ROWS_H(D, G) LV_ROW(D, G, 0, 0) LV_ROW(D, G, 0, 1) LV_ROW(D, G, 1, 0) LV_ROW(D, G, 1, 1)
#define LV_ROWS_G(D) LV_ROWS_H(D, 1) LV_ROWS_H(D, 2) LV_ROWS_H(D, 3) LV_ROWS_H(D, 4)
LV_ROWS_G(2)
LV_ROWS_G(3)
#define LV_ENTRY(D, G)                                                                         \
    {{row_##D##_##G##_0_0, row_##D##_##G##_0_1}, {row_##D##_##G##_1_0, row_##D##_##G##_1_1}}
static const lv_row_fn row_table[2][4][2][2] = {
    {LV_ENTRY(2, 1), LV_ENTRY(2, 2), LV_ENTRY(2, 3), LV_ENTRY(2, 4)},
    {LV_ENTRY(3, 1), LV_ENTRY(3, 2), LV_ENTRY(3, 3), LV_ENTRY(3, 4)}};

/* A diagonal tensor (T) when the mobility has dim > 1 components; the harmonic pair mobility
 * (H) when asked for. */
lv_row_fn lv_row_for(const lv_ctx *k)
{
    return row_table[k->c.dim - 2][k->variant - 1][k->c.ncomp > 1][k->harmonic];
}

/* <grad u>_I = C_I sum_J V_J (u_J - u_I) g_IJ (54) of row i into g, a chunk of neighbours at a
 * time: the chunk's geometry (chunk_geometry), then g_IJ (gradient_from) and the D sums in
 * vector lanes. Per pair about the chunk rows' work less the weight. */
PST_KHOT void gradient_row_t(const lv_ctx *k, const int64_t *off, const uint32_t *idx, size_t i,
                             const double *u, double *g, int D, int G)
{
    double s[3] = {0, 0, 0};
    for (int64_t c0 = off[i]; c0 < off[i + 1]; c0 += LV_CHUNK) {
        int n = (int)(off[i + 1] - c0 < LV_CHUNK ? off[i + 1] - c0 : LV_CHUNK);
        const uint32_t *ix = idx + c0;
        lv_chunk ch;
        chunk_geometry(k, D, needs_w(G), i, ix, n, &ch, NULL, NULL);
        double s0 = 0, s1 = 0, s2 = 0;
#pragma omp simd reduction(+ : s0, s1, s2)
        for (int c = 0; c < n; ++c) {
            double gc[3], du = k->c.V[ix[c]] * (u[ix[c]] - u[i]);
            gradient_from(k, D, G, i, ix[c], &ch.x[0][c], LV_CHUNK, ch.d2[c], ch.a[c], ch.W[c],
                          gc);
            s0 += du * gc[0];
            s1 += du * gc[1];
            if (D == 3)
                s2 += du * gc[2];
        }
        s[0] += s0;
        s[1] += s1;
        s[2] += s2;
    }
    const double *C = k->d->C + (size_t)D * D * i;
    for (int a = 0; a < D; ++a) {
        double v = 0;
        for (int c = 0; c < D; ++c)
            v += C[a * D + c] * s[c];
        g[a] = v;
    }
}

/* gradient_row_t per dimension and gradient variant, in the widest vector ISA. */
#define LV_GRADIENT_ROW(D, G)                                                                  \
    PST_ISA_DISPATCH static void gradient_row_##D##_##G(                                       \
        const lv_ctx *k, const int64_t *off, const uint32_t *idx, size_t i, const double *u,   \
        double *g)                                                                             \
    {                                                                                          \
        gradient_row_t(k, off, idx, i, u, g, D, G);                                            \
    }
LV_GRADIENT_ROW(2, 1) LV_GRADIENT_ROW(2, 2) LV_GRADIENT_ROW(2, 3) LV_GRADIENT_ROW(2, 4)
LV_GRADIENT_ROW(3, 1) LV_GRADIENT_ROW(3, 2) LV_GRADIENT_ROW(3, 3) LV_GRADIENT_ROW(3, 4)
static const lv_gradient_row_fn gradient_row_table[2][4] = {
    {gradient_row_2_1, gradient_row_2_2, gradient_row_2_3, gradient_row_2_4},
    {gradient_row_3_1, gradient_row_3_2, gradient_row_3_3, gradient_row_3_4}};

lv_gradient_row_fn lv_gradient_row_for(const lv_ctx *k)
{
    return gradient_row_table[k->c.dim - 2][k->variant - 1];
}
