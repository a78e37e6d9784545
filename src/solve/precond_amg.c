/* Algebraic multigrid preconditioner: one hypre BoomerAMG V-cycle on an assembled low-order
 * operator (docs/solving.md, "Algebraic multigrid (hypre BoomerAMG)").
 *
 * The AMG matrix is A = S L_low with a row sign S chosen so that every diagonal is positive:
 * interior rows of L have -sum_J w_IJ < 0 on the diagonal (S = -1); Neumann flux rows
 * n . M grad u have neighbours on the inner side of the outward normal, so their weights are
 * negative and their diagonal positive (S = +1, measured for brookshaw, cb, lv, qsfdi; -1 there
 * would hand BoomerAMG negative diagonals); Dirichlet rows are the
 * identity (S = +1). Then M^-1 r = A^-1 (S r). Since z_D = r_D on Dirichlet rows, the Dirichlet
 * columns are eliminated: hypre gets only the non-Dirichlet block A_II and the right-hand side
 * S (r_I - L_ID r_D). That is the same z, and it keeps the boundary values out of the coarse
 * grids (they are not unknowns) and A_II symmetric whenever the low-order weights are. */
#include "solve.h"

#include <stdio.h>
#include <string.h>

#ifndef PSTENCIL_HAVE_HYPRE

int pst_prec_amg(pst_prec *p, const pst_op *op, const pst_solve_opts *o, char *err)
{
    (void)op;
    (void)o;
    *p = (pst_prec){0};
    pst_set_err(err, "pstencil was built without hypre: the AMG preconditioner is unavailable");
    return PST_EINVAL;
}

void pst_prec_amg_stats(const pst_prec *p, pst_krylov_stats *st)
{
    (void)p;
    (void)st;
}

int pst_prec_amg_ready(char *err)
{
    pst_set_err(err, "pstencil was built without hypre: the AMG preconditioner is unavailable");
    return PST_EINVAL;
}

int pst_have_amg(void) { return 0; }

#else

#include <HYPRE.h>
#include <HYPRE_IJ_mv.h>
#include <HYPRE_parcsr_ls.h>
#include <HYPRE_utilities.h>
#include <limits.h>
#include <math.h>
#include <mpi.h>
#include <omp.h>
#include <stdlib.h>

/* ---- MPI and hypre's process-wide state ---------------------------------------------------- */
/* hypre is built with MPI, so MPI must be initialised before any hypre call. MPI belongs to
 * the program: pstencil never initialises or finalises it, it checks at every AMG set-up (a
 * program may finalise MPI between solves). hypre keeps process-wide state (its handle and
 * error flag): HYPRE_Init runs at every set-up (in hypre 2.26 it returns at once when hypre is
 * initialised), and pstencil never calls HYPRE_Finalize, so the library itself keeps no global
 * state. Every hypre call runs inside the named critical section pst_hypre, so concurrent
 * solves from different threads serialise their AMG work (hypre's error flag and
 * MPI_THREAD_SERIALIZED both need that). */

int pst_prec_amg_ready(char *err)
{
    int initialized = 0, finalized = 0;
    MPI_Initialized(&initialized);
    MPI_Finalized(&finalized);
    PST_CHECK(finalized, PST_EINVAL, err,
              "MPI has already been finalised: the AMG preconditioner (hypre) needs MPI; call "
              "MPI_Finalize only after the last AMG solve (docs/solving.md, \"MPI\")");
    PST_CHECK(!initialized, PST_EINVAL, err,
              "MPI is not initialised: the AMG preconditioner (hypre) needs MPI, and pstencil "
              "leaves it to the program; call MPI_Init (or MPI_Init_thread) before the first "
              "AMG solve and MPI_Finalize after the last (docs/solving.md, \"MPI\")");
    int level = MPI_THREAD_SINGLE, main_thread = 1;
    MPI_Query_thread(&level);
    MPI_Is_thread_main(&main_thread);
    PST_CHECK(!main_thread && level < MPI_THREAD_SERIALIZED, PST_EINVAL, err,
              "an AMG solve on a thread other than MPI's main thread needs MPI initialised with "
              "MPI_Init_thread(..., MPI_THREAD_SERIALIZED, ...) or higher");
    return PST_OK;
}

int pst_have_amg(void) { return 1; }

/* The mobility contrast above which the automatic proxy keeps the whole list (docs/solving.md,
 * "The AMG matrix's stencil"); below it the radius is the scheme's (pst_scheme_amg_radius). */
#define PST_AMG_CONTRAST 10.0

/* MPI checked, then hypre initialised (when it is not yet). */
static int runtime_ready(char *err)
{
    PST_TRY(pst_prec_amg_ready(err));
    int e = 0;
#pragma omp critical(pst_hypre)
    e = (int)HYPRE_Init();
    PST_CHECK(e != 0, PST_EINVAL, err, "HYPRE_Init failed (hypre error %d)", e);
    return PST_OK;
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
    long long entries;     /* of A_II, for pst_krylov_get_stats                               */
    int own;               /* 1: the scheme's own matrix, 0: the Brookshaw proxy               */
    size_t full_rows;      /* rows of the cut proxy that kept their full support              */
    double seconds;        /* of the set-up                                                   */
} amg_ctx;

/* hypre's destroy calls make MPI calls, which MPI forbids after MPI_Finalize (Open MPI aborts
 * the process): then hypre's objects are left allocated and only pstencil's memory is freed. */
static void amg_free(amg_ctx *c)
{
    if (!c)
        return;
    int finalized = 0;
    MPI_Finalized(&finalized);
    if (!finalized && (c->amg || c->A || c->B || c->X)) {
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

/* What the set-up holds only until hypre has its matrix. */
typedef struct {
    pst_csr a;             /* the low-order matrix                                            */
    int64_t *aoff;         /* offsets of the AMG rows' entries (m + 1)                        */
    HYPRE_Int *ncols;      /* entries per AMG row (m)                                         */
    HYPRE_BigInt *cols;    /* the AMG matrix's columns and values                             */
    double *vals;
} amg_build;

static void build_free(amg_build *t)
{
    pst_csr_free(&t->a);
    pst_free(t->aoff);
    pst_free(t->ncols);
    pst_free(t->cols);
    pst_free(t->vals);
    *t = (amg_build){0};
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
static int hypre_setup(amg_ctx *c, int dim, const pst_solve_opts *o, amg_build *t, char *err)
{
    HYPRE_Int *ncols = t->ncols;
    const HYPRE_BigInt *cols = t->cols;
    const double *vals = t->vals;
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
    build_free(t); /* hypre holds its copy now: a lower peak for the coarsening */
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
    /* Coarsening, interpolation and its truncation: amg_coarsen, amg_interp, amg_pmax, the
     * defaults chosen from the measured table (docs/solving.md, "hypre's coarsening and
     * interpolation"). The option values index these hypre codes. */
    static const HYPRE_Int coarsen_type[] = {10, 8, 6}; /* HMIS, PMIS, Falgout */
    static const HYPRE_Int interp_type[] = {6, 0}; /* extended+i, classical modified */
    HYPRE_BoomerAMGSetCoarsenType(c->amg, coarsen_type[o->amg_coarsen]);
    HYPRE_BoomerAMGSetInterpType(c->amg, interp_type[o->amg_interp]);
    HYPRE_BoomerAMGSetPMaxElmts(c->amg, o->amg_pmax);
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
    /* Aggressive coarsening on the first amg_aggressive levels (multipass interpolation there):
     * half the set-up for 4-10 more iterations in the measured table, so off by default. */
    HYPRE_BoomerAMGSetAggNumLevels(c->amg, o->amg_aggressive);
    HYPRE_BoomerAMGSetStrongThreshold(c->amg, o->amg_strong > 0 ? o->amg_strong
                                              : dim == 3     ? 0.5
                                                             : 0.25);
    e = HYPRE_GetError();
    if (!e)
        e = HYPRE_BoomerAMGSetup(c->amg, c->pA, c->pB, c->pX);
    if (e)
        return hypre_failure(err, "BoomerAMGSetup", e);
    return PST_OK;
}

/* ---- set-up ------------------------------------------------------------------------------- */

/* The largest ratio max / min over the particles of a mobility component (1 without one). */
static double mobility_contrast(const pst_cloud *c)
{
    double worst = 1;
    for (int a = 0; a < c->mob_ncomp; ++a) {
        double lo = INFINITY, hi = 0;
#pragma omp parallel for schedule(static) reduction(min : lo) reduction(max : hi)
        for (size_t i = 0; i < c->n; ++i) {
            lo = fmin(lo, c->mob[a][i]);
            hi = fmax(hi, c->mob[a][i]);
        }
        worst = fmax(worst, lo > 0 ? hi / lo : INFINITY);
    }
    return worst;
}

/* The proxy's radius in h: amg_radius, or for the automatic choice (< 0) the measured default,
 * except where the mobility varies more than tenfold: there the long pairs of the scheme couple
 * cells across a low-mobility neighbour, and a proxy without them stalls (SPE10: 57 iterations
 * with the whole list, no convergence in 3000 with the cut one). */
static double proxy_radius(const pst_op *op, double asked)
{
    if (asked >= 0)
        return asked;
    return mobility_contrast(op->cloud) > PST_AMG_CONTRAST ? 0
                                                           : pst_scheme_amg_radius(op->scheme->name);
}

int pst_amg_low_order(const pst_op *op, double amg_radius, int own, pst_csr *a,
                      size_t *full_rows, char *err)
{
    *full_rows = 0;
    double support = pst_nlist_support(op->nl), radius = proxy_radius(op, amg_radius);
    double cut = radius > 0 && radius < support ? radius / support : 1;
    PST_CHECK(own && op->half, PST_EINVAL, err,
              "the scheme's own AMG matrix needs the whole neighbour list, and the operator uses "
              "a half list (pst_op_use_half_list): use the Brookshaw matrix");
    if (own || (strcmp(op->scheme->name, "brookshaw") == 0 && cut == 1 && !op->half)) {
        int st = pst_op_assemble(op, a);
        PST_CHECK(st != PST_OK, st, err, "cannot assemble the AMG matrix of %zu rows", op->n);
        return PST_OK;
    }
    pst_nlist *list = NULL;
    if (cut < 1 || op->half) /* a half list's cut is whole, even at cut 1 */
        PST_TRY(pst_nlist_cut(&list, op->cloud, op->nl, cut, full_rows, err));
    pst_op_opts o = op->opts;
    o.scheme = "brookshaw";
    o.kernel = (int)op->kernel;
    o.variant = 0;
    o.progress.fn = NULL; /* the proxy is part of the solve's set-up, not a call of the user's */
    pst_op *brookshaw = NULL;
    int st = pst_op_create(&brookshaw, op->cloud, list ? list : op->nl, &o, err);
    if (st == PST_OK) {
        st = pst_op_assemble(brookshaw, a);
        if (st != PST_OK)
            pst_set_err(err, "cannot assemble the AMG matrix of %zu rows", op->n);
    }
    pst_op_destroy(brookshaw);
    pst_nlist_destroy(list);
    return st;
}

/* The AMG unknowns (the non-Dirichlet rows, in row order), both maps and the per-row arrays. */
static int amg_layout(amg_ctx *c, const uint8_t *kind, amg_build *t, char *err)
{
    const size_t n = c->n;
    c->map = pst_alloc(n * sizeof *c->map);
    PST_CHECK_ALLOC(c->map, err, "cannot allocate the AMG matrix of %zu rows", n);
    HYPRE_Int m = 0;
    for (size_t i = 0; i < n; ++i)
        c->map[i] = kind[i] == PST_DIRICHLET ? -1 : m++;
    c->m = m;
    c->row = pst_alloc((size_t)m * sizeof *c->row);
    c->doff = pst_alloc(((size_t)m + 1) * sizeof *c->doff);
    t->aoff = pst_alloc(((size_t)m + 1) * sizeof *t->aoff);
    c->diag = pst_alloc((size_t)m * sizeof *c->diag);
    c->sign = pst_alloc((size_t)m * sizeof *c->sign);
    c->idx = pst_alloc((size_t)m * sizeof *c->idx);
    c->b = pst_alloc((size_t)m * sizeof *c->b);
    c->x = pst_alloc((size_t)m * sizeof *c->x);
    t->ncols = pst_alloc((size_t)m * sizeof *t->ncols);
    PST_CHECK_ALLOC(c->row && c->doff && t->aoff && c->diag && c->sign && c->idx && c->b &&
                        c->x && t->ncols,
                    err, "cannot allocate the AMG matrix of %zu rows", n);
    for (size_t i = 0; i < n; ++i)
        if (c->map[i] >= 0)
            c->row[c->map[i]] = i;
    return PST_OK;
}

/* Count each AMG row's entries: Dirichlet columns go to the elimination, exact zeros off the
 * diagonal are dropped (they would only enlarge the strength graph). This pass and the fill
 * stream the assembled matrix once each: memory-bound, like an apply. */
static int count_entries(amg_ctx *c, amg_build *t, char *err)
{
    const HYPRE_Int m = c->m;
    const pst_csr *a = &t->a;
    int64_t *aoff = t->aoff;
#pragma omp parallel for schedule(static)
    for (HYPRE_Int k = 0; k < m; ++k) {
        size_t i = c->row[k];
        int64_t nd = 0, na = 0;
        for (int64_t q = a->rowptr[i]; q < a->rowptr[i + 1]; ++q) {
            if (c->map[a->col[q]] < 0)
                nd += a->val[q] != 0;
            else
                na += a->col[q] == i || a->val[q] != 0;
        }
        c->doff[k + 1] = nd;
        aoff[k + 1] = na;
        c->idx[k] = k;
    }
    c->doff[0] = aoff[0] = 0;
    for (HYPRE_Int k = 0; k < m; ++k) {
        c->doff[k + 1] += c->doff[k];
        aoff[k + 1] += aoff[k];
        t->ncols[k] = (HYPRE_Int)(aoff[k + 1] - aoff[k]);
    }
    PST_CHECK(aoff[m] > INT_MAX, PST_EINVAL, err,
              "%lld AMG matrix entries exceed hypre's 32-bit indices", (long long)aoff[m]);
    c->dcol = pst_alloc((size_t)c->doff[m] * sizeof *c->dcol);
    c->dval = pst_alloc((size_t)c->doff[m] * sizeof *c->dval);
    t->cols = pst_alloc((size_t)aoff[m] * sizeof *t->cols);
    t->vals = pst_alloc((size_t)aoff[m] * sizeof *t->vals);
    PST_CHECK_ALLOC(c->dcol && c->dval && t->cols && t->vals, err,
                    "cannot allocate the AMG matrix of %zu rows", c->n);
    return PST_OK;
}

/* Fill A = S L row by row (and the Dirichlet couplings); a row without a positive diagonal or
 * with a non-finite entry is refused, naming the first such row. */
static int fill_entries(amg_ctx *c, amg_build *t, const pst_op *op, char *err)
{
    const HYPRE_Int m = c->m;
    const pst_csr *a = &t->a;
    const uint8_t *kind = op->kind;
    size_t bad_row = SIZE_MAX;
#pragma omp parallel for schedule(static)
    for (HYPRE_Int k = 0; k < m; ++k) {
        size_t i = c->row[k];
        int64_t pd = c->doff[k], pa = t->aoff[k];
        double d = 0, sg = kind[i] == PST_INTERIOR ? -1.0 : 1.0;
        c->sign[k] = sg;
        int finite = 1;
        for (int64_t q = a->rowptr[i]; q < a->rowptr[i + 1]; ++q) {
            double v = a->val[q];
            finite &= isfinite(v);
            HYPRE_Int j = c->map[a->col[q]];
            if (j < 0) {
                if (v != 0) {
                    c->dcol[pd] = a->col[q];
                    c->dval[pd++] = v;
                }
            } else if (a->col[q] == i || v != 0) {
                t->cols[pa] = j;
                t->vals[pa++] = sg * v;   /* A = S L */
                if (a->col[q] == i)
                    d = sg * v;
            }
        }
        c->diag[k] = d;
        if (!finite || !(d > 0)) {
#pragma omp critical(pst_amg_bad_row)
            bad_row = i < bad_row ? i : bad_row;   /* the first such row: thread-independent */
        }
    }
    PST_CHECK(bad_row != SIZE_MAX, PST_ENUMERIC, err,
              "AMG matrix row %zu (particle id %lld) has diagonal %g or a non-finite entry: "
              "BoomerAMG needs a positive diagonal (the Brookshaw source always has one when "
              "every row has neighbours)",
              bad_row, (long long)op->cloud->id[bad_row], c->diag[c->map[bad_row]] + 0.0);
    return PST_OK;
}

/* The preconditioner on the scheme's own matrix (own = 1) or the Brookshaw proxy. */
static int prec_amg_on(pst_prec *p, const pst_op *op, const pst_solve_opts *o, int own,
                       char *err)
{
    double t0 = omp_get_wtime();
    amg_build t = {0};
    size_t full_rows;
    PST_TRY(pst_amg_low_order(op, o->amg_radius, own, &t.a, &full_rows, err));
    int st = PST_OK;
    amg_ctx *c = calloc(1, sizeof *c);
    PST_CHECK_GOTO(!c, st, PST_ENOMEM, fail, err, "cannot allocate the AMG matrix of %zu rows",
                   op->n);
    c->n = op->n;
    c->full_rows = full_rows;
    c->own = own;
    PST_TRY_GOTO(st, amg_layout(c, op->kind, &t, err), fail);
    PST_TRY_GOTO(st, count_entries(c, &t, err), fail);
    PST_TRY_GOTO(st, fill_entries(c, &t, op, err), fail);
    pst_csr_free(&t.a);   /* before hypre builds its copy: a lower peak */
    c->entries = c->m > 0 ? (long long)t.aoff[c->m] : 0;
    if (c->m > 0) {
#pragma omp critical(pst_hypre)
        {
            st = hypre_setup(c, op->dim, o, &t, err);
            HYPRE_ClearAllErrors();
        }
        if (st != PST_OK)
            goto fail;
    }
    build_free(&t);
    c->seconds = omp_get_wtime() - t0;
    p->lin = (pst_linop){.n = op->n, .apply = amg_apply, .ctx = c};
    p->destroy = amg_destroy;
    return PST_OK;

fail:
    build_free(&t);
    amg_free(c);
    return st;
}

int pst_prec_amg(pst_prec *p, const pst_op *op, const pst_solve_opts *o, char *err)
{
    *p = (pst_prec){0};
    PST_TRY(pst_solve_check_opts(o, NULL, err));
    PST_CHECK(op->n > (size_t)INT_MAX, PST_EINVAL, err,
              "%zu particles exceed hypre's 32-bit indices", op->n);
    PST_TRY(runtime_ready(err));
    int automatic = o->amg_source == PST_AMG_AUTO;
    /* AUTO takes the scheme's own matrix only where the whole list is there to assemble it */
    int own = o->amg_source == PST_AMG_OWN || (automatic && op->scheme->amg_own && !op->half);
    int st = prec_amg_on(p, op, o, own, err);
    /* AUTO's own matrix is not an M-matrix: on a rough cloud a row may lose its positive
     * diagonal (lsmps on a free surface), and then the proxy, which always has one, serves. */
    if (st == PST_ENUMERIC && own && automatic) {
        if (err)
            err[0] = '\0';
        st = prec_amg_on(p, op, o, 0, err);
    }
    return st;
}

void pst_prec_amg_stats(const pst_prec *p, pst_krylov_stats *st)
{
    const amg_ctx *c = p->lin.ctx;
    if (!c)
        return;
    st->amg_entries = c->entries;
    st->amg_full_rows = c->full_rows;
    st->amg_setup_seconds = c->seconds;
    st->amg_own = c->own;
}

#endif
