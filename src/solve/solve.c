/* pst_solve: checks, Dirichlet elimination, the choice of method and preconditioner, the
 * Jacobi preconditioner and the deterministic vector kernels the Krylov methods share.
 * docs/solving.md. */
#include "solve.h"

#include <math.h>
#include <omp.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

void pst_solve_defaults(pst_solve_opts *o)
{
    o->solver = PST_SOLVER_AUTO;
    o->precond = PST_PREC_JACOBI;
    o->amg_source = PST_AMG_BROOKSHAW;
    o->restart = 50;
    o->max_iter = 5000;
    o->rtol = 1e-10;
    o->stored = 0;
    o->history = 0;
    o->monitor = NULL;
    o->monitor_ctx = NULL;
}

void pst_solve_result_free(pst_solve_result *r)
{
    if (!r)
        return;
    free(r->history);
    r->history = NULL;
    r->nhistory = 0;
}

/* ---- deterministic kernels ------------------------------------------------------------------ */

/* Elementwise loops are memory-bound (streams of 8-byte doubles); reductions go through fixed
 * blocks so the summation order never depends on the thread count. */

double pst_ksp_dot(pst_ksp *k, const double *a, const double *b)
{
    size_t n = k->n, nb = k->nblocks;
    double *part = k->part;
#pragma omp parallel for schedule(static)
    for (size_t blk = 0; blk < nb; ++blk) {
        size_t lo = blk * PST_KSP_BLOCK, hi = lo + PST_KSP_BLOCK < n ? lo + PST_KSP_BLOCK : n;
        double s = 0;
        for (size_t i = lo; i < hi; ++i)
            s += a[i] * b[i];
        part[blk] = s;
    }
    double s = 0;
    for (size_t blk = 0; blk < nb; ++blk)
        s += part[blk];
    return s;
}

void pst_ksp_mdot(pst_ksp *k, int m, double *const *V, const double *w, double *out)
{
    size_t n = k->n, nb = k->nblocks;
    double *part = k->part;
    /* One pass over w for all m vectors: memory-bound on the m + 1 streams. */
#pragma omp parallel for schedule(static)
    for (size_t blk = 0; blk < nb; ++blk) {
        size_t lo = blk * PST_KSP_BLOCK, hi = lo + PST_KSP_BLOCK < n ? lo + PST_KSP_BLOCK : n;
        for (int j = 0; j < m; ++j) {
            const double *v = V[j];
            double s = 0;
            for (size_t i = lo; i < hi; ++i)
                s += v[i] * w[i];
            part[blk * (size_t)m + (size_t)j] = s;
        }
    }
    for (int j = 0; j < m; ++j) {
        double s = 0;
        for (size_t blk = 0; blk < nb; ++blk)
            s += part[blk * (size_t)m + (size_t)j];
        out[j] = s;
    }
}

double pst_ksp_norm2_div(pst_ksp *k, const double *a, const double *sc)
{
    size_t n = k->n, nb = k->nblocks;
    double *part = k->part;
#pragma omp parallel for schedule(static)
    for (size_t blk = 0; blk < nb; ++blk) {
        size_t lo = blk * PST_KSP_BLOCK, hi = lo + PST_KSP_BLOCK < n ? lo + PST_KSP_BLOCK : n;
        double s = 0;
        for (size_t i = lo; i < hi; ++i) {
            double t = a[i] / sc[i];
            s += t * t;
        }
        part[blk] = s;
    }
    double s = 0;
    for (size_t blk = 0; blk < nb; ++blk)
        s += part[blk];
    return s;
}

void pst_ksp_apply(pst_ksp *k, const double *x, double *y)
{
    if (k->stored)
        pst_op_apply_stored(k->op, x, y); /* the store was checked in pst_solve */
    else
        pst_op_apply(k->op, x, y);
}

void pst_ksp_prec(pst_ksp *k, const double *r, double *z)
{
    if (k->prec) {
        k->prec->apply(k->prec->ctx, r, z);
        return;
    }
    memcpy(z, r, k->n * sizeof *z);
}

double pst_ksp_residual(pst_ksp *k, const double *x, double *r)
{
    pst_ksp_apply(k, x, r);
    const double *b = k->b;
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < k->n; ++i)
        r[i] = b[i] - r[i];
    return sqrt(pst_ksp_dot(k, r, r));
}

int pst_ksp_update(pst_ksp *k, double *x, double a, const double *p, double c, const double *q)
{
    size_t n = k->n;
    int bad = 0;
    /* Check first, write second, so that a failed update leaves the last finite iterate. */
#pragma omp parallel for schedule(static) reduction(| : bad)
    for (size_t i = 0; i < n; ++i)
        bad |= !isfinite(x[i] + a * p[i] + (q ? c * q[i] : 0.0));
    if (bad)
        return 0;
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; ++i)
        x[i] += a * p[i] + (q ? c * q[i] : 0.0);
    return 1;
}

void pst_ksp_axpby(pst_ksp *k, double a, const double *x, double c, double *y)
{
#pragma omp parallel for schedule(static)
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

void pst_ksp_finish(pst_ksp *k, const char *method, double rnorm)
{
    k->rel_residual = rnorm / k->bnorm;
    k->converged = rnorm <= k->target;
    if (k->converged)
        pst_set_err(k->message, "converged in %d iterations to relative residual %.3e (%s)",
                    k->iterations, k->rel_residual, method);
    else
        pst_set_err(k->message,
                    "iteration limit %d reached at relative residual %.3e (target %.3e, %s)",
                    k->max_iter, k->rel_residual, k->target / k->bnorm, method);
}

void pst_ksp_fail(pst_ksp *k, double rnorm, const char *fmt, ...)
{
    char what[PST_ERRLEN];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    k->rel_residual = rnorm / k->bnorm;
    k->converged = 0;
    pst_set_err(k->message, "%s at iteration %d; relative residual %.3e", what, k->iterations,
                k->rel_residual);
}

/* ---- preconditioners ------------------------------------------------------------------------ */

typedef struct {
    size_t n;
    double *dinv;
} jacobi_ctx;

/* z = r / diag(L): memory-bound, three streams. */
static void jacobi_apply(void *ctx, const double *r, double *z)
{
    const jacobi_ctx *j = ctx;
    const double *dinv = j->dinv;
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < j->n; ++i)
        z[i] = dinv[i] * r[i];
}

static void jacobi_destroy(void *ctx)
{
    jacobi_ctx *j = ctx;
    if (j)
        pst_free(j->dinv);
    free(j);
}

/* 1 / diag(L); a zero (or non-finite) diagonal, which only an isolated row can have, gets 1. */
static int jacobi_create(pst_prec *p, const pst_op *op, char *err)
{
    jacobi_ctx *j = calloc(1, sizeof *j);
    double *d = j ? pst_alloc(op->n * sizeof *d) : NULL;
    if (!d || pst_op_diagonal(op, d) != PST_OK) {
        pst_free(d);
        free(j);
        pst_set_err(err, "cannot allocate the Jacobi preconditioner of %zu rows", op->n);
        return PST_ENOMEM;
    }
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < op->n; ++i)
        d[i] = d[i] != 0 && isfinite(d[i]) ? 1.0 / d[i] : 1.0;
    j->n = op->n;
    j->dinv = d;
    p->apply = jacobi_apply;
    p->destroy = jacobi_destroy;
    p->ctx = j;
    return PST_OK;
}


/* ---- pst_solve -------------------------------------------------------------------------------- */

static const char *solver_name(int s)
{
    static const char *const names[] = {"auto", "CG", "GMRES", "BiCGSTAB"};
    return s >= 0 && s <= PST_SOLVER_BICGSTAB ? names[s] : "unknown";
}

/* The symmetric scaling of spec lukyanov_vuik §4.5 exists for Brookshaw and corrected
 * Brookshaw with the radial G1 gradient (F_IJ symmetric) and no Neumann (flux) rows. */
static int symmetrisable(const pst_op *op, size_t neumann)
{
    return pst_scheme_symmetrisable(op->scheme) && op->opts.gradient == PST_GRAD_G1 &&
           neumann == 0;
}

static int check_opts(const pst_op *op, const pst_solve_opts *o, char *err)
{
    if (o->solver < PST_SOLVER_AUTO || o->solver > PST_SOLVER_BICGSTAB) {
        pst_set_err(err, "unknown solver %d (AUTO, CG, GMRES or BICGSTAB)", o->solver);
        return PST_EINVAL;
    }
    if (o->precond < PST_PREC_NONE || o->precond > PST_PREC_AMG) {
        pst_set_err(err, "unknown preconditioner %d (NONE, JACOBI or AMG)", o->precond);
        return PST_EINVAL;
    }
    if (o->amg_source != PST_AMG_BROOKSHAW && o->amg_source != PST_AMG_OWN) {
        pst_set_err(err, "unknown AMG source %d (BROOKSHAW or OWN)", o->amg_source);
        return PST_EINVAL;
    }
    if (o->restart < 1 || o->restart > 100000 || o->max_iter < 0) {
        pst_set_err(err, "restart must be in [1, 100000] and max_iter >= 0 (got %d, %d)",
                    o->restart, o->max_iter);
        return PST_EINVAL;
    }
    if (!(o->rtol > 0 && o->rtol < 1)) {
        pst_set_err(err, "rtol must be in (0, 1) (got %g)", o->rtol);
        return PST_EINVAL;
    }
    if (o->stored && !op->w) {
        pst_set_err(err, "stored = 1 needs the weights: call pst_op_store(op) first");
        return PST_EINVAL;
    }
    return PST_OK;
}

/* S = -V/s on non-Dirichlet rows (V/s > 0 checked), 1 on Dirichlet rows. */
static int cg_scaling(const pst_op *op, double *S, char *err)
{
    const double *V = pst_cloud_volume_const(op->cloud);
    const uint8_t *kind = op->kind;
    pst_op_scale(op, S);
    for (size_t i = 0; i < op->n; ++i) {
        if (kind[i] == PST_DIRICHLET) {
            S[i] = 1.0;
            continue;
        }
        double v = V[i] / S[i];
        if (!(v > 0) || !isfinite(v)) {
            pst_set_err(err, "CG needs V_I / s_I > 0 for the symmetric scaling, but particle "
                             "%zu has V = %g, s = %g: use GMRES",
                        i, V[i], S[i]);
            return PST_EINVAL;
        }
        S[i] = -v;
    }
    return PST_OK;
}

int pst_solve(const pst_op *op, const double *b, double *u, const pst_solve_opts *o,
              pst_solve_result *r, char *err_out)
{
    double t0 = omp_get_wtime();
    char err[PST_ERRLEN] = "";
    pst_solve_opts defaults;
    pst_solve_result local;
    if (!o) {
        pst_solve_defaults(&defaults);
        o = &defaults;
    }
    if (!r)
        r = &local;
    memset(r, 0, sizeof *r);
    if (!op || !b || !u) {
        pst_set_err(err, "pst_solve needs an operator, b and u");
        pst_set_err(r->message, "%s", err);
        if (err_out)
            pst_set_err(err_out, "%s", err);
        return PST_EINVAL;
    }
    int st = check_opts(op, o, err);
    size_t n = op->n, ndir = 0, nneu = 0;
    const uint8_t *kind = op->kind;
    for (size_t i = 0; i < n && st == PST_OK; ++i) {
        ndir += kind[i] == PST_DIRICHLET;
        nneu += kind[i] == PST_NEUMANN;
        if (!isfinite(b[i]) || (kind[i] != PST_DIRICHLET && !isfinite(u[i]))) {
            pst_set_err(err, "%s[%zu] is not finite", isfinite(b[i]) ? "u" : "b", i);
            st = PST_EINPUT;
        }
    }
    int solver = o->solver;
    if (st == PST_OK && ndir == 0) {
        pst_set_err(err, "no Dirichlet particle: with only interior and Neumann rows L u = b "
                         "determines u only up to a constant (L has the constants in its "
                         "nullspace); mark at least one particle Dirichlet");
        st = PST_EINVAL;
    }
    if (st == PST_OK) {
        if (solver == PST_SOLVER_AUTO)
            solver = symmetrisable(op, nneu) ? PST_SOLVER_CG : PST_SOLVER_GMRES;
        else if (solver == PST_SOLVER_CG && !symmetrisable(op, nneu)) {
            pst_set_err(err, "CG needs a symmetrisable operator (brookshaw or cb, gradient G1, "
                             "no Neumann rows); %s%s is not: use GMRES or BiCGSTAB",
                        op->scheme->name, nneu ? " with Neumann rows" : "");
            st = PST_EINVAL;
        }
    }
    r->solver = solver;
    if (st != PST_OK) {
        pst_set_err(r->message, "%s", err);
        if (err_out)
            pst_set_err(err_out, "%s", err);
        return st;
    }

    pst_ksp k = {0};
    k.op = op;
    k.stored = o->stored;
    k.n = n;
    k.kind = kind;
    k.max_iter = o->max_iter;
    k.restart = o->restart;
    k.monitor = o->monitor;
    k.monitor_ctx = o->monitor_ctx;
    k.message = r->message;
    k.nblocks = (n + PST_KSP_BLOCK - 1) / PST_KSP_BLOCK;
    size_t nb = k.nblocks ? k.nblocks : 1;
    double *bp = pst_alloc(n * sizeof *bp), *x = pst_alloc(n * sizeof *x);
    double *S = solver == PST_SOLVER_CG ? pst_alloc(n * sizeof *S) : NULL;
    k.part = pst_alloc(nb * ((size_t)o->restart + 2) * sizeof *k.part);
    if (o->history)
        k.history = malloc(((size_t)o->max_iter + 1) * sizeof *k.history);
    pst_prec prec = {0};
    if (!bp || !x || !k.part || (solver == PST_SOLVER_CG && !S) || (o->history && !k.history)) {
        pst_set_err(err, "cannot allocate the solver's vectors for %zu particles", n);
        st = PST_ENOMEM;
        goto done;
    }
    if (S && (st = cg_scaling(op, S, err)) != PST_OK)
        goto done;
    if (o->precond == PST_PREC_JACOBI)
        st = jacobi_create(&prec, op, err);
    else if (o->precond == PST_PREC_AMG)
        st = pst_prec_amg(&prec, op, o->amg_source, err); /* PST_EINVAL without hypre */
    if (st != PST_OK)
        goto done;
    k.prec = prec.apply ? &prec : NULL;

    /* Elimination: u_D = b on Dirichlet rows (in x for one apply), b' = b - L u_D elsewhere. */
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; ++i)
        x[i] = kind[i] == PST_DIRICHLET ? b[i] : 0.0;
    pst_ksp_apply(&k, x, bp);
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; ++i) {
        bp[i] = kind[i] == PST_DIRICHLET ? 0.0 : b[i] - bp[i];
        x[i] = kind[i] == PST_DIRICHLET ? 0.0 : u[i];
    }
    k.b = bp;
    k.x = x;
    k.bnorm = sqrt(pst_ksp_dot(&k, b, b));
    k.target = o->rtol * k.bnorm;
    if (k.bnorm == 0) {
        /* b = 0 everywhere: u_D = 0 and the unique solution is u = 0 */
        memset(x, 0, n * sizeof *x);
        k.converged = 1;
        pst_set_err(r->message, "b = 0: u = u_D");
        if (k.history)
            k.history[k.nhistory++] = 0;
    } else if (solver == PST_SOLVER_CG) {
        st = pst_ksp_cg(&k, S);
    } else if (solver == PST_SOLVER_GMRES) {
        st = pst_ksp_gmres(&k);
    } else {
        st = pst_ksp_bicgstab(&k);
    }
    if (st == PST_ENOMEM) {
        pst_set_err(err, "%s", r->message);
        goto done;
    }
    /* u = x + u_D; x is finite (the methods keep the last finite iterate). */
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; ++i)
        u[i] = kind[i] == PST_DIRICHLET ? b[i] : x[i];
    r->converged = k.converged;
    r->iterations = k.iterations;
    r->rel_residual = k.rel_residual;
    st = k.converged ? PST_OK : PST_ENUMERIC;
    if (st != PST_OK)
        pst_set_err(err, "%s did not converge: %s", solver_name(solver), r->message);
    if (k.history) {
        r->history = k.history;
        r->nhistory = k.nhistory;
        k.history = NULL;
    }

done:
    if (prec.destroy)
        prec.destroy(prec.ctx);
    free(k.history);
    pst_free(k.part);
    pst_free(S);
    pst_free(x);
    pst_free(bp);
    if (st != PST_OK && !r->message[0]) /* also a numeric failure before the iteration */
        pst_set_err(r->message, "%s", err);
    if (err_out && st != PST_OK)
        pst_set_err(err_out, "%s", err);
    r->seconds = omp_get_wtime() - t0;
    return st;
}
