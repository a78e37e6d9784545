/* The Lukyanov-Vuik family's G1 rows in lanes (docs/operators.md, "Matrix-free rows in lanes"):
 * the matrix-free apply of the operators of the default gradient G1, any mobility (none,
 * scalar, diagonal tensor), either pair mean, one h or h per particle, 8 pairs at a time from
 * the packed rows like qsfdi's, through the pair rules of lv_family.h, so with the chunk rows'
 * weights bit for bit; and the half-list rows of the G1 operators with a scalar or no
 * mobility, one h or h per particle (docs/operators.md, "The half-list apply"). A file of its
 * own so that its 64 + 16 instantiations (dimension, kernel, tensor, pair mean, h layout: the
 * half-list rows take it at run time) compile beside lv_family.c. */
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
 * slower. The pairs' a into *av (the half-list rows' other direction reads it). */
PST_KHOT pst_v8 g1_lane_weights(pst_kernel K, int D, int T, int H, int HS,
                                const lv_lane_row *r, const pst_lanes_block *b, pst_v8 vj,
                                const pst_v8 mj[3], pst_v8 hj, pst_v8 *av)
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
        (*av)[l] = a;
    }
    return w;
}

/* What row i reads besides its pairs (lv_lane_row). */
PST_KHOT lv_lane_row lane_row_of(const lv_ctx *k, int D, int T, size_t i)
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
    return r;
}

/* Row i of the matrix-free apply for such a row (not a Neumann row), 8 pairs at a time like
 * qsfdi's, each block taken one ahead (kernels/lanes.h): the weights of row_t's chunks without
 * their passes through arrays. The row's last block reads on into the list like row_t's (the
 * lanes past the row computed and kept out of the sum); the list's last row pads. */
PST_KHOT void g1_lane_row(const lv_ctx *k, int D, pst_kernel K, int T, int H, int HS,
                          const int64_t *off, const uint32_t *idx, size_t i, double *y)
{
    lv_lane_row r = lane_row_of(k, D, T, i);
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
        pst_v8 av;
        L.acc = pst_lanes_add(L.acc,
                              g1_lane_weights(K, D, T, H, HS, &r, b, vj, mj, hj, &av) * b->du,
                              b->n);
    });
    y[i] = pst_v8_sum(L.acc);
}

/* The weights w_JI of a block of half-list pairs seen from their rows J (G1, a scalar or no
 * mobility): the pair's a (h~ and the distance are the same both ways), g = a x_JI with
 * x_JI = -x_IJ exactly, and row J's s_J, eta_J (etaj, D vectors) and mobility mj against row
 * I's V_I and mi: scalar_weight as row J's own lane row computes it, bit for bit. */
PST_KHOT pst_v8 g1_lane_reverse(int D, int H, double vi, double mi, const pst_lanes_block *b,
                                pst_v8 a, pst_v8 sj, const pst_v8 etaj[3], pst_v8 mj)
{
    const double *e = (const double *)etaj;
    pst_v8 w;
#pragma omp simd
    for (int l = 0; l < PST_LANES; ++l) {
        double gx = a[l] * -b->x[l], gy = a[l] * -b->y[l], gz = a[l] * -b->z[l];
        double wv = scalar_weight_strided(D, sj[l] * vi, pair_mobility(mj[l], mi, H), a[l], e + l,
                                          PST_LANES, gx, gy, gz);
        w[l] = a[l] == 0.0 ? 0.0 : wv;
    }
    return w;
}

/* One block of half-list row i (pst_lanes_half_add): both weights, a Neumann row J's w_JI a
 * pair at a time (its own rule, lv_row_weight). HS (h per particle) is a run-time flag here:
 * h~ = (h_I + h_J) / 2 is the same sum both ways, so a is too. */
PST_KHOT pst_v8 g1_half_step(const lv_ctx *k, int D, pst_kernel K, int H, int HS,
                             const lv_lane_row *r, size_t i, const pst_lanes_block *b,
                             pst_v8 acc, double *y)
{
    const double *mob = k->c.ncomp ? k->c.mob[0] : NULL;
    pst_v8 mj[3] = {mob ? pst_v8_gather(mob, b->j) : pst_v8_splat(1.0)}, av, etaj[3];
    pst_v8 hj = HS ? pst_v8_gather(k->c.h, b->j) : pst_v8_splat(0.0);
    pst_v8 wij =
        g1_lane_weights(K, D, 0, H, HS, r, b, pst_v8_gather(k->c.V, b->j), mj, hj, &av);
    for (int a = 0; a < 3; ++a)
        etaj[a] = a < D ? pst_v8_gather_stride(k->d->eta + a, (size_t)D, b->j) : pst_v8_splat(0.0);
    pst_v8 wji = g1_lane_reverse(D, H, k->c.V[i], r->m[0], b, av,
                                 pst_v8_gather(k->d->s, b->j), etaj, mj[0]);
    for (int l = 0; l < b->n; ++l)
        if (k->c.kind[b->j[l]] == PST_NEUMANN)
            wji[l] = lv_row_weight(k, b->j[l], i);
    return pst_lanes_half_add(acc, wij, wji, b, k->c.kind, y);
}

/* Half-list row i (not a Neumann row) in lanes, 8 pairs at a time like g1_lane_row: y_J for
 * the pairs, then y_I += its sum unless it is a Dirichlet row. */
PST_KHOT void g1_half_lane_row(const lv_ctx *k, int D, pst_kernel K, int H, int HS,
                               const int64_t *off, const uint32_t *idx, size_t i, double *y)
{
    lv_lane_row r = lane_row_of(k, D, 0, i);
    pst_lanes L = pst_lanes_row(&k->c, i, 1.0);
    PST_LANES_HALF_ROW(L, D, idx, off[i], off[i + 1], b, k->c.kind, y,
                       g1_half_step(k, D, K, H, HS, &r, i, b, L.acc, y));
}

/* g1_half_lane_row for the rows [i0, i1) but the Neumann rows, per dimension, kernel and pair
 * mean, in the widest vector ISA; one h or h per particle. */
#define LV_HALF_ROWS(D, K, name, H)                                                            \
    PST_ISA_DISPATCH static void half_rows_##D##_##name##_##H(                                 \
        const lv_ctx *k, const int64_t *off, const uint32_t *idx, size_t i0, size_t i1,       \
        double *y)                                                                             \
    {                                                                                          \
        const int hs = k->c.h != NULL;                                                         \
        for (size_t i = i0; i < i1; ++i)                                                       \
            if (k->c.kind[i] != PST_NEUMANN)                                                   \
                g1_half_lane_row(k, D, K, H, hs, off, idx, i, y);                              \
    }
#define LV_HALF_ROWS_K(D, K, name) LV_HALF_ROWS(D, K, name, 0) LV_HALF_ROWS(D, K, name, 1)
PST_FOR_KERNELS(LV_HALF_ROWS_K, 2)
PST_FOR_KERNELS(LV_HALF_ROWS_K, 3)
#define LV_HALF_ENTRY(D, name) {half_rows_##D##_##name##_0, half_rows_##D##_##name##_1}
static const lv_lane_rows_fn half_rows_table[2][4][2] = PST_KERNEL_TABLE(LV_HALF_ENTRY);

lv_lane_rows_fn lv_half_lane_rows_for(const lv_ctx *k)
{
    if (k->variant != PST_GRAD_G1 || k->c.ncomp > 1)
        return NULL;
    return half_rows_table[k->c.dim - 2][k->c.kernel][k->harmonic];
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
PST_FOR_KERNELS(LV_LANE_ROWS_K, 2)
PST_FOR_KERNELS(LV_LANE_ROWS_K, 3)
#define LV_LANE_ENTRY_T(D, name, T)                                                            \
    {{lane_rows_##D##_##name##_##T##_0_0, lane_rows_##D##_##name##_##T##_0_1},                 \
     {lane_rows_##D##_##name##_##T##_1_0, lane_rows_##D##_##name##_##T##_1_1}}
#define LV_LANE_ENTRY(D, name) {LV_LANE_ENTRY_T(D, name, 0), LV_LANE_ENTRY_T(D, name, 1)}
static const lv_lane_rows_fn lane_rows_table[2][4][2][2][2] = PST_KERNEL_TABLE(LV_LANE_ENTRY);

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
