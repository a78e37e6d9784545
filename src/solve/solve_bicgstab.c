/* BiCGSTAB (van der Vorst 1992) with right preconditioning, so its residuals are those of the
 * original system. A breakdown (rho or omega ~ 0, or (r^, v) ~ 0) restarts from the true
 * residual when the last pass made progress, and is reported otherwise. */
#include "solve.h"

#include <math.h>
#include <string.h>

#define TINY 1e-14 /* relative size of rho, (r^, v) or omega treated as zero */

/* One pass from the residual r with the shadow r^ = r (norm rhn): iterations until the
 * recursive residual reaches the target, the limit, or a breakdown (in *b). */
static void bicg_pass(pst_ksp *k, double rhn, pst_ksp_break *b)
{
    size_t n = k->n;
    double *r = k->vec[0], *rh = k->vec[1], *p = k->vec[2], *v = k->vec[3], *ph = k->vec[4],
           *s = k->vec[5], *sh = k->vec[6], *t = k->vec[7], *x = k->x;
    double rn = rhn, rho_old = 1, alpha = 1, omega = 1;
    for (int first = 1; k->iterations < k->max_iter; first = 0) {
        double rho = pst_ksp_dot(k, rh, r);
        if (!(fabs(rho) > TINY * rhn * rn) &&
            pst_ksp_broke(b, isfinite(rho), rho, "breakdown: rho = (r^, r) ~ 0",
                  "non-finite rho = (r^, r): stopped at the last finite iterate"))
            return;
        if (first) {
            memcpy(p, r, n * sizeof *r);
        } else {
            double beta = rho / rho_old * (alpha / omega);
#pragma omp parallel for schedule(static) if (PST_KSP_THREADED(n))
            for (size_t i = 0; i < n; ++i)
                p[i] = r[i] + beta * (p[i] - omega * v[i]);
        }
        pst_ksp_prec(k, p, ph);
        pst_ksp_apply(k, ph, v);
        double rv_vv[2];
        pst_ksp_mdot(k, 2, (double *[]){rh, v}, v, rv_vv); /* (r^, v) and ||v||^2, one pass */
        double rv = rv_vv[0], vn = sqrt(rv_vv[1]);
        if ((!(fabs(rv) > TINY * rhn * vn) || !isfinite(rv)) &&
            pst_ksp_broke(b, isfinite(rv) && isfinite(vn), rv, "breakdown: (r^, A p) ~ 0",
                  "non-finite (r^, A p): stopped at the last finite iterate"))
            return;
        alpha = rho / rv;
        double sn = sqrt(pst_ksp_axpy_norm2(k, -alpha, v, r, s)); /* s = r - alpha v */
        if (sn <= k->target) {
            if (!pst_ksp_update(k, x, alpha, ph, 0, NULL))
                *b = (pst_ksp_break){"non-finite iterate: stopped at the last finite iterate",
                                  PST_STOP_NON_FINITE, 0};
            k->iterations++;
            pst_ksp_record(k, sn);
            return;
        }
        pst_ksp_prec(k, s, sh);
        pst_ksp_apply(k, sh, t);
        double tt_ts[2];
        pst_ksp_mdot(k, 2, (double *[]){t, s}, t, tt_ts); /* ||t||^2 and (t, s), one pass */
        double tt = tt_ts[0], ts = tt_ts[1];
        omega = ts / tt;
        if ((!(fabs(omega) > 0) || !isfinite(omega) || !(fabs(ts) > TINY * sqrt(tt) * sn)) &&
            pst_ksp_broke(b, isfinite(tt) && isfinite(ts), omega, "breakdown: omega ~ 0",
                  "non-finite omega: stopped at the last finite iterate"))
            return;
        if (!pst_ksp_update(k, x, alpha, ph, omega, sh)) {
            *b = (pst_ksp_break){"non-finite iterate: stopped at the last finite iterate",
                              PST_STOP_NON_FINITE, 0};
            return;
        }
        k->iterations++;
        double est = sqrt(pst_ksp_axpy_norm2(k, -omega, t, s, r)); /* r = s - omega t */
        if (!isfinite(est)) {
            *b = (pst_ksp_break){"non-finite residual: stopped at the last finite iterate",
                              PST_STOP_NON_FINITE, 0};
            return;
        }
        pst_ksp_record(k, est);
        rn = est;
        rho_old = rho;
        if (est <= k->target)
            return;
    }
}

int pst_ksp_bicgstab(pst_ksp *k)
{
    double *r = k->vec[0], *rh = k->vec[1];
    pst_ksp_break b = {0};
    double rn = pst_ksp_residual(k, k->x, r);
    pst_ksp_record(k, rn);
    double rn_pass = rn; /* true residual at the start of the pass */
    while (rn > k->target && k->iterations < k->max_iter) {
        memcpy(rh, r, k->n * sizeof *r);
        b = (pst_ksp_break){0};
        bicg_pass(k, rn, &b);
        rn = pst_ksp_residual(k, k->x, r);
        /* a pass that ended in a breakdown without lowering the true residual is final */
        if (b.what && !(rn < rn_pass))
            break;
        b = (pst_ksp_break){0};
        rn_pass = rn;
    }
    if (b.what && !(rn <= k->target)) /* also a non-finite rn */
        pst_ksp_fail(k, b.stop, rn, "%s (value %.3e)", b.what, b.value);
    else
        pst_ksp_finish(k, "BiCGSTAB", rn);
    return k->converged ? PST_OK : PST_ENUMERIC;
}
