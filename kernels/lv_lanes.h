/* The Lukyanov-Vuik family's G1 rows in lanes, what the whole-list rows (kernels/lv_lanes.c)
 * and the half-list rows (kernels/lv_half_lanes.c) share: a row's own data and the weights of
 * a block of its pairs, through the pair rules of lv_family.h, so that both have the chunk
 * rows' weights bit for bit (docs/operators.md, "Matrix-free rows in lanes"). Internal; every
 * function is inlined into the rows that call it. */
#ifndef PSTENCIL_LV_LANES_H
#define PSTENCIL_LV_LANES_H

#include "lanes.h"
#include "lv_family.h"

/* What a G1 row reads besides its pairs: h_I and, on a cloud of one h, h~ = (h_I + h) / 2; the
 * row's s_I, its mobility (m[0], or the tensor's D components), and eta_I (scalar rows) or
 * zeta_I and C_I (tensor rows); and the arrays its blocks gather the mobility of J from (mob[0],
 * or the tensor's D components; NULL without a mobility, m = 1). */
typedef struct {
    double hi, ht, eps, s, m[3], eta[3], zeta[3], C[9];
    const double *mob[3];
} lv_lane_row;

/* The weights of a block of pairs of such a row, lane by lane through the chunk rows' own
 * functions (pair_a, pair_mobility, scalar_weight or tensor_weight; the G1 gradient is a x):
 * their weights bit for bit. T: a diagonal tensor; H: the harmonic pair mean; HS: h per
 * particle, h~ = (h_I + h_J) / 2 as the chunk rows form it. V_J, the mobility of J (mj[0], or
 * the tensor's D components) and h_J gathered for the block (hj read only with HS). With g
 * as an array (gradient_from, weight_from) GCC 12 does not vectorise the lane loop: 3x
 * slower. The pairs' a into *av (the half-list rows' other direction reads it). */
PST_KHOT pst_vl g1_lane_weights(pst_kernel K, int D, int T, int H, int HS,
                                const lv_lane_row *r, const pst_lanes_block *b, pst_vl vj,
                                const pst_vl mj[3], pst_vl hj, pst_vl *av)
{
    /* every lane is written below; the zeros keep GCC's flow analysis quiet (in the 2-lane
     * copy it saw the lanes "maybe uninitialized") */
    pst_vl w = pst_vl_splat(0.0), a_all = w;
#pragma omp simd
    for (int l = 0; l < PST_LW; ++l) {
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
        a_all[l] = a;
    }
    *av = a_all;
    return w;
}

/* What a block of such a row gathers of its neighbours J: V_J (returned), the mobility of J
 * (mj[0], or the tensor's D components) and, with HS, h_J. */
PST_KHOT pst_vl g1_lane_gathers(const lv_ctx *k, int D, int T, int HS, const lv_lane_row *r,
                                const pst_lanes_block *b, pst_vl mj[3], pst_vl *hj)
{
    for (int a = 0; a < (T ? D : 1); ++a)
        mj[a] = r->mob[a] ? pst_vl_gather(r->mob[a], b->j) : pst_vl_splat(1.0);
    *hj = HS ? pst_vl_gather(k->c.h, b->j) : pst_vl_splat(0.0);
    return pst_vl_gather(k->c.V, b->j);
}

/* What row i reads besides its pairs (lv_lane_row). */
PST_KHOT lv_lane_row lane_row_of(const lv_ctx *k, int D, int T, size_t i)
{
    lv_lane_row r = {.hi = pst_h(&k->c, i),
                     .ht = 0.5 * (pst_h(&k->c, i) + k->c.h_uniform),
                     .eps = k->c.pair_eps,
                     .s = k->d->s[i]};
    for (int a = 0; a < (T ? D : 1); ++a)
        r.mob[a] = k->c.ncomp ? k->c.mob[a] : NULL;
    for (int a = 0; a < D; ++a) {
        r.m[a] = T ? k->c.mob[a][i] : pst_mob(&k->c, 0, i); /* row_mobility's mi */
        r.eta[a] = k->d->eta[(size_t)D * i + a];
        r.zeta[a] = T ? k->d->zeta[(size_t)D * i + a] : 0.0;
        for (int e = 0; e < D; ++e)
            r.C[a * D + e] = T ? k->d->C[(size_t)D * D * i + (size_t)(a * D + e)] : 0.0;
    }
    return r;
}

#endif /* PSTENCIL_LV_LANES_H */
