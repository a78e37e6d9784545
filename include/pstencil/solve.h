/* pstencil: Solving L u = b. Part of the public API; include <pstencil.h>. */
#ifndef PSTENCIL_PUBLIC_SOLVE_H
#define PSTENCIL_PUBLIC_SOLVE_H

#include "pstencil/operator.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------------------------------------------ */
/* The operator contract                                                                      */
/* ------------------------------------------------------------------------------------------ */

/* A linear operator as every solver sees it (docs/solving.md, "The operator contract"): n rows
 * and columns, y = A x through `apply` (x and y of n values, never aliased; it must not keep
 * them, and it is called from the calling thread outside any parallel region, so it may use
 * OpenMP itself), and optionally the diagonal of A through `diagonal` (n values; PST_OK or a
 * PST_E* code; NULL when the operator has none). A preconditioner is a pst_linop too: its
 * `apply` computes z = M^-1 r. A deterministic `apply` keeps the solves deterministic. */
typedef struct {
    size_t n;
    void (*apply)(void *ctx, const double *x, double *y);
    int (*diagonal)(void *ctx, double *d);
    void *ctx;
} pst_linop;

/* The solve layer's view of an engine operator: apply is pst_op_apply (stored = 0) or
 * pst_op_apply_stored (stored = 1, after pst_op_store or pst_op_store_with, either precision),
 * diagonal is pst_op_diagonal, ctx is op (which must outlive the linop). PST_EINVAL for a NULL
 * argument, an operator without rows, or stored = 1 before a store. */
int pst_op_linop(const pst_op *op, int stored, pst_linop *out, char *err);

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
                              and without Neumann rows), else GMRES; GMRES for a user linop   */
    PST_SOLVER_CG = 1,     /* on diag(V/s) K, the symmetric scaling of docs/schemes/cb.md;
                              on a user linop as it is, which must then be SPD               */
    PST_SOLVER_GMRES = 2,  /* restarted GMRES(m), right preconditioning, CGS2 orthogonalisation */
    PST_SOLVER_BICGSTAB = 3
} pst_solver;

typedef enum {
    PST_PREC_NONE = 0,
    PST_PREC_JACOBI = 1,   /* 1 / diag(L) (pst_op_diagonal, or the linop's diagonal)          */
    PST_PREC_AMG = 2       /* hypre BoomerAMG on an assembled low-order M-matrix; engine
                              operators only, and MPI must be initialised by the caller      */
} pst_precond;

typedef enum {
    PST_AMG_BROOKSHAW = 0, /* the Brookshaw operator on the same cloud (an M-matrix)          */
    PST_AMG_OWN = 1,       /* the scheme's own assembled stencil                             */
    PST_AMG_AUTO = 2       /* the one the scheme names (pst_scheme_amg_own): own for lsmps,
                              Brookshaw for the others (docs/solving.md, measured)           */
} pst_amg_source;

/* hypre's coarsening (one process: the serial forms of its parallel algorithms). */
typedef enum {
    PST_AMG_HMIS = 0,      /* HMIS (hypre CoarsenType 10)                                    */
    PST_AMG_PMIS = 1,      /* PMIS (CoarsenType 8)                                           */
    PST_AMG_FALGOUT = 2    /* Falgout (CoarsenType 6): classical Ruge-Stueben on one process */
} pst_amg_coarsen;

/* hypre's interpolation. */
typedef enum {
    PST_AMG_EXT_I = 0,     /* extended+i (hypre InterpType 6)                                */
    PST_AMG_CLASSICAL = 1  /* classical modified (InterpType 0)                              */
} pst_amg_interp;

typedef struct {
    pst_solver solver;     /* default AUTO                                                    */
    pst_precond precond;   /* default JACOBI                                                  */
    pst_amg_source amg_source; /* default AUTO                                                */
    /* The AMG matrix's stencil and hypre's coarsening (docs/solving.md, "The AMG matrix's
     * stencil" and "hypre's coarsening and interpolation"; the defaults come from the
     * measured tables there): */
    double amg_radius;     /* the Brookshaw proxy keeps the pairs closer than
                              amg_radius * h (h of the pair, (h_I + h_J) / 2); 0, or at least
                              the kernel's support, keeps the whole list; -1 (the default):
                              the scheme's radius (pst_scheme_amg_radius: 1.3 h for qsfdi,
                              1.6 h for the others), or the whole list where the mobility's
                              max / min over the particles exceeds 10                         */
    int amg_aggressive;    /* levels of aggressive coarsening, 0-10 (default 0)              */
    double amg_strong;     /* strong threshold in (0, 1); 0 = by dimension (0.25 in 2D, 0.5
                              in 3D, the default)                                            */
    pst_amg_coarsen amg_coarsen; /* default HMIS                                              */
    pst_amg_interp amg_interp; /* default EXT_I                                               */
    int amg_pmax;          /* interpolation entries kept per row, 0-100; 0 = no truncation
                              (default 4)                                                    */
    int amg_reuse;         /* pst_krylov_refresh: refreshes an AMG hierarchy serves before it
                              is set up again, 0-1000 (0: at every refresh; default 8); it is
                              set up sooner when a solve needs more than 1.5x the iterations
                              of the first solve after its set-up (docs/solving.md)          */
    int restart;           /* GMRES restart length m (default 50)                             */
    int max_iter;          /* iteration limit (default 5000)                                  */
    double rtol;           /* stop when ||b - L u|| <= rtol ||b|| (2-norms, default 1e-10)      */
    int stored;            /* 1: apply the stored weights (pst_op_store, or pst_op_store_with
                              in either precision), 0: matrix-free                           */
    int history;           /* 1: keep the relative residual of every iteration                */
    int fix_mean;          /* 1: a problem without Dirichlet rows (a periodic box, a pure
                              Neumann problem), whose L has the constants in its nullspace:
                              the u with sum_I V_I u_I = 0 of L u = b - lambda 1, lambda the
                              part of b outside L's range (0 for a compatible b; reported in
                              the result). Solved as (L + c 1 V^T) u = b, which is regular,
                              by GMRES or BiCGSTAB (docs/solving.md, "Singular problems").
                              Engine operators only; refused with Dirichlet rows. Default 0. */
    /* Called after every iteration with the iteration count and the estimated relative
     * residual, from the calling thread outside any parallel region (progress bars); NULL
     * (the default) for none. */
    void (*monitor)(int iteration, double rel_residual, void *ctx);
    void *monitor_ctx;
} pst_solve_opts;

/* The defaults noted beside each field. */
void pst_solve_defaults(pst_solve_opts *o);

/* 1 when this build has the AMG preconditioner (pstencil built with hypre), else 0. */
int pst_have_amg(void);

/* Why a solve stopped (pst_solve_result.stop); the message gives the numbers. */
typedef enum {
    PST_STOP_NONE = 0,            /* refused before iterating: see the status and message    */
    PST_STOP_CONVERGED = 1,       /* ||b - L u|| <= rtol ||b|| (also b = 0)                   */
    PST_STOP_ITERATION_LIMIT = 2, /* max_iter iterations without reaching the tolerance       */
    PST_STOP_BREAKDOWN = 3,       /* a method's recurrence broke down (CG p.Ap <= 0, GMRES
                                     L M^-1 v = 0, BiCGSTAB rho, (r^, v) or omega ~ 0)        */
    PST_STOP_STAGNATION = 4,      /* a GMRES(m) cycle left u unchanged: every later cycle
                                     would repeat it                                          */
    PST_STOP_NON_FINITE = 5,      /* an iterate, residual or Krylov value overflowed: u is the
                                     last finite iterate                                      */
    PST_STOP_PRECOND_SETUP = 6    /* the preconditioner could not be set up (AMG, Jacobi)    */
} pst_stop_reason;

/* A short lower-case name of a pst_stop_reason ("converged", "iteration limit", ...). */
const char *pst_stop_reason_name(int stop);

typedef struct {
    int converged;         /* 1 when the tolerance was reached                                */
    pst_stop_reason stop;  /* why it stopped                                                  */
    pst_solver solver;     /* the solver actually used                                        */
    int iterations;
    double rel_residual;   /* true residual ||b - L u|| / ||b|| at return                      */
    double *history;       /* relative residual per iteration (when asked); free with
                              pst_solve_result_free                                          */
    int nhistory;
    double seconds;
    double setup_seconds;  /* the part of seconds spent setting up (the method's workspace and
                              the preconditioner: the AMG hierarchy); 0 for pst_krylov_solve */
    double mean_shift;     /* fix_mean: lambda, the constant taken off b (0 otherwise); the
                              residuals are those of L u = b - lambda 1                      */
    char message[PST_ERRLEN]; /* why it stopped, in words, with the numbers                  */
} pst_solve_result;
/* Free the history of r and reset it (NULL allowed); the other fields stay readable. */
void pst_solve_result_free(pst_solve_result *r);

/* Returns PST_OK when converged, PST_ENUMERIC (with the reached residual in r->message) when
 * not converged or broken down, PST_EINVAL for a bad request (e.g. CG on a non-symmetrisable
 * operator, AMG without hypre or without MPI initialised), PST_ENOMEM. Results are identical
 * for every thread count. One call is pst_krylov_create + pst_krylov_solve +
 * pst_krylov_destroy, with the same bits. */
int pst_solve(const pst_op *op, const double *b, double *u, const pst_solve_opts *o,
              pst_solve_result *r, char *err);

/* ------------------------------------------------------------------------------------------ */
/* A reusable solver: set up once, solve many times                                           */
/* ------------------------------------------------------------------------------------------ */

/* pst_krylov holds everything a solve needs besides b and u: the chosen method, the
 * preconditioner (the Jacobi diagonal, the AMG hierarchy) and the Krylov workspace. It is
 * built once by a create call; each pst_krylov_solve then only iterates, so time steps and
 * parameter sweeps with a fixed operator pay the set-up once (docs/solving.md, "A reusable
 * solver"). The options are copied at creation and fixed for the handle's life. A handle is
 * used by one thread at a time. */
typedef struct pst_krylov pst_krylov;

/* For an engine operator, as pst_solve does it: Dirichlet elimination, AUTO chooses CG for a
 * symmetrisable operator (with its symmetric scaling) and GMRES otherwise, the preconditioner
 * of o->precond (AMG built from op). op (its rows, weights and kinds) must outlive the handle
 * and not change. o NULL: the defaults. PST_EINVAL for a bad request (see pst_solve, and no
 * Dirichlet particle), PST_ENUMERIC or PST_EINVAL when the preconditioner cannot be set up,
 * PST_ENOMEM. */
int pst_krylov_create(pst_krylov **out, const pst_op *op, const pst_solve_opts *o, char *err);

/* For a user operator A: solves A u = b as it is (no rows are eliminated). M is the user's
 * preconditioner (z = M^-1 r, right preconditioning; M->n == A->n) or NULL: then o->precond
 * chooses NONE or JACOBI (1 / A->diagonal, which must then exist); AMG is refused (it needs an
 * engine operator). AUTO means GMRES; CG assumes A (and M) symmetric positive definite and
 * reports a breakdown when p.Ap <= 0. o->stored and o->amg_source are not used. A, M and
 * their contexts are copied by pointer and must outlive the handle. PST_EINVAL for n = 0, a
 * NULL apply, M->n != A->n or a bad option; PST_ENUMERIC when the diagonal callback fails or
 * PST_ENOMEM. */
int pst_krylov_create_linop(pst_krylov **out, const pst_linop *A, const pst_linop *M,
                            const pst_solve_opts *o, char *err);

/* Bring a handle of an engine operator up to date after pst_op_refresh changed the operator's
 * weights (the particles moved; the same particles and kinds): Jacobi's diagonal, CG's
 * symmetric scaling and fix_mean's constant are computed again from the new weights (one pass
 * over the rows each); an AMG hierarchy is kept while it has served fewer than o.amg_reuse
 * refreshes and the last solve needed at most 1.5x the iterations of the first solve after its
 * set-up, else it is set up again (docs/solving.md, "Refreshing a solver"). The workspace is
 * kept. A stored solve (o.stored) needs the operator stored again (pst_op_refresh does it).
 * A user operator's handle (pst_krylov_create_linop) whose values changed behind the same
 * apply gets its Jacobi diagonal again from A->diagonal (a user M is the caller's to update).
 * PST_EINVAL for an operator without rows, or the failures of a set-up (pst_krylov_create);
 * after a failure every pst_krylov_solve refuses the handle. */
int pst_krylov_refresh(pst_krylov *s, char *err);

/* Solve with a new right-hand side b and initial guess u (solution on return), n values each,
 * not aliased, as pst_solve describes; r (NULL allowed) receives the result, with r->seconds
 * the time of this solve only. Returns PST_OK, PST_ENUMERIC (not converged: r->stop says why),
 * PST_EINPUT (non-finite b or u), PST_EINVAL (NULL arguments; an AMG handle after
 * MPI_Finalize), PST_ENOMEM (the history). Nothing of the set-up is rebuilt. */
int pst_krylov_solve(pst_krylov *s, const double *b, double *u, pst_solve_result *r,
                     char *err);

/* What a handle did: counters a caller (or a test) can check. */
typedef struct {
    size_t n;              /* rows of the operator                                            */
    pst_solver solver;     /* the solver chosen at set-up                                     */
    pst_precond precond;   /* the preconditioner in use (PST_PREC_NONE when M is the user's)  */
    int user_precond;      /* 1 when the preconditioner is the caller's M                     */
    int precond_setups;    /* preconditioner set-ups (AMG hierarchies, Jacobi diagonals) done */
    int solves;            /* pst_krylov_solve calls that iterated (or found b = 0)           */
    int refreshes;         /* pst_krylov_refresh calls                                        */
    int amg_reuses;        /* refreshes that kept the AMG hierarchy                           */
    /* AMG only (0 otherwise): */
    long long amg_entries; /* entries of the matrix handed to hypre                           */
    size_t amg_full_rows;  /* rows of the cut proxy that had no pair within amg_radius and
                              kept their full support (the fallback)                          */
    double amg_setup_seconds; /* the AMG matrix and hypre's set-up, last set-up               */
    int amg_own;           /* 1 when the AMG matrix was the scheme's own, 0 the Brookshaw
                              proxy (AUTO falls back to the proxy where the own matrix has a
                              row without a positive diagonal)                               */
} pst_krylov_stats;
/* The counters of s (all 0 for NULL). */
void pst_krylov_get_stats(const pst_krylov *s, pst_krylov_stats *st);

/* Free a handle and its preconditioner (NULL allowed). An AMG handle is destroyed before
 * MPI_Finalize: after it, hypre's objects cannot be freed and are left allocated. */
void pst_krylov_destroy(pst_krylov *s);

#ifdef __cplusplus
}
#endif

#endif /* PSTENCIL_PUBLIC_SOLVE_H */
