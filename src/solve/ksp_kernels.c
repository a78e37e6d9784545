/* The deterministic vector kernels the Krylov methods share, their workspace and their closing
 * messages (docs/solving.md, "Determinism"). */
#include "solve.h"

#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

/* ---- workspace ------------------------------------------------------------------------------ */

/* Vectors of n values per method: CG r, z, p, q; GMRES the basis V_0..V_m, w and t; BiCGSTAB
 * r, r^, p, v, p^, s, s^, t. */
static int method_vectors(int solver, int restart)
{
    return solver == PST_SOLVER_CG ? 4 : solver == PST_SOLVER_GMRES ? restart + 3 : 8;
}

int pst_ksp_alloc(pst_ksp *k, int solver, char *err)
{
    size_t n = k->n, m = (size_t)k->restart;
    k->nblocks = (n + PST_KSP_BLOCK - 1) / PST_KSP_BLOCK;
    size_t nb = k->nblocks ? k->nblocks : 1;
    k->part = pst_alloc(nb * (m + 2) * sizeof *k->part);
    k->nvec = method_vectors(solver, k->restart);
    k->vec = calloc((size_t)k->nvec, sizeof *k->vec);
    PST_CHECK_ALLOC(k->part && k->vec, err, "cannot allocate the solver's workspace of %zu rows",
                    n);
    for (int v = 0; v < k->nvec; ++v)
        PST_CHECK_ALLOC(k->vec[v] = pst_alloc(n * sizeof **k->vec), err,
                        "cannot allocate the %d Krylov vectors of %zu rows", k->nvec, n);
    if (solver != PST_SOLVER_GMRES)
        return PST_OK;
    /* H column-major (m + 1) x m; rotations; right-hand side g; projections h, h2; y */
    k->H = malloc((m + 1) * m * sizeof *k->H);
    k->small = malloc(6 * (m + 2) * sizeof *k->small);
    PST_CHECK_ALLOC(k->H && k->small, err, "cannot allocate the GMRES(%zu) matrices", m);
    return PST_OK;
}

void pst_ksp_free(pst_ksp *k)
{
    for (int v = 0; k->vec && v < k->nvec; ++v)
        pst_free(k->vec[v]);
    free(k->vec);
    free(k->H);
    free(k->small);
    pst_free(k->part);
    k->vec = NULL;
    k->H = k->small = k->part = NULL;
}

/* ---- deterministic kernels ------------------------------------------------------------------ */

/* Elementwise loops are memory-bound (streams of 8-byte doubles); reductions go through fixed
 * blocks so the summation order never depends on the thread count. Inside a block, LANES
 * independent partial sums (lane l takes the entries lo + l, lo + l + LANES, ...) break the
 * chain of dependent additions, so the loop vectorises and runs at the speed of its streams
 * instead of the latency of one adder; the lanes are combined in a fixed pairwise order. */
#define LANES 8

static double lanes_sum(const double *acc)
{
    return ((acc[0] + acc[1]) + (acc[2] + acc[3])) + ((acc[4] + acc[5]) + (acc[6] + acc[7]));
}

/* The sum of part[0..nb) in block order. */
static double sum_blocks(const double *part, size_t nb)
{
    double s = 0;
    for (size_t blk = 0; blk < nb; ++blk)
        s += part[blk];
    return s;
}

/* [lo, hi) of block blk. */
static size_t block_end(size_t blk, size_t n)
{
    size_t hi = (blk + 1) * PST_KSP_BLOCK;
    return hi < n ? hi : n;
}

/* One block's sum of a_i b_i, or of (a_i / b_i)^2. The block is walked as rows of LANES entries
 * through bumped pointers: written with a running index, GCC vectorises across rows instead
 * and the loop runs slower than one accumulator. */
static double block_dot(const double *restrict a, const double *restrict b, size_t lo, size_t hi)
{
    double acc[LANES] = {0};
    size_t rows = (hi - lo) / LANES;
    const double *pa = a + lo, *pb = b + lo;
    for (size_t r = 0; r < rows; ++r, pa += LANES, pb += LANES)
        for (int l = 0; l < LANES; ++l)
            acc[l] += pa[l] * pb[l];
    double s = lanes_sum(acc);
    for (size_t i = lo + rows * LANES; i < hi; ++i)
        s += a[i] * b[i];
    return s;
}

static double block_norm2_div(const double *restrict a, const double *restrict sc, size_t lo,
                              size_t hi)
{
    double acc[LANES] = {0};
    size_t rows = (hi - lo) / LANES;
    const double *pa = a + lo, *ps = sc + lo;
    for (size_t r = 0; r < rows; ++r, pa += LANES, ps += LANES)
        for (int l = 0; l < LANES; ++l) {
            double t = pa[l] / ps[l];
            acc[l] += t * t;
        }
    double s = lanes_sum(acc);
    for (size_t i = lo + rows * LANES; i < hi; ++i) {
        double t = a[i] / sc[i];
        s += t * t;
    }
    return s;
}

double pst_ksp_dot(pst_ksp *k, const double *a, const double *b)
{
    size_t n = k->n, nb = k->nblocks;
    double *part = k->part;
    /* the block sums in parallel, then their sum in order: memory-bound on two streams */
#pragma omp parallel for schedule(static) if (PST_KSP_THREADED(n))
    for (size_t blk = 0; blk < nb; ++blk)
        part[blk] = block_dot(a, b, blk * PST_KSP_BLOCK, block_end(blk, n));
    return sum_blocks(part, nb);
}

void pst_ksp_mdot(pst_ksp *k, int m, double *const *V, const double *w, double *out)
{
    size_t n = k->n, nb = k->nblocks;
    double *part = k->part;
    /* One pass over w for all m vectors: each V[j] streams from memory once while w's block
     * stays in L1, so the pass is memory-bound on m streams. */
#pragma omp parallel for schedule(static) if (PST_KSP_THREADED(n))
    for (size_t blk = 0; blk < nb; ++blk) {
        size_t lo = blk * PST_KSP_BLOCK, hi = block_end(blk, n);
        for (int j = 0; j < m; ++j)
            part[blk * (size_t)m + (size_t)j] = block_dot(V[j], w, lo, hi);
    }
    for (int j = 0; j < m; ++j) {
        double s = 0;
        for (size_t blk = 0; blk < nb; ++blk)
            s += part[blk * (size_t)m + (size_t)j];
        out[j] = s;
    }
}

double pst_ksp_subtract_norm2(pst_ksp *k, int m, double *const *V, const double *h, double *w)
{
    size_t n = k->n, nb = k->nblocks;
    double *part = k->part;
    /* Block by block: the vectors stream from memory four at a time (never m streams at once,
     * which would defeat the prefetchers), w's block is updated in L1, every entry in the order
     * j = 0, 1, ..., and its norm is summed before it leaves the cache: memory-bound on m
     * streams plus w read and written once. */
#pragma omp parallel for schedule(static) if (PST_KSP_THREADED(n))
    for (size_t blk = 0; blk < nb; ++blk) {
        size_t lo = blk * PST_KSP_BLOCK, hi = block_end(blk, n);
        double *restrict wb = w;
        int j = 0;
        for (; j + 4 <= m; j += 4) {
            const double *restrict v0 = V[j], *restrict v1 = V[j + 1], *restrict v2 = V[j + 2],
                                   *restrict v3 = V[j + 3];
            double c0 = h[j], c1 = h[j + 1], c2 = h[j + 2], c3 = h[j + 3];
            for (size_t i = lo; i < hi; ++i)
                wb[i] = wb[i] - c0 * v0[i] - c1 * v1[i] - c2 * v2[i] - c3 * v3[i];
        }
        for (; j < m; ++j) {
            const double *restrict v = V[j];
            double c = h[j];
            for (size_t i = lo; i < hi; ++i)
                wb[i] -= c * v[i];
        }
        part[blk] = block_dot(wb, wb, lo, hi);
    }
    return sum_blocks(part, nb);
}

double pst_ksp_axpy_norm2(pst_ksp *k, double a, const double *x, const double *y, double *z)
{
    size_t n = k->n, nb = k->nblocks;
    double *part = k->part;
    /* memory-bound on three streams; the norm reads z's block back from L1 */
#pragma omp parallel for schedule(static) if (PST_KSP_THREADED(n))
    for (size_t blk = 0; blk < nb; ++blk) {
        size_t lo = blk * PST_KSP_BLOCK, hi = block_end(blk, n);
        for (size_t i = lo; i < hi; ++i)
            z[i] = y[i] + a * x[i];
        part[blk] = block_dot(z, z, lo, hi);
    }
    return sum_blocks(part, nb);
}

int pst_ksp_update_residual(pst_ksp *k, double *x, double a, const double *p, double *r,
                            const double *q, const double *sc, double *norm2)
{
    size_t n = k->n, nb = k->nblocks;
    double *part = k->part;
    int bad = 0;
    /* One pass updates r, sums its norm from L1 and checks x + a p (memory-bound on five
     * streams); x is written in a second pass only when every entry is finite, so that a
     * failed update leaves the last finite iterate. */
#pragma omp parallel for schedule(static) reduction(| : bad) if (PST_KSP_THREADED(n))
    for (size_t blk = 0; blk < nb; ++blk) {
        size_t lo = blk * PST_KSP_BLOCK, hi = block_end(blk, n);
        for (size_t i = lo; i < hi; ++i) {
            r[i] -= a * q[i];
            bad |= !isfinite(x[i] + a * p[i]);
        }
        part[blk] = sc ? block_norm2_div(r, sc, lo, hi) : block_dot(r, r, lo, hi);
    }
    *norm2 = sum_blocks(part, nb);
    if (bad)
        return 0;
#pragma omp parallel for schedule(static) if (PST_KSP_THREADED(n))
    for (size_t i = 0; i < n; ++i)
        x[i] += a * p[i];
    return 1;
}

void pst_ksp_apply(pst_ksp *k, const double *x, double *y)
{
    k->A->apply(k->A->ctx, x, y);
}

void pst_ksp_prec(pst_ksp *k, const double *r, double *z)
{
    if (k->M) {
        k->M->apply(k->M->ctx, r, z);
        return;
    }
    memcpy(z, r, k->n * sizeof *z);
}

double pst_ksp_residual(pst_ksp *k, const double *x, double *r)
{
    pst_ksp_apply(k, x, r);
    const double *b = k->b;
#pragma omp parallel for schedule(static) if (PST_KSP_THREADED(k->n))
    for (size_t i = 0; i < k->n; ++i)
        r[i] = b[i] - r[i];
    return sqrt(pst_ksp_dot(k, r, r));
}

int pst_ksp_update(pst_ksp *k, double *x, double a, const double *p, double c, const double *q)
{
    size_t n = k->n;
    int bad = 0;
    /* Check first, write second, so that a failed update leaves the last finite iterate. */
#pragma omp parallel for schedule(static) reduction(| : bad) if (PST_KSP_THREADED(n))
    for (size_t i = 0; i < n; ++i)
        bad |= !isfinite(x[i] + a * p[i] + (q ? c * q[i] : 0.0));
    if (bad)
        return 0;
#pragma omp parallel for schedule(static) if (PST_KSP_THREADED(n))
    for (size_t i = 0; i < n; ++i)
        x[i] += a * p[i] + (q ? c * q[i] : 0.0);
    return 1;
}

void pst_ksp_axpby(pst_ksp *k, double a, const double *x, double c, double *y)
{
#pragma omp parallel for schedule(static) if (PST_KSP_THREADED(k->n))
    for (size_t i = 0; i < k->n; ++i)
        y[i] = a * x[i] + c * y[i];
}

void pst_ksp_record(pst_ksp *k, double rnorm)
{
    if (k->history && k->nhistory <= k->max_iter)
        k->history[k->nhistory++] = rnorm / k->bnorm;
    if (k->monitor)
        k->monitor(k->iterations, rnorm / k->bnorm, k->monitor_ctx);
}

/* ---- closing messages ----------------------------------------------------------------------- */

void pst_ksp_finish(pst_ksp *k, const char *method, double rnorm)
{
    if (!isfinite(rnorm)) {
        /* A user operator can overflow on a finite iterate: no limit was the reason. */
        pst_ksp_fail(k, PST_STOP_NON_FINITE, rnorm, "non-finite residual ||b - A u|| (%s)",
                     method);
        return;
    }
    k->rel_residual = rnorm / k->bnorm;
    k->converged = rnorm <= k->target;
    k->stop = k->converged ? PST_STOP_CONVERGED : PST_STOP_ITERATION_LIMIT;
    if (k->converged)
        pst_set_err(k->message, "converged in %d iterations to relative residual %.3e (%s)",
                    k->iterations, k->rel_residual, method);
    else
        pst_set_err(k->message,
                    "iteration limit %d reached at relative residual %.3e (target %.3e, %s)",
                    k->max_iter, k->rel_residual, k->target / k->bnorm, method);
}

int pst_ksp_broke(pst_ksp_break *b, int finite, double value, const char *breakdown,
                  const char *nonfinite)
{
    *b = finite ? (pst_ksp_break){breakdown, PST_STOP_BREAKDOWN, value}
                : (pst_ksp_break){nonfinite, PST_STOP_NON_FINITE, value};
    return 1;
}

void pst_ksp_fail(pst_ksp *k, int stop, double rnorm, const char *fmt, ...)
{
    char what[PST_ERRLEN];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    k->rel_residual = rnorm / k->bnorm;
    k->converged = 0;
    k->stop = stop;
    pst_set_err(k->message, "%s at iteration %d; relative residual %.3e", what, k->iterations,
                k->rel_residual);
}
