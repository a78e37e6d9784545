/* The solves that run in PETSc (docs/distributed.md): on one process the task's operator
 * itself goes into PETSc's KSP; over several ranks each rank builds the neighbour list and the
 * operator of its own part of the cloud (its Morton range and the ghosts within reach), PETSc
 * solves the distributed system, and the owned values of every rank are gathered into u on
 * every rank, so that norms and outputs read the whole answer as on one process. */
#include "run_state.h"

#include "progress.h"
#include "report.h"

#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The task's options then the command line's (which override them), into buf. */
static int petsc_options(run_state *r, const sc_task *t, char *buf, size_t len)
{
    int w = snprintf(buf, len, "%s %s", t->petsc ? t->petsc : "",
                     r->o->petsc_options ? r->o->petsc_options : "");
    if (w < 0 || (size_t)w >= len)
        return run_fail(r, PST_EINPUT, "%s: task '%s': the PETSc options are longer than %zu "
                        "characters", r->s->path, t->name, len - 1);
    return PST_OK;
}

/* Rank r's part of the cloud on the task's boundary (kind and normal over the whole cloud),
 * with the rings of ghosts the scheme's rows read, its neighbour list and its operator. */
static int part_operator(run_state *r, const uint8_t *kind, double *const normal[3],
                         pst_part **p, pst_nlist **nl, pst_op **op, char *msg)
{
    const double *nrm[3] = {normal[0], normal[1], normal[2]};
    int st = pst_part_create(p, r->c, kind, nrm, r->o->ranks, r->o->rank, r->plan.support,
                             pst_scheme_halo(r->s->op.scheme), msg);
    if (st == PST_OK)
        st = pst_nlist_build(nl, pst_part_cloud(*p), r->plan.support, msg);
    pst_op_opts oo;
    pst_scene_op_opts(r->s, &oo);
    oo.laplacian = 1;
    if (st == PST_OK)
        st = pst_op_create(op, pst_part_cloud(*p), *nl, &oo, msg);
    if (st == PST_OK) {
        r->cnt.neighbour_lists++;
        r->cnt.laplacian_precomputes++;
        report_operator(r->report, *op);
    }
    return st;
}

/* The distributed solve of b into u (whole-cloud arrays on every rank); pj gains this rank's
 * owned and ghost counts and the seconds of its part, list and operator. */
static int solve_ranks(run_state *r, const uint8_t *kind, double *const normal[3],
                       const double *b, double *u, const pst_petsc_opts *po,
                       pst_solve_result *res, cJSON *pj, char *msg)
{
    pst_part *p = NULL;
    pst_nlist *nl = NULL;
    pst_op *op = NULL;
    double *bl = NULL, *ul = NULL, t0 = omp_get_wtime();
    int st = part_operator(r, kind, normal, &p, &nl, &op, msg);
    if (st == PST_OK) {
        pst_part_info pi;
        pst_part_layout(p, &pi);
        cJSON_AddNumberToObject(pj, "rank0_owned", (double)(pi.hi - pi.lo));
        cJSON_AddNumberToObject(pj, "rank0_ghosts", (double)pi.nghost);
        cJSON_AddNumberToObject(pj, "rank0_part_seconds", omp_get_wtime() - t0);
    }
    size_t m = st == PST_OK ? pst_cloud_size(pst_part_cloud(p)) : 0;
    if (st == PST_OK) {
        bl = malloc((m ? m : 1) * sizeof *bl);
        ul = malloc((m ? m : 1) * sizeof *ul);
        if (!bl || !ul) {
            st = PST_ENOMEM;
            snprintf(msg, PST_ERRLEN, "out of memory for the part's vectors");
        }
    }
    if (st == PST_OK) {
        pst_part_take(p, b, bl);
        pst_part_take(p, u, ul);
        st = pst_petsc_solve(op, p, bl, ul, po, res, msg);
    }
    if (st == PST_OK || st == PST_ENUMERIC) {
        char why[PST_ERRLEN];
        int gs = pst_part_gather(p, ul, u, why); /* also the last iterate of a failed solve */
        if (gs != PST_OK) {
            st = gs;
            snprintf(msg, PST_ERRLEN, "%s", why);
        }
    }
    free(bl);
    free(ul);
    pst_op_destroy(op);
    pst_nlist_destroy(nl);
    pst_part_destroy(p);
    return st;
}

int run_solve_petsc(run_state *r, int k, cJSON *tj, pst_op *op, const uint8_t *kind,
                    double *const normal[3], const double *b, double *u, int fix_mean)
{
    const sc_task *t = &r->s->tasks[k];
    char opts[1024], msg[PST_ERRLEN];
    int st = petsc_options(r, t, opts, sizeof opts);
    if (st != PST_OK)
        return st;
    if (!r->o->start_petsc || r->o->start_petsc(msg) != 0)
        return run_fail(r, PST_EINPUT, "%s: task '%s' runs in PETSc: %s", r->s->path, t->name,
                        r->o->start_petsc ? msg : "this program does not start PETSc");
    pst_petsc_opts po;
    pst_petsc_defaults(&po);
    po.options = opts;
    po.rtol = t->rtol;
    po.max_iter = t->max_iter;
    po.restart = r->plan.task_restart[k];
    po.amg_source = r->plan.task_amg_source[k];
    po.amg_radius = r->plan.task_amg_radius[k];
    po.history = 1;
    po.fix_mean = fix_mean;
    cli_progress pg;
    run_monitor_ctx mc = {&pg, t->rtol};
    po.monitor = run_solve_monitor;
    po.monitor_ctx = &mc;
    char label[PST_MAX_NAME + 8];
    snprintf(label, sizeof label, "task %s", t->name);
    pst_solve_result res;
    cJSON *pj = cJSON_AddObjectToObject(tj, "petsc");
    cJSON_AddNumberToObject(pj, "ranks", r->dist ? r->o->ranks : 1);
    cJSON_AddStringToObject(pj, "options", opts);
    progress_begin(&pg, !r->o->quiet, label, NULL);
    st = r->dist ? solve_ranks(r, kind, normal, b, u, &po, &res, pj, msg)
                 : pst_petsc_solve(op, NULL, b, u, &po, &res, msg);
    progress_end(&pg);
    return run_solve_finish(r, k, tj, &res, fix_mean, st, msg);
}
