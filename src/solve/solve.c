/* pst_solve, the one-call solve: a reusable solver created, used once and destroyed
 * (docs/solving.md). The options' defaults, the result and the stop reasons' names. */
#include "solve.h"

#include <omp.h>
#include <stdlib.h>
#include <string.h>

void pst_solve_defaults(pst_solve_opts *o)
{
    o->solver = PST_SOLVER_AUTO;
    o->precond = PST_PREC_JACOBI;
    o->amg_source = PST_AMG_AUTO;
    o->amg_radius = -1;
    o->amg_aggressive = 0;
    o->amg_strong = 0;
    o->amg_coarsen = PST_AMG_HMIS;
    o->amg_interp = PST_AMG_EXT_I;
    o->amg_pmax = 4;
    o->amg_reuse = 8;
    o->restart = 50;
    o->max_iter = 5000;
    o->rtol = 1e-10;
    o->stored = 0;
    o->history = 0;
    o->fix_mean = 0;
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

const char *pst_stop_reason_name(int stop)
{
    static const char *const names[] = {"none",       "converged",  "iteration limit",
                                        "breakdown",  "stagnation", "non-finite",
                                        "preconditioner set-up"};
    return stop >= 0 && stop <= PST_STOP_PRECOND_SETUP ? names[stop] : "unknown";
}

/* The checks pst_solve makes before any set-up, in the order of their messages: arguments,
 * options, then b and u finite. */
static int check_request(const pst_op *op, const double *b, const double *u,
                         const pst_solve_opts *o, char *err)
{
    PST_CHECK(!op || !b || !u, PST_EINVAL, err, "pst_solve needs an operator, b and u");
    PST_TRY(pst_solve_check_opts(o, op, err));
    return pst_solve_check_finite(op, op->n, b, u, err);
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
    pst_krylov *s = NULL;
    int solver = o->solver, stop = PST_STOP_NONE;
    int st = check_request(op, b, u, o, err);
    if (st == PST_OK)
        st = pst_krylov_build(&s, op, o, &solver, &stop, err);
    double setup = omp_get_wtime() - t0;
    if (st != PST_OK) {
        r->solver = op && b && u ? solver : 0;
        r->stop = stop;
        st = pst_solve_refused(r, st, err, err_out, t0);
        r->setup_seconds = setup;
        return st;
    }
    st = pst_krylov_solve(s, b, u, r, err_out);
    pst_krylov_destroy(s);
    r->seconds = omp_get_wtime() - t0;
    r->setup_seconds = setup;
    return st;
}
