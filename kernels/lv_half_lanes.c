/* The Lukyanov-Vuik family's G1 half-list rows in lanes (docs/operators.md, "The half-list
 * apply"): pairs (I, J > I), a block at a time from the packed rows, both weights of each pair (row
 * I's through lv_lanes.h as the whole-list rows compute it, row J's from J's data gathered or
 * transposed), any mobility (none, scalar, diagonal tensor), either pair mean, one h or h per
 * particle: each weight the whole-list apply's bit for bit. A file of its own, compiled once per
 * ISA level (src/core/isa.h) so that its blocks are as wide as the level's vectors
 * (kernels/lanes.h), and so that its 32 instantiations (dimension, kernel, tensor, pair mean)
 * compile beside lv_lanes.c. */
#include "lv_lanes.h"
#include "isa.h"

/* What a block of half-list row I reads of its rows J besides their positions: s_J, and
 * eta_J (scalar rows) or C_J and zeta_J (tensor rows, T) as vectors, lane l of entry m at
 * [m * PST_LW + l]. */
typedef struct {
    pst_vl s;
    union {
        pst_vl eta[3];
        struct {
            pst_vl C[16], zeta[3];
        };
    };
} lv_lane_back;

/* Row J's data of a block into j: C_J from transposes (pst_lanes_coefs; C keeps 8 doubles past
 * its last row for the 2D rows of 4), the D entries of eta_J or zeta_J by strided
 * gathers (0 beyond D). */
PST_KHOT void lane_back_of(const lv_ctx *k, int D, int T, const pst_lanes_block *b,
                           lv_lane_back *j)
{
    j->s = pst_vl_gather(k->d->s, b->j);
    const double *v = T ? k->d->zeta : k->d->eta;
    pst_vl *e = T ? j->zeta : j->eta;
    for (int a = 0; a < 3; ++a)
        e[a] = a < D ? pst_vl_gather_stride(v + a, (size_t)D, b->j) : pst_vl_splat(0.0);
    if (T)
        pst_lanes_coefs(k->d->C, D * D, b->j, j->C);
}

/* The weights w_JI of a block of half-list pairs seen from their rows J (G1): the pair's a
 * (h~ and the distance are the same both ways), g = a x_JI with x_JI = -x_IJ exactly, and row
 * J's data (jb) and mobility mj (T: its D components) against row I's V_I and mobility (r):
 * scalar_weight or tensor_weight as row J's own lane row computes it, bit for bit. */
PST_KHOT pst_vl g1_lane_reverse(int D, int T, int H, double vi, const lv_lane_row *r,
                                const pst_lanes_block *b, pst_vl a, const lv_lane_back *jb,
                                const pst_vl mj[3])
{
    const double *e = (const double *)jb->eta, *C = (const double *)jb->C,
                 *z = (const double *)jb->zeta, *m = (const double *)mj;
    pst_vl w;
#pragma omp simd
    for (int l = 0; l < PST_LW; ++l) {
        double x = -b->x[l], y = -b->y[l], zz = -b->z[l];
        double gx = a[l] * x, gy = a[l] * y, gz = a[l] * zz, wv;
        if (T)
            wv = tensor_weight_strided(D, H, jb->s[l] * vi, m + l, r->m[0], r->m[1], r->m[D - 1],
                                       b->d2[l], C + l, z + l, PST_LW, x, y, zz, gx, gy, gz);
        else
            wv = scalar_weight_strided(D, jb->s[l] * vi, pair_mobility(mj[0][l], r->m[0], H),
                                       a[l], e + l, PST_LW, gx, gy, gz);
        w[l] = a[l] == 0.0 ? 0.0 : wv;
    }
    return w;
}

/* One block of half-list row i (pst_lanes_half_add): both weights, a Neumann row J's w_JI a
 * pair at a time (its own rule, lv_row_weight). HS (h per particle) is a run-time flag here:
 * h~ = (h_I + h_J) / 2 is the same sum both ways, so a is too, and the blocks are unscaled
 * with either layout. The flag costs the one-h rows 2-3 % (measured); as a constant it would
 * double this file's 32 instantiations, among the slowest of the library to compile. */
PST_KHOT pst_vl g1_half_step(const lv_ctx *k, int D, pst_kernel K, int T, int H, int HS,
                             const lv_lane_row *r, size_t i, const pst_lanes_block *b,
                             pst_vl acc, double *y)
{
    pst_vl mj[3], hj, av;
    pst_vl vj = g1_lane_gathers(k, D, T, HS, r, b, mj, &hj);
    pst_vl wij = g1_lane_weights(K, D, T, H, HS, r, b, vj, mj, hj, &av);
    lv_lane_back jb;
    lane_back_of(k, D, T, b, &jb);
    pst_vl wji = g1_lane_reverse(D, T, H, k->c.V[i], r, b, av, &jb, mj);
    for (int l = 0; l < b->n; ++l)
        if (k->c.kind[b->j[l]] == PST_NEUMANN)
            wji[l] = lv_row_weight(k, b->j[l], i);
    return pst_lanes_half_add(acc, wij, wji, b, k->c.kind, y);
}

/* Half-list row i (not a Neumann row) in lanes, a block at a time like g1_lane_row: y_J for
 * the pairs, then y_I += its sum unless it is a Dirichlet row. */
PST_KHOT void g1_half_lane_row(const lv_ctx *k, int D, pst_kernel K, int T, int H, int HS,
                               const int64_t *off, const uint32_t *idx, size_t i, double *y)
{
    lv_lane_row r = lane_row_of(k, D, T, i);
    pst_lanes L = pst_lanes_row(&k->c, i, 1.0);
    PST_LANES_HALF_ROW(L, D, idx, off[i], off[i + 1], b, k->c.kind, y,
                       g1_half_step(k, D, K, T, H, HS, &r, i, b, L.acc[b->s], y));
}

/* g1_half_lane_row for the rows [i0, i1) but the Neumann rows, per dimension, kernel,
 * mobility (T) and pair mean; one h or h per particle. */
#define LV_HALF_ROWS(D, K, name, T, H)                                                         \
    static void half_rows_##D##_##name##_##T##_##H(                                            \
        const lv_ctx *k, const int64_t *off, const uint32_t *idx, size_t i0, size_t i1,       \
        double *y)                                                                             \
    {                                                                                          \
        const int hs = k->c.h != NULL;                                                         \
        for (size_t i = i0; i < i1; ++i)                                                       \
            if (k->c.kind[i] != PST_NEUMANN)                                                   \
                g1_half_lane_row(k, D, K, T, H, hs, off, idx, i, y);                           \
    }
#define LV_HALF_ROWS_K(D, K, name)                                                             \
    LV_HALF_ROWS(D, K, name, 0, 0)                                                             \
    LV_HALF_ROWS(D, K, name, 0, 1) LV_HALF_ROWS(D, K, name, 1, 0) LV_HALF_ROWS(D, K, name, 1, 1)
PST_FOR_KERNELS(LV_HALF_ROWS_K, 2)
PST_FOR_KERNELS(LV_HALF_ROWS_K, 3)
#define LV_HALF_ENTRY(D, name)                                                                 \
    {{half_rows_##D##_##name##_0_0, half_rows_##D##_##name##_0_1},                             \
     {half_rows_##D##_##name##_1_0, half_rows_##D##_##name##_1_1}}
static const lv_lane_rows_fn half_rows_table[2][4][2][2] = PST_KERNEL_TABLE(LV_HALF_ENTRY);

lv_lane_rows_fn PST_LEVEL_NAME(lv_half_lane_rows_for)(const lv_ctx *k)
{
    if (k->variant != PST_GRAD_G1)
        return NULL;
    return half_rows_table[k->c.dim - 2][k->c.kernel][k->c.ncomp > 1][k->harmonic];
}
