/* The discrete maximum principle by a dense solve: A_uu u = -A_ud g for a step and a linear g.
 * docs/stability.md. */
#include "analyse_dmp.h"

#include "pstencil.h"

#include <lapacke.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Range, violations and overshoot of the unknowns' values u (m) against the data g (n) on
 * the Dirichlet particles, and with `with_neumann` also on the Neumann particles (data with
 * a non-zero flux there: the principle bounds u by g on the whole boundary). */
static void judge(const uint8_t *kind, size_t n, const double *g, const double *u, size_t m,
                  int with_neumann, pst_dmp_case *r)
{
    r->gmin = INFINITY;
    r->gmax = -INFINITY;
    for (size_t i = 0; i < n; ++i)
        if (kind[i] == PST_DIRICHLET || (with_neumann && kind[i] == PST_NEUMANN)) {
            r->gmin = fmin(r->gmin, g[i]);
            r->gmax = fmax(r->gmax, g[i]);
        }
    double range = r->gmax - r->gmin;
    /* a zero range (constant data) judges the absolute excursion */
    double unit = range > 0 ? range : 1.0;
    double tol = 1e-12 * (range > 0 ? range : fmax(1.0, fabs(r->gmax)));
    r->violations = 0;
    r->overshoot = 0;
    for (size_t j = 0; j < m; ++j) {
        double out = fmax(u[j] - r->gmax, r->gmin - u[j]);
        if (out > tol)
            ++r->violations;
        if (out > 0)
            r->overshoot = fmax(r->overshoot, out / unit);
    }
}

int pst_dmp_check(const pst_cloud *c, const pst_csr *a, pst_dmp *d, char *err, size_t errlen)
{
    memset(d, 0, sizeof *d);
    size_t n = pst_cloud_size(c);
    if (a->n != n) {
        snprintf(err, errlen, "maximum principle: the matrix has %zu rows, the cloud %zu "
                              "particles", a->n, n);
        return PST_EINVAL;
    }
    const uint8_t *kind = pst_cloud_kinds_const(c);
    const double *x = pst_cloud_coord_const(c, 0);
    const double *nx = pst_cloud_normal_const(c, 0);
    double lo[3], hi[3];
    pst_cloud_bbox(c, lo, hi);
    d->xmid = 0.5 * (lo[0] + hi[0]);
    for (size_t i = 0; i < n; ++i)
        d->dirichlet += kind[i] == PST_DIRICHLET;
    d->unknowns = n - d->dirichlet;
    d->step.max_err = -1;
    if (d->dirichlet == 0 || d->unknowns == 0)
        return PST_OK; /* not applicable */
    d->applicable = 1;
    size_t m = d->unknowns;
    size_t *idx = malloc(n * sizeof *idx); /* particle -> unknown, SIZE_MAX: Dirichlet */
    double *g = malloc(2 * n * sizeof *g); /* step, linear */
    double *A = calloc(m * m, sizeof *A);
    double *b = calloc(2 * m, sizeof *b);  /* two right-hand sides, then the solutions */
    lapack_int *piv = malloc(m * sizeof *piv);
    int st = PST_OK;
    if (!idx || !g || !A || !b || !piv) {
        snprintf(err, errlen, "maximum principle: out of memory for a %zu x %zu matrix", m, m);
        st = PST_ENOMEM;
        goto done;
    }
    for (size_t i = 0, k = 0; i < n; ++i) {
        idx[i] = kind[i] != PST_DIRICHLET ? k++ : (size_t)-1;
        g[i] = x[i] > d->xmid ? 1.0 : 0.0;
        g[n + i] = x[i];
    }
    /* rows of the unknowns: A_uu in A (column major), the flux of g on a Neumann row (0 for
     * the step, n_x for x) minus A_ud g in b */
    for (size_t i = 0; i < n; ++i) {
        size_t r = idx[i];
        if (r == (size_t)-1)
            continue;
        if (kind[i] == PST_NEUMANN)
            b[m + r] = nx[i];
        for (int64_t p = a->rowptr[i]; p < a->rowptr[i + 1]; ++p) {
            size_t j = a->col[p];
            if (idx[j] != (size_t)-1) {
                A[r + idx[j] * m] += a->val[p];
            } else {
                b[r] -= a->val[p] * g[j];
                b[m + r] -= a->val[p] * g[n + j];
            }
        }
    }
    lapack_int info = LAPACKE_dgesv(LAPACK_COL_MAJOR, (lapack_int)m, 2, A, (lapack_int)m, piv, b,
                                    (lapack_int)m);
    if (info < 0) {
        snprintf(err, errlen, "maximum principle: LAPACKE_dgesv rejected argument %d", -(int)info);
        st = PST_EINVAL;
        goto done;
    }
    if (info > 0) {
        d->singular = 1;
        snprintf(d->why, sizeof d->why, "LAPACKE_dgesv: U(%d,%d) is exactly zero: the unknowns' "
                 "block of L is singular", (int)info, (int)info);
        goto done;
    }
    for (size_t r = 0; r < 2 * m; ++r)
        if (!isfinite(b[r])) {
            d->singular = 1;
            snprintf(d->why, sizeof d->why, "the solution overflows: the unknowns' block of L "
                     "is numerically singular");
            goto done;
        }
    judge(kind, n, g, b, m, 0, &d->step);     /* zero flux on Neumann rows */
    judge(kind, n, g + n, b + m, m, 1, &d->linear);
    d->linear.max_err = 0;
    for (size_t i = 0; i < n; ++i)
        if (idx[i] != (size_t)-1)
            d->linear.max_err = fmax(d->linear.max_err, fabs(b[m + idx[i]] - x[i]));
done:
    free(idx);
    free(g);
    free(A);
    free(b);
    free(piv);
    return st;
}
