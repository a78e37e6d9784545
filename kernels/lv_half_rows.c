/* The Lukyanov-Vuik family's half-list rows in chunks (docs/operators.md, "The half-list
 * apply"): the rows of the half list that the lanes (lv_half_lanes.c) do not serve (G2-G4, and
 * every Neumann row), both weights of each pair (i, j > i) from one geometry, each the
 * whole-list rows' weight bit for bit. A file of its own so that its 32 instantiations
 * (dimension, gradient variant, tensor, pair mean) compile beside lv_rows.c. */
#include "isa.h"
#include "lv_chunks.h"

/* The weights w_JI of the pairs (J = idx[c], i) of a half-list chunk into t, each as row J's
 * own rows form it: weight_from reading row J's data by its index, with the pair's geometry ch
 * seen from J (x_JI = -x_IJ exactly; d^2, h~, a and W are the same both ways). GCC 12 leaves
 * the weight loop scalar ("no vectype for stmt"); the shared geometry is the gain (row J's
 * data copied per lane first vectorised it, at no clear gain: docs/operators.md). A Neumann row
 * J's weight a pair at a time (row_weight); degenerate pairs 0, as in chunk_weights_of. */
PST_KHOT void chunk_reverse_weights(const lv_ctx *k, int D, int G, int T, int H, size_t i,
                                    const uint32_t *idx, int n, const lv_chunk *ch, double *t)
{
    /* mrow: row J's own mobility (row_mobility's); mcol: I's, as J's pair reads its column */
    double x[3][LV_CHUNK], mrow[LV_CHUNK][3], mcol[3][LV_CHUNK], F[LV_CHUNK];
    for (int b = 0; b < D; ++b)
        for (int c = 0; c < n; ++c)
            x[b][c] = -ch->x[b][c];
    for (int b = 0; b < (T ? D : 1); ++b) {
        double m = pst_mob(&k->c, b, i);
        for (int c = 0; c < n; ++c) {
            mrow[c][b] = T ? k->c.mob[b][idx[c]] : pst_mob(&k->c, 0, idx[c]);
            mcol[b][c] = m;
        }
    }
#pragma omp simd
    for (int c = 0; c < n; ++c)
        t[c] = weight_from(k, D, G, T, H, idx[c], i, &x[0][c], LV_CHUNK, ch->d2[c], ch->a[c],
                           ch->W[c], mrow[c], &mcol[0][c], &F[c]);
    chunk_cut(n, F, t);
    for (int c = 0; c < n; ++c)
        if (k->c.kind[idx[c]] == PST_NEUMANN)
            t[c] = row_weight(k, D, G, T, H, idx[c], i);
}

/* Row i of a half list (operator.h, half_rows), for constant D, G, T, H, a chunk of its pairs
 * (i, j > i) at a time: the geometry once for both directions (chunk_geometry from the
 * positions, as the emission), w_IJ as the whole-list rows form it (chunk_weights_of) and w_JI
 * as row J's (chunk_reverse_weights); then, in list order, y_I += sum_J w_IJ (u_J - u_I)
 * unless I is a Dirichlet row and y_J -= w_JI (u_J - u_I) for each non-Dirichlet J.
 * The G1 rows but Neumann ones take lv_half_lanes.c's rows instead. */
PST_KHOT void half_row_t(const lv_ctx *k, const int64_t *off, const uint32_t *idx, size_t i,
                         const double *u, double *y, int D, int G, int T, int H)
{
    const uint8_t *kind = k->c.kind;
    const double ui = u[i];
    double s = 0;
    for (int64_t c0 = off[i]; c0 < off[i + 1]; c0 += LV_CHUNK) {
        int n = (int)(off[i + 1] - c0 < LV_CHUNK ? off[i + 1] - c0 : LV_CHUNK);
        const uint32_t *ic = idx + c0;
        lv_chunk ch;
        double wij[LV_CHUNK], wji[LV_CHUNK];
        chunk_geometry(k, D, needs_w(G), i, ic, n, &ch, NULL, NULL);
        chunk_weights_of(k, D, G, T, H, i, ic, n, &ch, wij);
        chunk_reverse_weights(k, D, G, T, H, i, ic, n, &ch, wji);
        for (int c = 0; c < n; ++c) {
            double du = u[ic[c]] - ui;
            s += wij[c] * du;
            if (kind[ic[c]] != PST_DIRICHLET)
                y[ic[c]] -= wji[c] * du;
        }
    }
    if (kind[i] != PST_DIRICHLET)
        y[i] += s;
}

/* half_row_t instantiated per dimension, gradient variant, mobility (T) and pair mean (H), in
 * the widest vector ISA. */
#define LV_HALF_ROW(D, G, T, H)                                                                \
    PST_ISA_DISPATCH static void half_row_##D##_##G##_##T##_##H(                               \
        const lv_ctx *k, const int64_t *off, const uint32_t *idx, size_t i, const double *u,   \
        double *y)                                                                             \
    {                                                                                          \
        half_row_t(k, off, idx, i, u, y, D, G, T, H);                                          \
    }
#define LV_HALF_ROWS_H(D, G)                                                                   \
    LV_HALF_ROW(D, G, 0, 0) LV_HALF_ROW(D, G, 0, 1) LV_HALF_ROW(D, G, 1, 0) LV_HALF_ROW(D, G, 1, 1)
#define LV_HALF_ROWS_G(D)                                                                      \
    LV_HALF_ROWS_H(D, 1) LV_HALF_ROWS_H(D, 2) LV_HALF_ROWS_H(D, 3) LV_HALF_ROWS_H(D, 4)
LV_HALF_ROWS_G(2)
LV_HALF_ROWS_G(3)
#define LV_HALF_ENTRY(D, G)                                                                    \
    {{half_row_##D##_##G##_0_0, half_row_##D##_##G##_0_1},                                     \
     {half_row_##D##_##G##_1_0, half_row_##D##_##G##_1_1}}
static const lv_half_row_fn half_row_table[2][4][2][2] = {
    {LV_HALF_ENTRY(2, 1), LV_HALF_ENTRY(2, 2), LV_HALF_ENTRY(2, 3), LV_HALF_ENTRY(2, 4)},
    {LV_HALF_ENTRY(3, 1), LV_HALF_ENTRY(3, 2), LV_HALF_ENTRY(3, 3), LV_HALF_ENTRY(3, 4)}};

lv_half_row_fn lv_half_row_for(const lv_ctx *k)
{
    return half_row_table[k->c.dim - 2][k->variant - 1][k->c.ncomp > 1][k->harmonic];
}

double lv_row_weight(const lv_ctx *k, size_t i, size_t j)
{
    return row_weight(k, k->c.dim, k->variant, k->c.ncomp > 1, k->harmonic, i, j);
}
