/* Preconditioned conjugate gradients. For an engine operator CG runs on the symmetric system
 * S L x = S b' (docs/schemes/cb.md, "Symmetry"): S = -diag(V/s) makes Brookshaw and
 * corrected-Brookshaw rows symmetric with a positive diagonal; with x and r zero on Dirichlet
 * rows, CG sees the SPD block of the unknowns. A user operator (S = NULL) is taken as SPD. */
#include "solve.h"

#include <math.h>
#include <string.h>

/* z = M^-1 r for the scaled system: the preconditioner approximates L^-1, so it is applied to
 * the unscaled residual r / S (Jacobi then divides by S_I d_I, the diagonal of S L). */
static void cg_prec(pst_ksp *k, const double *S, const double *r, double *tmp, double *z)
{
    if (!k->M) {
        memcpy(z, r, k->n * sizeof *z);
        return;
    }
    if (!S) {
        pst_ksp_prec(k, r, z);
        return;
    }
#pragma omp parallel for schedule(static) if (PST_KSP_THREADED(k->n))
    for (size_t i = 0; i < k->n; ++i)
        tmp[i] = r[i] / S[i];
    pst_ksp_prec(k, tmp, z);
}

/* v *= S elementwise (nothing without a scaling). */
static void scale(pst_ksp *k, const double *S, double *v)
{
    if (!S)
        return;
#pragma omp parallel for schedule(static) if (PST_KSP_THREADED(k->n))
    for (size_t i = 0; i < k->n; ++i)
        v[i] *= S[i];
}

/* A curvature p.Ap or r.z that must be positive, with the step it gives: 0 when both are
 * fine, else 1 with the reason in *b (a non-finite curvature is an overflow, not a breakdown). */
static int broken(pst_ksp_break *b, double v, double step, const char *breakdown,
                  const char *nonfinite)
{
    return !(v > 0 && isfinite(step)) && pst_ksp_broke(b, isfinite(v), v, breakdown, nonfinite);
}

/* One pass from the residual r (scaled in place): iterations until the recursive residual
 * reaches the target, the limit, or a breakdown (returned in *b, what NULL when none). */
static void cg_pass(pst_ksp *k, const double *S, pst_ksp_break *b)
{
    size_t n = k->n;
    double *r = k->vec[0], *z = k->vec[1], *p = k->vec[2], *q = k->vec[3], *x = k->x;
    scale(k, S, r);
    cg_prec(k, S, r, q, z);
    memcpy(p, z, n * sizeof *p);
    double rz = pst_ksp_dot(k, r, z);
    while (k->iterations < k->max_iter) {
        pst_ksp_apply(k, p, q);
        scale(k, S, q);
        double pq = pst_ksp_dot(k, p, q), alpha = rz / pq;
        if (broken(b, pq, alpha,
                   "breakdown: p.Ap <= 0 (the scaled operator is not positive definite)",
                   "non-finite p.Ap: stopped at the last finite iterate"))
            return;
        double est2;
        if (!pst_ksp_update_residual(k, x, alpha, p, r, q, S, &est2)) {
            *b = (pst_ksp_break){"non-finite iterate: stopped at the last finite iterate",
                            PST_STOP_NON_FINITE, 0};
            return;
        }
        k->iterations++;
        double est = sqrt(est2); /* the unscaled residual's norm */
        if (!isfinite(est)) {
            *b = (pst_ksp_break){"non-finite residual: stopped at the last finite iterate",
                            PST_STOP_NON_FINITE, 0};
            return;
        }
        pst_ksp_record(k, est);
        if (est <= k->target)
            return;
        cg_prec(k, S, r, q, z);
        double rz_new = pst_ksp_dot(k, r, z), beta = rz_new / rz;
        if (broken(b, rz_new, beta,
                   "breakdown: r.z <= 0 (the preconditioner is not positive definite)",
                   "non-finite r.z: stopped at the last finite iterate"))
            return;
        rz = rz_new;
        pst_ksp_axpby(k, 1.0, z, beta, p);
    }
}

int pst_ksp_cg(pst_ksp *k, const double *S)
{
    double *r = k->vec[0];
    double rn = pst_ksp_residual(k, k->x, r);
    pst_ksp_record(k, rn);
    pst_ksp_break b = {0};
    /* Each pass restarts from the true residual: after the recursive residual reaches the
     * target, or never when the true one confirms it. Every pass makes >= 1 iteration. */
    while (rn > k->target && k->iterations < k->max_iter && !b.what) {
        cg_pass(k, S, &b);
        rn = pst_ksp_residual(k, k->x, r);
    }
    if (b.what && !(rn <= k->target)) /* also a non-finite rn */
        pst_ksp_fail(k, b.stop, rn, "%s (value %.3e)", b.what, b.value);
    else
        pst_ksp_finish(k, "CG", rn);
    return k->converged ? PST_OK : PST_ENUMERIC;
}
