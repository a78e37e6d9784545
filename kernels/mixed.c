/* The least-squares mixed schemes of seed 003 (docs/schemes/mixed.md): the mixed ordinary method
 * (Model 3, `mixed0`), the mixed first-order least squares (Model 4, `mixed1`) and the mixed
 * second-order least squares (Model 5, `mixed2`).
 *
 * The paper solves the first-order system for F = (f, f_x, f_y[, f_z]) by collocation; with the
 * gradient rows kept at every node it is the nested operator on u alone (docs/schemes/mixed.md,
 * "Equations"):
 *     (L u)_I = sum_a D_a (M^a D_a u)_I,   (D_a u)_I = sum_{j in N(I)} phi^a_Ij (u_j - u_I)
 * with M^a the mobility (1, a scalar m, or a diagonal tensor component). D is the derivative row
 * of a weighted least-squares Taylor fit about I that includes I itself (eqs. 15-24, rebuilt):
 *     M_I = sum_{j in N(I) + I} w_j p_j p_j^T,   phi^a_Ij = w_j (M_I^-1 p_j)_{1+a}
 *     mixed0: p = (1, x),               w_j = W(d_Ij, h_I) V~_j, V~_j = 1 / sum_k W_jk (eq. 4)
 *     mixed1: p = (1, x),               w_j = W(d_Ij, h_I)
 *     mixed2: p = (1, x, x^2/2, x y ...) w_j = W(d_Ij, h_I)
 * The derivative rows sum to zero (constants are reproduced), so the difference form is exact.
 * Per particle only Q_I = rows 1..D of M_I^-1 (basis unscaled) is stored (mixed_fit.c); the
 * pair weight phi is recomputed from positions and Q by one inline function (mixed.h) that the
 * matrix-free apply, emit_row and the gradient share. The matrix-free apply is two one-ring
 * sweeps over the neighbour list (mixed_rows.c). The stored rows' stencil is the neighbours of
 * neighbours (~1500 columns per row in 3D): that pattern (mixed_pattern.c) is built only when
 * the operator layer asks for it (the wide_pattern hook: stored weights, assembly, diagonal,
 * audit), never by the precompute, and emit_row writes the composed weights in it.
 *
 * Fallback chain (docs/schemes/mixed.md): quadratic fit (mixed2) -> linear fit -> "no fit": the
 * particle's gradient is the uncorrected kernel gradient sum_J V_J (u_J - u_I) grad W_IJ (cloud
 * volumes) and its interior row is the Brookshaw row V_J sum_a (M^a_I + M^a_J) a_IJ x_a^2 / d^2.
 * Neumann rows are n . M_I . (D u)_I with the particle's gradient. Never NaN.
 *
 * This file holds the three scheme tables; the code map is in docs/schemes/mixed.md. */
#include "mixed.h"

static int pre_ordinary(pst_op *op, char *err) { return pst_mx_precompute(op, MX_ORDINARY, err); }
static int pre_linear(pst_op *op, char *err) { return pst_mx_precompute(op, MX_LINEAR, err); }
static int pre_quadratic(pst_op *op, char *err) { return pst_mx_precompute(op, MX_QUADRATIC, err); }

#define MX_FALLBACK_LINEAR                                                                     \
    "linear fit: too few neighbours or singular -> kernel gradient and Brookshaw row -> zero row"

/* HALO, the hops a row reaches (pst_scheme.halo): 2, the neighbours' gradients, whose fits read
 * their own neighbours; 3 for mixed0, whose fits weigh those neighbours by volumes V~ that come
 * from the next ring. */
#define MX_SCHEME(ID, NAME, DESC, FALLBACK, DEG, HALO, PRE, MIN, HESS, BYTES2, BYTES3)         \
    const pst_scheme ID = {.name = NAME,                                                       \
                           .description = DESC,                                                \
                           .fallback = FALLBACK,                                               \
                           .default_kernel = PST_KERNEL_QUINTIC,                               \
                           .degree = DEG,                                                      \
                           .degree_lattice = 2,                                                \
                           .mobility = 1,                                                      \
                           .halo = HALO,                                                       \
                           .min_neighbours = MIN,                                              \
                           .precompute = PRE,                                                  \
                           .wide_pattern = pst_mx_wide_pattern,                                \
                           .apply = pst_mx_apply,                                              \
                           .emit_row = pst_mx_emit_row,                                        \
                           .gradient = pst_mx_gradient,                                        \
                           .hessian = HESS,                                                    \
                           .free_data = pst_mx_free,                                           \
                           .data_bytes = {BYTES2, BYTES3}} /* Q, mode, Vn (mixed0) */

MX_SCHEME(pst_scheme_mixed0, "mixed0",
          "mixed ordinary method, nested LS gradient with W V weights (seed 003 Model 3)",
          MX_FALLBACK_LINEAR, 1, 3, pre_ordinary, mx_min_linear, NULL, 57, 105);
MX_SCHEME(pst_scheme_mixed1, "mixed1",
          "mixed least squares 1st order, nested linear LS gradient (seed 003 Model 4)",
          MX_FALLBACK_LINEAR, 1, 2, pre_linear, mx_min_linear, NULL, 49, 97);
MX_SCHEME(pst_scheme_mixed2, "mixed2",
          "mixed least squares 2nd order, nested quadratic LS gradient (seed 003 Model 5)",
          "quadratic fit: too few neighbours or singular -> linear fit -> kernel gradient and "
          "Brookshaw row -> zero row",
          2, 2, pre_quadratic, mx_min_quadratic, pst_mx_hessian, 97, 241);
