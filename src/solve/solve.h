/* Internal interface between the solver (src/solve*.c) and its preconditioners. */
#ifndef PSTENCIL_SOLVE_H
#define PSTENCIL_SOLVE_H

#include "operator.h"

/* A right preconditioner: z = M^-1 r (r and z of the operator's length, never aliased). */
typedef struct {
    void (*apply)(void *ctx, const double *r, double *z);
    void (*destroy)(void *ctx);
    void *ctx;
} pst_prec;

/* hypre BoomerAMG on an assembled low-order operator (src/precond_amg.c): `source` is a
 * pst_amg_source. L has a negative diagonal on interior rows and a positive one on Neumann
 * (flux) and Dirichlet rows, so the AMG matrix is A = S L_low with S = -1 on interior rows and
 * +1 elsewhere (an M-matrix with a positive diagonal for Brookshaw), and apply computes
 * z = A^-1 (S r). Dirichlet rows are eliminated inside (they give z = r). */
int pst_prec_amg(pst_prec *p, const pst_op *op, int source, char *err);

/* ---- The Krylov methods (src/solve_cg.c, solve_gmres.c, solve_bicgstab.c) ----------------- *
 * pst_solve (src/solve.c) eliminates the Dirichlet values and hands the methods the system
 * L x = b' with full-length vectors: b' and every Krylov vector are 0 on Dirichlet rows, and L
 * keeps its identity Dirichlet rows, so L x = b' is equivalent to the original L u = b with
 * u = x + u_D, and ||b' - L x|| = ||b - L u|| row by row. The methods stop on that true
 * residual: ||b' - L x|| <= target = rtol ||b||. */
typedef struct {
    const pst_op *op;
    int stored;            /* apply the stored weights                                    */
    size_t n;
    const uint8_t *kind;   /* the cloud's kinds                                           */
    const pst_prec *prec;  /* right preconditioner approximating L^-1, or NULL (identity) */
    const double *b;       /* b' (0 on Dirichlet rows)                                    */
    double *x;             /* the iterate: initial guess in, last finite iterate out      */
    double bnorm;          /* ||b|| of the caller's b (the residuals' reference)          */
    double target;         /* rtol * bnorm                                                */
    int max_iter, restart;
    /* results */
    int iterations, converged;
    double rel_residual;   /* true residual of x at return                                */
    double *history;       /* max_iter + 1 entries or NULL                                */
    int nhistory;
    void (*monitor)(int iteration, double rel_residual, void *ctx); /* or NULL             */
    void *monitor_ctx;
    char *message;         /* PST_ERRLEN bytes                                            */
    /* scratch of the deterministic reductions: nblocks * (restart + 2) partial sums       */
    size_t nblocks;
    double *part;
} pst_ksp;

/* The methods: PST_OK when converged, PST_ENUMERIC (message says why) when not, PST_ENOMEM.
 * cg_scale is S of the symmetric system S L x = S b' (S = -V/s on non-Dirichlet rows, 1 on
 * Dirichlet rows): CG runs on it, and its preconditioner is z = prec(r / S). */
int pst_ksp_cg(pst_ksp *k, const double *cg_scale);
int pst_ksp_gmres(pst_ksp *k);
int pst_ksp_bicgstab(pst_ksp *k);

/* Deterministic kernels (src/solve.c). Reductions sum fixed blocks of PST_KSP_BLOCK entries
 * serially, then the block sums in block order: the same bits for every thread count. */
#define PST_KSP_BLOCK 2048
double pst_ksp_dot(pst_ksp *k, const double *a, const double *b);
/* out[j] = V[j] . w for j < m, one pass over w (m <= restart + 2). */
void pst_ksp_mdot(pst_ksp *k, int m, double *const *V, const double *w, double *out);
/* sum (a_i / s_i)^2: the norm of the unscaled residual from CG's scaled one. */
double pst_ksp_norm2_div(pst_ksp *k, const double *a, const double *s);
/* y = L x (the chosen apply path). */
void pst_ksp_apply(pst_ksp *k, const double *x, double *y);
/* z = M^-1 r, or z = r without a preconditioner. */
void pst_ksp_prec(pst_ksp *k, const double *r, double *z);
/* r = b' - L x; returns ||r||. */
double pst_ksp_residual(pst_ksp *k, const double *x, double *r);
/* x += a p + c q (q may be NULL) only when every result is finite: returns 1 when done, 0
 * (x untouched) when an entry would be NaN or infinite. */
int pst_ksp_update(pst_ksp *k, double *x, double a, const double *p, double c, const double *q);
/* y = a x + c y, elementwise. */
void pst_ksp_axpby(pst_ksp *k, double a, const double *x, double c, double *y);
/* Append the relative residual of an iteration to the history (when kept) and report it to
 * the monitor (when set). */
void pst_ksp_record(pst_ksp *k, double rnorm);
/* The closing messages; they also set rel_residual and converged. */
void pst_ksp_finish(pst_ksp *k, const char *method, double rnorm);
void pst_ksp_fail(pst_ksp *k, double rnorm, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

#endif
