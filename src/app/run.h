/* The scene runner: follows the plan (plan.h), computes the tasks, writes the outputs (CSV,
 * VTU, JSON report) and counts what it computed. docs/running.md. */
#ifndef PSTENCIL_RUN_H
#define PSTENCIL_RUN_H

#include "plan.h"

typedef struct {
    int quiet;          /* no progress lines and no summary on stdout                      */
    int plan_only;      /* print the plan and stop before allocating anything big; over     */
                        /* several ranks, rank 0 prints one rank's plan                     */
    /* When not NULL, receives the run's JSON report (docs/running.md; cJSON_Delete it), also
     * after a solve that did not converge; NULL after any other failure. */
    struct cJSON **report;
    /* Called before the first AMG set-up of the run (NULL: none). hypre needs MPI and the
     * library never starts it (docs/solving.md, "MPI"), so the program starts it here, only
     * for the runs that need it. Non-zero: the run stops with PST_ENUMERIC. */
    int (*start_mpi)(void);
    /* The ranks of the run and this process's (the program runs under mpirun and started MPI
     * and PETSc): with more than one, every solve runs in PETSc over the ranks, each building
     * the neighbours and the operator of its own part of the cloud (docs/distributed.md), and
     * rank 0 alone writes the outputs. 0 or 1: one process. */
    int ranks, rank;
    /* How many of the ranks share this node's memory (their plans each take a share of it);
     * 0: all of them. */
    int node_ranks;
    /* PETSc options from the command line, read after each solve's own (tasks[].petsc); not
     * NULL: every solve runs in PETSc. */
    const char *petsc_options;
    /* Called before the first PETSc solve (starts MPI, then PETSc); NULL: PETSc solves are
     * refused. Non-zero: the run stops with the library's message. */
    int (*start_petsc)(char *err);
} pst_run_opts;

/* Run scene `s`. On success the counters and the plan are filled (either may be NULL) and,
 * when `cloud` is not NULL, the cloud with every task's output field is handed to the caller
 * (pst_cloud_destroy). Errors: the library's status (PST_EINPUT for bad expressions or data,
 * PST_ENOMEM for a plan that does not fit, PST_ENUMERIC for a solve that did not converge —
 * its outputs are still written, marked as not converged in the report) with the reason in
 * err. */
int pst_run_scene(const pst_scene *s, const pst_run_opts *o, pst_plan *plan,
                  pst_run_counters *counters, pst_cloud **cloud, char *err, size_t errlen);

/* The operator options of scene `s` (its "operator" object over pst_op_defaults). */
void pst_scene_op_opts(const pst_scene *s, pst_op_opts *oo);

/* Build scene `s`'s cloud, neighbour list and base operator (with Laplacian rows), as
 * pst_run_scene would, on the boundary kinds of the scene's first solve task with boundary
 * groups (the operator that task solves with), else on the cloud's own kinds, and hand them
 * to the caller (destroy op, then nl, then cloud). The cloud handed over carries that
 * boundary (its kinds and normals are the task's), so that whatever reads it sees the
 * problem the operator was built for; unlike pst_run_scene's, it is the caller's alone. With max_unknowns > 0, a cloud with more
 * interior + Neumann particles is refused (PST_EINPUT) before the operator is built. Errors
 * as pst_run_scene. */
int pst_run_build_operator(const pst_scene *s, int quiet, size_t max_unknowns, pst_cloud **cloud,
                           pst_nlist **nl, pst_op **op, char *err, size_t errlen);

#endif
