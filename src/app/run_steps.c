/* The diffuse tasks (docs/time-stepping.md): du/dt = m L u + f from u(0) = initial, with L the
 * run's operator (div(M grad u), m the constant mobility's factor), by the theta-method
 *     (I - theta dt m L) u^{n+1} = u^n + (1 - theta) dt (m L u^n + f^n) + theta dt f^{n+1}
 * on the interior rows (theta 0 forward Euler, 1 backward Euler, 1/2 Crank-Nicolson), the
 * Dirichlet rows held at the boundary value of t^{n+1}. The explicit part reads the operator
 * where the particles are, then they move (velocity), then the implicit part solves with the
 * operator where they arrived. The step: the scene's, or for forward Euler safety * 2 / rho
 * (run_steps_limit.c), shortened so that whole steps end at t_end. */
#include "run_steps.h"

#include "progress.h"
#include "report.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    run_state *r;
    int k;
    const sc_task *t;
    pst_op *op;
    size_t n;
    const uint8_t *kind;
    double theta, m, rho, dt, time; /* time: the t that expressions read (r->time)          */
    int stored, nsteps, every;
    double *u, *lu, *b, *w, *v[3]; /* u the task's field; w a scratch for expressions      */
    steps_system sys;
    pst_krylov *kr;
    int setups;
    long iterations, rebuilds;
    steps_series sr;
    steps_row *rows; /* one per step for steps_csv, else NULL */
} stepper;

/* Expression `text` of the task's key `name` at the particles, at time t. */
static int eval_at(stepper *st, const char *name, const char *text, double t, double *out)
{
    char key[64];
    snprintf(key, sizeof key, "tasks[%d].%s", st->k, name);
    st->time = t;
    return run_eval_at_particles(st->r, key, text, out);
}

/* The boundary value at time t into the held rows of b (and of u, the solve's first guess). */
static int held_values(stepper *st, double t, double *b)
{
    const char *g = st->t->boundary_value ? st->t->boundary_value : st->t->exact[0];
    if (!g) /* no Dirichlet particle: check_boundary refused the task otherwise */
        return PST_OK;
    int rc = eval_at(st, st->t->boundary_value ? "boundary_value" : "exact", g, t, st->w);
    for (size_t i = 0; rc == PST_OK && i < st->n; ++i)
        if (st->kind[i] != PST_INTERIOR)
            b[i] = st->u[i] = st->w[i];
    return rc;
}

/* The task's boundary: Dirichlet particles need a value, Neumann rows are not stepped. */
static int check_boundary(stepper *st)
{
    size_t dirichlet = 0;
    for (size_t i = 0; i < st->n; ++i) {
        if (st->kind[i] == PST_NEUMANN)
            return run_fail(st->r, PST_EINPUT, "%s: task '%s': the cloud has Neumann "
                            "particles, which a diffuse task does not step (Dirichlet "
                            "boundaries and periodic boxes only)", st->r->s->path,
                            st->t->name);
        dirichlet += st->kind[i] == PST_DIRICHLET;
    }
    if (dirichlet && !st->t->boundary_value && !st->t->exact[0])
        return run_fail(st->r, PST_EINPUT, "%s: task '%s': the cloud's %zu Dirichlet particles "
                        "need a value: give tasks[%d].boundary_value or tasks[%d].exact",
                        st->r->s->path, st->t->name, dirichlet, st->k, st->k);
    return PST_OK;
}

/* The step and the number of steps; the explicit method's scene dt above its limit is
 * refused. */
static int choose_dt(stepper *st, cJSON *sj)
{
    const sc_task *t = st->t;
    double limit = st->rho > 0 ? 2.0 / st->rho : INFINITY;
    if (t->method == SC_METHOD_EXPLICIT && t->dt > limit)
        return run_fail(st->r, PST_EINPUT, "%s: tasks[%d].dt: %g exceeds the forward-Euler step "
                        "limit 2/rho = %.6g (rho = %.6g, the Gershgorin bound of the interior "
                        "rows): give dt <= %.6g, leave dt out for %g of the limit, or use an "
                        "implicit method", st->r->s->path, st->k, t->dt, limit, st->rho, limit,
                        t->safety);
    double want = t->dt > 0 ? t->dt : t->safety * limit;
    if (!(want < INFINITY)) /* rho 0: no row evolves through L, one step does */
        want = t->t_end;
    double steps = ceil(t->t_end / want * (1 - 1e-12));
    if (!(steps <= t->max_steps))
        return run_fail(st->r, PST_EINPUT, "%s: task '%s': %.0f steps of dt %.6g to t_end %g, "
                        "more than tasks[%d].max_steps (%d)", st->r->s->path, t->name, steps,
                        want, t->t_end, st->k, t->max_steps);
    st->nsteps = steps < 1 ? 1 : (int)steps;
    st->dt = t->t_end / st->nsteps;
    cJSON_AddNumberToObject(sj, "rho", st->rho);
    if (limit < INFINITY)
        cJSON_AddNumberToObject(sj, "dt_limit", limit);
    cJSON_AddStringToObject(sj, "dt_from", t->dt > 0 ? "scene" : "limit");
    cJSON_AddNumberToObject(sj, "dt", st->dt);
    cJSON_AddNumberToObject(sj, "steps", st->nsteps);
    return PST_OK;
}

/* 1 when step s writes a VTU of the series: the first, every output_every, the last. */
static int snapshot_step(const stepper *st, int s)
{
    return s == 0 || s % st->every == 0 || s == st->nsteps;
}

static int alloc_arrays(stepper *st)
{
    size_t bytes = (st->n ? st->n : 1) * sizeof(double);
    st->lu = malloc(bytes);
    st->b = malloc(bytes);
    st->w = malloc(bytes);
    int ok = st->lu && st->b && st->w;
    for (int d = 0; d < st->t->nvelocity; ++d)
        ok &= (st->v[d] = malloc(bytes)) != NULL;
    if (st->t->steps_csv)
        ok &= (st->rows = calloc((size_t)st->nsteps, sizeof *st->rows)) != NULL;
    return ok ? PST_OK : run_fail(st->r, PST_ENOMEM, "out of memory for the time steps");
}

/* Everything before the first step: the field at t = 0, the limit, the step, the weights,
 * the solver handle and the series' first file. */
static int set_up(stepper *st, cJSON *sj)
{
    run_state *r = st->r;
    int s = check_boundary(st);
    if (s == PST_OK && r->plan.task_stored[st->k])
        s = run_store_weights(r, st->k, st->op);
    if (s == PST_OK)
        s = steps_rho(r, st->op, st->m, &st->rho);
    if (s == PST_OK)
        s = choose_dt(st, sj);
    size_t count = (size_t)(st->nsteps / st->every) + 1 + (st->nsteps % st->every != 0);
    if (s == PST_OK && st->t->pvd && count > STEPS_MAX_SNAPSHOTS)
        s = run_fail(r, PST_EINPUT, "%s: task '%s': %zu files in the time series, more than "
                     "%d: raise tasks[%d].output_every", r->s->path, st->t->name, count,
                     STEPS_MAX_SNAPSHOTS, st->k);
    if (s == PST_OK)
        s = alloc_arrays(st);
    if (s == PST_OK)
        s = eval_at(st, "initial", st->t->initial, 0.0, st->u);
    if (s == PST_OK)
        s = held_values(st, 0.0, st->b);
    st->sys = (steps_system){st->op, st->stored, st->kind, st->n, st->theta * st->dt * st->m};
    if (s == PST_OK && st->theta > 0 && (s = steps_solver_create(r, st->k, &st->sys, &st->kr)) ==
                                            PST_OK)
        st->setups++;
    if (s == PST_OK)
        s = steps_series_open(r, st->k, count, &st->sr);
    return s == PST_OK ? steps_series_add(r, st->k, &st->sr, 0, 0.0, st->op) : s;
}

/* b = u + (1 - theta) dt (m L u + f(t0)) on the interior rows: the explicit part, with the
 * operator where the particles are now. */
static int explicit_part(stepper *st, double t0, steps_row *row)
{
    const sc_task *t = st->t;
    double c = (1 - st->theta) * st->dt;
    int s = PST_OK;
    if (c > 0) {
        double a0 = omp_get_wtime();
        s = steps_apply(st->op, st->stored, st->u, st->lu);
        row->apply_s = omp_get_wtime() - a0;
        st->r->cnt.applies++;
        if (s != PST_OK)
            return run_fail(st->r, s, "%s: task '%s': L u failed", st->r->s->path, t->name);
        for (size_t i = 0; i < st->n; ++i)
            st->lu[i] *= st->m;
    }
    if (c > 0 && t->source && (s = eval_at(st, "source", t->source, t0, st->w)) == PST_OK)
        for (size_t i = 0; i < st->n; ++i)
            st->lu[i] += st->w[i];
    for (size_t i = 0; i < st->n; ++i)
        st->b[i] = st->kind[i] == PST_INTERIOR && c > 0 ? st->u[i] + c * st->lu[i] : st->u[i];
    return s;
}

/* The particles move by dt v(x, t0); the explicit method checks its step against the moved
 * particles' limit, the implicit ones refresh their solver (its Jacobi diagonal was that of
 * the old rows: docs/time-stepping.md, "The implicit system and solver reuse"). */
static int move(stepper *st, int step, double t0, steps_row *row)
{
    const sc_task *t = st->t;
    int s = PST_OK;
    for (int d = 0; d < t->nvelocity && s == PST_OK; ++d) {
        char name[32];
        snprintf(name, sizeof name, "velocity[%d]", d);
        s = eval_at(st, name, t->velocity[d], t0, st->v[d]);
    }
    if (s == PST_OK)
        s = steps_move(st->r, st->op, st->dt, st->v, row);
    st->rebuilds += row->rebuilt;
    if (s == PST_OK && st->theta == 0 && (s = steps_rho(st->r, st->op, st->m, &row->rho)) ==
                                              PST_OK && st->dt * row->rho > 2)
        s = run_fail(st->r, PST_ENUMERIC, "%s: task '%s': step %d: the moved particles' step "
                     "limit 2/rho = %.6g is below dt = %.6g: use a smaller dt or safety",
                     st->r->s->path, t->name, step, 2 / row->rho, st->dt);
    if (s == PST_OK && st->theta > 0) {
        /* the handle's Jacobi diagonal was the old rows': taken again from the new ones */
        double a0 = omp_get_wtime();
        char msg[PST_ERRLEN];
        if (pst_krylov_refresh(st->kr, msg) != PST_OK)
            s = run_fail(st->r, PST_ENUMERIC, "%s: task '%s': step %d: %s", st->r->s->path,
                         t->name, step, msg);
        st->setups += s == PST_OK;
        row->setup_s = omp_get_wtime() - a0;
    }
    return s;
}

/* The implicit part: b += theta dt f(t1), then A u = b. A solve that does not converge stops
 * the steps as a solve task's does: the outputs are written and say so (exit 3). */
static int implicit_part(stepper *st, int step, double t1, steps_row *row)
{
    const sc_task *t = st->t;
    int s = PST_OK;
    if (t->source && (s = eval_at(st, "source", t->source, t1, st->w)) == PST_OK)
        for (size_t i = 0; i < st->n; ++i)
            st->b[i] += st->kind[i] == PST_INTERIOR ? st->theta * st->dt * st->w[i] : 0.0;
    if (s == PST_OK)
        s = held_values(st, t1, st->b);
    if (s != PST_OK)
        return s;
    pst_solve_result res;
    char msg[PST_ERRLEN];
    s = pst_krylov_solve(st->kr, st->b, st->u, &res, msg);
    st->r->cnt.solves++;
    row->iterations = res.iterations;
    row->residual = res.rel_residual;
    row->solve_s = res.seconds;
    st->iterations += res.iterations;
    pst_solve_result_free(&res);
    if (s == PST_ENUMERIC) {
        st->r->solve_failed = 1;
        snprintf(st->r->err, st->r->errlen, "%s: task '%s': step %d: %s", st->r->s->path, t->name,
                 step, msg);
        s = PST_OK;
    } else if (s != PST_OK) {
        s = run_fail(st->r, s, "%s: task '%s': step %d: %s", st->r->s->path, t->name, step, msg);
    }
    return s;
}

/* max |u|, or a failure when u is not finite (it never is below the step limit). */
static int check_u(stepper *st, int step, steps_row *row)
{
    double most = 0;
    size_t bad = 0;
    const double *u = st->u;
#pragma omp parallel for reduction(max : most) reduction(+ : bad) schedule(static)
    for (size_t i = 0; i < st->n; ++i) {
        bad += !isfinite(u[i]);
        most = fmax(most, fabs(u[i]));
    }
    row->max_abs = most;
    if (bad)
        return run_fail(st->r, PST_ENUMERIC, "%s: task '%s': step %d: u is not finite at %zu "
                        "particles", st->r->s->path, st->t->name, step, bad);
    return PST_OK;
}

static int step(stepper *st, int s, steps_row *row)
{
    double t0 = (s - 1) * st->dt, t1 = s == st->nsteps ? st->t->t_end : s * st->dt;
    *row = (steps_row){.t = t1, .dt = st->dt, .rho = st->rho};
    int rc = explicit_part(st, t0, row);
    if (rc == PST_OK && st->t->nvelocity)
        rc = move(st, s, t0, row);
    if (rc == PST_OK && st->theta > 0)
        rc = implicit_part(st, s, t1, row);
    else if (rc == PST_OK) {
        memcpy(st->u, st->b, st->n * sizeof *st->u);
        rc = held_values(st, t1, st->b);
    }
    if (rc == PST_OK)
        rc = check_u(st, s, row);
    st->r->cnt.steps++;
    st->time = t1;
    if (rc == PST_OK && snapshot_step(st, s))
        rc = steps_series_add(st->r, st->k, &st->sr, s, t1, st->op);
    return rc;
}

/* The steps, with a progress line. */
static int run_loop(stepper *st, int *done)
{
    cli_progress pg;
    char label[PST_MAX_NAME + 8], detail[64];
    snprintf(label, sizeof label, "task %s", st->t->name);
    progress_begin(&pg, !st->r->o->quiet, label, NULL);
    int rc = PST_OK;
    steps_row row;
    for (*done = 0; *done < st->nsteps && rc == PST_OK && !st->r->solve_failed;) {
        ++*done;
        rc = step(st, *done, st->rows ? &st->rows[*done - 1] : &row);
        snprintf(detail, sizeof detail, "step %d of %d", *done, st->nsteps);
        progress_update(&pg, (double)*done / st->nsteps, detail);
    }
    progress_end(&pg);
    return rc;
}

static void report_steps(const stepper *st, cJSON *sj, int done, double seconds)
{
    static const char *const methods[] = {"explicit", "implicit", "crank_nicolson"};
    cJSON_AddStringToObject(sj, "method", methods[st->t->method]);
    cJSON_AddStringToObject(sj, "operator", report_operator_use(st->r->plan.task_stored[st->k]));
    cJSON_AddNumberToObject(sj, "theta", st->theta);
    cJSON_AddNumberToObject(sj, "t_end", st->t->t_end);
    cJSON_AddNumberToObject(sj, "steps_done", done);
    cJSON_AddNumberToObject(sj, "t_reached", st->time);
    cJSON_AddBoolToObject(sj, "moving", st->t->nvelocity > 0);
    cJSON_AddNumberToObject(sj, "list_rebuilds", (double)st->rebuilds);
    cJSON_AddNumberToObject(sj, "solver_setups", st->setups);
    cJSON_AddNumberToObject(sj, "iterations", (double)st->iterations);
    cJSON_AddNumberToObject(sj, "series_files", (double)st->sr.n);
    cJSON_AddNumberToObject(sj, "seconds", seconds);
}

int run_steps(run_state *r, int k, cJSON *tj)
{
    static const double thetas[] = {0.0, 1.0, 0.5};
    const sc_task *t = &r->s->tasks[k];
    stepper st = {.r = r, .k = k, .t = t, .op = r->base, .n = pst_cloud_size(r->c),
                  .kind = pst_cloud_kinds_const(r->c), .theta = thetas[t->method],
                  .m = r->plan.mobility_factor,
                  .stored = r->plan.task_stored[k] != SC_OPERATOR_MATRIX_FREE,
                  .every = t->output_every};
    double t0 = omp_get_wtime();
    cJSON *sj = cJSON_AddObjectToObject(tj, "steps");
    r->time = &st.time;
    double *out[6] = {NULL};
    int done = 0, rc = run_add_outputs(r, t, 1, out);
    st.u = out[0];
    if (rc == PST_OK)
        rc = set_up(&st, sj);
    if (rc == PST_OK)
        rc = run_loop(&st, &done);
    if (rc == PST_OK)
        rc = steps_write_table(r, k, st.rows, (size_t)done);
    double seconds = omp_get_wtime() - t0;
    report_steps(&st, sj, done, seconds);
    cJSON_AddNumberToObject(tj, "seconds", seconds);
    if (rc == PST_OK) /* the exact solution at the time reached */
        rc = run_task_norms(r, k, tj, 1, &st.u, NULL, 0);
    r->time = NULL;
    pst_krylov_destroy(st.kr);
    steps_series_free(&st.sr);
    free(st.lu);
    free(st.b);
    free(st.w);
    for (int d = 0; d < 3; ++d)
        free(st.v[d]);
    free(st.rows);
    return rc;
}
