/* The CSPM family of the QSFDI paper's comparison schemes (docs/schemes/cspm.md, equation
 * numbers of Yan, Ma & Wang 2020): CSPM (38)-(41), ICSPM (7) = (47)-(48) with the Schur
 * complement M_2,ICSPM, and CSPH2Gamma (45), with the quintic kernel (9) and the volumes
 * V_j = 1 / sum_k W_jk (self term included) of a separate pre-pass.
 *
 * Notation: r = x_j - x_I, d = |r|, W' and W'' the radial derivatives of W(d, h_I) (I's own h
 * for I's fit), B_j = V_j W'/d, A_j = V_j (W'' - W'/d)/d^2, C_j = B_j/d^2, so that
 *     V grad W = B r,   V d_a d_b W = A r_a r_b + B delta_ab,   V check-grad W = C r^(2s).
 * Every row, whatever the scheme, its fallback or a Neumann row, has the weight
 *     a_Ij = V_j [ (W''/d^2) Q_lam(r) + (W'/d^3) Q_sig(r) + (W'/d) (c0 - mu . r) ]
 * with Q_c(r) = sum_p c_p r_a(p) r_b(p) over the packed second-derivative components p
 * (2D: xx, xy, yy; 3D: xx, xy, xz, yy, yz, zz) and per-particle coefficients (lam, sig, mu,
 * c0): 9 doubles in 2D, 16 in 3D. For CSPM / ICSPM lam = 2 X^-T I, mu = M1^-1 N21^T lam,
 * sig = -lam, c0 = tr lam (X = M2 or its Schur complement); for CSPH2Gamma lam = 0,
 * sig = 2 M2C^-T 1 on the diagonal slots, mu = M1^-1 Ncr^T sig, c0 = 0; the Brookshaw row is
 * c0 = -2 and the rest 0.
 * Fallback chain (docs/schemes/cspm.md): icspm -> cspm -> csph2g -> Brookshaw; a singular M1
 * gives the Brookshaw row directly. Never NaN.
 *
 * This file holds the three scheme tables; cspm_family.h the parts the others share,
 * cspm_moments.c the volumes and moments, cspm_fit.c the inversions, coefficients and the
 * precompute, cspm_lanes.c the matrix-free apply, cspm_rows.c the emission, cspm_derivs.c the
 * gradient and Hessian (linear in a row's data sums through matrices the precompute can keep). */
#include "cspm_family.h"
#include "cspm_lanes.h"

static int cs_min_icspm(int dim) { return level_min(CS_ICSPM, dim); }
static int cs_min_cspm(int dim) { return level_min(CS_CSPM, dim); }
static int cs_min_csph(int dim) { return level_min(CS_CSPH, dim); }

static int pre_icspm(pst_op *op, char *err) { return pst_cs_precompute(op, CS_ICSPM, err); }
static int pre_cspm(pst_op *op, char *err) { return pst_cs_precompute(op, CS_CSPM, err); }
static int pre_csph(pst_op *op, char *err) { return pst_cs_precompute(op, CS_CSPH, err); }

/* keep_bytes: the gradient's D x cs_ng and the Hessian's n2 x cs_ns doubles (ICSPM 1: the
 * scheme whose rows have the ICSPM level and a Hessian) */
#define CS_SCHEME(ID, NAME, DESC, FALLBACK, DEG, PRE, MIN, HESS, ICSPM)                       \
    const pst_scheme ID = {.name = NAME,                                                      \
                           .description = DESC,                                               \
                           .fallback = FALLBACK,                                              \
                           .default_kernel = PST_KERNEL_QUINTIC,                              \
                           .degree = DEG,                                                     \
                           .degree_lattice = 2,                                               \
                           .halo = 2, /* the neighbours' volumes */                           \
                           .min_neighbours = MIN,                                             \
                           .precompute = PRE,                                                 \
                           .apply = pst_cs_apply,                                             \
                           .lanes = 1,                                                        \
                           .emit_row = pst_cs_emit_row,                                       \
                           .gradient = pst_cs_gradient,                                       \
                           .hessian = HESS,                                                   \
                           .degrade = pst_cs_degrade,                                         \
                           .free_data = pst_cs_free,                                          \
                           .keep_bytes = {{(ICSPM) ? 80 : 32, (ICSPM) * 120},                 \
                                          {(ICSPM) ? 216 : 72, (ICSPM) * 432}},               \
                           .data_bytes = {80, 136}} /* V and cs_ncoef = 9 / 16 doubles */

CS_SCHEME(pst_scheme_cspm, "cspm", "CSPM, Chen et al. 1999 (QSFDI eqs. 38-41)",
          "too few neighbours or singular -> csph2g row -> Brookshaw row -> zero row; flat "
          "neighbours off the particle -> normalised Brookshaw row",
          1, pre_cspm, cs_min_cspm, NULL, 0);
CS_SCHEME(pst_scheme_icspm, "icspm", "improved CSPM, quadratic-exact (QSFDI eqs. 7, 47-48)",
          "too few neighbours or singular -> cspm row -> csph2g row -> Brookshaw row -> zero "
          "row; flat neighbours off the particle -> normalised Brookshaw row",
          2, pre_icspm, cs_min_icspm, pst_cs_hessian, 1);
CS_SCHEME(pst_scheme_csph2g, "csph2g", "CSPH2Gamma, Schwaiger's variant (QSFDI eq. 45)",
          "too few neighbours or singular -> Brookshaw row -> zero row; flat neighbours off "
          "the particle -> normalised Brookshaw row",
          1, pre_csph, cs_min_csph, NULL, 0);

/* The volumes of a CSPM-family operator (NULL for other schemes). Internal: for the tests. */
const double *pst_cspm_volumes(const pst_op *op);
const double *pst_cspm_volumes(const pst_op *op)
{
    return op->scheme->free_data == pst_cs_free ? ((const cs_data *)op->data)->V : NULL;
}
