/* One solve of a reusable solver: the right-hand side (with the Dirichlet elimination of an
 * engine operator), the method, and the result. Nothing of the set-up is rebuilt here. */
#include "solve.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Elimination: u_D = b on Dirichlet rows (in x for one apply), b' = b - L u_D elsewhere, and
 * the initial guess x = u off the Dirichlet rows. */
static void eliminate(pst_krylov *s, const double *b, const double *u)
{
    size_t n = s->A.n;
    const uint8_t *kind = s->op->kind;
    double *x = s->x, *bp = s->bp;
#pragma omp parallel for schedule(static) if (PST_KSP_THREADED(n))
    for (size_t i = 0; i < n; ++i)
        x[i] = kind[i] == PST_DIRICHLET ? b[i] : 0.0;
    pst_ksp_apply(&s->k, x, bp);
#pragma omp parallel for schedule(static) if (PST_KSP_THREADED(n))
    for (size_t i = 0; i < n; ++i) {
        bp[i] = kind[i] == PST_DIRICHLET ? 0.0 : b[i] - bp[i];
        x[i] = kind[i] == PST_DIRICHLET ? 0.0 : u[i];
    }
}

/* The method chosen at set-up on the system in s->k. */
static int iterate(pst_krylov *s)
{
    pst_ksp *k = &s->k;
    if (k->bnorm == 0) {
        /* b = 0 everywhere: u_D = 0 and the unique solution is u = 0 */
        memset(k->x, 0, k->n * sizeof *k->x);
        k->converged = 1;
        k->stop = PST_STOP_CONVERGED;
        pst_set_err(k->message, "b = 0: u = %s", s->op ? "u_D" : "0");
        if (k->history)
            k->history[k->nhistory++] = 0;
        return PST_OK;
    }
    if (s->solver == PST_SOLVER_CG)
        return pst_ksp_cg(k, s->S);
    if (s->solver == PST_SOLVER_GMRES)
        return pst_ksp_gmres(k);
    return pst_ksp_bicgstab(k);
}

/* The per-solve state of the method: the system, the target and an empty record. */
static int start(pst_krylov *s, const double *b, double *u, char *message, char *err)
{
    pst_ksp *k = &s->k;
    k->iterations = k->converged = k->nhistory = 0;
    k->stop = PST_STOP_NONE;
    k->rel_residual = 0;
    k->message = message;
    k->history = NULL;
    if (s->o.history) {
        k->history = malloc(((size_t)s->o.max_iter + 1) * sizeof *k->history);
        PST_CHECK_ALLOC(k->history, err, "cannot allocate the solver's vectors for %zu "
                        "particles", k->n);
    }
    if (s->op) {
        eliminate(s, b, u);
        k->b = s->bp;
        k->x = s->x;
    } else {
        k->b = b;
        k->x = u;
    }
    k->bnorm = sqrt(pst_ksp_dot(k, b, b));
    k->target = s->o.rtol * k->bnorm;
    return PST_OK;
}

/* The checks of a solve's arguments (the AMG check: MPI may have been finalised since). */
static int check_solve(const pst_krylov *s, const double *b, const double *u, char *err)
{
    PST_CHECK(!s || !b || !u, PST_EINVAL, err, "pst_krylov_solve needs a handle, b and u");
    PST_CHECK(s->unusable, PST_EINVAL, err,
              "the solver handle's last refresh failed (pst_krylov_refresh): refresh it again "
              "or create a new one");
    PST_TRY(pst_solve_check_finite(s->op, s->A.n, b, u, err));
    if (s->op && s->o.precond == PST_PREC_AMG)
        PST_TRY(pst_prec_amg_ready(err));
    return PST_OK;
}

int pst_solve_refused(pst_solve_result *r, int st, const char *err, char *err_out, double t0)
{
    pst_set_err(r->message, "%s", err);
    if (err_out)
        pst_set_err(err_out, "%s", err);
    r->seconds = omp_get_wtime() - t0;
    return st;
}

/* What to try after a solve that stopped short of the tolerance, by its preconditioner. */
static const char *stall_hint(const pst_krylov *s)
{
    if (s->user_precond || !s->op)
        return "";
    if (s->o.precond != PST_PREC_AMG)
        return pst_have_amg() ? "; try the AMG preconditioner (precond amg)" : "";
    pst_krylov_stats st = {0};
    pst_prec_amg_stats(&s->prec, &st);
    if (st.amg_own)
        return "; try a longer GMRES restart, or BiCGSTAB";
    /* AUTO on a scheme that names its own matrix is on the proxy only where the own one has
     * no positive diagonal somewhere: asking for it again would fail */
    return s->o.amg_source == PST_AMG_AUTO && s->op->scheme->amg_own
               ? "; try a wider AMG matrix (amg_radius 0) or a longer GMRES restart"
               : "; try the scheme's own matrix for AMG (amg_source own), a wider AMG matrix "
                 "(amg_radius 0) or a longer GMRES restart";
}

int pst_krylov_solve(pst_krylov *s, const double *b, double *u, pst_solve_result *r,
                     char *err_out)
{
    double t0 = omp_get_wtime();
    char err[PST_ERRLEN] = "";
    pst_solve_result local;
    if (!r)
        r = &local;
    memset(r, 0, sizeof *r);
    int st = check_solve(s, b, u, err);
    if (s)
        r->solver = s->solver;
    if (st == PST_OK)
        st = start(s, b, u, r->message, err);
    if (st != PST_OK)
        return pst_solve_refused(r, st, err, err_out, t0);
    st = iterate(s);
    s->solves++;
    pst_ksp *k = &s->k;
    s->last_iters = k->iterations; /* the AMG reuse rule's measure (pst_krylov_refresh) */
    if (s->amg_first_iters == 0)
        s->amg_first_iters = k->iterations;
    if (s->op) {
        /* u = x + u_D; x is finite (the methods keep the last finite iterate). */
        const uint8_t *kind = s->op->kind;
#pragma omp parallel for schedule(static) if (PST_KSP_THREADED(k->n))
        for (size_t i = 0; i < k->n; ++i)
            u[i] = kind[i] == PST_DIRICHLET ? b[i] : k->x[i];
        if (s->o.fix_mean)
            r->mean_shift = pst_fix_mean_finish(s, u);
    }
    r->converged = k->converged;
    r->stop = k->stop;
    r->iterations = k->iterations;
    r->rel_residual = k->rel_residual;
    r->history = k->history;
    r->nhistory = k->history ? k->nhistory : 0;
    k->history = NULL;
    if (st != PST_OK && k->stop == PST_STOP_ITERATION_LIMIT) {
        size_t len = strlen(r->message);
        snprintf(r->message + len, PST_ERRLEN - len, "%s", stall_hint(s));
    }
    if (st != PST_OK && err_out)
        pst_set_err(err_out, "%s did not converge: %s", pst_solver_label(s->solver), r->message);
    r->seconds = omp_get_wtime() - t0;
    return st;
}
