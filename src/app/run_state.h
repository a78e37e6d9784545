/* What the parts of the scene runner (run*.c) share: the state of one run and the steps that
 * more than one part calls. Private to the runner; run.h is its interface. */
#ifndef PSTENCIL_RUN_STATE_H
#define PSTENCIL_RUN_STATE_H

#include "progress.h"
#include "run.h"

#include "pstencil.h"

#include <cjson/cJSON.h>
#include <stdint.h>

typedef struct {
    const pst_scene *s;
    const pst_run_opts *o;
    pst_plan plan;
    pst_run_counters cnt;
    pst_cloud *c; /* gains fields; its kinds and normals are never written during a run */
    pst_nlist *nl;
    pst_op *base;
    const uint8_t *task_kinds; /* the kinds a task's error region reads; NULL: the cloud's     */
    int task_mean_fixed;       /* 1: the task's solve fixed the mean of u, so its errors are
                                  against the exact solution shifted to the same mean         */
    const double *time; /* the t of a diffuse task's expressions; NULL: expressions have no t */
    cJSON *report, *tasks;
    int solve_failed;
    int dist;        /* more than one rank (pst_run_opts.ranks): every solve on the rank's part */
    pst_plan_where where; /* the ranks and PETSc, as the plan takes them */
    uint8_t *status; /* the row status of a solve's own operator, when there is no base one */
    char *err;
    size_t errlen;
} run_state;

/* The boundary of one solve with boundary groups, in cloud order: the cloud's kinds and
 * normals with the groups' particles changed. The operator of that solve reads it
 * (pst_op_opts.kinds, .normals); the cloud keeps its own. */
typedef struct {
    uint8_t *kind;
    double *normal[3];
} run_boundary;

/* Write the message into r->err and return status. */
int run_fail(run_state *r, int status, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

/* Expression `text` (scene key `key`) at every particle, or at m points pts[d][q], into out;
 * a non-finite value is an error naming the particle or point. */
int run_eval_at_particles(run_state *r, const char *key, const char *text, double *out);
int run_eval_at_points(run_state *r, const char *key, const char *text, double *const pts[3],
                       size_t m, double *out);

/* The cloud, mobility and fields of the scene (run_inputs.c). */
int run_make_cloud(run_state *r);
int run_make_mobility(run_state *r);
int run_make_fields(run_state *r);

/* An operator of the scene's options, with Laplacian rows or not, on the boundary `bnd`
 * (NULL: the cloud's own); counted and reported. */
int run_make_operator(run_state *r, int laplacian, const run_boundary *bnd, pst_op **op);

/* Task k's stored weights on op, in the precision its plan chose (pst_plan.task_stored),
 * in place of weights an earlier task stored in the other precision; counted. */
int run_store_weights(run_state *r, int k, pst_op *op);

/* Task k's norms of approx (ncomp components) against its exact expressions, into tj's
 * "norms"; pts non-NULL: at m points instead of the particles. */
int run_task_norms(run_state *r, int k, cJSON *tj, int ncomp, double *const *approx,
                   double *const pts[3], size_t m);

/* The output fields of task t (one per component) added to the cloud, into out. */
int run_add_outputs(run_state *r, const sc_task *t, int ncomp, double *out[6]);

/* Keep a copy of op's row status for outputs.vtu (r->status). */
int run_keep_status(run_state *r, const pst_op *op);

/* The four kinds of task (run_estimate.c, run_interpolate.c, run_solve.c, run_steps.c). */
int run_estimate(run_state *r, int k, cJSON *tj);
int run_interpolate(run_state *r, int k, cJSON *tj);
int run_solve(run_state *r, int k, cJSON *tj);
int run_steps(run_state *r, int k, cJSON *tj);

/* The solve monitor: the iterations' progress line. */
typedef struct {
    cli_progress *pg;
    double rtol;
} run_monitor_ctx;
void run_solve_monitor(int it, double rel, void *ctx);

/* The end of solve task k, either solver: the result into tj (then freed), counted; a solve
 * that did not converge (st PST_ENUMERIC) is not an error here, its outputs are still written
 * and the run reports it at the end (r->solve_failed); another failure is, with msg. */
int run_solve_finish(run_state *r, int k, cJSON *tj, pst_solve_result *res, int fix_mean,
                     int st, const char *msg);

/* Solve task k in PETSc (run_petsc.c): b into u over the whole cloud, on the task's boundary
 * (kind, normal), with the mean of u fixed when fix_mean; op is the task's operator on one
 * process, NULL over several ranks (each builds its part's). */
int run_solve_petsc(run_state *r, int k, cJSON *tj, pst_op *op, const uint8_t *kind,
                    double *const normal[3], const double *b, double *u, int fix_mean);

/* The boundary of solve task k (which has groups) into bnd, and its group values into b
 * (fluxes divided by a constant mobility's factor); claim[i] becomes the kind its group gave
 * particle i, -1 for none; tj gains "boundary_groups", each group's count and where its
 * normals came from. Free with run_boundary_free, also after a failure. */
int run_boundary_make(run_state *r, int k, double *b, int8_t *claim, run_boundary *bnd,
                      cJSON *tj);
void run_boundary_free(run_boundary *bnd);

#endif
