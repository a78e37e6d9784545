/* Restarted GMRES(m) with right preconditioning: Arnoldi on A M^-1 with classical Gram-Schmidt
 * (two block passes per step instead of j dependent ones) and a second pass only when the
 * first cancelled too much (REORTH_ETA), Givens rotations on the Hessenberg matrix, and a
 * restart from the true residual ||b' - A x||, which is also the stopping test. */
#include "solve.h"

#include <math.h>
#include <string.h>

/* One Gram-Schmidt pass leaves w a component along the basis of about (rounding + the basis's
 * own loss of orthogonality) * ||w before|| / ||w after||, so a second pass is taken only when
 * the pass cancelled more than a decimal digit: ||w after|| < REORTH_ETA ||w before||, the
 * classic factor-10 test. DGKS's eta = 1/sqrt(2) keeps every vector orthogonal to a few
 * roundoffs, which GMRES does not need (its residual stays reliable while the basis keeps full
 * rank, and every restart checks the true residual), and it would take the second pass on
 * almost every step of a Jacobi-preconditioned Laplacian, whose ratio sits near 0.4. */
#define REORTH_ETA 0.1

/* The small arrays of a cycle (k->small): rotations cs, sn; the right-hand side g; the
 * projections h, h2; the least-squares solution y. m + 2 entries each. */
typedef struct {
    double *cs, *sn, *g, *h, *h2, *y;
} gmres_small;

/* Arnoldi step j: V[j + 1] = A M^-1 V[j] orthogonalised, its rotation applied and column j of
 * H stored. Returns ||w|| after orthogonalisation (hn) and, in *w0, before it; -1 after a
 * breakdown or a non-finite value (reason in *b). */
static double arnoldi_step(pst_ksp *k, int j, gmres_small *a, double *w0, pst_ksp_break *b)
{
    int m = k->restart;
    double **V = k->vec, *t = k->vec[m + 2], *h = a->h, *h2 = a->h2;
    pst_ksp_prec(k, V[j], t);
    pst_ksp_apply(k, t, V[j + 1]);
    double *wj = V[j + 1];
    /* one classical Gram-Schmidt pass: the projections and ||w||^2 before it (V[j + 1] is w
     * itself) in one read of the basis, the subtraction and ||w||^2 after it in another */
    pst_ksp_mdot(k, j + 2, V, wj, h);
    *w0 = sqrt(h[j + 1]);
    double hn = sqrt(pst_ksp_subtract_norm2(k, j + 1, V, h, wj));
    if (hn < REORTH_ETA * *w0) {
        pst_ksp_mdot(k, j + 1, V, wj, h2);
        hn = sqrt(pst_ksp_subtract_norm2(k, j + 1, V, h2, wj));
        for (int i = 0; i <= j; ++i)
            h[i] += h2[i];
        k->reorthogonalised++;
    }
    int finite = isfinite(hn) && isfinite(*w0);
    for (int i = 0; i <= j; ++i)
        finite = finite && isfinite(h[i]);
    if (!finite) {
        *b = (pst_ksp_break){"non-finite value in the Arnoldi process: stopped at the last finite "
                           "iterate", PST_STOP_NON_FINITE, 0};
        return -1;
    }
    /* apply the previous rotations, then the one that zeroes H[j+1][j] */
    for (int i = 0; i < j; ++i) {
        double x = h[i], y = h[i + 1];
        h[i] = a->cs[i] * x + a->sn[i] * y;
        h[i + 1] = -a->sn[i] * x + a->cs[i] * y;
    }
    double rr = hypot(h[j], hn);
    if (rr == 0) {
        *b = (pst_ksp_break){"breakdown: L M^-1 maps a Krylov vector to 0 (singular system)",
                           PST_STOP_BREAKDOWN, 0};
        return -1;
    }
    a->cs[j] = h[j] / rr;
    a->sn[j] = hn / rr;
    h[j] = rr;
    a->g[j + 1] = -a->sn[j] * a->g[j];
    a->g[j] = a->cs[j] * a->g[j];
    for (int i = 0; i <= j; ++i)
        k->H[(size_t)j * ((size_t)m + 1) + (size_t)i] = h[i];
    return hn;
}

/* x += M^-1 (V y) with y = R^-1 g over the j finished columns. A y of exact zeros would leave
 * x as it was (M^-1 0 = 0), and the next cycle would repeat this one bit for bit: stagnation. */
static void cycle_update(pst_ksp *k, int j, gmres_small *a, pst_ksp_break *b)
{
    int m = k->restart;
    double **V = k->vec, *w = k->vec[m + 1], *t = k->vec[m + 2], *y = a->y;
    const double *H = k->H;
    int moved = 0;
    for (int i = j - 1; i >= 0; --i) {
        double s = a->g[i];
        for (int l = i + 1; l < j; ++l)
            s -= H[(size_t)l * ((size_t)m + 1) + (size_t)i] * y[l];
        y[i] = s / H[(size_t)i * ((size_t)m + 1) + (size_t)i];
        moved |= y[i] != 0;
    }
    if (j == 0)
        return;
    if (!moved) {
        if (!b->what)
            *b = (pst_ksp_break){"stagnation: the cycle's update is 0 and every restart would "
                               "repeat it", PST_STOP_STAGNATION, 0};
        return;
    }
#pragma omp parallel for schedule(static) if (PST_KSP_THREADED(k->n))
    for (size_t i = 0; i < k->n; ++i) {
        double s = 0;
        for (int l = 0; l < j; ++l)
            s += y[l] * V[l][i];
        t[i] = s;
    }
    pst_ksp_prec(k, t, w);
    if (!pst_ksp_update(k, k->x, 1.0, w, 0, NULL))
        *b = (pst_ksp_break){"non-finite update: stopped at the last finite iterate",
                           PST_STOP_NON_FINITE, 0};
}

/* One cycle from the residual V[0] of norm rn: Arnoldi steps until m, the limit, the target,
 * a lucky breakdown or a failure (in *b); then the update of x. */
static void gmres_cycle(pst_ksp *k, double rn, gmres_small *a, pst_ksp_break *b)
{
    size_t n = k->n;
    int m = k->restart;
    double **V = k->vec, inv = 1.0 / rn;
#pragma omp parallel for schedule(static) if (PST_KSP_THREADED(n))
    for (size_t i = 0; i < n; ++i)
        V[0][i] *= inv;
    memset(a->g, 0, ((size_t)m + 1) * sizeof *a->g);
    a->g[0] = rn;
    int j = 0;
    while (j < m && k->iterations < k->max_iter) {
        double w0, hn = arnoldi_step(k, j, a, &w0, b);
        if (hn < 0)
            break;
        k->iterations++;
        j++;
        double est = fabs(a->g[j]);
        pst_ksp_record(k, est);
        /* lucky breakdown: the Krylov space is invariant and x solves the system in it */
        if (hn <= 1e-14 * w0 || est <= k->target)
            break;
        double hinv = 1.0 / hn, *wj = V[j];
#pragma omp parallel for schedule(static) if (PST_KSP_THREADED(n))
        for (size_t i = 0; i < n; ++i)
            wj[i] *= hinv;
    }
    cycle_update(k, j, a, b);
}

int pst_ksp_gmres(pst_ksp *k)
{
    int m = k->restart;
    double *s = k->small;
    gmres_small a = {s, s + m + 2, s + 2 * (m + 2), s + 3 * (m + 2), s + 4 * (m + 2),
                     s + 5 * (m + 2)};
    pst_ksp_break b = {0};
    k->reorthogonalised = 0;
    double rn = pst_ksp_residual(k, k->x, k->vec[0]);
    pst_ksp_record(k, rn);
    while (rn > k->target && k->iterations < k->max_iter && !b.what) {
        gmres_cycle(k, rn, &a, &b);
        rn = pst_ksp_residual(k, k->x, k->vec[0]);
    }
    char method[32];
    snprintf(method, sizeof method, "GMRES(%d)", m);
    if (b.what && !(rn <= k->target)) /* also a non-finite rn */
        pst_ksp_fail(k, b.stop, rn, "%s", b.what);
    else
        pst_ksp_finish(k, method, rn);
    return k->converged ? PST_OK : PST_ENUMERIC;
}
