/* The solve tasks: the right-hand side, the boundary values (boundary groups, else the exact
 * solution), the operator the boundary asks for, and the solver the plan chose, with the mean
 * of u fixed where nothing else fixes it (a periodic cloud without Dirichlet particles). */
#include "run_state.h"

#include "progress.h"
#include "report.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

void run_solve_monitor(int it, double rel, void *ctx)
{
    run_monitor_ctx *m = ctx;
    char detail[96];
    snprintf(detail, sizeof detail, "iteration %d, residual %.2e", it, rel);
    double frac = rel > 0 && rel < 1 ? log(rel) / log(m->rtol) : 0;
    progress_update(m->pg, frac > 1 ? 1 : frac, detail);
}

/* The task's right-hand side into b (divided by a constant mobility's factor) and, when the
 * task gives one, its exact solution into *ue. */
static int rhs_and_exact(run_state *r, int k, double *b, double **ue)
{
    const sc_task *t = &r->s->tasks[k];
    size_t n = pst_cloud_size(r->c);
    char key[64];
    snprintf(key, sizeof key, "tasks[%d].rhs", k);
    int st = run_eval_at_particles(r, key, t->rhs, b);
    for (size_t i = 0; st == PST_OK && i < n; ++i)
        b[i] /= r->plan.mobility_factor;
    if (st != PST_OK || !t->exact[0])
        return st;
    *ue = malloc((n ? n : 1) * sizeof **ue);
    if (!*ue)
        return run_fail(r, PST_ENOMEM, "out of memory for the exact solution");
    snprintf(key, sizeof key, "tasks[%d].exact", k);
    return run_eval_at_particles(r, key, t->exact[0], *ue);
}

/* Boundary particles no group claimed keep their kind and take the exact solution's value. */
static int unclaimed_values(run_state *r, int k, const int8_t *claim, const double *ue, double *b)
{
    const sc_task *t = &r->s->tasks[k];
    size_t n = pst_cloud_size(r->c);
    const uint8_t *kind = pst_cloud_kinds_const(r->c);
    for (size_t i = 0; i < n; ++i) {
        if (kind[i] == PST_INTERIOR || (claim && claim[i] >= 0))
            continue;
        if (kind[i] == PST_NEUMANN)
            return run_fail(r, PST_EINPUT,
                            "%s: task '%s': the cloud's Neumann particles need a "
                            "boundary group with their flux",
                            r->s->path, t->name);
        if (!ue)
            return run_fail(r, PST_EINPUT,
                            "%s: task '%s': boundary particles outside every "
                            "boundary group take the exact solution, which is "
                            "not given (tasks[%d].exact)",
                            r->s->path, t->name, k);
        b[i] = ue[i];
    }
    return PST_OK;
}

/* The kinds and normals the solve used, as output fields NAME_kind and (with a Neumann
 * particle) NAME_normal_x, _y[, _z]: the cloud's own stay as they were read. */
static int boundary_outputs(run_state *r, const sc_task *t, const run_boundary *bnd)
{
    static const char axis[3] = {'x', 'y', 'z'};
    size_t n = pst_cloud_size(r->c);
    int neumann = 0;
    for (size_t i = 0; i < n && !neumann; ++i)
        neumann = bnd->kind[i] == PST_NEUMANN;
    for (int a = -1; a < (neumann ? r->s->dim : 0); ++a) {
        char name[PST_MAX_NAME], why[PST_ERRLEN];
        if (a < 0)
            snprintf(name, sizeof name, "%s_kind", t->name);
        else
            snprintf(name, sizeof name, "%s_normal_%c", t->name, axis[a]);
        double *out;
        if (pst_cloud_add_field(r->c, name, &out, why) != PST_OK)
            return run_fail(r, PST_EINPUT, "%s: task '%s': output field %s: %s", r->s->path,
                            t->name, name, why);
        for (size_t i = 0; i < n; ++i)
            out[i] = a < 0 ? (double)bnd->kind[i] : bnd->normal[a][i];
    }
    return PST_OK;
}

/* 1 when a solve on the boundary `kind` must fix the mean of u: on a periodic cloud without
 * Dirichlet particles the constants are in L's nullspace (docs/periodic.md). A non-periodic
 * cloud without them (pure Neumann) is left to the solver, which refuses it. */
static int needs_fixed_mean(run_state *r, const uint8_t *kind)
{
    if (!pst_cloud_periodic(r->c, NULL, NULL, NULL))
        return 0;
    size_t n = pst_cloud_size(r->c);
    for (size_t i = 0; i < n; ++i)
        if (kind[i] == PST_DIRICHLET)
            return 0;
    return 1;
}

/* The solve of task k on op (stored weights when the plan says so), its report in tj. A solve
 * that does not converge is not an error here: its outputs are still written, and the run
 * reports it at the end (r->solve_failed). */
static int solve_with(run_state *r, int k, cJSON *tj, pst_op *op, const double *b, double *u,
                      int fix_mean)
{
    const sc_task *t = &r->s->tasks[k];
    if (fix_mean && t->solver == PST_SOLVER_CG)
        return run_fail(r, PST_EINPUT,
                        "%s: task '%s': the cloud is periodic and the solve has no Dirichlet "
                        "particle, so the mean of u is fixed, which CG cannot do: use gmres or "
                        "bicgstab (tasks[%d].solver)",
                        r->s->path, t->name, k);
    if (r->plan.task_stored[k]) {
        int st = run_store_weights(r, k, op);
        if (st != PST_OK)
            return st;
    }
    pst_solve_opts so;
    pst_solve_defaults(&so);
    so.solver = r->plan.task_solver[k];
    so.fix_mean = fix_mean;
    if (fix_mean && so.solver == PST_SOLVER_CG) /* auto's choice: the fixed mean is not symmetric */
        so.solver = PST_SOLVER_GMRES;
    so.precond = r->plan.task_precond[k];
    so.amg_source = r->plan.task_amg_source[k];
    so.amg_radius = r->plan.task_amg_radius[k];
    so.amg_aggressive = t->amg_aggressive;
    so.amg_strong = t->amg_strong;
    so.amg_coarsen = t->amg_coarsen;
    so.amg_interp = t->amg_interp;
    so.amg_pmax = t->amg_pmax;
    so.restart = r->plan.task_restart[k];
    so.max_iter = t->max_iter;
    so.rtol = t->rtol;
    so.stored = r->plan.task_stored[k] != SC_OPERATOR_MATRIX_FREE;
    so.history = 1;
    cli_progress pg;
    run_monitor_ctx mc = {&pg, t->rtol};
    so.monitor = run_solve_monitor;
    so.monitor_ctx = &mc;
    if (so.precond == PST_PREC_AMG && r->o->start_mpi && r->o->start_mpi() != 0)
        return run_fail(r, PST_ENUMERIC, "%s: task '%s': MPI, which the AMG preconditioner "
                        "needs, could not be started", r->s->path, t->name);
    pst_solve_result res;
    char msg[PST_ERRLEN];
    char label[PST_MAX_NAME + 8];
    snprintf(label, sizeof label, "task %s", t->name);
    progress_begin(&pg, !r->o->quiet, label, NULL);
    int ss = pst_solve(op, b, u, &so, &res, msg);
    progress_end(&pg);
    return run_solve_finish(r, k, tj, &res, fix_mean, ss, msg);
}

int run_solve_finish(run_state *r, int k, cJSON *tj, pst_solve_result *res, int fix_mean,
                     int st, const char *msg)
{
    const sc_task *t = &r->s->tasks[k];
    r->cnt.solves++;
    report_solve(tj, res, r->plan.task_stored[k], fix_mean);
    cJSON_AddNumberToObject(tj, "seconds", res->seconds);
    pst_solve_result_free(res);
    if (st == PST_ENUMERIC) {
        r->solve_failed = 1;
        snprintf(r->err, r->errlen, "%s: task '%s': %s", r->s->path, t->name, msg);
        return PST_OK;
    }
    return st == PST_OK ? PST_OK : run_fail(r, st, "%s: task '%s': %s", r->s->path, t->name, msg);
}

int run_solve(run_state *r, int k, cJSON *tj)
{
    const sc_task *t = &r->s->tasks[k];
    size_t n = pst_cloud_size(r->c);
    int grouped = t->ngroups > 0;
    double *u[6] = {NULL}, *b = calloc(n ? n : 1, sizeof *b), *ue = NULL;
    int8_t *claim = grouped ? malloc(n ? n : 1) : NULL;
    run_boundary bnd = {NULL, {NULL, NULL, NULL}};
    if (!b || (grouped && !claim)) {
        free(b);
        free(claim);
        return run_fail(r, PST_ENOMEM, "out of memory for the right-hand side");
    }
    int st = run_add_outputs(r, t, 1, u);
    if (st == PST_OK)
        st = rhs_and_exact(r, k, b, &ue);
    if (st == PST_OK && grouped)
        st = run_boundary_make(r, k, b, claim, &bnd, tj);
    if (st == PST_OK && grouped)
        st = boundary_outputs(r, t, &bnd);
    if (st == PST_OK)
        st = unclaimed_values(r, k, claim, ue, b);
    pst_op *op = r->base;
    if (st == PST_OK && grouped && !r->dist)
        st = run_make_operator(r, 1, &bnd, &op);
    const uint8_t *kind = grouped ? bnd.kind : pst_cloud_kinds_const(r->c);
    int fix_mean = st == PST_OK && needs_fixed_mean(r, kind);
    int petsc = r->plan.task_petsc[k]; /* several ranks, tasks[k].petsc or --petsc */
    double *normal[3] = {NULL, NULL, NULL};
    for (int d = 0; d < r->s->dim; ++d)
        normal[d] = grouped ? bnd.normal[d] : pst_cloud_normal(r->c, d);
    if (st == PST_OK && petsc)
        st = run_solve_petsc(r, k, tj, op, kind, normal, b, u[0], fix_mean);
    else if (st == PST_OK)
        st = solve_with(r, k, tj, op, b, u[0], fix_mean);
    if (st == PST_OK && op != r->base && !r->base) /* outputs.vtu: this solve's rows */
        st = run_keep_status(r, op);
    if (op != r->base)
        pst_op_destroy(op);
    r->task_kinds = bnd.kind;
    r->task_mean_fixed = fix_mean;
    if (st == PST_OK)
        st = run_task_norms(r, k, tj, 1, u, NULL, 0);
    r->task_kinds = NULL;
    r->task_mean_fixed = 0;
    run_boundary_free(&bnd);
    free(b);
    free(ue);
    free(claim);
    return st;
}
