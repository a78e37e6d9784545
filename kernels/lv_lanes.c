/* The Lukyanov-Vuik family's G1 rows in lanes (docs/operators.md, "Matrix-free rows in lanes"):
 * the matrix-free apply of the operators of the default gradient G1, any mobility (none,
 * scalar, diagonal tensor), either pair mean, one h or h per particle, 8 pairs at a time from
 * the packed rows like qsfdi's, through the pair rules of lv_family.h, so with the chunk rows'
 * weights bit for bit. A file of its own so that its 64 instantiations (dimension, kernel,
 * tensor, pair mean, h layout) compile beside lv_family.c. */
#include "lv_family.h"
#include "isa.h"
#include "lanes.h"

/* What a G1 row reads besides its pairs: h_I and, on a cloud of one h, h~ = (h_I + h) / 2; the
 * row's s_I, its mobility (m[0], or the tensor's D components), and eta_I (scalar rows) or
 * zeta_I and C_I (tensor rows). */
typedef struct {
    double hi, ht, eps, s, m[3], eta[3], zeta[3], C[9];
} lv_lane_row;

/* The weights of a block of 8 pairs of such a row, lane by lane through the chunk rows' own
 * functions (pair_a, pair_mobility, scalar_weight or tensor_weight; the G1 gradient is a x):
 * their weights bit for bit. T: a diagonal tensor; H: the harmonic pair mean; HS: h per
 * particle, h~ = (h_I + h_J) / 2 as the chunk rows form it. V_J, the mobility of J (mj[0], or
 * the tensor's D components) and h_J gathered for the block (hj read only with HS). With g
 * as an array (gradient_from, weight_from) GCC 12 does not vectorise the lane loop: 3x
 * slower. */
PST_KHOT pst_v8 g1_lane_weights(pst_kernel K, int D, int T, int H, int HS,
                                const lv_lane_row *r, const pst_lanes_block *b, pst_v8 vj,
                                const pst_v8 mj[3], pst_v8 hj)
{
    pst_v8 w;
#pragma omp simd
    for (int l = 0; l < PST_LANES; ++l) {
        double ht = HS ? 0.5 * (r->hi + hj[l]) : r->ht;
        double a = pair_a(K, D, b->q[l], ht, r->eps); /* G1 (15): g = a x, F = a */
        double gx = a * b->x[l], gy = a * b->y[l], gz = a * b->z[l], wv;
        if (T)
            wv = tensor_weight(D, H, r->s * vj[l], r->m, mj[0][l], mj[1][l], mj[D - 1][l],
                               b->d2[l], r->C, r->zeta, b->x[l], b->y[l], b->z[l], gx, gy, gz);
        else
            wv = scalar_weight(D, r->s * vj[l], pair_mobility(r->m[0], mj[0][l], H), a, r->eta,
                               gx, gy, gz);
        w[l] = a == 0.0 ? 0.0 : wv;
    }
    return w;
}

/* Row i of the matrix-free apply for such a row (not a Neumann row), 8 pairs at a time like
 * qsfdi's, each block taken one ahead (kernels/lanes.h): the weights of row_t's chunks without
 * their passes through arrays. The row's last block reads on into the list like row_t's (the
 * lanes past the row computed and kept out of the sum); the list's last row pads. */
PST_KHOT void g1_lane_row(const lv_ctx *k, int D, pst_kernel K, int T, int H, int HS,
                          const int64_t *off, const uint32_t *idx, size_t i, double *y)
{
    lv_lane_row r = {.hi = pst_h(&k->c, i),
                     .ht = 0.5 * (pst_h(&k->c, i) + k->c.h_uniform),
                     .eps = k->c.pair_eps,
                     .s = k->d->s[i]};
    for (int a = 0; a < D; ++a) {
        r.m[a] = T ? k->c.mob[a][i] : pst_mob(&k->c, 0, i); /* row_mobility's mi */
        r.eta[a] = k->d->eta[(size_t)D * i + a];
        r.zeta[a] = T ? k->d->zeta[(size_t)D * i + a] : 0.0;
        for (int e = 0; e < D; ++e)
            r.C[a * D + e] = T ? k->d->C[(size_t)D * D * i + (size_t)(a * D + e)] : 0.0;
    }
    const double *mob[3] = {NULL, NULL, NULL};
    for (int a = 0; a < (T ? D : 1); ++a)
        mob[a] = k->c.ncomp ? k->c.mob[a] : NULL;
    pst_lanes L = pst_lanes_row(&k->c, i, 1.0);
    PST_LANES_EACH_TO(L, D, idx, off[i], off[i + 1], k->list_end, b, {
        pst_v8 vj = pst_v8_gather(k->c.V, b->j);
        pst_v8 mj[3];
        for (int a = 0; a < (T ? D : 1); ++a)
            mj[a] = mob[a] ? pst_v8_gather(mob[a], b->j) : pst_v8_splat(1.0);
        pst_v8 hj = HS ? pst_v8_gather(k->c.h, b->j) : pst_v8_splat(0.0);
        L.acc = pst_lanes_add(L.acc, g1_lane_weights(K, D, T, H, HS, &r, b, vj, mj, hj) * b->du,
                              b->n);
    });
    y[i] = pst_v8_sum(L.acc);
}

/* g1_lane_row for the rows [i0, i1) that are neither Dirichlet nor Neumann rows, per dimension,
 * kernel, mobility (T), pair mean and h layout, in the widest vector ISA. */
#define LV_LANE_ROWS(D, K, name, T, H, HS)                                                     \
    PST_ISA_DISPATCH static void lane_rows_##D##_##name##_##T##_##H##_##HS(                    \
        const lv_ctx *k, const int64_t *off, const uint32_t *idx, size_t i0, size_t i1,       \
        double *y)                                                                             \
    {                                                                                          \
        for (size_t i = i0; i < i1; ++i)                                                       \
            if (k->c.kind[i] != PST_DIRICHLET && k->c.kind[i] != PST_NEUMANN)                  \
                g1_lane_row(k, D, K, T, H, HS, off, idx, i, y);                                \
    }
#define LV_LANE_ROWS_T(D, K, name, T)                                                          \
    LV_LANE_ROWS(D, K, name, T, 0, 0)                                                          \
    LV_LANE_ROWS(D, K, name, T, 0, 1)                                                          \
    LV_LANE_ROWS(D, K, name, T, 1, 0) LV_LANE_ROWS(D, K, name, T, 1, 1)
#define LV_LANE_ROWS_K(D, K, name) LV_LANE_ROWS_T(D, K, name, 0) LV_LANE_ROWS_T(D, K, name, 1)
#define LV_LANE_ROWS_D(D)                                                                      \
    LV_LANE_ROWS_K(D, PST_KERNEL_CUBIC, cubic)                                                 \
    LV_LANE_ROWS_K(D, PST_KERNEL_QUINTIC, quintic)                                             \
    LV_LANE_ROWS_K(D, PST_KERNEL_WENDLAND_C2, wc2)                                             \
    LV_LANE_ROWS_K(D, PST_KERNEL_WENDLAND_C4, wc4)
LV_LANE_ROWS_D(2)
LV_LANE_ROWS_D(3)
#define LV_LANE_ENTRY_T(D, name, T)                                                            \
    {{lane_rows_##D##_##name##_##T##_0_0, lane_rows_##D##_##name##_##T##_0_1},                 \
     {lane_rows_##D##_##name##_##T##_1_0, lane_rows_##D##_##name##_##T##_1_1}}
#define LV_LANE_ENTRY(D, name) {LV_LANE_ENTRY_T(D, name, 0), LV_LANE_ENTRY_T(D, name, 1)}
static const lv_lane_rows_fn lane_rows_table[2][4][2][2][2] = {
    {LV_LANE_ENTRY(2, cubic), LV_LANE_ENTRY(2, quintic), LV_LANE_ENTRY(2, wc2),
     LV_LANE_ENTRY(2, wc4)},
    {LV_LANE_ENTRY(3, cubic), LV_LANE_ENTRY(3, quintic), LV_LANE_ENTRY(3, wc2),
     LV_LANE_ENTRY(3, wc4)}};

/* The lane rows serve the G1 operators (the default gradient), whatever their mobility, pair
 * mean and h; NULL for G2-G4 (the chunk rows serve every operator, and the Neumann rows of
 * these). */
lv_lane_rows_fn lv_lane_rows_for(const lv_ctx *k)
{
    if (k->variant != PST_GRAD_G1)
        return NULL;
    return lane_rows_table[k->c.dim - 2][k->c.kernel][k->c.ncomp > 1][k->harmonic]
                          [k->c.h != NULL];
}
