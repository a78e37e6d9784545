/* The implicit system of a diffuse task, (I - theta dt L) u = b on the interior rows with the
 * Dirichlet rows held (u_i = b_i), as a pst_linop for one reusable solver handle
 * (pst_krylov_create_linop): the Jacobi diagonal is set up once (again when the particles
 * moved: pst_krylov_refresh) and each step only iterates.
 * A linop because the engine's solver eliminates Dirichlet rows of L itself and has no
 * shifted form; its AMG, which needs the engine's rows, is refused by the planner. */
#include "run_steps.h"

#include <stdio.h>

int steps_apply(const pst_op *op, int stored, const double *u, double *y)
{
    return stored ? pst_op_apply_stored(op, u, y) : pst_op_apply(op, u, y);
}

/* y = A x. The apply cannot fail here: the operator has its rows, and a refresh that would
 * have left it without stops the task before any solve. */
static void system_apply(void *ctx, const double *x, double *y)
{
    const steps_system *sys = ctx;
    const pst_op *op = sys->op;
    (void)steps_apply(op, sys->stored, x, y);
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < sys->n; ++i)
        y[i] = sys->kind[i] == PST_INTERIOR ? x[i] - sys->c * y[i] : x[i];
}

static int system_diagonal(void *ctx, double *d)
{
    const steps_system *sys = ctx;
    int st = pst_op_diagonal(sys->op, d);
    for (size_t i = 0; st == PST_OK && i < sys->n; ++i)
        d[i] = sys->kind[i] == PST_INTERIOR ? 1.0 - sys->c * d[i] : 1.0;
    return st;
}

int steps_solver_create(run_state *r, int k, steps_system *sys, pst_krylov **out)
{
    const sc_task *t = &r->s->tasks[k];
    pst_linop A = {sys->n, system_apply, system_diagonal, sys};
    pst_solve_opts so;
    pst_solve_defaults(&so);
    so.solver = r->plan.task_solver[k];
    so.precond = r->plan.task_precond[k];
    so.restart = r->plan.task_restart[k];
    so.max_iter = t->max_iter;
    so.rtol = t->rtol;
    char msg[PST_ERRLEN];
    int st = pst_krylov_create_linop(out, &A, NULL, &so, msg);
    return st == PST_OK ? PST_OK
                        : run_fail(r, st, "%s: task '%s': the implicit system's solver: %s",
                                   r->s->path, t->name, msg);
}
