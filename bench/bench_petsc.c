/* pstencil against PETSc on the same linear system, in one process and one run (docs/petsc.md).
 * The manufactured Poisson problem of bench_solve (bench_poisson_cloud, bench_poisson_rhs) is
 * solved by pstencil from the cloud to the answer (Morton sort, neighbour list, operator
 * precompute, stored weights, solver set-up, solve). Its operator is then assembled
 * (pst_op_assemble: Dirichlet rows are identity rows, so with the same b the system has
 * pstencil's solution; by default (--eliminate 1) the Dirichlet columns are moved to the
 * right-hand side too, as pstencil's solver does) and handed to PETSc as a SeqAIJ matrix (not
 * timed), which solves it with KSP: GMRES + BoomerAMG, GMRES + ILU(0), BiCGStab + ILU(0) and
 * GMRES + Jacobi. Every solve starts from u = 0 and stops at the same rtol on the
 * unpreconditioned residual relative to ||b|| (right preconditioning); the true residual
 * ||b - A u|| / ||b|| of every answer is recomputed here. PETSc's time is KSPSetUp (the
 * preconditioner's set-up) + KSPSolve. Then GMRES + Jacobi runs a fixed number of iterations
 * in both, alternating R times (medians), for the cost of one iteration.
 *
 * usage: bench_petsc [--dim 2|3] [--n N] [--scheme S] [--precond amg|jacobi|none]
 *                    [--stored 0|1] [--rtol R] [--restart M] [--jacobi-iters K]
 *                    [--reps R] [--eliminate 0|1] [-- PETSc options]
 *
 * The PETSc options reach PetscInitialize. Each configuration has its own prefix (amg_, gilu_,
 * bilu_, jac_), and one more, x_, runs when -x_pc_type or -x_ksp_type is given (GMRES +
 * Jacobi unless they say otherwise), e.g. `-- -x_pc_type gamg`.
 */
#define _POSIX_C_SOURCE 200809L /* getline */

#include "bench_common.h"
#include "peak.h"
#include "pstencil.h"
#include "support.h"

#include <math.h>
#include <omp.h>
#include <petscksp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAX_REPS 9 /* --reps: alternating runs of the per-iteration comparison */

typedef struct {
    int dim, precond, stored, restart, jacobi_iters, reps, eliminate;
    size_t n;
    const char *scheme;
    double rtol;
} options;

/* One row of the table. */
typedef struct {
    char label[64];
    double setup, solve;   /* seconds */
    int iterations;
    double rel_residual;   /* ||b - A u|| / ||b||, recomputed here */
    double peak_mb;        /* the process's peak resident memory during the run */
    const char *note;      /* why it stopped when it did not converge, else "" */
} result;

/* The system handed to PETSc: CSR in PETSc's index type, Dirichlet rows identity rows. With
 * elimination the Dirichlet columns of the other rows are moved to the right-hand side too
 * (b_I - A_ID b_D), as pstencil's solver does; the solution is the same either way. */
typedef struct {
    PetscInt n, *ia, *ja;
    PetscScalar *va;
    double *b;             /* the right-hand side of this system */
    double bnorm;          /* ||b|| of the problem as posed: every rtol is relative to it */
    double rhs_norm;       /* ||b|| of this system (PETSc's rtol is relative to it)        */
    uint8_t *dirichlet;    /* 1 on Dirichlet rows */
    int eliminated;
} csr_system;

/* ---- options ------------------------------------------------------------------------------- */

static int precond_of(const char *s)
{
    return strcmp(s, "amg") == 0      ? PST_PREC_AMG
           : strcmp(s, "jacobi") == 0 ? PST_PREC_JACOBI
           : strcmp(s, "none") == 0   ? PST_PREC_NONE
                                      : -1;
}

/* Our options up to "--"; *petsc_first is the index of the first PETSc option (argc: none).
 * 0, or -1 after a message. */
static int parse_options(int argc, char **argv, options *o, int *petsc_first)
{
    pst_solve_opts so;
    pst_solve_defaults(&so);
    *o = (options){.dim = 3, .precond = PST_PREC_AMG, .stored = 1, .restart = so.restart,
                   .jacobi_iters = 100, .reps = 3, .eliminate = 1, .n = 130000,
                   .scheme = "qsfdi", .rtol = 1e-8};
    int i = 1;
    for (; i < argc && strcmp(argv[i], "--") != 0; i += 2) {
        const char *k = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!v) {
            fprintf(stderr, "bench_petsc: %s needs a value\n", k);
            return -1;
        }
        if (strcmp(k, "--dim") == 0)
            o->dim = atoi(v);
        else if (strcmp(k, "--n") == 0)
            o->n = (size_t)atof(v);
        else if (strcmp(k, "--scheme") == 0)
            o->scheme = v;
        else if (strcmp(k, "--precond") == 0)
            o->precond = precond_of(v);
        else if (strcmp(k, "--stored") == 0)
            o->stored = atoi(v);
        else if (strcmp(k, "--rtol") == 0)
            o->rtol = atof(v);
        else if (strcmp(k, "--restart") == 0)
            o->restart = atoi(v);
        else if (strcmp(k, "--jacobi-iters") == 0)
            o->jacobi_iters = atoi(v);
        else if (strcmp(k, "--reps") == 0)
            o->reps = atoi(v);
        else if (strcmp(k, "--eliminate") == 0)
            o->eliminate = atoi(v);
        else {
            fprintf(stderr, "bench_petsc: unknown option %s\n", k);
            return -1;
        }
    }
    *petsc_first = i < argc ? i + 1 : argc;
    if ((o->dim != 2 && o->dim != 3) || o->precond < 0 || o->jacobi_iters < 1 || o->reps < 1 ||
        o->reps > MAX_REPS) {
        fprintf(stderr, "bench_petsc: --dim 2|3, --precond amg|jacobi|none, --jacobi-iters >= 1, "
                        "--reps 1..%d\n", MAX_REPS);
        return -1;
    }
    return 0;
}

/* ---- the system ---------------------------------------------------------------------------- */

/* ||b - A x|| / ||b|| of the problem as posed, for x with x_D = b_D (then the eliminated
 * system's residual is the original one's); one pass over the rows, not timed. */
static double true_residual(const csr_system *s, const double *x)
{
    double rr = 0;
    for (PetscInt i = 0; i < s->n; ++i) {
        double r = s->b[i];
        for (PetscInt k = s->ia[i]; k < s->ia[i + 1]; ++k)
            r -= s->va[k] * x[s->ja[k]];
        rr += r * r;
    }
    return sqrt(rr) / s->bnorm;
}

/* Entry k of row i is kept: the diagonal of a Dirichlet row (the zeros the assembly keeps in
 * its neighbour pattern are dropped), a column that is not eliminated otherwise. */
static int kept(const csr_system *s, size_t i, uint32_t col, int eliminate)
{
    return s->dirichlet[i] ? col == i : !(eliminate && s->dirichlet[col]);
}

/* The assembled operator in PETSc's index type, with b (and the eliminated columns moved into
 * it). */
static int export_system(const pst_op *op, const uint8_t *kind, const double *b, int eliminate,
                         csr_system *s)
{
    pst_csr a;
    if (pst_op_assemble(op, &a) != PST_OK)
        return -1;
    size_t n = a.n, nnz = (size_t)a.rowptr[n];
    *s = (csr_system){.n = (PetscInt)n};
    s->ia = malloc((n + 1) * sizeof *s->ia);
    s->ja = malloc(nnz * sizeof *s->ja);
    s->va = malloc(nnz * sizeof *s->va);
    s->b = malloc(n * sizeof *s->b);
    s->dirichlet = malloc(n);
    int ok = s->ia && s->ja && s->va && s->b && s->dirichlet && nnz <= PETSC_MAX_INT;
    for (size_t i = 0; ok && i < n; ++i) {
        s->dirichlet[i] = kind[i] == PST_DIRICHLET;
        s->bnorm += b[i] * b[i];
    }
    s->bnorm = sqrt(s->bnorm);
    PetscInt p = 0;
    for (size_t i = 0; ok && i < n; ++i) {
        s->ia[i] = p;
        s->b[i] = b[i];
        for (int64_t k = a.rowptr[i]; k < a.rowptr[i + 1]; ++k) {
            if (kept(s, i, a.col[k], eliminate)) {
                s->ja[p] = (PetscInt)a.col[k];
                s->va[p++] = a.val[k];
            } else if (!s->dirichlet[i]) {
                s->b[i] -= a.val[k] * b[a.col[k]];
            }
        }
    }
    for (size_t i = 0; ok && i < n; ++i)
        s->rhs_norm += s->b[i] * s->b[i];
    s->rhs_norm = sqrt(s->rhs_norm);
    s->eliminated = eliminate;
    if (ok)
        s->ia[n] = p;
    pst_csr_free(&a);
    return ok ? 0 : -1;
}

static void free_system(csr_system *s)
{
    free(s->ia);
    free(s->ja);
    free(s->va);
    free(s->b);
    free(s->dirichlet);
}

/* ---- pstencil ------------------------------------------------------------------------------ */

static void pst_fail(const char *what, const char *err)
{
    fprintf(stderr, "bench_petsc: %s: %s\n", what, err);
    exit(1);
}

static pst_solve_opts solve_opts(const options *o, int precond, double rtol, int max_iter)
{
    pst_solve_opts so;
    pst_solve_defaults(&so);
    so.precond = precond;
    so.stored = o->stored;
    so.rtol = rtol;
    so.restart = o->restart;
    if (max_iter > 0)
        so.max_iter = max_iter;
    return so;
}

/* pstencil from the unsorted cloud to u: every phase timed, the set-up being everything before
 * the Krylov iterations. *op and *nl stay for the export. */
static void pstencil_run(const options *o, pst_cloud *c, const double *b, double *u,
                         pst_op **op, pst_nlist **nl, result *r, double phase[4])
{
    char err[PST_ERRLEN];
    double support = pst_kernel_support(pst_scheme_default_kernel(o->scheme));
    double t0 = omp_get_wtime();
    pst_cloud_morton_sort(c, support * 1.2 * (1.0 / bench_side(o->n, o->dim)), NULL);
    if (pst_nlist_build(nl, c, support, err) != PST_OK)
        pst_fail("neighbour list", err);
    phase[0] = omp_get_wtime() - t0;
    pst_op_opts oo;
    pst_op_defaults(&oo);
    oo.scheme = o->scheme;
    if (pst_op_create(op, c, *nl, &oo, err) != PST_OK)
        pst_fail("operator", err);
    phase[1] = omp_get_wtime() - t0 - phase[0];
    if (o->stored && pst_op_store(*op) != PST_OK)
        pst_fail("operator", "cannot store the weights");
    phase[2] = omp_get_wtime() - t0 - phase[0] - phase[1];
    pst_solve_opts so = solve_opts(o, o->precond, o->rtol, 0);
    pst_krylov *k = NULL;
    if (pst_krylov_create(&k, *op, &so, err) != PST_OK)
        pst_fail("solver set-up", err);
    double t1 = omp_get_wtime();
    phase[3] = t1 - t0 - phase[0] - phase[1] - phase[2];
    pst_solve_result sr;
    int st = pst_krylov_solve(k, b, u, &sr, err);
    double t2 = omp_get_wtime();
    static const char *const precs[] = {"none", "Jacobi", "AMG"};
    pst_krylov_stats ks;
    pst_krylov_get_stats(k, &ks);
    snprintf(r->label, sizeof r->label, "pstencil %s + %s, %s", ks.solver == PST_SOLVER_CG ? "CG"
             : ks.solver == PST_SOLVER_GMRES ? "GMRES" : "BiCGStab",
             precs[o->precond], o->stored ? "stored" : "matrix-free");
    r->setup = t1 - t0;
    r->solve = t2 - t1;
    r->iterations = sr.iterations;
    r->note = st == PST_OK ? "" : pst_stop_reason_name(sr.stop);
    pst_krylov_destroy(k);
}

/* Seconds per iteration of pstencil's GMRES + Jacobi run for `iters` iterations (a tolerance
 * it cannot reach), the Jacobi set-up excluded. */
static double pstencil_jacobi_iteration(const options *o, const pst_op *op, const double *b,
                                        size_t n)
{
    char err[PST_ERRLEN];
    pst_solve_opts so = solve_opts(o, PST_PREC_JACOBI, 1e-300, o->jacobi_iters);
    so.solver = PST_SOLVER_GMRES;
    pst_krylov *k = NULL;
    if (pst_krylov_create(&k, op, &so, err) != PST_OK)
        pst_fail("Jacobi set-up", err);
    double *u = calloc(n, sizeof *u);
    pst_solve_result sr;
    double t0 = omp_get_wtime();
    pst_krylov_solve(k, b, u, &sr, err);
    double t = omp_get_wtime() - t0;
    free(u);
    pst_krylov_destroy(k);
    return sr.iterations == o->jacobi_iters ? t / sr.iterations : NAN;
}

/* ---- PETSc --------------------------------------------------------------------------------- */

typedef struct {
    const char *label, *prefix;
    KSPType ksp;
    PCType pc;
} petsc_config;

static const petsc_config configs[] = {
    {"PETSc GMRES + BoomerAMG", "amg_", KSPGMRES, PCHYPRE},
    {"PETSc GMRES + ILU(0)", "gilu_", KSPGMRES, PCILU},
    {"PETSc BiCGStab + ILU(0)", "bilu_", KSPBCGS, PCILU},
    {"PETSc GMRES + Jacobi", "jac_", KSPGMRES, PCJACOBI},
    {"PETSc x_ options", "x_", KSPGMRES, PCJACOBI},
};
#define NCONFIGS (int)(sizeof configs / sizeof configs[0])

/* A KSP on A as pstencil solves: right preconditioning, the stopping test on the
 * unpreconditioned residual relative to ||b|| (u0 = 0, so r0 = b), pstencil's restart, PETSc's
 * default orthogonalisation (one classical Gram-Schmidt pass, no refinement: what a PETSc user
 * gets; pstencil's one pass plus a second only on a large norm drop is no more work), then the
 * prefix's options. */
static PetscErrorCode petsc_ksp(Mat A, const petsc_config *c, const options *o, double rtol,
                                int max_iter, KSP *out)
{
    KSP ksp;
    PC pc;
    PetscFunctionBeginUser;
    PetscCall(KSPCreate(PETSC_COMM_SELF, &ksp));
    PetscCall(KSPSetOptionsPrefix(ksp, c->prefix));
    PetscCall(KSPSetOperators(ksp, A, A));
    PetscCall(KSPSetType(ksp, c->ksp));
    PetscCall(KSPGetPC(ksp, &pc));
    PetscCall(PCSetType(pc, c->pc));
    if (strcmp(c->pc, PCHYPRE) == 0)
        PetscCall(PCHYPRESetType(pc, "boomeramg"));
    PetscCall(KSPSetPCSide(ksp, PC_RIGHT));
    PetscCall(KSPSetNormType(ksp, KSP_NORM_UNPRECONDITIONED));
    PetscCall(KSPSetTolerances(ksp, rtol, 1e-300, PETSC_DEFAULT, max_iter));
    PetscCall(KSPGMRESSetRestart(ksp, o->restart));
    PetscCall(KSPSetFromOptions(ksp));
    *out = ksp;
    PetscFunctionReturn(0);
}

/* One configuration on A x = b from x = 0: set-up (KSPSetUp, which sets up the
 * preconditioner) and solve timed; `fixed` > 0 runs exactly that many iterations instead. */
static PetscErrorCode petsc_run(Mat A, const csr_system *s, const petsc_config *c,
                                const options *o, int fixed, result *r)
{
    KSP ksp;
    Vec b, x;
    pst_solve_opts so;
    pst_solve_defaults(&so);
    PetscFunctionBeginUser;
    /* the same target ||r|| <= rtol ||b|| as pstencil's, in the terms of this system's b */
    int max_iter = fixed > 0 ? fixed : so.max_iter;
    PetscCall(petsc_ksp(A, c, o, o->rtol * s->bnorm / s->rhs_norm, max_iter, &ksp));
    if (fixed > 0)
        PetscCall(KSPSetConvergenceTest(ksp, KSPConvergedSkip, NULL, NULL));
    PetscCall(VecCreateSeqWithArray(PETSC_COMM_SELF, 1, s->n, s->b, &b));
    PetscCall(VecDuplicate(b, &x));
    PetscCall(VecSet(x, 0.0));
    bench_peak_reset();
    double t0 = omp_get_wtime();
    PetscCall(KSPSetUp(ksp));
    double t1 = omp_get_wtime();
    PetscCall(KSPSolve(ksp, b, x));
    double t2 = omp_get_wtime();
    r->peak_mb = bench_memory("VmHWM") / (1 << 20);
    PetscInt its;
    KSPConvergedReason why;
    PetscCall(KSPGetIterationNumber(ksp, &its));
    PetscCall(KSPGetConvergedReason(ksp, &why));
    PetscScalar *xa;
    PetscCall(VecGetArray(x, &xa));
    for (PetscInt i = 0; s->eliminated && i < s->n; ++i)
        if (s->dirichlet[i])
            xa[i] = s->b[i]; /* the data, as pstencil's u_D */
    r->rel_residual = true_residual(s, xa);
    PetscCall(VecRestoreArray(x, &xa));
    KSPType kt;
    PCType pt;
    PC pc;
    PetscCall(KSPGetType(ksp, &kt));
    PetscCall(KSPGetPC(ksp, &pc));
    PetscCall(PCGetType(pc, &pt));
    snprintf(r->label, sizeof r->label, "%s (%s + %s)", c->label, kt, pt);
    r->setup = t1 - t0;
    r->solve = t2 - t1;
    r->iterations = (int)its;
    r->note = why > 0 || fixed > 0 ? "" : KSPConvergedReasons[why];
    PetscCall(VecDestroy(&x));
    PetscCall(VecDestroy(&b));
    PetscCall(KSPDestroy(&ksp));
    PetscFunctionReturn(0);
}

/* The x_ configuration runs only when its options name a method or a preconditioner. */
static int wanted(const petsc_config *c)
{
    if (strcmp(c->prefix, "x_") != 0)
        return 1;
    PetscBool k = PETSC_FALSE, p = PETSC_FALSE;
    PetscOptionsHasName(NULL, c->prefix, "-ksp_type", &k);
    PetscOptionsHasName(NULL, c->prefix, "-pc_type", &p);
    return k || p;
}

/* ---- the report ---------------------------------------------------------------------------- */

static void print_machine(const options *o, size_t np, double pairs, const csr_system *s)
{
    pstb_probes p;
    pstb_probes_run(&p);
    char line[2048];
    pstb_probes_line(&p, line, sizeof line);
    printf("# machine: %s\n", line);
    printf("# threads: pstencil %d OpenMP threads (its AMG is hypre, serial); PETSc one MPI "
           "process, serial (PETSc and hypre built without OpenMP)\n",
           omp_get_max_threads());
    printf("# problem: %dD, %zu particles, scheme %s, rtol %.0e, restart %d, u0 = 0; PETSc's "
           "matrix: %lld nonzeros (%.1f per row), Dirichlet rows identity%s; pstencil's "
           "neighbour list: %.0f pairs (%.1f per row, Dirichlet rows included)\n\n",
           o->dim, np, o->scheme, o->rtol, o->restart, (long long)s->ia[s->n],
           (double)s->ia[s->n] / (double)s->n,
           s->eliminated ? ", Dirichlet columns eliminated" : "", pairs, pairs / (double)np);
}

static void print_table(const result *r, int nr)
{
    printf("| configuration | set-up s | solve s | total s | iterations | per-iteration ms "
           "| true rel. residual | peak RSS MB | total / pstencil |\n"
           "|---|---|---|---|---|---|---|---|---|\n");
    double ref = r[0].setup + r[0].solve;
    for (int i = 0; i < nr; ++i) {
        double tot = r[i].setup + r[i].solve;
        printf("| %s | %.3f | %.3f | %.3f | %d%s%s%s | %.2f | %.1e | %.0f | %.2f |\n",
               r[i].label, r[i].setup, r[i].solve, tot, r[i].iterations,
               *r[i].note ? " (" : "", r[i].note, *r[i].note ? ")" : "",
               r[i].iterations ? 1e3 * r[i].solve / r[i].iterations : 0.0, r[i].rel_residual,
               r[i].peak_mb, tot / ref);
    }
}

/* GMRES + Jacobi for a fixed number of iterations on the same matrix, pstencil and PETSc
 * alternating o->reps times (the machine may be shared): the medians of the seconds per
 * iteration, pstencil's in med[0], PETSc's in med[1]. */
static PetscErrorCode jacobi_compare(Mat A, const csr_system *s, const options *o,
                                     const pst_op *op, const double *b, double med[2])
{
    double t[2][MAX_REPS];
    PetscFunctionBeginUser;
    for (int k = 0; k < o->reps; ++k) {
        result r;
        t[0][k] = pstencil_jacobi_iteration(o, op, b, (size_t)s->n);
        PetscCall(petsc_run(A, s, &configs[3], o, o->jacobi_iters, &r));
        t[1][k] = r.solve / r.iterations;
    }
    med[0] = bench_median(t[0], o->reps);
    med[1] = bench_median(t[1], o->reps);
    PetscFunctionReturn(0);
}

static void print_jacobi_line(const options *o, const double med[2])
{
    printf("\nGMRES(%d) + Jacobi, %d iterations on the same matrix, median of %d alternating "
           "runs: pstencil (%s) %.2f ms per iteration, PETSc %.2f ms (PETSc / pstencil = %.2f)\n",
           o->restart, o->jacobi_iters, o->reps, o->stored ? "stored weights" : "matrix-free",
           1e3 * med[0], 1e3 * med[1], med[1] / med[0]);
}

/* Every PETSc configuration wanted, one after the other, into r[*nr..]. */
static PetscErrorCode petsc_table(Mat A, const csr_system *s, const options *o, result *r,
                                  int *nr)
{
    PetscFunctionBeginUser;
    for (int i = 0; i < NCONFIGS; ++i)
        if (wanted(&configs[i]))
            PetscCall(petsc_run(A, s, &configs[i], o, 0, &r[(*nr)++]));
    PetscFunctionReturn(0);
}

/* PetscInitialize on our argv[0] and the options after "--" (argv[first..]). */
static PetscErrorCode petsc_start(int argc, char **argv, int first, char ***pargv)
{
    int pargc = 1 + argc - first;
    *pargv = malloc(((size_t)pargc + 1) * sizeof **pargv);
    if (!*pargv)
        return PETSC_ERR_MEM;
    (*pargv)[0] = argv[0];
    for (int i = first; i <= argc; ++i)
        (*pargv)[1 + i - first] = argv[i];
    return PetscInitialize(&pargc, pargv, NULL, NULL);
}

int main(int argc, char **argv)
{
    options o;
    int first;
    char **pargv = NULL;
    if (parse_options(argc, argv, &o, &first) != 0)
        return 1;
    /* MPI first (pstencil's AMG needs it; finalised at exit): PETSc leaves it running. */
    test_mpi_init();
    PetscCall(petsc_start(argc, argv, first, &pargv));
    pst_cloud *c = bench_poisson_cloud("bench_petsc", o.dim, o.n, 1.2);
    if (!c)
        return 1;
    size_t np = pst_cloud_size(c);
    double *b = malloc(np * sizeof *b), *u = calloc(np, sizeof *u), *ue = malloc(np * sizeof *ue);
    bench_poisson_rhs(c, b, ue);
    free(ue);
    result r[1 + NCONFIGS];
    double phase[4], med[2] = {0, 0};
    pst_op *op = NULL;
    pst_nlist *nl = NULL;
    bench_peak_reset();
    pstencil_run(&o, c, b, u, &op, &nl, &r[0], phase);
    r[0].peak_mb = bench_memory("VmHWM") / (1 << 20);

    csr_system s;
    Mat A;
    if (export_system(op, pst_cloud_kinds_const(c), b, o.eliminate, &s) != 0) {
        fprintf(stderr, "bench_petsc: cannot export the matrix\n");
        return 1;
    }
    r[0].rel_residual = true_residual(&s, u);
    /* The matrix on the exported arrays (PETSc does not copy them), not timed. */
    PetscCall(MatCreateSeqAIJWithArrays(PETSC_COMM_SELF, s.n, s.n, s.ia, s.ja, s.va, &A));
    PetscCall(jacobi_compare(A, &s, &o, op, b, med));
    double pairs = (double)pst_nlist_pairs(nl);
    pst_op_destroy(op);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
    int nr = 1;
    PetscCall(petsc_table(A, &s, &o, r, &nr));
    print_machine(&o, np, pairs, &s);
    print_table(r, nr);
    print_jacobi_line(&o, med);
    printf("pstencil phases: sort + neighbours %.3f s, precompute %.3f s, store %.3f s, solver "
           "set-up %.3f s\n", phase[0], phase[1], phase[2], phase[3]);
    PetscCall(MatDestroy(&A));
    free_system(&s);
    free(b);
    free(u);
    PetscCall(PetscFinalize());
    free(pargv);
    return 0;
}
