/* The scene runner (docs/running.md): cloud, mobility, fields, neighbours, operators, tasks,
 * error norms and outputs, in that order, doing only what the plan says. Every step that
 * computes something increments its counter, which is how the tests check that a run did not
 * compute what its scene did not ask for. The steps live in run_*.c (run_state.h). */
#include "run_state.h"

#include "progress.h"
#include "report.h"

#include <omp.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

int run_fail(run_state *r, int status, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(r->err, r->errlen, fmt, ap);
    va_end(ap);
    return status;
}

void pst_scene_op_opts(const pst_scene *s, pst_op_opts *oo)
{
    pst_op_defaults(oo);
    oo->scheme = s->op.scheme;
    oo->kernel = s->op.kernel;
    if (s->op.gradient)
        oo->gradient = s->op.gradient;
    oo->variant = s->op.variant;
    oo->cond_max = s->op.cond_max;
    oo->rank_tol = s->op.rank_tol;
    oo->min_pair_distance = s->op.min_pair_distance;
    oo->on_degenerate = s->op.on_degenerate;
    oo->mobility_mean = s->op.mobility_mean;
}

/* The plan's low-memory layout: the run's one operator switches to the half of the list, and
 * the whole list is freed before the solves allocate anything (docs/running.md). */
static int use_half_list(run_state *r, pst_op *op)
{
    char msg[PST_ERRLEN];
    pst_nlist *half = NULL;
    int st = pst_nlist_halve(&half, r->nl, msg);
    if (st == PST_OK)
        st = pst_op_use_half_list(op, half, msg);
    if (st != PST_OK) {
        pst_nlist_destroy(half);
        return run_fail(r, st, "%s: half neighbour list: %s", r->s->path, msg);
    }
    pst_nlist_destroy(r->nl);
    r->nl = half;
    r->cnt.half_lists++;
    return PST_OK;
}

int run_make_operator(run_state *r, int laplacian, const run_boundary *bnd, pst_op **op)
{
    pst_op_opts oo;
    pst_scene_op_opts(r->s, &oo);
    oo.laplacian = laplacian;
    oo.keep = bnd ? 0 : r->plan.base_keep;
    if (bnd) {
        oo.kinds = bnd->kind;
        for (int d = 0; d < 3; ++d)
            oo.normals[d] = bnd->normal[d];
    }
    char msg[PST_ERRLEN];
    cli_progress pg;
    progress_begin(&pg, !r->o->quiet, "precompute", "rows");
    oo.progress = progress_hook(&pg);
    int st = pst_op_create(op, r->c, r->nl, &oo, msg);
    progress_end(&pg);
    if (st == PST_OK)
        pst_op_set_progress(*op, NULL); /* pg ends here; each task attaches its own */
    if (st != PST_OK)
        return run_fail(r, st, "%s: operator %s: %s", r->s->path, oo.scheme, msg);
    if (laplacian)
        r->cnt.laplacian_precomputes++;
    else
        r->cnt.derivative_operators++;
    report_operator(r->report, *op);
    return r->plan.half_list ? use_half_list(r, *op) : PST_OK;
}

int run_store_weights(run_state *r, int k, pst_op *op)
{
    pst_op_store_opts so;
    pst_op_store_defaults(&so);
    if (r->plan.task_stored[k] == SC_OPERATOR_STORED_FLOAT)
        so.precision = PST_STORE_FLOAT;
    pst_store_precision have = pst_op_store_precision(op);
    if (have != PST_STORE_NONE && have != so.precision)
        pst_op_drop_store(op); /* an earlier task on this operator stored the other precision */
    char msg[PST_ERRLEN] = "";
    int st = pst_op_store_with(op, &so, msg);
    r->cnt.stored_weights++;
    if (st != PST_OK)
        return run_fail(r, st, "%s: task '%s': cannot store the operator's weights%s: %s",
                        r->s->path, r->s->tasks[k].name,
                        so.precision == PST_STORE_FLOAT ? " in float" : "", msg);
    return PST_OK;
}

/* User + system CPU time of the process: with the wall-clock total it shows the parallel
 * efficiency of a run. */
static double cpu_seconds(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return (double)(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) +
           1e-6 * (double)(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
}

/* Over several ranks only solves run, each on the rank's part of the cloud (run_petsc.c). */
static int check_ranks(run_state *r)
{
    for (int k = 0; k < r->s->ntasks && r->dist; ++k)
        if (r->s->tasks[k].type != SC_TASK_SOLVE)
            return run_fail(r, PST_EINPUT, "%s: task '%s': over %d ranks only solve tasks run "
                            "(docs/distributed.md); run this one on one process",
                            r->s->path, r->s->tasks[k].name, r->o->ranks);
    return PST_OK;
}

static int run_tasks(run_state *r)
{
    const pst_scene *s = r->s;
    if (r->plan.base_operator && !r->dist) {
        int st = run_make_operator(r, r->plan.base_laplacian, NULL, &r->base);
        if (st != PST_OK)
            return st;
    }
    for (int k = 0; k < s->ntasks; ++k) {
        cJSON *tj = cJSON_CreateObject();
        cJSON_AddItemToArray(r->tasks, tj);
        report_task_header(tj, &s->tasks[k]);
        int st;
        switch (s->tasks[k].type) {
        case SC_TASK_INTERPOLATE: st = run_interpolate(r, k, tj); break;
        case SC_TASK_SOLVE: st = run_solve(r, k, tj); break;
        case SC_TASK_DIFFUSE: st = run_steps(r, k, tj); break;
        default: st = run_estimate(r, k, tj); break;
        }
        if (st != PST_OK)
            return st;
    }
    return PST_OK;
}

static int build(run_state *r)
{
    const pst_scene *s = r->s;
    double t0 = omp_get_wtime();
    int st = run_make_cloud(r);
    if (st == PST_OK && s->cloud.source == SC_CLOUD_FILE) /* the file's size and h */
        st = pst_plan_make_for_cloud(&r->plan, s, r->c, &r->where, r->err, r->errlen);
    if (st == PST_OK)
        st = run_make_mobility(r);
    if (st == PST_OK)
        st = run_make_fields(r);
    double t1 = omp_get_wtime();
    report_timer(r->report, "cloud", t1 - t0);
    if (st != PST_OK || !r->plan.need_neighbours)
        return st;
    char msg[PST_ERRLEN];
    cli_progress pg;
    progress_begin(&pg, !r->o->quiet, "neighbours", "rows");
    pst_progress hook = progress_list_hook(&pg);
    double cell = (r->plan.support + r->plan.skin) * pst_cloud_h_max(r->c);
    st = pst_cloud_morton_sort(r->c, cell, msg);
    if (st == PST_OK && r->dist) { /* the ranks build their parts' lists (run_petsc.c) */
        progress_end(&pg);
        return PST_OK;
    }
    if (st == PST_OK && r->plan.moving) /* the Verlet list the particles' moves update */
        st = pst_nlist_build_skin(&r->nl, r->c, r->plan.support, r->plan.skin, msg);
    else if (st == PST_OK)
        st = pst_nlist_build_with(&r->nl, r->c, r->plan.support, &hook, msg);
    progress_end(&pg);
    if (st != PST_OK)
        return run_fail(r, st, "%s: neighbours: %s", s->path, msg);
    r->cnt.neighbour_lists++;
    report_timer(r->report, "neighbours", omp_get_wtime() - t1);
    return PST_OK;
}

int pst_run_scene(const pst_scene *s, const pst_run_opts *o, pst_plan *plan,
                  pst_run_counters *counters, pst_cloud **cloud, char *err, size_t errlen)
{
    run_state r = {.s = s, .o = o, .err = err, .errlen = errlen, .dist = o->ranks > 1,
                   .where = {.ranks = o->ranks, .node_ranks = o->node_ranks,
                             .petsc = o->petsc_options != NULL}};
    err[0] = '\0';
    if (o->report)
        *o->report = NULL;
    if (cloud)
        *cloud = NULL;
    int st = check_ranks(&r);
    if (st == PST_OK)
        st = pst_plan_make(&r.plan, s, pst_plan_particles(s), &r.where, err, errlen);
    if (st == PST_OK && o->plan_only && s->cloud.source == SC_CLOUD_FILE) {
        st = run_make_cloud(&r); /* a file cloud's plan needs its size and its h */
        if (st == PST_OK)
            st = pst_plan_make_for_cloud(&r.plan, s, r.c, &r.where, err, errlen);
        pst_cloud_destroy(r.c);
        r.c = NULL;
    }
    if (st == PST_OK && o->plan_only) {
        if (o->rank == 0) /* over several ranks, one plan (every rank's is the same) */
            pst_plan_print(stdout, &r.plan, s);
        if (plan)
            *plan = r.plan;
        return PST_OK;
    }
    r.report = report_begin(s);
    r.tasks = cJSON_AddArrayToObject(r.report, "tasks");
    double t0 = omp_get_wtime(), cpu0 = cpu_seconds();
    if (st == PST_OK)
        st = build(&r);
    if (st == PST_OK)
        st = run_tasks(&r);
    if (st == PST_OK) {
        report_timer(r.report, "total", omp_get_wtime() - t0);
        report_timer(r.report, "cpu", cpu_seconds() - cpu0);
        report_peak_memory(r.report);
        report_finish(r.report, &r.plan, &r.cnt, r.c);
        if (o->rank == 0) /* over several ranks, rank 0 writes */
            st = report_write_outputs(s, r.c, r.base ? pst_op_status(r.base) : r.status,
                                      r.report, &r.cnt, err, errlen);
    }
    if (st == PST_OK && !o->quiet)
        report_summary(stdout, r.report);
    if (st == PST_OK && r.solve_failed)
        st = PST_ENUMERIC; /* err holds the solver's message */
    if (plan)
        *plan = r.plan;
    if (counters)
        *counters = r.cnt;
    if (o->report && (st == PST_OK || (st == PST_ENUMERIC && r.solve_failed)))
        *o->report = r.report;
    else
        cJSON_Delete(r.report);
    pst_op_destroy(r.base);
    pst_nlist_destroy(r.nl);
    free(r.status);
    if (cloud && (st == PST_OK || (st == PST_ENUMERIC && r.solve_failed)))
        *cloud = r.c;
    else
        pst_cloud_destroy(r.c);
    return st;
}

/* The boundary of the scene's first solve task with boundary groups, written into the cloud
 * before any operator exists, so that the operator, and the analysis that reads the cloud, are
 * those of that task; no such task: the cloud's own. The cloud is the caller's alone. */
static int first_solve_boundary(run_state *r)
{
    for (int k = 0; k < r->s->ntasks; ++k) {
        if (r->s->tasks[k].type != SC_TASK_SOLVE || r->s->tasks[k].ngroups == 0)
            continue;
        size_t n = pst_cloud_size(r->c);
        double *b = calloc(n ? n : 1, sizeof *b);
        int8_t *claim = malloc(n ? n : 1);
        run_boundary bnd = {NULL, {NULL, NULL, NULL}};
        cJSON *counts = cJSON_CreateObject(); /* the analysis reports no group counts */
        int st = b && claim && counts
                     ? run_boundary_make(r, k, b, claim, &bnd, counts)
                     : run_fail(r, PST_ENOMEM, "out of memory for the boundary groups");
        cJSON_Delete(counts);
        if (st == PST_OK) {
            memcpy(pst_cloud_kinds(r->c), bnd.kind, n);
            for (int d = 0; d < r->s->dim; ++d)
                memcpy(pst_cloud_normal(r->c, d), bnd.normal[d], n * sizeof(double));
        }
        run_boundary_free(&bnd);
        free(b);
        free(claim);
        return st;
    }
    return PST_OK;
}

int pst_run_build_operator(const pst_scene *s, int quiet, size_t max_unknowns, pst_cloud **cloud,
                           pst_nlist **nl, pst_op **op, char *err, size_t errlen)
{
    pst_run_opts o = {.quiet = quiet};
    run_state r = {.s = s, .o = &o, .err = err, .errlen = errlen};
    err[0] = '\0';
    *cloud = NULL;
    *nl = NULL;
    *op = NULL;
    int st = pst_plan_make(&r.plan, s, pst_plan_particles(s), NULL, err, errlen);
    r.report = report_begin(s);
    r.plan.need_neighbours = 1;
    r.plan.half_list = 0; /* the caller reads the whole rows (the analysis assembles them) */
    r.plan.base_keep = 0; /* and asks for no derivatives */
    if (st == PST_OK)
        st = build(&r);
    if (st == PST_OK && !r.nl)
        st = run_fail(&r, PST_EINPUT, "%s: no task of the scene uses the operator", s->path);
    if (st == PST_OK)
        st = first_solve_boundary(&r);
    if (st == PST_OK && max_unknowns) {
        size_t n = pst_cloud_size(r.c), m = 0;
        const uint8_t *kind = pst_cloud_kinds_const(r.c);
        for (size_t i = 0; i < n; ++i)
            m += kind[i] != PST_DIRICHLET;
        if (m > max_unknowns)
            st = run_fail(&r, PST_EINPUT,
                          "%s: %zu unknowns (interior and Neumann particles), more "
                          "than %zu: use a coarser cloud.spacing",
                          s->path, m, max_unknowns);
    }
    if (st == PST_OK)
        st = run_make_operator(&r, 1, NULL, &r.base);
    cJSON_Delete(r.report);
    if (st != PST_OK) {
        pst_op_destroy(r.base);
        pst_nlist_destroy(r.nl);
        pst_cloud_destroy(r.c);
        return st;
    }
    *cloud = r.c;
    *nl = r.nl;
    *op = r.base;
    return PST_OK;
}
