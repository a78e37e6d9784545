/* LP-MPS (Tamai, Murotani & Koshizuka 2017) as reconstructed in docs/schemes/lpmps.md [unsure]:
 * the full quadratic weighted least-squares fit on the scaled offsets x^ = (x_j - x_I) / h_I
 * with one weight omega = the quintic w in both blocks, the gradient block eliminated:
 *     M1 = sum w r r^T (D x D),  C = sum w r r2^T,  M2 = sum w r2 r2^T,
 *     S  = M2 - C^T M1^-1 C      (3 x 3 in 2D, 6 x 6 in 3D; SPD),
 *     grad2 = S^-1 (sum w r2 u - C^T M1^-1 sum w r u),  L_I = 2 (sum of the squares' entries)
 * with r = (x, y[, z]) and r2 = (xx, yy[, zz], xy[, xz, yz]) (coefficients u_aa/2 and u_ab).
 * Per particle it inverts M1 (closed-form 2x2 / 3x3 adjugate) and S (closed-form 3x3 in 2D,
 * LDL^T 6x6 in 3D). The Laplacian coefficients have the closed form
 *     sigma = S^-1 h2 (h2 = 2/h^2 on the squares),  tau = -M1^-1 C sigma,
 *     a_Ij = w_j (tau . r_j + sigma . r2_j),
 * which is lambda = (tau; sigma) of quadric LSMPS type A: with one weight the two schemes are
 * algebraically identical and differ only in rounding and cost. The moment pass, the apply, the
 * fallback chain, Neumann rows, gradient, Hessian and interpolation are those of the WLS
 * engine (kernels/wls.c); this file supplies the block factorisation and its solve. */
#include "check.h"
#include "small_matrix.h"
#include "wls.h"

#include <math.h>
#include <string.h>

/* fac = [M1^-1 (D x D) | T = M1^-1 C (D x n2) | S^-1 (2D) or the LDL^T factor of S (3D)];
 * returns the larger condition estimate of the two inversions (1-norm for the closed forms,
 * the inverse pivot ratio for LDL^T), INFINITY when either is singular. Bound by the Schur
 * product C^T T: D n2^2 FMAs (18 in 2D, 108 in 3D). */
static inline __attribute__((always_inline)) double schur_factor(int D, const double *M,
                                                                 double *fac)
{
    const int nb = D == 2 ? 5 : 9, n2 = nb - D;
    double M1[9], *M1i = fac, *T = fac + D * D, *S = T + D * n2;
    for (int a = 0; a < D; ++a)
        for (int c = 0; c < D; ++c)
            M1[a * D + c] = M[a * nb + c];
    double cond1 = pst_mat_inverse(D, M1, M1i);
    if (!isfinite(cond1))
        return INFINITY;
    for (int a = 0; a < D; ++a)
        for (int s = 0; s < n2; ++s) {
            double t = 0;
            for (int c = 0; c < D; ++c)
                t += M1i[a * D + c] * M[c * nb + D + s];
            T[a * n2 + s] = t;
        }
    /* S = M2 - C^T T; symmetric, the lower triangle is all LDL^T reads */
    double Sm[36];
    for (int s = 0; s < n2; ++s)
        for (int t = 0; t <= s; ++t) {
            double v = M[(D + s) * nb + D + t];
            for (int a = 0; a < D; ++a)
                v -= M[a * nb + D + s] * T[a * n2 + t];
            Sm[s * n2 + t] = Sm[t * n2 + s] = v;
        }
    double cond2;
    if (D == 2) {
        cond2 = pst_mat_inverse(3, Sm, S);
    } else {
        memcpy(S, Sm, 36 * sizeof *S);
        double ratio = pst_ldlt_factor(6, S);
        cond2 = ratio > 0 ? 1.0 / ratio : INFINITY;
    }
    return cond1 > cond2 ? cond1 : cond2;
}

/* b <- M^-1 b by blocks: y2 = S^-1 (b2 - T^T b1), y1 = M1^-1 b1 - T y2. */
static inline __attribute__((always_inline)) void schur_solve(int D, const double *fac,
                                                              double *b)
{
    const int n2 = D == 2 ? 3 : 6;
    const double *M1i = fac, *T = fac + D * D, *S = T + D * n2;
    double r[6], y1[3];
    for (int s = 0; s < n2; ++s) {
        double v = b[D + s];
        for (int a = 0; a < D; ++a)
            v -= T[a * n2 + s] * b[a];
        r[s] = v;
    }
    if (D == 2) {
        for (int s = 0; s < 3; ++s)
            b[2 + s] = S[s * 3] * r[0] + S[s * 3 + 1] * r[1] + S[s * 3 + 2] * r[2];
    } else {
        pst_ldlt_solve(6, S, r);
        for (int s = 0; s < 6; ++s)
            b[3 + s] = r[s];
    }
    for (int a = 0; a < D; ++a) {
        double v = 0;
        for (int c = 0; c < D; ++c)
            v += M1i[a * D + c] * b[c];
        for (int s = 0; s < n2; ++s)
            v -= T[a * n2 + s] * b[D + s];
        y1[a] = v;
    }
    for (int a = 0; a < D; ++a)
        b[a] = y1[a];
}

/* One instantiation per dimension so that the block algebra unrolls. */
static double lpmps_factor(int dim, int nb, const double *M, double *fac)
{
    (void)nb;
    return dim == 2 ? schur_factor(2, M, fac) : schur_factor(3, M, fac);
}

static void lpmps_solve(int dim, int nb, const double *M, const double *fac, double *b)
{
    (void)nb;
    (void)M;
    if (dim == 2)
        schur_solve(2, fac, b);
    else
        schur_solve(3, fac, b);
}

static int lpmps_precompute(pst_op *op, char *err)
{
    return pst_wls_precompute(op, 0, lpmps_factor, lpmps_solve, err);
}

const pst_scheme pst_scheme_lpmps = {
    .name = "lpmps",
    .description = "LP-MPS, block-eliminated quadratic WLS, weight w in both blocks "
                   "(QSFDI sec. 2.6, a reconstruction)",
    .precompute = lpmps_precompute,
    .keep_bytes = {{2 * 40, 3 * 40}, {3 * 72, 6 * 72}}, /* D and nh kappas of nb = 5 / 9 */
    PST_WLS_ENTRY_POINTS};
