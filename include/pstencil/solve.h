/* pstencil: Solving L u = b. Part of the public API; include <pstencil.h>. */
#ifndef PSTENCIL_PUBLIC_SOLVE_H
#define PSTENCIL_PUBLIC_SOLVE_H

#include "pstencil/operator.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------------------------------------------ */
/* Solving                                                                                    */
/* ------------------------------------------------------------------------------------------ */

/* Solve L u = b for an operator L (docs/solving.md). Row by row the right-hand side b means:
 *   interior particles:  (L u)_I = b_I          (div(M grad u) = g, so b = g)
 *   Neumann particles:   flux row (LV eq. 100) = b_I   (n . M grad u = g_N)
 *   Dirichlet particles: u_I = b_I               (the value; moved to the right-hand side)
 * u holds the initial guess on entry (Dirichlet entries are ignored) and the solution on
 * return, also on failure (the last iterate, never NaN). */
typedef enum {
    PST_SOLVER_AUTO = 0,   /* CG when the operator is symmetrisable (brookshaw, cb with G1
                              and without Neumann rows), else GMRES                          */
    PST_SOLVER_CG = 1,     /* on diag(V/s) K, the symmetric scaling of spec lukyanov_vuik §4.5 */
    PST_SOLVER_GMRES = 2,  /* restarted GMRES(m), right preconditioning, CGS2 orthogonalisation */
    PST_SOLVER_BICGSTAB = 3
} pst_solver;

typedef enum {
    PST_PREC_NONE = 0,
    PST_PREC_JACOBI = 1,   /* 1 / diag(L) (pst_op_diagonal)                                   */
    PST_PREC_AMG = 2       /* hypre BoomerAMG on an assembled low-order M-matrix              */
} pst_precond;

typedef enum {
    PST_AMG_BROOKSHAW = 0, /* the Brookshaw operator on the same cloud (an M-matrix)          */
    PST_AMG_OWN = 1        /* the scheme's own assembled stencil                             */
} pst_amg_source;

typedef struct {
    int solver;            /* pst_solver (default AUTO)                                       */
    int precond;           /* pst_precond (default JACOBI)                                    */
    int amg_source;        /* pst_amg_source (default BROOKSHAW)                              */
    int restart;           /* GMRES restart length m (default 50)                             */
    int max_iter;          /* iteration limit (default 5000)                                  */
    double rtol;           /* stop when ||b - L u|| <= rtol ||b|| (2-norms, default 1e-10)      */
    int stored;            /* 1: apply the stored weights (pst_op_store), 0: matrix-free      */
    int history;           /* 1: keep the relative residual of every iteration                */
    /* Called after every iteration with the iteration count and the estimated relative
     * residual, from the calling thread outside any parallel region (progress bars); NULL
     * (the default) for none. */
    void (*monitor)(int iteration, double rel_residual, void *ctx);
    void *monitor_ctx;
} pst_solve_opts;

void pst_solve_defaults(pst_solve_opts *o);

typedef struct {
    int converged;         /* 1 when the tolerance was reached                                */
    int solver;            /* the pst_solver actually used                                    */
    int iterations;
    double rel_residual;   /* true residual ||b - L u|| / ||b|| at return                      */
    double *history;       /* relative residual per iteration (when asked); free with
                              pst_solve_result_free                                          */
    int nhistory;
    double seconds;
    char message[PST_ERRLEN]; /* why it stopped: converged, iteration limit, breakdown, ...   */
} pst_solve_result;
void pst_solve_result_free(pst_solve_result *r);

/* Returns PST_OK when converged, PST_ENUMERIC (with the reached residual in r->message) when
 * not converged or broken down, PST_EINVAL for a bad request (e.g. CG on a non-symmetrisable
 * operator, AMG without hypre), PST_ENOMEM. Results are identical for every thread count. */
int pst_solve(const pst_op *op, const double *b, double *u, const pst_solve_opts *o,
              pst_solve_result *r, char *err);

#ifdef __cplusplus
}
#endif

#endif /* PSTENCIL_PUBLIC_SOLVE_H */
