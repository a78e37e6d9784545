/* BiCGSTAB (van der Vorst 1992) with right preconditioning, so its residuals are those of the
 * original system. A breakdown (rho or omega ~ 0, or (r^, v) ~ 0) restarts from the true
 * residual when the last pass made progress, and is reported otherwise. */
#include "solve.h"

#include <math.h>
#include <string.h>

#define NVEC 8
#define TINY 1e-14 /* relative size of rho, (r^, v) or omega treated as zero */

int pst_ksp_bicgstab(pst_ksp *k)
{
    size_t n = k->n;
    double *vec[NVEC] = {0};
    int ok = 1;
    for (int v = 0; v < NVEC; ++v)
        ok = ok && (vec[v] = pst_alloc(n * sizeof **vec)) != NULL;
    if (!ok) {
        for (int v = 0; v < NVEC; ++v)
            pst_free(vec[v]);
        pst_set_err(k->message, "cannot allocate the BiCGSTAB vectors of %zu rows", n);
        return PST_ENOMEM;
    }
    double *r = vec[0], *rh = vec[1], *p = vec[2], *v = vec[3], *ph = vec[4], *s = vec[5],
           *sh = vec[6], *t = vec[7];
    double *x = k->x;
    const char *broke = NULL;
    double bad = 0;
    double rn = pst_ksp_residual(k, x, r);
    pst_ksp_record(k, rn);
    double rn_pass = rn; /* true residual at the start of the pass */
    while (rn > k->target && k->iterations < k->max_iter) {
        memcpy(rh, r, n * sizeof *r);
        double rhn = rn, rho_old = 1, alpha = 1, omega = 1;
        int first = 1;
        broke = NULL;
        while (k->iterations < k->max_iter) {
            double rho = pst_ksp_dot(k, rh, r);
            if (!(fabs(rho) > TINY * rhn * rn)) {
                broke = "breakdown: rho = (r^, r) ~ 0";
                bad = rho;
                break;
            }
            if (first) {
                memcpy(p, r, n * sizeof *r);
            } else {
                double beta = rho / rho_old * (alpha / omega);
#pragma omp parallel for schedule(static)
                for (size_t i = 0; i < n; ++i)
                    p[i] = r[i] + beta * (p[i] - omega * v[i]);
            }
            first = 0;
            pst_ksp_prec(k, p, ph);
            pst_ksp_apply(k, ph, v);
            double rv = pst_ksp_dot(k, rh, v), vn = sqrt(pst_ksp_dot(k, v, v));
            if (!(fabs(rv) > TINY * rhn * vn) || !isfinite(rv)) {
                broke = "breakdown: (r^, A p) ~ 0";
                bad = rv;
                break;
            }
            alpha = rho / rv;
#pragma omp parallel for schedule(static)
            for (size_t i = 0; i < n; ++i)
                s[i] = r[i] - alpha * v[i];
            double sn = sqrt(pst_ksp_dot(k, s, s));
            if (sn <= k->target) {
                if (!pst_ksp_update(k, x, alpha, ph, 0, NULL))
                    broke = "non-finite iterate: stopped at the last finite iterate";
                k->iterations++;
                pst_ksp_record(k, sn);
                break;
            }
            pst_ksp_prec(k, s, sh);
            pst_ksp_apply(k, sh, t);
            double tt = pst_ksp_dot(k, t, t), ts = pst_ksp_dot(k, t, s);
            omega = ts / tt;
            if (!(fabs(omega) > 0) || !isfinite(omega) ||
                !(fabs(ts) > TINY * sqrt(tt) * sn)) {
                broke = "breakdown: omega ~ 0";
                bad = omega;
                break;
            }
            if (!pst_ksp_update(k, x, alpha, ph, omega, sh)) {
                broke = "non-finite iterate: stopped at the last finite iterate";
                break;
            }
#pragma omp parallel for schedule(static)
            for (size_t i = 0; i < n; ++i)
                r[i] = s[i] - omega * t[i];
            k->iterations++;
            double est = sqrt(pst_ksp_dot(k, r, r));
            if (!isfinite(est)) {
                broke = "non-finite residual: stopped at the last finite iterate";
                break;
            }
            pst_ksp_record(k, est);
            rn = est;
            rho_old = rho;
            if (est <= k->target)
                break;
        }
        rn = pst_ksp_residual(k, x, r);
        /* a pass that ended in a breakdown without lowering the true residual is final */
        if (broke && !(rn < rn_pass))
            break;
        broke = NULL;
        rn_pass = rn;
    }
    if (broke && rn > k->target)
        pst_ksp_fail(k, rn, "%s (value %.3e)", broke, bad);
    else
        pst_ksp_finish(k, "BiCGSTAB", rn);
    for (int i = 0; i < NVEC; ++i)
        pst_free(vec[i]);
    return k->converged ? PST_OK : PST_ENUMERIC;
}
