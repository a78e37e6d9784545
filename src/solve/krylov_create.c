/* The reusable solver's set-up (docs/solving.md, "A reusable solver"): the checks of a
 * request, the choice of method, CG's symmetric scaling, the preconditioner and the Krylov
 * workspace, built once per handle. */
#include "solve.h"

#include <math.h>
#include <stdlib.h>

const char *pst_solver_label(int s)
{
    static const char *const names[] = {"auto", "CG", "GMRES", "BiCGSTAB"};
    return s >= 0 && s <= PST_SOLVER_BICGSTAB ? names[s] : "unknown";
}

int pst_solve_check_opts(const pst_solve_opts *o, const pst_op *op, char *err)
{
    PST_CHECK(o->solver < PST_SOLVER_AUTO || o->solver > PST_SOLVER_BICGSTAB, PST_EINVAL, err,
              "unknown solver %d (AUTO, CG, GMRES or BICGSTAB)", o->solver);
    PST_CHECK(o->precond < PST_PREC_NONE || o->precond > PST_PREC_AMG, PST_EINVAL, err,
              "unknown preconditioner %d (NONE, JACOBI or AMG)", o->precond);
    PST_CHECK(o->amg_source < PST_AMG_BROOKSHAW || o->amg_source > PST_AMG_AUTO, PST_EINVAL,
              err, "unknown AMG source %d (BROOKSHAW, OWN or AUTO)", o->amg_source);
    PST_CHECK(o->amg_coarsen < PST_AMG_HMIS || o->amg_coarsen > PST_AMG_FALGOUT, PST_EINVAL,
              err, "unknown AMG coarsening %d (HMIS, PMIS or FALGOUT)", o->amg_coarsen);
    PST_CHECK(o->amg_interp < PST_AMG_EXT_I || o->amg_interp > PST_AMG_CLASSICAL, PST_EINVAL,
              err, "unknown AMG interpolation %d (EXT_I or CLASSICAL)", o->amg_interp);
    PST_CHECK(o->amg_pmax < 0 || o->amg_pmax > 100, PST_EINVAL, err,
              "amg_pmax must be in [0, 100] (interpolation entries per row, 0 = no truncation; "
              "got %d)",
              o->amg_pmax);
    PST_CHECK(!(o->amg_radius >= -1 && o->amg_radius <= 1e3), PST_EINVAL, err,
              "amg_radius must be in [-1, 1000] (in units of h; 0 for the whole list, -1 for "
              "the automatic choice; got %g)",
              o->amg_radius);
    PST_CHECK(o->amg_reuse < 0 || o->amg_reuse > 1000, PST_EINVAL, err,
              "amg_reuse must be in [0, 1000] (refreshes an AMG hierarchy serves; got %d)",
              o->amg_reuse);
    PST_CHECK(o->amg_aggressive < 0 || o->amg_aggressive > 10, PST_EINVAL, err,
              "amg_aggressive must be in [0, 10] (levels of aggressive coarsening; got %d)",
              o->amg_aggressive);
    PST_CHECK(!(o->amg_strong >= 0 && o->amg_strong < 1), PST_EINVAL, err,
              "amg_strong must be in [0, 1) (0: by dimension; got %g)", o->amg_strong);
    PST_CHECK(o->restart < 1 || o->restart > 100000 || o->max_iter < 0, PST_EINVAL, err,
              "restart must be in [1, 100000] and max_iter >= 0 (got %d, %d)", o->restart,
              o->max_iter);
    PST_CHECK(!(o->rtol > 0 && o->rtol < 1), PST_EINVAL, err, "rtol must be in (0, 1) (got %g)",
              o->rtol);
    PST_CHECK(op && o->stored && !pst_op_has_store(op), PST_EINVAL, err,
              "stored = 1 needs the weights: call pst_op_store(op) first");
    return PST_OK;
}

int pst_solve_check_finite(const pst_op *op, size_t n, const double *b, const double *u,
                           char *err)
{
    const uint8_t *kind = op ? op->kind : NULL;
    for (size_t i = 0; i < n; ++i) {
        int unknown = !kind || kind[i] != PST_DIRICHLET;
        PST_CHECK(!isfinite(b[i]) || (unknown && !isfinite(u[i])), PST_EINPUT, err,
                  "%s[%zu] is not finite", isfinite(b[i]) ? "u" : "b", i);
    }
    return PST_OK;
}

/* ---- the handle ----------------------------------------------------------------------------- */

/* A handle with its options and operator, the rest empty. */
static int handle_new(pst_krylov **out, const pst_linop *A, const pst_solve_opts *o, char *err)
{
    pst_krylov *s = calloc(1, sizeof *s);
    PST_CHECK_ALLOC(s, err, "cannot allocate a solver handle");
    s->o = *o;
    s->A = *A;
    s->k.n = A->n;
    s->k.max_iter = o->max_iter;
    s->k.restart = o->restart;
    s->k.monitor = o->monitor;
    s->k.monitor_ctx = o->monitor_ctx;
    *out = s;
    return PST_OK;
}

void pst_krylov_destroy(pst_krylov *s)
{
    if (!s)
        return;
    pst_prec_free(&s->prec);
    pst_ksp_free(&s->k);
    pst_free(s->S);
    pst_free(s->bp);
    pst_free(s->x);
    free(s);
}

/* The method's workspace, and for an engine operator b' and the iterate. */
static int handle_workspace(pst_krylov *s, char *err)
{
    s->k.A = &s->A;
    PST_TRY(pst_ksp_alloc(&s->k, s->solver, err));
    if (!s->op)
        return PST_OK;
    size_t n = s->A.n;
    s->bp = pst_alloc(n * sizeof *s->bp);
    s->x = pst_alloc(n * sizeof *s->x);
    PST_CHECK_ALLOC(s->bp && s->x, err, "cannot allocate the solver's vectors for %zu particles",
                    n);
    return PST_OK;
}

/* ---- engine operators ----------------------------------------------------------------------- */

/* The symmetric scaling of docs/schemes/cb.md ("Symmetry") exists for Brookshaw and corrected
 * Brookshaw with the radial G1 gradient (F_IJ symmetric) and no Neumann (flux) rows. */
static int symmetrisable(const pst_op *op, size_t neumann)
{
    return pst_scheme_symmetrisable(op->scheme) && op->opts.gradient == PST_GRAD_G1 &&
           neumann == 0;
}

/* The method for op: AUTO resolved, CG refused where the scaling does not exist, and no
 * Dirichlet row refused (the constants would be in L's nullspace) unless the mean is fixed,
 * which in turn needs a problem without Dirichlet rows and a method other than CG. */
static int choose_method(const pst_op *op, const pst_solve_opts *o, int *solver, char *err)
{
    size_t ndir = 0, nneu = 0;
    for (size_t i = 0; i < op->n; ++i) {
        ndir += op->kind[i] == PST_DIRICHLET;
        nneu += op->kind[i] == PST_NEUMANN;
    }
    int asked = o->solver;
    PST_CHECK(ndir == 0 && !o->fix_mean, PST_EINVAL, err,
              "no Dirichlet particle: with only interior and Neumann rows L u = b determines u "
              "only up to a constant (L has the constants in its nullspace); mark at least one "
              "particle Dirichlet, or fix the mean (fix_mean)");
    PST_CHECK(ndir > 0 && o->fix_mean, PST_EINVAL, err,
              "fix_mean is for problems without Dirichlet rows; this one has %zu, which "
              "already fix the constant",
              ndir);
    PST_CHECK(o->fix_mean && asked == PST_SOLVER_CG, PST_EINVAL, err,
              "fix_mean solves L + c 1 V^T, which is not symmetric: use GMRES or BiCGSTAB");
    PST_CHECK(asked == PST_SOLVER_CG && !symmetrisable(op, nneu), PST_EINVAL, err,
              "CG needs a symmetrisable operator (brookshaw or cb, gradient G1, no Neumann "
              "rows); %s%s is not: use GMRES or BiCGSTAB",
              op->scheme->name, nneu ? " with Neumann rows" : "");
    *solver = asked != PST_SOLVER_AUTO               ? asked
              : symmetrisable(op, nneu) && !o->fix_mean ? PST_SOLVER_CG
                                                        : PST_SOLVER_GMRES;
    return PST_OK;
}

/* S = -V/s on non-Dirichlet rows (V/s > 0 checked), 1 on Dirichlet rows. */
static int cg_scaling(const pst_op *op, double *S, char *err)
{
    const double *V = pst_cloud_volume_const(op->cloud);
    const uint8_t *kind = op->kind;
    pst_op_scale(op, S);
    for (size_t i = 0; i < op->n; ++i) {
        if (kind[i] == PST_DIRICHLET) {
            S[i] = 1.0;
            continue;
        }
        double v = V[i] / S[i];
        PST_CHECK(!(v > 0) || !isfinite(v), PST_EINVAL, err,
                  "CG needs V_I / s_I > 0 for the symmetric scaling, but particle %zu has "
                  "V = %g, s = %g: use GMRES",
                  i, V[i], S[i]);
        S[i] = -v;
    }
    return PST_OK;
}

/* CG's symmetric scaling of the operator's current weights (S allocated once). */
static int scaling(pst_krylov *s, char *err)
{
    if (s->solver != PST_SOLVER_CG)
        return PST_OK;
    if (!s->S)
        s->S = pst_alloc(s->A.n * sizeof *s->S);
    PST_CHECK_ALLOC(s->S, err, "cannot allocate the solver's vectors for %zu particles", s->A.n);
    return cg_scaling(s->op, s->S, err);
}

/* The preconditioner of o->precond from the operator's current weights, replacing any earlier
 * one (*stop set when it fails). */
static int precond_setup(pst_krylov *s, int *stop, char *err)
{
    pst_prec_free(&s->prec);
    s->k.M = NULL;
    if (s->o.precond == PST_PREC_NONE)
        return PST_OK;
    s->precond_setups++;
    s->amg_age = s->amg_first_iters = 0;
    int st = s->o.precond == PST_PREC_JACOBI ? pst_prec_jacobi(&s->prec, &s->A, err)
                                             : pst_prec_amg(&s->prec, s->op, &s->o, err);
    if (st != PST_OK)
        *stop = PST_STOP_PRECOND_SETUP;
    s->k.M = st == PST_OK ? &s->prec.lin : NULL;
    return st;
}

/* Workspace, fix_mean's operator, CG's scaling, then the preconditioner. */
static int op_setup(pst_krylov *s, int *stop, char *err)
{
    PST_TRY(handle_workspace(s, err));
    if (s->o.fix_mean)
        PST_TRY(pst_fix_mean_wrap(s, err));
    PST_TRY(scaling(s, err));
    return precond_setup(s, stop, err);
}

/* The AMG reuse rule of pst_krylov_refresh: the hierarchy has served fewer than amg_reuse
 * refreshes and the last solve needed at most 1.5x the iterations of the first one after its
 * set-up (a hierarchy of the old positions that slows the solves down is set up again). */
static int amg_still_good(const pst_krylov *s)
{
    return s->o.precond == PST_PREC_AMG && s->k.M && s->amg_age < s->o.amg_reuse &&
           !(s->amg_first_iters > 0 && 2 * s->last_iters > 3 * s->amg_first_iters);
}

int pst_krylov_refresh(pst_krylov *s, char *err)
{
    PST_CHECK(!s, PST_EINVAL, err, "pst_krylov_refresh needs a handle");
    s->unusable = 1; /* until every step below succeeds */
    if (!s->op) { /* a user operator whose values changed behind the same apply */
        s->refreshes++;
        int stop;
        if (!s->user_precond)
            PST_TRY(precond_setup(s, &stop, err));
        s->unusable = 0;
        return PST_OK;
    }
    PST_CHECK(!pst_op_has_rows(s->op), PST_EINVAL, err,
              "pst_krylov_refresh: the operator has no rows (its refresh failed)");
    PST_CHECK(s->o.stored && !pst_op_has_store(s->op), PST_EINVAL, err,
              "pst_krylov_refresh: the handle solves with the stored weights; store them again");
    s->refreshes++;
    if (s->o.fix_mean)
        PST_TRY(pst_fix_mean_update(s, err));
    PST_TRY(scaling(s, err));
    if (amg_still_good(s)) {
        s->amg_age++;
        s->amg_reuses++;
    } else {
        int stop;
        PST_TRY(precond_setup(s, &stop, err));
    }
    s->unusable = 0;
    return PST_OK;
}

int pst_krylov_build(pst_krylov **out, const pst_op *op, const pst_solve_opts *o, int *solver,
                     int *stop, char *err)
{
    pst_solve_opts defaults;
    if (!o) {
        pst_solve_defaults(&defaults);
        o = &defaults;
    }
    *solver = o->solver;
    *stop = PST_STOP_NONE;
    if (out)
        *out = NULL;
    PST_CHECK(!out || !op, PST_EINVAL, err, "pst_krylov_create needs an operator and a handle");
    PST_TRY(pst_solve_check_opts(o, op, err));
    pst_linop A;
    PST_TRY(pst_op_linop(op, o->stored, &A, err));
    PST_TRY(choose_method(op, o, solver, err));
    pst_krylov *s;
    PST_TRY(handle_new(&s, &A, o, err));
    s->op = op;
    s->solver = *solver;
    int st = op_setup(s, stop, err);
    if (st != PST_OK) {
        pst_krylov_destroy(s);
        return st;
    }
    *out = s;
    return PST_OK;
}

int pst_krylov_create(pst_krylov **out, const pst_op *op, const pst_solve_opts *o, char *err)
{
    int solver, stop;
    return pst_krylov_build(out, op, o, &solver, &stop, err);
}

/* ---- user operators ------------------------------------------------------------------------- */

/* A user linop is usable: rows and an apply. */
static int check_linop(const pst_linop *A, const char *what, char *err)
{
    PST_CHECK(!A, PST_EINVAL, err, "no %s: pass a pst_linop", what);
    PST_CHECK(A->n == 0, PST_EINVAL, err, "the %s has n = 0 rows", what);
    PST_CHECK(!A->apply, PST_EINVAL, err, "the %s has no apply function (apply is NULL)", what);
    return PST_OK;
}

int pst_krylov_create_linop(pst_krylov **out, const pst_linop *A, const pst_linop *M,
                            const pst_solve_opts *o, char *err)
{
    pst_solve_opts defaults;
    if (!o) {
        pst_solve_defaults(&defaults);
        o = &defaults;
    }
    PST_CHECK(!out, PST_EINVAL, err, "pst_krylov_create_linop needs a place for the handle");
    *out = NULL;
    PST_TRY(check_linop(A, "operator", err));
    if (M) {
        PST_TRY(check_linop(M, "preconditioner", err));
        PST_CHECK(M->n != A->n, PST_EINVAL, err,
                  "the preconditioner has %zu rows and the operator %zu: they must match",
                  M->n, A->n);
    }
    PST_TRY(pst_solve_check_opts(o, NULL, err));
    PST_CHECK(o->fix_mean, PST_EINVAL, err,
              "fix_mean needs an engine operator (pst_krylov_create): its volumes weight the "
              "mean");
    PST_CHECK(!M && o->precond == PST_PREC_AMG, PST_EINVAL, err,
              "the AMG preconditioner needs an engine operator (pst_krylov_create); for a user "
              "operator give a preconditioner, or use JACOBI (from its diagonal) or NONE");
    pst_krylov *s;
    PST_TRY(handle_new(&s, A, o, err));
    s->solver = o->solver == PST_SOLVER_AUTO ? PST_SOLVER_GMRES : o->solver;
    int st = handle_workspace(s, err);
    if (st == PST_OK && M) {
        s->user_M = *M;
        s->k.M = &s->user_M;
        s->user_precond = 1;
    } else if (st == PST_OK && o->precond == PST_PREC_JACOBI) {
        s->precond_setups++;
        st = pst_prec_jacobi(&s->prec, &s->A, err);
        s->k.M = &s->prec.lin;
    }
    if (st != PST_OK) {
        pst_krylov_destroy(s);
        return st;
    }
    *out = s;
    return PST_OK;
}

void pst_krylov_get_stats(const pst_krylov *s, pst_krylov_stats *st)
{
    *st = (pst_krylov_stats){0};
    if (!s)
        return;
    st->n = s->A.n;
    st->solver = s->solver;
    st->precond = s->user_precond ? PST_PREC_NONE : s->o.precond;
    st->user_precond = s->user_precond;
    st->precond_setups = s->precond_setups;
    st->solves = s->solves;
    st->refreshes = s->refreshes;
    st->amg_reuses = s->amg_reuses;
    if (st->precond == PST_PREC_AMG)
        pst_prec_amg_stats(&s->prec, st);
}
