/* What the parts of a diffuse task (run_steps*.c, docs/time-stepping.md) share: the step
 * limit, the implicit system, the moving particles and the output files. Private to the
 * runner. */
#ifndef PSTENCIL_RUN_STEPS_H
#define PSTENCIL_RUN_STEPS_H

#include "run_state.h"

/* Files a time series may hold: a cap on what a scene's output_every can ask for. */
enum { STEPS_MAX_SNAPSHOTS = 10000 };

/* One row of the per-step table (tasks[].steps_csv). */
typedef struct {
    double t, dt;
    double list_s, refresh_s;  /* the neighbour update and the operator's refresh (moving)   */
    double apply_s;            /* the explicit part's L u                                    */
    double setup_s, solve_s;   /* the solver handle's set-up and the solve (implicit)         */
    double residual, rho, max_abs;
    int rebuilt;               /* 1: the update built the Verlet list again                  */
    int iterations;
} steps_row;

/* y = L u by the stored weights or matrix-free. */
int steps_apply(const pst_op *op, int stored, const double *u, double *y);

/* rho, the Gershgorin bound of the spectral radius of L on the rows that evolve (interior
 * rows, columns of interior particles; times the mobility factor m): the forward-Euler limit
 * is dt <= 2 / rho. */
int steps_rho(run_state *r, const pst_op *op, double m, double *rho);

/* The implicit system A = I - c L (c = theta dt m) on the interior rows, A = I on the held
 * Dirichlet rows, as the pst_linop of a reusable solver. */
typedef struct {
    const pst_op *op;
    int stored;
    const uint8_t *kind;       /* the cloud's, n of them                                     */
    size_t n;
    double c;
} steps_system;

/* A solver handle for sys with task k's options (the plan's method and preconditioner). */
int steps_solver_create(run_state *r, int k, steps_system *sys, pst_krylov **out);

/* Particles moved by dt v (v[d] at the particles): the interior ones step, the cloud folds
 * them into its periodic box, the list is updated and the mobility re-sampled, then op is
 * refreshed; the row gets the seconds and whether the list was rebuilt. */
int steps_move(run_state *r, pst_op *op, double dt, double *const v[3], steps_row *row);

/* The time series of tasks[].pvd: one VTU per output step, STEM_STEP.vtu beside the .pvd,
 * which is written again after each so that it always lists whole files. */
typedef struct {
    char *stem;                /* the .pvd path without its extension                       */
    pst_pvd_dataset *d;
    char **names;              /* each dataset's VTU name, relative to the .pvd's folder    */
    size_t n, cap;
} steps_series;

/* Room for `count` outputs of task k's series (nothing when the task has no pvd). */
int steps_series_open(run_state *r, int k, size_t count, steps_series *sr);
/* The cloud at `step`, time t, with op's row status, then the .pvd. */
int steps_series_add(run_state *r, int k, steps_series *sr, int step, double t,
                     const pst_op *op);
void steps_series_free(steps_series *sr);

/* tasks[].steps_csv: rows[0..n) as one row per step. */
int steps_write_table(run_state *r, int k, const steps_row *rows, size_t n);

#endif
