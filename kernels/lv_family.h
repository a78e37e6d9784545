/* The Lukyanov-Vuik family's shared parts (kernels/lv_family.c has the scheme): its data, the
 * context the pair functions read, the pair rules that both the chunk rows (lv_rows.c,
 * lv_half_rows.c, through lv_chunks.h) and the lane rows (lv_lanes.c, lv_half_lanes.c) call,
 * so that their weights agree bit for bit, and the rows each file exports. Internal. */
#ifndef PSTENCIL_LV_FAMILY_H
#define PSTENCIL_LV_FAMILY_H

#include "isa.h"
#include "kernel_common.h"
#include "sph_kernels.h"

#include <stddef.h>
#include <stdint.h>

enum { LV_BROOKSHAW, LV_CB, LV_SCHWAIGER, LV_MSPH };

typedef struct {
    int which;     /* LV_* */
    double *nu;    /* Shepard nu_I (13)-(14), G2-G4; NULL for G1          */
    double *gnu;   /* grad nu_I, dim per particle, G2 only               */
    double *C;     /* dim*dim per particle, row-major                    */
    double *zeta;  /* dim per particle: N (schwaiger), N~ (lv), else 0   */
    double *eta;   /* dim per particle: C^T zeta                          */
    double *s;     /* the normalising factor s_I                          */
} lv_data;

/* Everything the pair functions read, gathered once per call (pair_eps in units of h~). */
typedef struct {
    pst_kctx c;
    int variant;  /* opts.gradient */
    int harmonic; /* opts.mobility_mean == PST_MEAN_HARMONIC */
    const lv_data *d;
    int64_t list_end; /* the apply: off[n], how far row_t and the lane rows may read past a
                         row; else 0 */
} lv_ctx;

/* The hot pair functions (PST_KHOT) take the dimension D, the gradient variant G, the tensor
 * flag T and the harmonic-mean flag H as arguments; the applies call them with constants (one
 * instantiation per combination), so the loops carry no per-pair branches on them. Other
 * callers pass runtime values. */

/* The pair mobility of one component: the paper's arithmetic sum a + b (29), or with H twice
 * the harmonic mean, 4 a b / (a + b) (an extension, not in the paper). The harmonic form is
 * written 4 a (b / s) so that it cannot overflow for finite a, b > 0 (b / s <= 1), and is 0
 * when s = a + b is not positive (or NaN): no NaN from it. Equal to a + b when a == b. */
PST_KHOT double pair_mobility(double a, double b, int H)
{
    if (!H)
        return a + b;
    double s = a + b, v = 4.0 * a * (b / s); /* evaluated always: a select, which vectorises */
    return s > 0 ? v : 0.0;
}

/* a = -dW/dr / d of a pair at distance d with h~ = ht, 0 for a degenerate pair (closer than
 * eps ht, pst_pair_live's rule): the arithmetic of every LV row, scalar, chunk or lanes. */
PST_KHOT double pair_a(pst_kernel K, int D, double d, double ht, double eps)
{
    double av = -pst_sph_dw(K, D, d, ht) / d;
    return d > eps * ht ? av : 0.0;
}

/* w_IJ of a scalar-mobility row, s_I V_J (pair mobility) [F - eta_I . g] (lv_family.c's file
 * comment), from Vs = s_I V_J, the pair mobility pm, F, eta_I and the components of g (gz not
 * read in 2D): scalars, not an array, so that a loop over lanes calling it vectorises.
 * eta_I^a is eta[a * stride]: a row's (stride 1), or one lane of vectors (stride 8). */
PST_KHOT double scalar_weight_strided(int D, double Vs, double pm, double F, const double *eta,
                                      int stride, double gx, double gy, double gz)
{
    double t = F;
    t -= eta[0] * gx;
    t -= eta[stride] * gy;
    if (D == 3)
        t -= eta[2 * stride] * gz;
    return Vs * pm * t;
}

PST_KHOT double scalar_weight(int D, double Vs, double pm, double F, const double *eta,
                              double gx, double gy, double gz)
{
    return scalar_weight_strided(D, Vs, pm, F, eta, 1, gx, gy, gz);
}

/* One component b of a diagonal-tensor row's sum, (M^b_I + M^b_J) [x^b g^b / d^2 -
 * zeta^b (C_I g)^b] (lv_family.c's file comment), from its pair mobility pm, x^b, g^b, 1 / d^2
 * (id2), zeta^b, row b of C_I (Cb, its entries stride apart) and the components of g (gz not
 * read in 2D). */
PST_KHOT double tensor_term(int D, double pm, double xb, double gb, double id2, double zb,
                            const double *Cb, int stride, double gx, double gy, double gz)
{
    double Cg = 0;
    Cg += Cb[0] * gx;
    Cg += Cb[stride] * gy;
    if (D == 3)
        Cg += Cb[2 * stride] * gz;
    return pm * (xb * gb * id2 - zb * Cg);
}

/* w_IJ of a diagonal-tensor row, s_I V_J sum_b tensor_term, from Vs = s_I V_J, the mobilities
 * of I (mi, D values) and of J (mjx, mjy, mjz), the pair mean H, d^2, C_I, zeta_I, the offset
 * and g (z components not read in 2D): scalars, like scalar_weight. mi, C and zeta are a
 * row's (stride 1) or one lane of vectors (stride 8), as in scalar_weight_strided. One division
 * by d^2 per pair rather than one per component: divisions are the costliest operations of
 * these rows (3D 10^6, 1 thread: 4-21 % off the tensor apply, bench/README.md). */
PST_KHOT double tensor_weight_strided(int D, int H, double Vs, const double *mi, double mjx,
                                      double mjy, double mjz, double d2, const double *C,
                                      const double *zeta, int stride, double x, double y,
                                      double z, double gx, double gy, double gz)
{
    const int r = stride;
    double s = 0, id2 = 1.0 / d2;
    s += tensor_term(D, pair_mobility(mi[0], mjx, H), x, gx, id2, zeta[0], C, r, gx, gy, gz);
    s += tensor_term(D, pair_mobility(mi[r], mjy, H), y, gy, id2, zeta[r], C + D * r, r, gx, gy,
                     gz);
    if (D == 3)
        s += tensor_term(D, pair_mobility(mi[2 * r], mjz, H), z, gz, id2, zeta[2 * r],
                         C + 2 * D * r, r, gx, gy, gz);
    return Vs * s;
}

PST_KHOT double tensor_weight(int D, int H, double Vs, const double *mi, double mjx, double mjy,
                              double mjz, double d2, const double *C, const double *zeta,
                              double x, double y, double z, double gx, double gy, double gz)
{
    return tensor_weight_strided(D, H, Vs, mi, mjx, mjy, mjz, d2, C, zeta, 1, x, y, z, gx, gy,
                                 gz);
}

/* The matrix-free apply's rows [i0, i1) that are neither Dirichlet nor Neumann rows into y,
 * a block of pairs at a time (kernels/lv_lanes.c). */
typedef void (*lv_lane_rows_fn)(const lv_ctx *k, const int64_t *off, const uint32_t *idx,
                                size_t i0, size_t i1, double *y);

/* The lane rows of k's operator, or NULL where only the chunk rows serve it (lv_lanes.c, compiled
 * once per ISA level: the rows of the CPU's level, src/core/isa.h). */
PST_LEVEL_ENTRY(lv_lane_rows_fn, lv_lane_rows_for, (const lv_ctx *k), (k))

/* The half-list rows [i0, i1) in lanes, every row but the Neumann rows (half_rows' rule: a
 * Dirichlet row I still writes its pairs' y_J), or NULL where they go in chunks (lv_half_rows.c):
 * the G1 operators (lv_half_lanes.c, compiled once per ISA level like lv_lanes.c). */
PST_LEVEL_ENTRY(lv_lane_rows_fn, lv_half_lane_rows_for, (const lv_ctx *k), (k))

/* Row i of the whole list in chunks (kernels/lv_rows.c): the matrix-free apply's row into y[i]
 * (w NULL; u_J - u_I from the packed rows), or the row's weights into w (emission). */
typedef void (*lv_row_fn)(const lv_ctx *k, const int64_t *off, const uint32_t *idx, size_t i,
                          double *y, double *w);

/* The chunk row of k's operator: every operator (lv_rows.c). */
lv_row_fn lv_row_for(const lv_ctx *k);

/* The gradient (54) of row i into g (D entries), in chunks (lv_rows.c): k's gradient variant. */
typedef void (*lv_gradient_row_fn)(const lv_ctx *k, const int64_t *off, const uint32_t *idx,
                                   size_t i, const double *u, double *g);
lv_gradient_row_fn lv_gradient_row_for(const lv_ctx *k);

/* Row i of a half list in chunks (kernels/lv_half_rows.c): y_I and the y_J of its pairs. */
typedef void (*lv_half_row_fn)(const lv_ctx *k, const int64_t *off, const uint32_t *idx,
                               size_t i, const double *u, double *y);

/* The half-list chunk row of k's operator: every operator (lv_half_rows.c). */
lv_half_row_fn lv_half_row_for(const lv_ctx *k);

/* w_IJ of row i at pair (i, j) for any operator, a pair at a time (lv_half_rows.c): the lane
 * half-list rows' weight of a Neumann row J. */
double lv_row_weight(const lv_ctx *k, size_t i, size_t j);

#endif /* PSTENCIL_LV_FAMILY_H */
