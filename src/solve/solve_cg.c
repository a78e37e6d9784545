/* Preconditioned conjugate gradients on the symmetric system S L x = S b' (spec lukyanov_vuik
 * §4.5): S = -diag(V/s) makes Brookshaw and corrected-Brookshaw rows symmetric with a positive
 * diagonal; with x and r zero on Dirichlet rows, CG sees the SPD block of the unknowns. */
#include "solve.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* z = M^-1 r for the scaled system: the preconditioner approximates L^-1, so it is applied to
 * the unscaled residual r / S (Jacobi then divides by S_I d_I, the diagonal of S L). */
static void cg_prec(pst_ksp *k, const double *S, const double *r, double *tmp, double *z)
{
    if (!k->prec) {
        memcpy(z, r, k->n * sizeof *z);
        return;
    }
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < k->n; ++i)
        tmp[i] = r[i] / S[i];
    pst_ksp_prec(k, tmp, z);
}

int pst_ksp_cg(pst_ksp *k, const double *S)
{
    size_t n = k->n;
    double *r = pst_alloc(n * sizeof *r), *z = pst_alloc(n * sizeof *z);
    double *p = pst_alloc(n * sizeof *p), *q = pst_alloc(n * sizeof *q);
    if (!r || !z || !p || !q) {
        pst_free(r), pst_free(z), pst_free(p), pst_free(q);
        pst_set_err(k->message, "cannot allocate the CG vectors of %zu rows", n);
        return PST_ENOMEM;
    }
    double *x = k->x;
    double rn = pst_ksp_residual(k, x, r);
    pst_ksp_record(k, rn);
    const char *broke = NULL;
    double bad = 0;
    /* Each pass restarts from the true residual: after the recursive residual reaches the
     * target, or never when the true one confirms it. Every pass makes >= 1 iteration. */
    while (rn > k->target && k->iterations < k->max_iter && !broke) {
#pragma omp parallel for schedule(static)
        for (size_t i = 0; i < n; ++i)
            r[i] *= S[i];
        cg_prec(k, S, r, q, z);
        memcpy(p, z, n * sizeof *p);
        double rz = pst_ksp_dot(k, r, z);
        while (k->iterations < k->max_iter) {
            pst_ksp_apply(k, p, q);
#pragma omp parallel for schedule(static)
            for (size_t i = 0; i < n; ++i)
                q[i] *= S[i];
            double pq = pst_ksp_dot(k, p, q), alpha = rz / pq;
            if (!(pq > 0) || !isfinite(alpha)) {
                broke = "breakdown: p.Ap <= 0 (the scaled operator is not positive definite)";
                bad = pq;
                break;
            }
            if (!pst_ksp_update(k, x, alpha, p, 0, NULL)) {
                broke = "non-finite iterate: stopped at the last finite iterate";
                break;
            }
            pst_ksp_axpby(k, -alpha, q, 1.0, r);
            k->iterations++;
            double est = sqrt(pst_ksp_norm2_div(k, r, S));
            if (!isfinite(est)) {
                broke = "non-finite residual: stopped at the last finite iterate";
                break;
            }
            pst_ksp_record(k, est);
            if (est <= k->target)
                break;
            cg_prec(k, S, r, q, z);
            double rz_new = pst_ksp_dot(k, r, z), beta = rz_new / rz;
            if (!(rz_new > 0) || !isfinite(beta)) {
                broke = "breakdown: r.z <= 0 (the preconditioner is not positive definite)";
                bad = rz_new;
                break;
            }
            rz = rz_new;
            pst_ksp_axpby(k, 1.0, z, beta, p);
        }
        rn = pst_ksp_residual(k, x, r);
    }
    if (broke && rn > k->target)
        pst_ksp_fail(k, rn, "%s (value %.3e)", broke, bad);
    else
        pst_ksp_finish(k, "CG", rn);
    pst_free(r), pst_free(z), pst_free(p), pst_free(q);
    return k->converged ? PST_OK : PST_ENUMERIC;
}
