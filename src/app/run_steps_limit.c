/* The forward-Euler step limit of a diffuse task: rho, a bound of the spectral radius of L
 * on the rows that evolve, from Gershgorin's theorem on the assembled rows. A bound, not an
 * estimate: every eigenvalue lies in a disc |lambda - a_ii| <= sum_j!=i |a_ij|, so |lambda|
 * <= max_i sum_j |a_ij|, and for L's negative real spectrum dt <= 2 / rho keeps every mode of
 * u <- u + dt L u from growing. One pass over the rows, deterministic, with no iteration
 * that could stop short (docs/time-stepping.md, "The step limit"). */
#include "run_steps.h"

#include <math.h>

int steps_rho(run_state *r, const pst_op *op, double m, double *rho)
{
    pst_csr a;
    int st = pst_op_assemble(op, &a);
    if (st != PST_OK)
        return run_fail(r, st, "%s: the step limit: cannot assemble the operator's rows",
                        r->s->path);
    const uint8_t *kind = pst_cloud_kinds_const(r->c);
    double most = 0;
    /* max is exact in any order: the same bound for every thread count */
#pragma omp parallel for reduction(max : most) schedule(static)
    for (size_t i = 0; i < a.n; ++i) {
        if (kind[i] != PST_INTERIOR)
            continue;
        double sum = 0;
        for (int64_t q = a.rowptr[i]; q < a.rowptr[i + 1]; ++q)
            sum += kind[a.col[q]] == PST_INTERIOR ? fabs(a.val[q]) : 0.0;
        most = fmax(most, sum);
    }
    pst_csr_free(&a);
    *rho = m * most;
    return PST_OK;
}
