/* Restarted GMRES(m) with right preconditioning: Arnoldi on L M^-1 with classical Gram-Schmidt
 * applied twice (CGS2: two block passes per step instead of j dependent ones, as accurate as
 * modified Gram-Schmidt), Givens rotations on the Hessenberg matrix, and a restart from the
 * true residual ||b' - L x||, which is also the stopping test. */
#include "solve.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* w -= sum_{i<m} h_i V_i: one pass over w, memory-bound on m + 1 streams. */
static void subtract(size_t n, int m, double *const *V, const double *h, double *w)
{
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; ++i) {
        double s = w[i];
        for (int j = 0; j < m; ++j)
            s -= h[j] * V[j][i];
        w[i] = s;
    }
}

int pst_ksp_gmres(pst_ksp *k)
{
    size_t n = k->n;
    int m = k->restart;
    double **V = calloc((size_t)m + 1, sizeof *V);
    double *w = pst_alloc(n * sizeof *w), *t = pst_alloc(n * sizeof *t);
    /* H column-major (m + 1) x m; rotations; right-hand side g; projections h, h2 */
    double *H = malloc(((size_t)m + 1) * (size_t)m * sizeof *H);
    double *small = malloc(6 * ((size_t)m + 2) * sizeof *small);
    int ok = V && w && t && H && small;
    for (int j = 0; ok && j <= m; ++j)
        ok = (V[j] = pst_alloc(n * sizeof **V)) != NULL;
    if (!ok) {
        for (int j = 0; V && j <= m; ++j)
            pst_free(V[j]);
        free(V), pst_free(w), pst_free(t), free(H), free(small);
        pst_set_err(k->message, "cannot allocate the GMRES(%d) basis of %zu rows", m, n);
        return PST_ENOMEM;
    }
    double *cs = small, *sn = cs + m + 2, *g = sn + m + 2, *h = g + m + 2, *h2 = h + m + 2,
           *y = h2 + m + 2;
    double *x = k->x;
    const char *broke = NULL;
    double rn = pst_ksp_residual(k, x, V[0]);
    pst_ksp_record(k, rn);
    while (rn > k->target && k->iterations < k->max_iter && !broke) {
        double inv = 1.0 / rn;
#pragma omp parallel for schedule(static)
        for (size_t i = 0; i < n; ++i)
            V[0][i] *= inv;
        memset(g, 0, ((size_t)m + 1) * sizeof *g);
        g[0] = rn;
        int j = 0;
        while (j < m && k->iterations < k->max_iter) {
            pst_ksp_prec(k, V[j], t);
            pst_ksp_apply(k, t, V[j + 1]);
            double *wj = V[j + 1];
            /* pass 1 also gives ||w||^2 before orthogonalisation (V[j + 1] is w itself) */
            pst_ksp_mdot(k, j + 2, V, wj, h);
            double w0 = sqrt(h[j + 1]);
            subtract(n, j + 1, V, h, wj);
            pst_ksp_mdot(k, j + 1, V, wj, h2);
            subtract(n, j + 1, V, h2, wj);
            for (int i = 0; i <= j; ++i)
                h[i] += h2[i];
            double hn = sqrt(pst_ksp_dot(k, wj, wj));
            int finite = isfinite(hn) && isfinite(w0);
            for (int i = 0; i <= j; ++i)
                finite = finite && isfinite(h[i]);
            if (!finite) {
                broke = "non-finite value in the Arnoldi process: stopped at the last finite "
                        "iterate";
                break;
            }
            /* apply the previous rotations, then the one that zeroes H[j+1][j] */
            for (int i = 0; i < j; ++i) {
                double a = h[i], b = h[i + 1];
                h[i] = cs[i] * a + sn[i] * b;
                h[i + 1] = -sn[i] * a + cs[i] * b;
            }
            double rr = hypot(h[j], hn);
            if (rr == 0) {
                broke = "breakdown: L M^-1 maps a Krylov vector to 0 (singular system)";
                break;
            }
            cs[j] = h[j] / rr;
            sn[j] = hn / rr;
            h[j] = rr;
            g[j + 1] = -sn[j] * g[j];
            g[j] = cs[j] * g[j];
            for (int i = 0; i <= j; ++i)
                H[(size_t)j * ((size_t)m + 1) + (size_t)i] = h[i];
            k->iterations++;
            j++;
            double est = fabs(g[j]);
            pst_ksp_record(k, est);
            /* lucky breakdown: the Krylov space is invariant and x solves the system in it */
            if (hn <= 1e-14 * w0 || est <= k->target)
                break;
            double hinv = 1.0 / hn;
#pragma omp parallel for schedule(static)
            for (size_t i = 0; i < n; ++i)
                wj[i] *= hinv;
        }
        /* y = R^-1 g over the j finished columns, then x += M^-1 (V y) */
        for (int i = j - 1; i >= 0; --i) {
            double s = g[i];
            for (int l = i + 1; l < j; ++l)
                s -= H[(size_t)l * ((size_t)m + 1) + (size_t)i] * y[l];
            y[i] = s / H[(size_t)i * ((size_t)m + 1) + (size_t)i];
        }
        if (j > 0) {
#pragma omp parallel for schedule(static)
            for (size_t i = 0; i < n; ++i) {
                double s = 0;
                for (int l = 0; l < j; ++l)
                    s += y[l] * V[l][i];
                t[i] = s;
            }
            pst_ksp_prec(k, t, w);
            if (!pst_ksp_update(k, x, 1.0, w, 0, NULL))
                broke = "non-finite update: stopped at the last finite iterate";
        }
        rn = pst_ksp_residual(k, x, V[0]);
    }
    char method[32];
    snprintf(method, sizeof method, "GMRES(%d)", m);
    if (broke && rn > k->target)
        pst_ksp_fail(k, rn, "%s", broke);
    else
        pst_ksp_finish(k, method, rn);
    for (int j = 0; j <= m; ++j)
        pst_free(V[j]);
    free(V), pst_free(w), pst_free(t), free(H), free(small);
    return k->converged ? PST_OK : PST_ENUMERIC;
}
