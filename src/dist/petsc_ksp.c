/* The operator inside PETSc (docs/distributed.md): the engine's operator as a MatShell whose
 * MatMult is pst_op_apply on the rank's local cloud (owned + ghosts) after one scatter of the
 * ghosts' values, its assembled stencil as the AIJ matrix PETSc's preconditioners are built
 * from, and KSP chosen by PETSc options. Dirichlet rows are identity rows in both, so b holds
 * the values there, as for pst_solve. Built only with PETSc (CMake finds petsc-dev). */
#include "check.h"
#include "operator.h"
#include "pstencil/dist.h"
#include "solve.h"

#include <math.h>
#include <petscksp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int started_here; /* 1: pst_petsc_start called PetscInitialize */

int pst_petsc_available(void) { return 1; }

const char *pst_petsc_version(void)
{
    static char v[32];
    snprintf(v, sizeof v, "%d.%d.%d", PETSC_VERSION_MAJOR, PETSC_VERSION_MINOR,
             PETSC_VERSION_SUBMINOR);
    return v;
}

int pst_petsc_start(int *argc, char ***argv, char *err)
{
    PetscBool up = PETSC_FALSE;
    PetscInitialized(&up);
    if (up)
        return PST_OK;
    PetscErrorCode e = PetscInitialize(argc, argv, NULL, NULL);
    PST_CHECK(e != 0, PST_EINVAL, err, "PETSc could not be started (error %d)", (int)e);
    PetscPushErrorHandler(PetscReturnErrorHandler, NULL); /* errors come back as codes */
    started_here = 1;
    return PST_OK;
}

void pst_petsc_stop(void)
{
    if (!started_here)
        return;
    PetscPopErrorHandler();
    PetscFinalize();
    started_here = 0;
}

/* A PETSc call inside a function with `int st`, `char *err` and a `done` label: on an error,
 * its message into err and PST_EINVAL. */
#define PETSC_TRY(call)                                                                        \
    do {                                                                                       \
        PetscErrorCode pe_ = (call);                                                           \
        if (pe_) {                                                                             \
            const char *text_ = NULL;                                                          \
            PetscErrorMessage(pe_, &text_, NULL);                                              \
            pst_set_err(err, "PETSc: %s failed: %s", #call, text_ ? text_ : "error");          \
            st = PST_EINVAL;                                                                   \
            goto done;                                                                         \
        }                                                                                      \
    } while (0)

/* What MatMult needs: the operator (with its kinds), where the owned rows lie in its local
 * order, and the scatter of x's owned and ghost values into that order. */
typedef struct {
    const pst_op *op;
    size_t own0, nown, nlocal;
    VecScatter gather;
    Vec xl;     /* x in the local order (sequential)  */
    double *yl; /* L x in the local order             */
    /* a fixed mean (pst_petsc_opts.fix_mean): the operator is L + c 1 V^T, as pst_solve's
     * (docs/solving.md, "Singular problems"); V NULL: none */
    const double *V;
    double c, vsum;
    MPI_Comm comm;
} shell_ctx;

/* S_i of the system S L u = S b: -1 on interior rows, so that every diagonal is positive. */
static inline double row_sign(const pst_op *op, size_t i)
{
    return op->kind[i] == PST_INTERIOR ? -1.0 : 1.0;
}

/* V . x over the owned particles of every rank (x in the local order). */
static double owned_dot(const shell_ctx *s, const double *x)
{
    double local = 0, all = 0;
    for (size_t k = 0; k < s->nown; ++k)
        local += s->V[s->own0 + k] * x[s->own0 + k];
    MPI_Allreduce(&local, &all, 1, MPI_DOUBLE, MPI_SUM, s->comm);
    return all;
}

static PetscErrorCode shell_mult(Mat A, Vec x, Vec y)
{
    shell_ctx *s;
    PetscCall(MatShellGetContext(A, &s));
    PetscCall(VecScatterBegin(s->gather, x, s->xl, INSERT_VALUES, SCATTER_FORWARD));
    PetscCall(VecScatterEnd(s->gather, x, s->xl, INSERT_VALUES, SCATTER_FORWARD));
    const PetscScalar *xl;
    PetscScalar *yo;
    PetscCall(VecGetArrayRead(s->xl, &xl));
    int st = s->nlocal ? pst_op_apply(s->op, xl, s->yl) : PST_OK;
    double t = s->V ? s->c * owned_dot(s, xl) : 0.0;
    PetscCall(VecGetArray(y, &yo));
    for (size_t k = 0; k < s->nown; ++k) {
        size_t i = s->own0 + k;
        uint8_t kd = s->op->kind[i];
        double v = s->yl[i] + t;
        yo[k] = kd == PST_DIRICHLET ? xl[i] : row_sign(s->op, i) * v;
    }
    PetscCall(VecRestoreArray(y, &yo));
    PetscCall(VecRestoreArrayRead(s->xl, &xl));
    PetscCheck(st == PST_OK, PETSC_COMM_SELF, PETSC_ERR_LIB, "pst_op_apply failed (%d)", st);
    return 0;
}

static PetscErrorCode shell_diagonal(Mat A, Vec d)
{
    shell_ctx *s;
    PetscCall(MatShellGetContext(A, &s));
    int st = s->nlocal ? pst_op_diagonal(s->op, s->yl) : PST_OK;
    PetscCheck(st == PST_OK, PETSC_COMM_SELF, PETSC_ERR_MEM, "pst_op_diagonal failed (%d)", st);
    PetscScalar *dv;
    PetscCall(VecGetArray(d, &dv));
    for (size_t k = 0; k < s->nown; ++k) {
        size_t i = s->own0 + k;
        double v = s->yl[i] + (s->V ? s->c * s->V[i] : 0.0);
        dv[k] = row_sign(s->op, i) * v;
    }
    PetscCall(VecRestoreArray(d, &dv));
    return 0;
}

/* 1 when an owned row of S a has no positive diagonal, on any rank. */
static int lacks_diagonal(const pst_op *op, MPI_Comm comm, const pst_part_info *pi,
                          const pst_csr *a)
{
    int bad = 0, any = 0;
    for (size_t k = 0; k < pi->hi - pi->lo && !bad; ++k) {
        size_t i = pi->own0 + k;
        double sign = row_sign(op, i), d = 0;
        for (int64_t e = a->rowptr[i]; e < a->rowptr[i + 1]; ++e)
            d = a->col[e] == i ? sign * a->val[e] : d;
        bad = !(d > 0);
    }
    MPI_Allreduce(&bad, &any, 1, MPI_INT, MPI_LOR, comm);
    return any;
}

/* The low-order matrix of o->amg_source (the scheme's own for AUTO where the scheme names it
 * and every owned row of S a has a positive diagonal, else the Brookshaw proxy). */
static int low_order(const pst_op *op, MPI_Comm comm, const pst_part_info *pi,
                     const pst_petsc_opts *o, pst_csr *a, char *err)
{
    size_t full = 0;
    int own = o->amg_source == PST_AMG_OWN ||
              (o->amg_source == PST_AMG_AUTO && op->scheme->amg_own);
    PST_TRY(pst_amg_low_order(op, o->amg_radius, own, a, &full, err));
    if (!own || o->amg_source != PST_AMG_AUTO || !lacks_diagonal(op, comm, pi, a))
        return PST_OK;
    pst_csr_free(a);
    return pst_amg_low_order(op, o->amg_radius, 0, a, &full, err);
}

/* The owned rows of S times the low-order matrix (low_order) as an AIJ matrix with global
 * column numbers (global[k] of local column k); preallocated exactly, diagonal and
 * off-diagonal blocks. */
static int preconditioner_matrix(const pst_op *op, MPI_Comm comm, const pst_part_info *pi,
                                 const size_t *global, const pst_petsc_opts *o, Mat *P,
                                 char *err)
{
    pst_csr a = {0};
    int st = low_order(op, comm, pi, o, &a, err);
    if (st != PST_OK)
        return st;
    size_t nown = pi->hi - pi->lo, width = 0;
    PetscInt *dn = calloc(nown + 1, sizeof *dn), *on = calloc(nown + 1, sizeof *on), *cols = NULL;
    PetscScalar *vals = NULL;
    for (size_t k = 0; dn && on && k < nown; ++k) {
        size_t i = pi->own0 + k;
        for (int64_t e = a.rowptr[i]; e < a.rowptr[i + 1]; ++e) {
            size_t g = global[a.col[e]];
            if (g >= pi->lo && g < pi->hi)
                dn[k]++;
            else
                on[k]++;
        }
        width = (size_t)(dn[k] + on[k]) > width ? (size_t)(dn[k] + on[k]) : width;
    }
    cols = dn && on ? malloc((width + 1) * sizeof *cols) : NULL;
    vals = cols ? malloc((width + 1) * sizeof *vals) : NULL;
    if (!vals) {
        st = PST_ENOMEM;
        pst_set_err(err, "out of memory for the preconditioner's matrix");
        goto done;
    }
    PETSC_TRY(MatCreateAIJ(comm, (PetscInt)nown, (PetscInt)nown, (PetscInt)pi->n,
                           (PetscInt)pi->n, 0, dn, 0, on, P));
    for (size_t k = 0; k < nown; ++k) {
        size_t i = pi->own0 + k;
        PetscInt row = (PetscInt)(pi->lo + k), m = 0;
        double sign = row_sign(op, i);
        for (int64_t e = a.rowptr[i]; e < a.rowptr[i + 1]; ++e) {
            vals[m] = sign * a.val[e];
            cols[m++] = (PetscInt)global[a.col[e]];
        }
        PETSC_TRY(MatSetValues(*P, 1, &row, m, cols, vals, INSERT_VALUES));
    }
    PETSC_TRY(MatAssemblyBegin(*P, MAT_FINAL_ASSEMBLY));
    PETSC_TRY(MatAssemblyEnd(*P, MAT_FINAL_ASSEMBLY));
done:
    free(dn);
    free(on);
    free(cols);
    free(vals);
    pst_csr_free(&a);
    return st;
}

typedef struct {
    const pst_petsc_opts *o;
    double bnorm;
} monitor_ctx;

static PetscErrorCode ksp_monitor(KSP ksp, PetscInt it, PetscReal rnorm, void *ctx)
{
    (void)ksp;
    monitor_ctx *m = ctx;
    m->o->monitor((int)it, m->bnorm > 0 ? rnorm / m->bnorm : 0.0, m->o->monitor_ctx);
    return 0;
}

/* PETSc's reason for stopping as a pst_stop_reason. */
static pst_stop_reason stop_of(KSPConvergedReason why)
{
    if (why > 0)
        return PST_STOP_CONVERGED;
    switch (why) {
    case KSP_DIVERGED_ITS: return PST_STOP_ITERATION_LIMIT;
    case KSP_DIVERGED_NANORINF: return PST_STOP_NON_FINITE;
    case KSP_DIVERGED_PC_FAILED: return PST_STOP_PRECOND_SETUP;
    default: return PST_STOP_BREAKDOWN;
    }
}

/* The KSP of a solve: the defaults of pst_petsc_solve, then the solve's own options from an
 * options database of its own (so they stay with this solve). BoomerAMG starts from the
 * settings of pstencil's own AMG (docs/solving.md): PETSc's (Falgout coarsening, classical
 * interpolation) break down on the lsmps stencil with Neumann rows. */
static int make_ksp(MPI_Comm comm, int dim, Mat A, Mat P, const pst_petsc_opts *o,
                    PetscOptions *db, KSP *ksp, char *err)
{
    int st = PST_OK;
    PC pc;
    char amg[512];
    /* with a fixed mean the matrix is singular (no Dirichlet row): elimination on the coarsest
     * grid would return a huge multiple of the constants, four smoothing sweeps stay bounded,
     * as in pstencil's own AMG (BoomerAMG's and GAMG's coarse solvers; GAMG's LU broke down on
     * the periodic test scene). -pc_use_amat false: the smoothers of PETSc's multigrid PCs
     * relax on the preconditioner's matrix (the low-order proxy), not on the MatShell, whose
     * rows (qsfdi's: not symmetric) GAMG's Chebyshev smoother diverged on by default (3D qsfdi
     * test scene: residual 2.1 after 5000 iterations; on the proxy 29) */
    snprintf(amg, sizeof amg,
             "-pc_use_amat false "
             "-pc_hypre_boomeramg_coarsen_type HMIS -pc_hypre_boomeramg_interp_type ext+i "
             "-pc_hypre_boomeramg_P_max 4 -pc_hypre_boomeramg_strong_threshold %g%s",
             dim == 2 ? 0.25 : 0.5,
             o->fix_mean ? " -pc_hypre_boomeramg_relax_type_coarse symmetric-SOR/Jacobi "
                           "-pc_hypre_boomeramg_grid_sweeps_coarse 4 -mg_coarse_ksp_type "
                           "richardson -mg_coarse_pc_type jacobi -mg_coarse_ksp_max_it 4"
                         : "");
    PETSC_TRY(PetscOptionsCreate(db));
    PETSC_TRY(PetscOptionsInsertString(*db, amg));
    if (o->options && o->options[0])
        PETSC_TRY(PetscOptionsInsertString(*db, o->options));
    PETSC_TRY(KSPCreate(comm, ksp));
    PETSC_TRY(PetscObjectSetOptions((PetscObject)*ksp, *db));
    PETSC_TRY(KSPSetOperators(*ksp, A, P));
    PETSC_TRY(KSPSetType(*ksp, KSPGMRES));
    PETSC_TRY(KSPGMRESSetRestart(*ksp, o->restart));
    PETSC_TRY(KSPSetPCSide(*ksp, PC_RIGHT));
    PETSC_TRY(KSPSetNormType(*ksp, KSP_NORM_UNPRECONDITIONED));
    PETSC_TRY(KSPSetTolerances(*ksp, o->rtol, 0.0, PETSC_DEFAULT, o->max_iter));
    PETSC_TRY(KSPSetInitialGuessNonzero(*ksp, PETSC_TRUE));
    PETSC_TRY(KSPGetPC(*ksp, &pc));
    PETSC_TRY(PetscObjectSetOptions((PetscObject)pc, *db));
#if defined(PETSC_HAVE_HYPRE)
    PETSC_TRY(PCSetType(pc, PCHYPRE));
#else
    PETSC_TRY(PCSetType(pc, PCGAMG));
#endif
    PETSC_TRY(KSPSetFromOptions(*ksp));
done:
    return st;
}

/* The solve's monitor (o->monitor, through mc) and residual history (o->history: into *hist,
 * which the caller frees, and r->history). */
static int watch(KSP ksp, const pst_petsc_opts *o, monitor_ctx *mc, double **hist,
                 pst_solve_result *r, char *err)
{
    int st = PST_OK;
    if (o->monitor)
        PETSC_TRY(KSPMonitorSet(ksp, ksp_monitor, mc, NULL));
    if (o->history) {
        size_t len = o->max_iter < PST_PETSC_HISTORY ? (size_t)o->max_iter + 1 : PST_PETSC_HISTORY;
        *hist = malloc(len * sizeof **hist);
        r->history = malloc(len * sizeof *r->history);
        PST_CHECK_GOTO(!*hist || !r->history, st, PST_ENOMEM, done, err,
                       "petsc solve: out of memory for the history");
        PETSC_TRY(KSPSetResidualHistory(ksp, *hist, (PetscInt)len, PETSC_TRUE));
    }
done:
    return st;
}

/* A fixed mean: c = -(mean |diag L|) / sum V over all ranks, as pst_solve takes it; refused
 * when a rank owns a Dirichlet row. */
static int fix_mean_setup(shell_ctx *s, size_t n, char *err)
{
    double part[3] = {0, 0, 0}, all[3];
    int st = s->nlocal ? pst_op_diagonal(s->op, s->yl) : PST_OK;
    PST_CHECK(st != PST_OK, st, err, "petsc solve: the operator's diagonal failed");
    const double *V = pst_cloud_volume_const(s->op->cloud);
    for (size_t k = 0; k < s->nown; ++k) {
        size_t i = s->own0 + k;
        part[0] += fabs(s->yl[i]);
        part[1] += V[i];
        part[2] += s->op->kind[i] == PST_DIRICHLET;
    }
    MPI_Allreduce(part, all, 3, MPI_DOUBLE, MPI_SUM, s->comm);
    PST_CHECK(all[2] > 0, PST_EINVAL, err,
              "petsc solve: fix_mean is for problems without Dirichlet rows (%.0f here)", all[2]);
    PST_CHECK(!(all[1] > 0), PST_EINVAL, err, "petsc solve: fix_mean needs positive volumes");
    s->V = V;
    s->vsum = all[1];
    s->c = pst_fix_mean_c(all[0], n, s->vsum);
    return PST_OK;
}

/* The arguments of pst_petsc_solve and the layout they describe (a whole operator: one rank
 * owning everything). */
static int check_solve(const pst_op *op, const pst_part *p, const double *b, const double *u,
                       const pst_petsc_opts *o, pst_part_info *pi, MPI_Comm *comm, char *err)
{
    PetscBool up = PETSC_FALSE;
    PST_CHECK(!op || !b || !u || !o, PST_EINVAL, err, "petsc solve: NULL argument");
    PST_CHECK(!pst_op_has_rows(op), PST_EINVAL, err,
              "petsc solve: the operator has no Laplacian rows");
    PST_CHECK(!(o->rtol > 0) || o->max_iter < 1 || o->restart < 1, PST_EINVAL, err,
              "petsc solve: rtol %g, max_iter %d, restart %d (rtol > 0, the others >= 1)",
              o->rtol, o->max_iter, o->restart);
    PetscInitialized(&up);
    PST_CHECK(!up, PST_EINVAL, err, "petsc solve: PETSc is not started (pst_petsc_start)");
    size_t n = pst_cloud_size(op->cloud);
    *comm = PETSC_COMM_SELF;
    *pi = (pst_part_info){.ranks = 1, .n = n, .hi = n, .nlocal = n};
    if (!p)
        return PST_OK;
    int size = 1;
    pst_part_layout(p, pi);
    MPI_Comm_size(PETSC_COMM_WORLD, &size);
    PST_CHECK(size != pi->ranks, PST_EINVAL, err,
              "petsc solve: the part is one of %d ranks, the run has %d", pi->ranks, size);
    PST_CHECK(op->cloud != pst_part_cloud(p), PST_EINVAL, err,
              "petsc solve: the operator is not built on the part's local cloud");
    PST_CHECK(pst_scheme_halo(op->scheme->name) > pi->hops, PST_EINVAL, err,
              "petsc solve: scheme %s's rows read %d rings of neighbours, the part holds %d "
              "(pst_part_create's hops: pst_scheme_halo)",
              op->scheme->name, pst_scheme_halo(op->scheme->name), pi->hops);
    *comm = PETSC_COMM_WORLD;
    return PST_OK;
}

/* PST_EINPUT naming the first owned particle with a non-finite b or u (on this rank). */
static int check_finite(const pst_part_info *pi, const size_t *global, const double *b,
                        const double *u, char *err)
{
    for (size_t k = pi->own0; k < pi->own0 + pi->hi - pi->lo; ++k)
        PST_CHECK(!isfinite(b[k]) || !isfinite(u[k]), PST_EINPUT, err,
                  "petsc solve: particle %zu has a non-finite %s (%g)",
                  global ? global[k] : k, isfinite(b[k]) ? "u" : "b",
                  isfinite(b[k]) ? u[k] : b[k]);
    return PST_OK;
}

/* Iterations, reason, history and the true residual of a finished solve into r. */
static int fill_result(KSP ksp, Mat A, Vec x, Vec rhs, double bnorm, pst_solve_result *r,
                       char *err)
{
    int st = PST_OK;
    PetscInt its = 0, nh = 0;
    KSPConvergedReason why;
    const PetscReal *hist = NULL;
    PetscReal rn = 0;
    Vec res = NULL;
    KSPType kt = NULL;
    PCType pt = NULL;
    PC pc;
    PETSC_TRY(KSPGetType(ksp, &kt));
    PETSC_TRY(KSPGetPC(ksp, &pc));
    PETSC_TRY(PCGetType(pc, &pt));
    PETSC_TRY(KSPGetIterationNumber(ksp, &its));
    PETSC_TRY(KSPGetConvergedReason(ksp, &why));
    PETSC_TRY(VecDuplicate(rhs, &res));
    PETSC_TRY(MatMult(A, x, res));
    PETSC_TRY(VecAYPX(res, -1.0, rhs));
    PETSC_TRY(VecNorm(res, NORM_2, &rn));
    r->iterations = (int)its;
    r->stop = stop_of(why);
    r->converged = why > 0;
    r->solver = strcmp(kt, KSPCG) == 0     ? PST_SOLVER_CG
                : strcmp(kt, KSPBCGS) == 0 ? PST_SOLVER_BICGSTAB
                                           : PST_SOLVER_GMRES; /* the message names the type */
    r->rel_residual = bnorm > 0 ? rn / bnorm : rn;
    snprintf(r->message, sizeof r->message, "PETSc %s + %s: %s after %d iterations, residual %.3e",
             kt, pt ? pt : "no PC", KSPConvergedReasons[why], (int)its, r->rel_residual);
    if (KSPGetResidualHistory(ksp, &hist, &nh) == 0 && nh > 0 && r->history) {
        r->nhistory = (int)nh;
        for (PetscInt k = 0; k < nh; ++k)
            r->history[k] = bnorm > 0 ? hist[k] / bnorm : hist[k];
    }
done:
    VecDestroy(&res);
    return st;
}

int pst_petsc_solve(const pst_op *op, const pst_part *p, const double *b, double *u,
                    const pst_petsc_opts *o, pst_solve_result *r, char *err)
{
    pst_solve_result mine;
    r = r ? r : &mine;
    memset(r, 0, sizeof *r);
    pst_part_info pi;
    MPI_Comm comm;
    PST_TRY(check_solve(op, p, b, u, o, &pi, &comm, err));
    PST_TRY(check_finite(&pi, p ? pst_part_global(p) : NULL, b, u, err));
    double t0 = MPI_Wtime();
    size_t nown = pi.hi - pi.lo;
    size_t *whole = NULL;
    const size_t *global = p ? pst_part_global(p) : NULL;
    if (!p) { /* one rank owning everything: the identity numbering */
        whole = malloc((pi.n ? pi.n : 1) * sizeof *whole);
        PST_CHECK_ALLOC(whole, err, "petsc solve: out of memory");
        for (size_t i = 0; i < pi.n; ++i)
            whole[i] = i;
        global = whole;
    }
    shell_ctx sc = {.op = op, .own0 = pi.own0, .nown = nown, .nlocal = pi.nlocal, .comm = comm};
    sc.yl = malloc((pi.nlocal ? pi.nlocal : 1) * sizeof *sc.yl);
    PetscInt *from = malloc((pi.nlocal ? pi.nlocal : 1) * sizeof *from);
    int st = PST_OK;
    Mat A = NULL, P = NULL;
    Vec x = NULL, rhs = NULL;
    IS isfrom = NULL;
    KSP ksp = NULL;
    PetscOptions db = NULL;
    int pushed = 0;
    double *hist = NULL;
    PetscReal bnorm = 0;
    monitor_ctx mc = {o, 0};
    if (!sc.yl || !from) {
        st = PST_ENOMEM;
        pst_set_err(err, "petsc solve: out of memory");
        goto done;
    }
    for (size_t k = 0; k < pi.nlocal; ++k)
        from[k] = (PetscInt)global[k];
    PETSC_TRY(VecCreateMPI(comm, (PetscInt)nown, (PetscInt)pi.n, &x));
    PETSC_TRY(VecDuplicate(x, &rhs));
    PETSC_TRY(VecCreateSeq(PETSC_COMM_SELF, (PetscInt)pi.nlocal, &sc.xl));
    PETSC_TRY(ISCreateGeneral(PETSC_COMM_SELF, (PetscInt)pi.nlocal, from, PETSC_USE_POINTER,
                              &isfrom));
    PETSC_TRY(VecScatterCreate(x, isfrom, sc.xl, NULL, &sc.gather));
    PETSC_TRY(MatCreateShell(comm, (PetscInt)nown, (PetscInt)nown, (PetscInt)pi.n,
                             (PetscInt)pi.n, &sc, &A));
    PETSC_TRY(MatShellSetOperation(A, MATOP_MULT, (void (*)(void))shell_mult));
    PETSC_TRY(MatShellSetOperation(A, MATOP_GET_DIAGONAL, (void (*)(void))shell_diagonal));
    if (o->fix_mean)
        PST_TRY_GOTO(st, fix_mean_setup(&sc, pi.n, err), done);
    PetscScalar *xv, *bv;
    PETSC_TRY(VecGetArray(x, &xv));
    PETSC_TRY(VecGetArray(rhs, &bv));
    for (size_t k = 0; k < nown; ++k) {
        size_t i = pi.own0 + k;
        bv[k] = row_sign(op, i) * b[i];
        xv[k] = op->kind[i] == PST_DIRICHLET ? b[i] : u[i]; /* Dirichlet values are known */
    }
    PETSC_TRY(VecRestoreArray(rhs, &bv));
    PETSC_TRY(VecRestoreArray(x, &xv));
    PETSC_TRY(VecNorm(rhs, NORM_2, &bnorm));
    mc.bnorm = bnorm;
    PST_TRY_GOTO(st, preconditioner_matrix(op, comm, &pi, global, o, &P, err), done);
    PST_TRY_GOTO(st, make_ksp(comm, op->dim, A, P, o, &db, &ksp, err), done);
    /* the objects a PC makes in its set-up (GAMG's levels and coarse solver, block Jacobi's
     * blocks) read the default options database, not their parent's: this solve's while it
     * sets up and runs, so that -mg_levels_... and -sub_... options reach them */
    PETSC_TRY(PetscOptionsPush(db));
    pushed = 1;
    PST_TRY_GOTO(st, watch(ksp, o, &mc, &hist, r, err), done);
    double t1 = MPI_Wtime();
    PETSC_TRY(KSPSetUp(ksp));
    r->setup_seconds = MPI_Wtime() - t1;
    PETSC_TRY(KSPSolve(ksp, rhs, x));
    PST_TRY_GOTO(st, fill_result(ksp, A, x, rhs, bnorm, r, err), done);
    const PetscScalar *xs;
    PETSC_TRY(VecGetArrayRead(x, &xs));
    for (size_t k = 0; k < nown; ++k)
        u[pi.own0 + k] = xs[k];
    PETSC_TRY(VecRestoreArrayRead(x, &xs));
    if (sc.V) { /* the solution with zero weighted mean, and lambda */
        double vu = owned_dot(&sc, u);
        for (size_t k = 0; k < nown; ++k)
            u[pi.own0 + k] -= vu / sc.vsum;
        r->mean_shift = sc.c * vu;
    }
    r->setup_seconds += t1 - t0; /* the matrices and the scatter too */
    r->seconds = MPI_Wtime() - t0;
    if (!r->converged) {
        st = PST_ENUMERIC;
        pst_set_err(err, "%s", r->message);
    }
done:
    if (pushed)
        PetscOptionsPop();
    KSPDestroy(&ksp);
    PetscOptionsDestroy(&db);
    MatDestroy(&P);
    MatDestroy(&A);
    VecScatterDestroy(&sc.gather);
    ISDestroy(&isfrom);
    VecDestroy(&sc.xl);
    VecDestroy(&rhs);
    VecDestroy(&x);
    free(hist);
    free(from);
    free(sc.yl);
    free(whole);
    if (r == &mine)
        pst_solve_result_free(r);
    return st;
}
