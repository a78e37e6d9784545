/* Algebraic multigrid preconditioner: one hypre BoomerAMG V-cycle on an assembled low-order
 * operator (docs/solving.md, "Algebraic multigrid (hypre BoomerAMG)").
 *
 * The AMG matrix is A = S L_low with a row sign S chosen so that every diagonal is positive:
 * interior rows of L have -sum_J w_IJ < 0 on the diagonal (S = -1); Neumann flux rows
 * n . M grad u have neighbours on the inner side of the outward normal, so their weights are
 * negative and their diagonal positive (S = +1, measured for brookshaw, cb, lv, qsfdi; src/solve.h
 * says -1 there, which would hand BoomerAMG negative diagonals); Dirichlet rows are the
 * identity (S = +1). Then M^-1 r = A^-1 (S r). Since z_D = r_D on Dirichlet rows, the Dirichlet
 * columns are eliminated: hypre gets only the non-Dirichlet block A_II and the right-hand side
 * S (r_I - L_ID r_D). That is the same z, and it keeps the boundary values out of the coarse
 * grids (they are not unknowns) and A_II symmetric whenever the low-order weights are. */
#include "solve.h"

#include <stdio.h>
#include <string.h>

#ifndef PSTENCIL_HAVE_HYPRE

int pst_prec_amg(pst_prec *p, const pst_op *op, int source, char *err)
{
    (void)op;
    memset(p, 0, sizeof *p);
    if (source != PST_AMG_BROOKSHAW && source != PST_AMG_OWN) {
        pst_set_err(err, "unknown AMG source %d (brookshaw = 0, own = 1)", source);
        return PST_EINVAL;
    }
    pst_set_err(err, "pstencil was built without hypre: the AMG preconditioner is unavailable");
    return PST_EINVAL;
}

#else

#include <HYPRE.h>
#include <HYPRE_IJ_mv.h>
#include <HYPRE_parcsr_ls.h>
#include <HYPRE_utilities.h>
#include <limits.h>
#include <math.h>
#include <mpi.h>
#include <stdlib.h>

/* ---- process-wide runtime ---------------------------------------------------------------- */
/* hypre is built with MPI, so MPI must be initialised before any hypre call, and hypre keeps
 * process-wide state (its handle and error flag). This is the one piece of global state of the
 * library, set once and never changed after: whether we initialised MPI (then we finalise it
 * at exit) and whether HYPRE_Init ran. Every hypre call runs inside the named critical section
 * pst_hypre, so concurrent solves from different threads serialise their AMG work (hypre's
 * error flag and MPI_THREAD_SERIALIZED both need that). */
static int runtime_state;             /* 0: not tried; 1: ready; -1: failed */
static char runtime_err[PST_ERRLEN];

static void finalize_mpi(void)
{
    int finalized = 1;
    MPI_Finalized(&finalized);
    if (!finalized)
        MPI_Finalize();
}

static void finalize_hypre(void) { HYPRE_Finalize(); }

/* Called inside the critical section. atexit runs handlers in reverse order of registration:
 * finalize_mpi is registered first, so HYPRE_Finalize (which only frees hypre's handle and
 * makes no MPI call) runs before MPI_Finalize. */
static void runtime_init(void)
{
    int initialized = 0, finalized = 0;
    MPI_Initialized(&initialized);
    MPI_Finalized(&finalized);
    if (finalized) {
        pst_set_err(runtime_err, "MPI has already been finalised: hypre cannot run");
        runtime_state = -1;
        return;
    }
    if (!initialized) {
        int provided = 0;
        if (MPI_Init_thread(NULL, NULL, MPI_THREAD_SERIALIZED, &provided) != MPI_SUCCESS) {
            pst_set_err(runtime_err, "MPI_Init_thread failed: hypre cannot run");
            runtime_state = -1;
            return;
        }
        /* our MPI: errors return codes instead of aborting the process */
        MPI_Comm_set_errhandler(MPI_COMM_SELF, MPI_ERRORS_RETURN);
        if (atexit(finalize_mpi) != 0) {
            pst_set_err(runtime_err, "cannot register MPI_Finalize with atexit");
            runtime_state = -1;
            return;
        }
    }
    if (HYPRE_Init() != 0 || atexit(finalize_hypre) != 0) {
        pst_set_err(runtime_err, "HYPRE_Init failed (hypre error %d)", (int)HYPRE_GetError());
        runtime_state = -1;
        return;
    }
    runtime_state = 1;
}

/* ---- the preconditioner -------------------------------------------------------------------- */

typedef struct {
    size_t n;              /* operator rows                                                   */
    HYPRE_Int m;           /* AMG unknowns: the non-Dirichlet rows                             */
    HYPRE_Int *map;        /* row -> AMG index, -1 on Dirichlet rows (n)                       */
    size_t *row;           /* AMG index -> row (m)                                            */
    int64_t *doff;         /* couplings to Dirichlet columns, eliminated into the right-hand  */
    uint32_t *dcol;        /* side: L_ij for j Dirichlet, CSR over the m AMG rows             */
    double *dval;
    double *diag;          /* A_ii: the Jacobi fallback if a cycle ever returns non-finite    */
    double *sign;          /* S_i of each AMG row: -1 interior, +1 Neumann                   */
    HYPRE_BigInt *idx;     /* 0..m-1, for the vector copies                                    */
    double *b, *x;         /* m values each                                                   */
    HYPRE_IJMatrix A;
    HYPRE_IJVector B, X;
    HYPRE_ParCSRMatrix pA;
    HYPRE_ParVector pB, pX;
    HYPRE_Solver amg;
} amg_ctx;

static void amg_free(amg_ctx *c)
{
    if (!c)
        return;
    if (c->amg || c->A || c->B || c->X) {
#pragma omp critical(pst_hypre)
        {
            if (c->amg)
                HYPRE_BoomerAMGDestroy(c->amg);
            if (c->A)
                HYPRE_IJMatrixDestroy(c->A);
            if (c->B)
                HYPRE_IJVectorDestroy(c->B);
            if (c->X)
                HYPRE_IJVectorDestroy(c->X);
            HYPRE_ClearAllErrors();
        }
    }
    pst_free(c->map);
    pst_free(c->row);
    pst_free(c->doff);
    pst_free(c->dcol);
    pst_free(c->dval);
    pst_free(c->diag);
    pst_free(c->sign);
    pst_free(c->idx);
    pst_free(c->b);
    pst_free(c->x);
    free(c);
}

static void amg_destroy(void *ctx) { amg_free(ctx); }

/* z = A^-1 (S r) with one V-cycle from a zero initial guess. Memory-bound outside hypre: the
 * right-hand side streams r once plus the Dirichlet couplings (a few per boundary-adjacent
 * row); the cycle itself costs a few matrix passes over the AMG hierarchy. */
static void amg_apply(void *ctx, const double *r, double *z)
{
    amg_ctx *c = ctx;
    const HYPRE_Int m = c->m;
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < c->n; ++i)
        if (c->map[i] < 0)
            z[i] = r[i];
    if (m == 0)
        return;
#pragma omp parallel for schedule(static)
    for (HYPRE_Int k = 0; k < m; ++k) {
        double s = r[c->row[k]];   /* S (r_i - L_iD r_D): the Dirichlet columns eliminated */
        for (int64_t q = c->doff[k]; q < c->doff[k + 1]; ++q)
            s -= c->dval[q] * r[c->dcol[q]];
        c->b[k] = c->sign[k] * s;
    }
    int hypre_failed = 0;
#pragma omp critical(pst_hypre)
    {
        HYPRE_ClearAllErrors();
        HYPRE_IJVectorSetValues(c->B, m, c->idx, c->b);
        HYPRE_ParVectorSetConstantValues(c->pX, 0.0);
        HYPRE_BoomerAMGSolve(c->amg, c->pA, c->pB, c->pX);
        HYPRE_IJVectorGetValues(c->X, m, c->idx, c->x);
        hypre_failed = HYPRE_GetError() != 0;
        HYPRE_ClearAllErrors();
    }
    int bad = hypre_failed;
#pragma omp parallel for schedule(static) reduction(| : bad)
    for (HYPRE_Int k = 0; k < m; ++k)
        bad |= !isfinite(c->x[k]);
    /* Never hand NaN to the Krylov method: a failed cycle degrades to Jacobi on A. */
#pragma omp parallel for schedule(static)
    for (HYPRE_Int k = 0; k < m; ++k)
        z[c->row[k]] = bad ? c->b[k] / c->diag[k] : c->x[k];
}

/* Message of a hypre error code. */
static int hypre_failure(char *err, const char *what, HYPRE_Int code)
{
    char descr[256] = "";
    HYPRE_DescribeError(code, descr);
    pst_set_err(err, "hypre %s failed: error %d (%s)", what, (int)code, descr);
    return PST_ENUMERIC;
}

/* The hypre objects: the IJ matrix of A_II, the two vectors and BoomerAMG set up on them.
 * Called inside the critical section. */
static int hypre_setup(amg_ctx *c, int dim, HYPRE_Int *ncols, const HYPRE_BigInt *cols,
                       const double *vals, char *err)
{
    const HYPRE_Int m = c->m;
    HYPRE_Int e = 0;
    HYPRE_ClearAllErrors();
    e = HYPRE_IJMatrixCreate(MPI_COMM_SELF, 0, m - 1, 0, m - 1, &c->A);
    if (!e)
        e = HYPRE_IJMatrixSetObjectType(c->A, HYPRE_PARCSR);
    if (!e)
        e = HYPRE_IJMatrixSetRowSizes(c->A, ncols);
    if (!e)
        e = HYPRE_IJMatrixInitialize(c->A);
    if (!e)
        e = HYPRE_IJMatrixSetValues(c->A, m, ncols, c->idx, cols, vals);
    if (!e)
        e = HYPRE_IJMatrixAssemble(c->A);
    if (!e)
        e = HYPRE_IJMatrixGetObject(c->A, (void **)&c->pA);
    if (e)
        return hypre_failure(err, "matrix assembly", e);
    HYPRE_IJVector *vec[2] = {&c->B, &c->X};
    HYPRE_ParVector *par[2] = {&c->pB, &c->pX};
    for (int v = 0; v < 2 && !e; ++v) {
        e = HYPRE_IJVectorCreate(MPI_COMM_SELF, 0, m - 1, vec[v]);
        if (!e)
            e = HYPRE_IJVectorSetObjectType(*vec[v], HYPRE_PARCSR);
        if (!e)
            e = HYPRE_IJVectorInitialize(*vec[v]);
        if (!e)
            e = HYPRE_IJVectorAssemble(*vec[v]);
        if (!e)
            e = HYPRE_IJVectorGetObject(*vec[v], (void **)par[v]);
    }
    if (e)
        return hypre_failure(err, "vector creation", e);
    e = HYPRE_BoomerAMGCreate(&c->amg);
    if (e)
        return hypre_failure(err, "BoomerAMGCreate", e);
    /* A preconditioner: exactly one V-cycle per apply, no residual norms, no output. */
    HYPRE_BoomerAMGSetPrintLevel(c->amg, 0);
    HYPRE_BoomerAMGSetLogging(c->amg, 0);
    HYPRE_BoomerAMGSetMaxIter(c->amg, 1);
    HYPRE_BoomerAMGSetTol(c->amg, 0.0);
    /* HMIS coarsening with extended+i interpolation truncated to 4 entries per row: the
     * low-complexity pairing recommended for 2D/3D unstructured diffusion (Brookshaw rows have
     * 20-60 neighbours, so classical Ruge-Stueben coarsening grows the complexity fast). */
    HYPRE_BoomerAMGSetCoarsenType(c->amg, 10);
    HYPRE_BoomerAMGSetInterpType(c->amg, 6);
    HYPRE_BoomerAMGSetPMaxElmts(c->amg, 4);
    /* Hybrid symmetric Gauss-Seidel (forward then backward; plain SSOR(1) on one process),
     * lexicographic order, one sweep down and one up: a symmetric cycle, so M is symmetric
     * whenever A_II is (usable inside CG). hypre here is serial: deterministic. */
    HYPRE_BoomerAMGSetRelaxType(c->amg, 6);
    HYPRE_BoomerAMGSetRelaxOrder(c->amg, 0);
    HYPRE_BoomerAMGSetNumSweeps(c->amg, 1);
    /* Gaussian elimination on the coarsest grid (at most 9 unknowns), unless no row is
     * Dirichlet: then A is singular (constants in its null space, pure Neumann) and elimination
     * would return a huge multiple of the null vector; four smoothing sweeps there stay
     * bounded and still solve the coarse problem on the complement. */
    if ((size_t)m < c->n) {
        HYPRE_BoomerAMGSetCycleRelaxType(c->amg, 9, 3);
    } else {
        HYPRE_BoomerAMGSetCycleRelaxType(c->amg, 6, 3);
        HYPRE_BoomerAMGSetCycleNumSweeps(c->amg, 4, 3);
    }
    HYPRE_BoomerAMGSetStrongThreshold(c->amg, dim == 3 ? 0.5 : 0.25);
    e = HYPRE_GetError();
    if (!e)
        e = HYPRE_BoomerAMGSetup(c->amg, c->pA, c->pB, c->pX);
    if (e)
        return hypre_failure(err, "BoomerAMGSetup", e);
    return PST_OK;
}

int pst_prec_amg(pst_prec *p, const pst_op *op, int source, char *err)
{
    memset(p, 0, sizeof *p);
    if (source != PST_AMG_BROOKSHAW && source != PST_AMG_OWN) {
        pst_set_err(err, "unknown AMG source %d (brookshaw = 0, own = 1)", source);
        return PST_EINVAL;
    }
    if (op->n > (size_t)INT_MAX) {
        pst_set_err(err, "%zu particles exceed hypre's 32-bit indices", op->n);
        return PST_EINVAL;
    }
    int ready;
#pragma omp critical(pst_hypre)
    {
        if (runtime_state == 0)
            runtime_init();
        ready = runtime_state;
    }
    if (ready < 0) {
        pst_set_err(err, "%s", runtime_err);
        return PST_EINVAL;
    }

    /* The low-order operator: Brookshaw with the operator's kernel, so the operator's
     * neighbour list covers its support, or the operator itself. */
    const pst_op *low = op;
    pst_op *brookshaw = NULL;
    if (source == PST_AMG_BROOKSHAW && strcmp(op->scheme->name, "brookshaw") != 0) {
        pst_op_opts o = op->opts;
        o.scheme = "brookshaw";
        o.kernel = (int)op->kernel;
        o.variant = 0;
        int st = pst_op_create(&brookshaw, op->cloud, op->nl, &o, err);
        if (st != PST_OK)
            return st;
        low = brookshaw;
    }
    pst_csr a;
    int st = pst_op_assemble(low, &a);
    pst_op_destroy(brookshaw);
    if (st != PST_OK) {
        pst_set_err(err, "cannot assemble the AMG matrix of %zu rows", op->n);
        return st;
    }

    const size_t n = op->n;
    const uint8_t *kind = op->kind;
    amg_ctx *c = calloc(1, sizeof *c);
    HYPRE_Int *ncols = NULL;
    HYPRE_BigInt *cols = NULL;
    double *vals = NULL;
    int64_t *aoff = NULL;   /* offsets of the AMG rows' entries */
    st = PST_ENOMEM;
    if (!c)
        goto fail;
    c->n = n;
    c->map = pst_alloc(n * sizeof *c->map);
    if (!c->map)
        goto fail;
    HYPRE_Int m = 0;
    for (size_t i = 0; i < n; ++i)
        c->map[i] = kind[i] == PST_DIRICHLET ? -1 : m++;
    c->m = m;
    c->row = pst_alloc((size_t)m * sizeof *c->row);
    c->doff = pst_alloc(((size_t)m + 1) * sizeof *c->doff);
    aoff = pst_alloc(((size_t)m + 1) * sizeof *aoff);
    c->diag = pst_alloc((size_t)m * sizeof *c->diag);
    c->sign = pst_alloc((size_t)m * sizeof *c->sign);
    c->idx = pst_alloc((size_t)m * sizeof *c->idx);
    c->b = pst_alloc((size_t)m * sizeof *c->b);
    c->x = pst_alloc((size_t)m * sizeof *c->x);
    ncols = pst_alloc((size_t)m * sizeof *ncols);
    if (!c->row || !c->doff || !aoff || !c->diag || !c->sign || !c->idx || !c->b || !c->x ||
        !ncols)
        goto fail;
    for (size_t i = 0; i < n; ++i)
        if (c->map[i] >= 0)
            c->row[c->map[i]] = i;

    /* Count each AMG row's entries: Dirichlet columns go to the elimination, exact zeros off
     * the diagonal are dropped (they would only enlarge the strength graph). This pass and the
     * fill below stream the assembled matrix once each: memory-bound, like an apply. */
    size_t bad_row = SIZE_MAX;
#pragma omp parallel for schedule(static)
    for (HYPRE_Int k = 0; k < m; ++k) {
        size_t i = c->row[k];
        int64_t nd = 0, na = 0;
        for (int64_t q = a.rowptr[i]; q < a.rowptr[i + 1]; ++q) {
            if (c->map[a.col[q]] < 0)
                nd += a.val[q] != 0;
            else
                na += a.col[q] == i || a.val[q] != 0;
        }
        c->doff[k + 1] = nd;
        aoff[k + 1] = na;
        c->idx[k] = k;
    }
    c->doff[0] = aoff[0] = 0;
    for (HYPRE_Int k = 0; k < m; ++k) {
        c->doff[k + 1] += c->doff[k];
        aoff[k + 1] += aoff[k];
        ncols[k] = (HYPRE_Int)(aoff[k + 1] - aoff[k]);
    }
    if (aoff[m] > INT_MAX) {
        pst_set_err(err, "%lld AMG matrix entries exceed hypre's 32-bit indices",
                    (long long)aoff[m]);
        st = PST_EINVAL;
        goto fail;
    }
    c->dcol = pst_alloc((size_t)c->doff[m] * sizeof *c->dcol);
    c->dval = pst_alloc((size_t)c->doff[m] * sizeof *c->dval);
    cols = pst_alloc((size_t)aoff[m] * sizeof *cols);
    vals = pst_alloc((size_t)aoff[m] * sizeof *vals);
    if (!c->dcol || !c->dval || !cols || !vals)
        goto fail;
#pragma omp parallel for schedule(static)
    for (HYPRE_Int k = 0; k < m; ++k) {
        size_t i = c->row[k];
        int64_t pd = c->doff[k], pa = aoff[k];
        double d = 0, sg = kind[i] == PST_INTERIOR ? -1.0 : 1.0;
        c->sign[k] = sg;
        int finite = 1;
        for (int64_t q = a.rowptr[i]; q < a.rowptr[i + 1]; ++q) {
            double v = a.val[q];
            finite &= isfinite(v);
            HYPRE_Int j = c->map[a.col[q]];
            if (j < 0) {
                if (v != 0) {
                    c->dcol[pd] = a.col[q];
                    c->dval[pd++] = v;
                }
            } else if (a.col[q] == i || v != 0) {
                cols[pa] = j;
                vals[pa++] = sg * v;   /* A = S L */
                if (a.col[q] == i)
                    d = sg * v;
            }
        }
        c->diag[k] = d;
        if (!finite || !(d > 0)) {
#pragma omp critical(pst_amg_bad_row)
            bad_row = i < bad_row ? i : bad_row;   /* the first such row: thread-independent */
        }
    }
    if (bad_row != SIZE_MAX) {
        double d = c->diag[c->map[bad_row]];
        pst_set_err(err, "AMG matrix row %zu (particle id %lld) has diagonal %g or a non-finite "
                         "entry: BoomerAMG needs a positive diagonal (the Brookshaw source "
                         "always has one when every row has neighbours)",
                    bad_row, (long long)op->cloud->id[bad_row], d + 0.0);
        st = PST_ENUMERIC;
        goto fail;
    }
    pst_csr_free(&a);
    pst_free(aoff);
    aoff = NULL;

    if (m > 0) {
#pragma omp critical(pst_hypre)
        {
            st = hypre_setup(c, op->dim, ncols, cols, vals, err);
            HYPRE_ClearAllErrors();
        }
        if (st != PST_OK)
            goto fail;
    }
    pst_free(ncols);
    pst_free(cols);
    pst_free(vals);
    p->apply = amg_apply;
    p->destroy = amg_destroy;
    p->ctx = c;
    return PST_OK;

fail:
    if (st == PST_ENOMEM)
        pst_set_err(err, "cannot allocate the AMG matrix of %zu rows", n);
    pst_csr_free(&a);
    pst_free(aoff);
    pst_free(ncols);
    pst_free(cols);
    pst_free(vals);
    amg_free(c);
    return st;
}

#endif
