/* Problems without Dirichlet rows (docs/solving.md, "Singular problems"): L has the constants
 * in its nullspace, so L u = b fixes u only up to a constant and only for a b in L's range.
 * With V the volumes, L + c 1 V^T is regular when the constants are L's only null vectors and
 * not in its range (index 1, true of the consistent schemes here): its solution u satisfies
 * L u = b - lambda 1 with lambda = c V^T u, and u - (V^T u / sum V) 1 is the one with zero
 * weighted mean. c < 0 puts the constant mode's eigenvalue, c sum V, at minus the mean
 * diagonal of L: inside the spectrum of an interior Laplacian (negative), not near 0. The
 * extra term costs one deterministic dot product per apply. */
#include "solve.h"

#include <math.h>

/* y = L x + c (V . x) 1. */
static void mean_apply(void *ctx, const double *x, double *y)
{
    pst_krylov *s = ctx;
    s->L.apply(s->L.ctx, x, y);
    double t = s->c * pst_ksp_dot(&s->k, s->V, x);
#pragma omp parallel for schedule(static) if (PST_KSP_THREADED(s->L.n))
    for (size_t i = 0; i < s->L.n; ++i)
        y[i] += t;
}

/* diag(L) + c V. */
static int mean_diagonal(void *ctx, double *d)
{
    pst_krylov *s = ctx;
    PST_TRY(s->L.diagonal(s->L.ctx, d));
#pragma omp parallel for schedule(static) if (PST_KSP_THREADED(s->L.n))
    for (size_t i = 0; i < s->L.n; ++i)
        d[i] += s->c * s->V[i];
    return PST_OK;
}

int pst_fix_mean_update(pst_krylov *s, char *err)
{
    size_t n = s->L.n;
    double *d = pst_alloc(n * sizeof *d);
    PST_CHECK_ALLOC(d, err, "cannot allocate the solver's vectors for %zu particles", n);
    int st = s->L.diagonal(s->L.ctx, d);
    double dsum = 0;
    for (size_t i = 0; st == PST_OK && i < n; ++i)
        dsum += fabs(d[i]);
    pst_free(d);
    PST_CHECK(st != PST_OK, st, err, "fix_mean: the operator's diagonal failed");
    s->c = pst_fix_mean_c(dsum, n, s->vsum); /* sum V > 0: the volumes are checked positive */
    return PST_OK;
}

int pst_fix_mean_wrap(pst_krylov *s, char *err)
{
    size_t n = s->A.n;
    s->V = pst_cloud_volume_const(s->op->cloud);
    s->vsum = 0;
    for (size_t i = 0; i < n; ++i)
        s->vsum += s->V[i];
    s->L = s->A;
    PST_TRY(pst_fix_mean_update(s, err));
    s->A = (pst_linop){.n = n, .apply = mean_apply, .diagonal = mean_diagonal, .ctx = s};
    return PST_OK;
}

double pst_fix_mean_finish(pst_krylov *s, double *u)
{
    double vu = pst_ksp_dot(&s->k, s->V, u), mean = vu / s->vsum;
#pragma omp parallel for schedule(static) if (PST_KSP_THREADED(s->A.n))
    for (size_t i = 0; i < s->A.n; ++i)
        u[i] -= mean;
    return s->c * vu;
}
