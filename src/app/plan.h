/* The planner: from a scene's tasks and outputs, what must be computed and nothing more
 * (docs/running.md), with a memory estimate checked before anything big is
 * allocated. The runner (run.c) follows the plan and counts what it actually computed. */
#ifndef PSTENCIL_PLAN_H
#define PSTENCIL_PLAN_H

#include "scene.h"

#include <stdio.h>

/* What a run computed: the runner increments these as it goes; a test compares them with
 * what the scene asked for. */
typedef struct {
    long mobility_arrays;     /* per-particle mobility arrays filled                          */
    long fields;              /* field expressions evaluated onto the cloud                   */
    long neighbour_lists;
    long laplacian_precomputes; /* operators whose Laplacian rows were precomputed            */
    long derivative_operators;  /* operators built for derivatives only (no Laplacian rows)   */
    long stored_weights;      /* pst_op_store calls                                           */
    long half_lists;          /* operators switched to a half list (pst_op_use_half_list)     */
    long applies;             /* L u outside solves                                           */
    long gradients, hessians, interpolations, solves;
    long steps;               /* time steps of diffuse tasks                                  */
    long refreshes;           /* operators refreshed after the particles moved (pst_op_refresh) */
    long norms;
    long files;               /* output files written                                         */
} pst_run_counters;

typedef struct {
    size_t particles;         /* exact for a file or a generated cloud                        */
    double h_ratio;           /* h / s0 of the estimates: the scene's, or a file cloud's mean */
                              /* h_i / V_i^(1/D) (pst_plan_make_for_cloud); 0 before the file */
    double neighbours;        /* estimated neighbours per particle (j != i)                   */
    int kernel;               /* the kernel the operators use                                 */
    double support;           /* kernel support in units of h                                 */
    /* Mobility as the operators see it: 0 = none (also a constant, folded into a factor),
     * 1 = scalar per particle, dim = diagonal tensor per particle. */
    int mobility_ncomp;
    double mobility_factor;   /* L_M u = factor * L u for a constant mobility (else 1)         */
    int need_neighbours;
    /* Operators: the base operator (the cloud's own boundary kinds) serves every task except
     * solves with boundary groups, which get one each. A base operator that only feeds
     * gradients, Hessians and interpolation is built without Laplacian rows. */
    int base_operator;        /* 1 when some task needs it                                     */
    int base_laplacian;       /* 1 when it needs Laplacian rows                                */
    /* PST_KEEP_* bits: the derivative weights the base operator's precompute keeps for the
     * gradient and Hessian tasks (pst_op_opts.keep), when its scheme can and they fit */
    int base_keep;
    /* 1: the one operator switches to a half neighbour list after its precompute
     * (pst_op_use_half_list): matrix-free solves and applies only */
    int half_list;
    /* 1: a diffuse task moves the particles: the list keeps a Verlet skin of `skin` h
     * (pst_nlist_build_skin) for its updates */
    int moving;
    double skin;
    int task_stored[SC_MAX_TASKS];  /* an sc_operator_use but auto: 0 matrix-free, 1 stored,  */
                                    /* 2 stored in float                                    */
    int task_petsc[SC_MAX_TASKS];   /* 1: a solve that runs in PETSc (matrix-free, whole list) */
    int task_solver[SC_MAX_TASKS];  /* pst_solver a solve task will use                        */
    int task_precond[SC_MAX_TASKS]; /* pst_precond a solve task will use                       */
    int task_restart[SC_MAX_TASKS]; /* its GMRES restart (the scene's, shortened to fit)       */
    double task_amg_radius[SC_MAX_TASKS]; /* its amg_radius (the scene's, or 1.3 h to fit)     */
    int task_amg_source[SC_MAX_TASKS];    /* its amg_source (the scene's, or brookshaw to fit)  */
    /* Memory estimate in bytes: the parts, and the total, the larger of the precompute phase
     * (cloud, list, half list, operators) and the solve phase (the half list instead of the
     * whole one where half_list). */
    double bytes_cloud, bytes_neighbours, bytes_half_list, bytes_operators, bytes_weights;
    double bytes_solver, bytes_total, bytes_available;
    const char *memory_limit; /* what bounds bytes_available (pst_memory_avail.limit)         */
    /* Over several ranks (pst_plan_where.ranks > 1) the bytes above are one rank's: the whole
     * cloud (every rank builds it) and its largest part, part_owned + part_ghosts particles
     * (the ghosts estimated), which the list, operator and solver parts count; the budget is
     * this node's share, bytes_available / node_ranks. 1 and 1 on one process. */
    int ranks, node_ranks;
    size_t part_owned, part_ghosts;
} pst_plan;

/* Where a run will go: over how many ranks (1 or 0: one process), how many of them share this
 * node's memory (0: all of them), and whether every solve runs in PETSc (pstencil run
 * --petsc; over several ranks they all do). NULL: one process, PETSc only for the tasks that
 * ask for it (tasks[].petsc). */
typedef struct {
    int ranks, node_ranks;
    int petsc;
} pst_plan_where;

/* Make the plan of scene `s` for a cloud of `particles` particles (pst_plan_particles gives
 * the count of a generated cloud before generating it), run where w says. Errors (PST_EINPUT,
 * with the reason in err) for an expression that does not compile (pst_scene_compile_exprs)
 * and for tasks the scheme cannot do (a Hessian from a scheme without one, CG on a
 * non-symmetrisable operator, a divergence task without mobility, ...); PST_ENOMEM with the
 * estimate when the plan does not fit in limits.memory_fraction of the available memory (of a
 * rank's share of it over several ranks). */
int pst_plan_make(pst_plan *p, const pst_scene *s, size_t particles, const pst_plan_where *w,
                  char *err, size_t errlen);

/* pst_plan_make for a cloud already read from the scene's cloud.file: its size, and h / s0
 * measured on it (the mean of h_i / V_i^(1/D), s0 = V^(1/D) being the spacing of a regular
 * cloud of volumes V) instead of the scene's cloud.h_ratio. */
int pst_plan_make_for_cloud(pst_plan *p, const pst_scene *s, const pst_cloud *c,
                            const pst_plan_where *w, char *err, size_t errlen);

/* The number of particles the scene's generated cloud will have (0 for a file cloud). */
size_t pst_plan_particles(const pst_scene *s);

/* Print the plan as `pstencil run --plan` shows it. */
void pst_plan_print(FILE *f, const pst_plan *p, const pst_scene *s);

#endif
