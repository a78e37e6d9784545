/* Internal interface of the solve layer: the preconditioners, the Krylov methods and the
 * kernels they share. Every method is written against pst_linop (include/pstencil/solve.h):
 * an operator and a preconditioner are each an apply and a context. */
#ifndef PSTENCIL_SOLVE_H
#define PSTENCIL_SOLVE_H

#include "check.h"
#include "operator.h"

#include <math.h>

/* A preconditioner the solver owns: its linop (z = M^-1 r, r and z of n values, never
 * aliased) and the function that frees the linop's context. */
typedef struct {
    pst_linop lin;
    void (*destroy)(void *ctx);
} pst_prec;

/* Jacobi (src/solve/precond_jacobi.c): z = r / diag(A) from A->diagonal; a zero or non-finite
 * diagonal (an isolated row) gets 1. PST_EINVAL when A has no diagonal, PST_ENUMERIC when its
 * callback fails, PST_ENOMEM. */
int pst_prec_jacobi(pst_prec *p, const pst_linop *A, char *err);

/* hypre BoomerAMG on an assembled low-order operator (src/solve/precond_amg.c), with the AMG
 * options of o (amg_*). L has a negative diagonal on interior rows and a positive one on Neumann
 * (flux) and Dirichlet rows, so the AMG matrix is A = S L_low with S = -1 on interior rows and
 * +1 elsewhere (an M-matrix with a positive diagonal for Brookshaw), and apply computes
 * z = A^-1 (S r). Dirichlet rows are eliminated inside (they give z = r). The caller must have
 * initialised MPI: PST_EINVAL saying so when it has not (or has finalised it). */
int pst_prec_amg(pst_prec *p, const pst_op *op, const pst_solve_opts *o, char *err);

/* The assembled low-order operator AMG is built on (also PETSc's preconditioner matrix,
 * src/dist/petsc_ksp.c): the operator itself (own), or the Brookshaw proxy with the operator's
 * kernel, mobility and boundary rows on its list cut to amg_radius h (< 0: the scheme's
 * measured radius, or the whole list where the mobility varies more than tenfold; the whole
 * list when the radius reaches the list's support: a Brookshaw operator is then its own
 * proxy). *full_rows: the rows the cut kept whole. PST_EINVAL (own on a half list), PST_ENOMEM
 * or the proxy's failure, with the reason in err. */
int pst_amg_low_order(const pst_op *op, double amg_radius, int own, pst_csr *a,
                      size_t *full_rows, char *err);
/* The AMG fields of st (amg_*) from an AMG preconditioner p. */
void pst_prec_amg_stats(const pst_prec *p, pst_krylov_stats *st);
/* PST_OK when hypre may run now: MPI initialised and not finalised, and, from a thread other
 * than MPI's main thread, at least MPI_THREAD_SERIALIZED; else PST_EINVAL saying what to do.
 * Checked by every AMG set-up and by every solve of a handle that holds an AMG hierarchy. */
int pst_prec_amg_ready(char *err);

/* Free a preconditioner's context (nothing when it has none). */
void pst_prec_free(pst_prec *p);

/* ---- The Krylov methods (src/solve/solve_cg.c, solve_gmres.c, solve_bicgstab.c) ----------- *
 * A handle of an engine operator (src/solve/krylov_solve.c) eliminates the Dirichlet values and
 * hands the methods the system L x = b' with full-length vectors: b' and every Krylov vector
 * are 0 on Dirichlet rows, and L keeps its identity Dirichlet rows, so L x = b' is equivalent
 * to the original L u = b with u = x + u_D, and ||b' - L x|| = ||b - L u|| row by row. A user
 * linop's system is solved as it is (b' = b). The methods stop on that true residual:
 * ||b' - A x|| <= target = rtol ||b||. They allocate nothing: their vectors come from the
 * workspace pst_ksp_alloc made for the method at set-up. */
typedef struct {
    const pst_linop *A;    /* the operator                                                */
    const pst_linop *M;    /* right preconditioner approximating A^-1, or NULL (identity) */
    size_t n;
    int max_iter, restart;
    /* the workspace (pst_ksp_alloc): nvec vectors of n, GMRES's Hessenberg matrix and small
     * arrays, and the partial sums of the deterministic reductions (nblocks * (restart + 2)) */
    double **vec;
    int nvec;
    double *H, *small;
    size_t nblocks;
    double *part;
    void (*monitor)(int iteration, double rel_residual, void *ctx); /* or NULL             */
    void *monitor_ctx;
    /* one solve */
    const double *b;       /* b' (0 on Dirichlet rows)                                    */
    double *x;             /* the iterate: initial guess in, last finite iterate out      */
    double bnorm;          /* ||b|| of the caller's b (the residuals' reference)          */
    double target;         /* rtol * bnorm                                                */
    /* results */
    int iterations, converged, stop; /* stop: a pst_stop_reason                           */
    int reorthogonalised;  /* GMRES: Arnoldi steps that needed a second Gram-Schmidt pass */
    double rel_residual;   /* true residual of x at return                                */
    double *history;       /* max_iter + 1 entries or NULL                                */
    int nhistory;
    char *message;         /* PST_ERRLEN bytes                                            */
} pst_ksp;

/* Why a method's pass or cycle stopped early: the message, its pst_stop_reason and the value
 * the message shows (what NULL: it did not stop early). */
typedef struct {
    const char *what;
    int stop;
    double value;
} pst_ksp_break;

/* Record a breakdown of the recurrence (message `breakdown`), or an overflow when the
 * quantities behind it are not finite (message `nonfinite`). Returns 1. */
int pst_ksp_broke(pst_ksp_break *b, int finite, double value, const char *breakdown,
                  const char *nonfinite);

/* The workspace of `solver` (a pst_solver, not AUTO) for k->n rows and k->restart; PST_ENOMEM
 * with a message. pst_ksp_free releases it (also after a failed alloc). */
int pst_ksp_alloc(pst_ksp *k, int solver, char *err);
void pst_ksp_free(pst_ksp *k);

/* The methods: PST_OK when converged, PST_ENUMERIC when not (k->stop says why, the message
 * gives the numbers). cg_scale is S of the symmetric system S L x = S b' (S = -V/s on
 * non-Dirichlet rows, 1 on Dirichlet rows) for an engine operator: CG runs on it, and its
 * preconditioner is z = prec(r / S). NULL for a user operator: CG runs on A itself. */
int pst_ksp_cg(pst_ksp *k, const double *cg_scale);
int pst_ksp_gmres(pst_ksp *k);
int pst_ksp_bicgstab(pst_ksp *k);

/* Deterministic kernels (src/solve/ksp_kernels.c). Reductions sum fixed blocks of
 * PST_KSP_BLOCK entries (each with 8 interleaved partial sums added in a fixed order), then the
 * block sums in block order: the same bits for every thread count. */
#define PST_KSP_BLOCK 2048
/* The solver's loops over vectors of at most one block run on the calling thread alone: the
 * team's fork and join (microseconds; tens of them where idle threads sleep) cost more than a
 * pass over 2048 doubles. Their results do not depend on it: element-wise updates, and block
 * sums in block order. */
#define PST_KSP_THREADED(n) ((n) > PST_KSP_BLOCK)
double pst_ksp_dot(pst_ksp *k, const double *a, const double *b);
/* out[j] = V[j] . w for j < m, one pass over w (m <= restart + 2). */
void pst_ksp_mdot(pst_ksp *k, int m, double *const *V, const double *w, double *out);
/* w -= sum_{j<m} h_j V[j] (subtracted in the order j = 0, 1, ...); returns ||w||^2 of the
 * result, summed in the same pass. */
double pst_ksp_subtract_norm2(pst_ksp *k, int m, double *const *V, const double *h, double *w);
/* z = y + a x (z may be y); returns ||z||^2, summed in the same pass. */
double pst_ksp_axpy_norm2(pst_ksp *k, double a, const double *x, const double *y, double *z);
/* CG's step: r -= a q with *norm2 = ||r||^2 (||r / sc||^2 when sc is not NULL) in one pass
 * that also checks x + a p; then x += a p when every entry is finite (returns 1), else x is
 * untouched (returns 0; r and *norm2 are updated all the same). */
int pst_ksp_update_residual(pst_ksp *k, double *x, double a, const double *p, double *r,
                            const double *q, const double *sc, double *norm2);
/* y = A x. */
void pst_ksp_apply(pst_ksp *k, const double *x, double *y);
/* z = M^-1 r, or z = r without a preconditioner. */
void pst_ksp_prec(pst_ksp *k, const double *r, double *z);
/* r = b' - A x; returns ||r||. */
double pst_ksp_residual(pst_ksp *k, const double *x, double *r);
/* x += a p + c q (q may be NULL) only when every result is finite: returns 1 when done, 0
 * (x untouched) when an entry would be NaN or infinite. */
int pst_ksp_update(pst_ksp *k, double *x, double a, const double *p, double c, const double *q);
/* y = a x + c y, elementwise. */
void pst_ksp_axpby(pst_ksp *k, double a, const double *x, double c, double *y);
/* Append the relative residual of an iteration to the history (when kept) and report it to
 * the monitor (when set). */
void pst_ksp_record(pst_ksp *k, double rnorm);
/* The closing messages; they also set rel_residual, converged and stop. finish: converged or
 * the iteration limit; fail: the method stopped early for `stop` (a pst_stop_reason). */
void pst_ksp_finish(pst_ksp *k, const char *method, double rnorm);
void pst_ksp_fail(pst_ksp *k, int stop, double rnorm, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

/* ---- The reusable solver (src/solve/krylov_create.c, krylov_solve.c) ---------------------- */

struct pst_krylov {
    pst_solve_opts o;      /* the options, copied at creation                                 */
    int solver;            /* the method chosen (never AUTO)                                  */
    pst_linop A;           /* the operator (an engine operator's view or the user's copy)     */
    const pst_op *op;      /* the engine operator, or NULL for a user linop                   */
    pst_linop user_M;      /* the caller's preconditioner (user_precond)                      */
    int user_precond;
    pst_prec prec;         /* the preconditioner the handle owns (Jacobi, AMG)                */
    double *S;             /* CG's symmetric scaling of an engine operator, or NULL           */
    double *bp, *x;        /* an engine operator's b' and iterate (n each), or NULL           */
    pst_ksp k;             /* the method's workspace; k.A = &A, k.M = &prec.lin, &user_M or NULL */
    int precond_setups, solves, refreshes, amg_reuses;
    /* the AMG reuse rule (pst_krylov_refresh): refreshes the hierarchy has served, the
     * iterations of the first solve after its set-up (0: none yet) and of the last solve */
    int amg_age, amg_first_iters, last_iters;
    int unusable;          /* a refresh failed: every solve refuses the handle                */
    /* o.fix_mean: A is L + c 1 V^T around the engine operator's view L (fix_mean.c) */
    pst_linop L;
    const double *V;
    double c, vsum;
};

/* o.fix_mean (src/solve/fix_mean.c): wrap s->A (the engine operator's view) into
 * L + c 1 V^T, c = -(mean |diag L|) / sum V, before the preconditioner is set up; after a
 * solve, shift u to sum V u = 0 and return lambda = c V^T u (the constant taken off b). */
int pst_fix_mean_wrap(pst_krylov *s, char *err);
/* c again from the refreshed operator's diagonal (pst_krylov_refresh). */
int pst_fix_mean_update(pst_krylov *s, char *err);
double pst_fix_mean_finish(pst_krylov *s, double *u);
/* That c from sum |diag L| over n rows and sum V > 0 (1 in place of a mean |diag L| that is 0
 * or not finite); PETSc's solves (src/dist/petsc_ksp.c) take the same. */
static inline double pst_fix_mean_c(double abs_diag_sum, size_t n, double vsum)
{
    return -(abs_diag_sum > 0 && isfinite(abs_diag_sum) ? abs_diag_sum / (double)n : 1.0) /
           vsum;
}

/* The checks of a request that come before the set-up: the options (also the engine
 * operator's stored path) and, when b is not NULL, b and u finite (u only where it is an
 * unknown: off the Dirichlet rows of op, everywhere for op NULL, n values). */
int pst_solve_check_opts(const pst_solve_opts *o, const pst_op *op, char *err);
int pst_solve_check_finite(const pst_op *op, size_t n, const double *b, const double *u,
                           char *err);

/* pst_krylov_create with what pst_solve reports on a failed set-up: the solver chosen (or the
 * one asked for when the failure came first) and the stop reason (PST_STOP_PRECOND_SETUP when
 * the preconditioner failed, else PST_STOP_NONE). */
int pst_krylov_build(pst_krylov **out, const pst_op *op, const pst_solve_opts *o, int *solver,
                     int *stop, char *err);

/* A request refused before iterating: err into r->message and err_out (NULL allowed), the
 * time since t0 into r->seconds. Returns st. */
int pst_solve_refused(pst_solve_result *r, int st, const char *err, char *err_out, double t0);

/* The name of a pst_solver ("CG", "GMRES", "BiCGSTAB"), for messages. */
const char *pst_solver_label(int solver);

#endif
