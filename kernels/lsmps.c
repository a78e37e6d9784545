/* Quadric LSMPS (docs/schemes/lsmps.md; Tamai & Koshizuka 2014), types A and B: the weighted-
 * least-squares engine of kernels/wls.c with the LDL^T factorisation of the full moment matrix.
 * The fit, its bases, the fallback chain and the Neumann rows are described in kernels/wls.c. */
#include "check.h"
#include "small_matrix.h"
#include "wls.h"

#include <math.h>
#include <string.h>

/* One instantiation per basis size so that the factorisation unrolls. */
static double lsmps_factor(int dim, int nb, const double *M, double *fac)
{
    (void)dim;
    memcpy(fac, M, (size_t)(nb * nb) * sizeof *fac);
    double ratio;
    switch (nb) {
    case 5: ratio = pst_ldlt_factor(5, fac); break;
    case 6: ratio = pst_ldlt_factor(6, fac); break;
    case 9: ratio = pst_ldlt_factor(9, fac); break;
    default: ratio = pst_ldlt_factor(10, fac); break;
    }
    /* the pivot ratio min D / max D as the condition estimate */
    return ratio > 0 ? 1.0 / ratio : INFINITY;
}

static void lsmps_solve(int dim, int nb, const double *M, const double *fac, double *b)
{
    (void)dim;
    (void)M;
    switch (nb) {
    case 5: pst_ldlt_solve(5, fac, b); break;
    case 6: pst_ldlt_solve(6, fac, b); break;
    case 9: pst_ldlt_solve(9, fac, b); break;
    default: pst_ldlt_solve(10, fac, b); break;
    }
}

static int lsmps_precompute(pst_op *op, char *err)
{
    PST_CHECK(op->opts.variant != 0 && op->opts.variant != 1, PST_EINVAL, err,
              "lsmps: variant must be 0 (type B) or 1 (type A), got %d", op->opts.variant);
    return pst_wls_precompute(op, op->opts.variant == 0, lsmps_factor, lsmps_solve, err);
}

const pst_scheme pst_scheme_lsmps = {
    .name = "lsmps",
    .description = "quadric LSMPS, type B (variant 0, 6x6 / 10x10) or A (variant 1) "
                   "(QSFDI sec. 2.5)",
    .variants = 2,
    .precompute = lsmps_precompute,
    .amg_own = 1,
    /* opts.keep: D and nh kappas of nb doubles, type B's nb (6 / 10), the larger */
    .keep_bytes = {{2 * 48, 3 * 48}, {3 * 80, 6 * 80}},
    PST_WLS_ENTRY_POINTS};
