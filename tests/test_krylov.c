/* The operator contract and the reusable solver on user operators (docs/solving.md): a 2D
 * finite-difference Laplacian written here, with a known discrete solution, solved by CG,
 * GMRES and BiCGSTAB without a preconditioner, with Jacobi from its diagonal and with a user
 * symmetric Gauss-Seidel preconditioner; a handle reused for several right-hand sides; the
 * same bits for 1 and 2 threads (also for sizes that end inside a reduction block); GMRES's
 * second Gram-Schmidt pass where the first cancels; every stop reason provoked; bad input
 * refused clearly; an engine operator through pst_op_linop. */
#include "check.h"
#include "pstencil.h"
#include "solve.h"
#include "support.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

/* ---- user operators ------------------------------------------------------------------------- */

/* -Laplacian, 5-point, on the m x m interior points of the unit square with spacing
 * h = 1 / (m + 1) and u = 0 outside: SPD. sign = -1 gives the Laplacian itself (negative
 * definite). nan_from > 0: every apply from call number nan_from on returns NaN in row 0. */
typedef struct {
    int m;
    double sign;
    int calls, nan_from;
} grid;

static double at(const grid *g, const double *x, int i, int j)
{
    return i < 0 || j < 0 || i >= g->m || j >= g->m ? 0.0 : x[(size_t)j * (size_t)g->m + (size_t)i];
}

static void lap_apply(void *ctx, const double *x, double *y)
{
    grid *g = ctx;
    double h2inv = (g->m + 1.0) * (g->m + 1.0);
    int m = g->m;
#pragma omp parallel for schedule(static)
    for (int j = 0; j < m; ++j)
        for (int i = 0; i < m; ++i)
            y[(size_t)j * (size_t)m + (size_t)i] =
                g->sign * h2inv *
                (4 * at(g, x, i, j) - at(g, x, i - 1, j) - at(g, x, i + 1, j) -
                 at(g, x, i, j - 1) - at(g, x, i, j + 1));
    if (g->nan_from > 0 && ++g->calls >= g->nan_from)
        y[0] = NAN;
}

static int lap_diagonal(void *ctx, double *d)
{
    grid *g = ctx;
    size_t n = (size_t)g->m * (size_t)g->m;
    for (size_t i = 0; i < n; ++i)
        d[i] = g->sign * 4 * (g->m + 1.0) * (g->m + 1.0);
    return PST_OK;
}

static int failing_diagonal(void *ctx, double *d)
{
    (void)ctx, (void)d;
    return PST_ENUMERIC;
}

/* Symmetric Gauss-Seidel for the SPD grid: z = (D + U)^-1 D (D + L)^-1 r, lexicographic. */
static void sgs_apply(void *ctx, const double *r, double *z)
{
    const grid *g = ctx;
    int m = g->m;
    double d = 4 * (m + 1.0) * (m + 1.0), off = -(m + 1.0) * (m + 1.0);
    for (int j = 0; j < m; ++j)
        for (int i = 0; i < m; ++i) {
            size_t k = (size_t)j * (size_t)m + (size_t)i;
            z[k] = (r[k] - off * (at(g, z, i - 1, j) + at(g, z, i, j - 1))) / d;
        }
    for (int j = m - 1; j >= 0; --j)
        for (int i = m - 1; i >= 0; --i) {
            size_t k = (size_t)j * (size_t)m + (size_t)i;
            z[k] = z[k] - off * (at(g, z, i + 1, j) + at(g, z, i, j + 1)) / d;
        }
}

static void zero_apply(void *ctx, const double *r, double *z)
{
    size_t n = *(const size_t *)ctx;
    (void)r;
    memset(z, 0, n * sizeof *z);
}

/* Pairs of rows rotated by 90 degrees: r . A r = 0 exactly for every r. */
static void rotation_apply(void *ctx, const double *x, double *y)
{
    size_t n = *(const size_t *)ctx;
    for (size_t i = 0; i + 1 < n; i += 2) {
        y[i] = -x[i + 1];
        y[i + 1] = x[i];
    }
}

static pst_linop grid_linop(grid *g)
{
    return (pst_linop){.n = (size_t)g->m * (size_t)g->m, .apply = lap_apply,
                       .diagonal = lap_diagonal, .ctx = g};
}

/* ---- helpers -------------------------------------------------------------------------------- */

static const char *const method_name[4] = {"auto", "CG", "GMRES", "BiCGSTAB"};

/* A discrete solution u* = x (1 - x) y (1 - y) (1 + x + 2 y) e^(seed y / 2) (no eigenvector of
 * the grid, so no Krylov method finds it in one step), and b = A u*. */
static void manufacture(grid *g, int seed, double *ustar, double *b)
{
    int m = g->m;
    for (int j = 0; j < m; ++j)
        for (int i = 0; i < m; ++i) {
            double x = (i + 1.0) / (m + 1.0), y = (j + 1.0) / (m + 1.0);
            ustar[(size_t)j * (size_t)m + (size_t)i] =
                16 * x * (1 - x) * y * (1 - y) * (1 + x + 2 * y) * exp(0.5 * seed * y);
        }
    lap_apply(g, ustar, b);
}

static double rel_err(const double *u, const double *v, size_t n)
{
    double num = 0, den = 0;
    for (size_t i = 0; i < n; ++i) {
        num += (u[i] - v[i]) * (u[i] - v[i]);
        den += v[i] * v[i];
    }
    return sqrt(num / den);
}

/* ||b - A u|| / ||b||, computed here, not by the library. */
static double true_residual(grid *g, const double *b, const double *u, size_t n)
{
    double *y = malloc(n * sizeof *y), num = 0, den = 0;
    lap_apply(g, u, y);
    for (size_t i = 0; i < n; ++i) {
        num += (b[i] - y[i]) * (b[i] - y[i]);
        den += b[i] * b[i];
    }
    free(y);
    return sqrt(num / den);
}

static pst_solve_opts opts(int solver, int precond)
{
    pst_solve_opts o;
    pst_solve_defaults(&o);
    o.solver = solver;
    o.precond = precond;
    o.rtol = 1e-10;
    o.history = 1;
    return o;
}

/* One solve of A u = b from u = 0 through a fresh handle; the result in *r. */
static int solve_once(const pst_linop *A, const pst_linop *M, const pst_solve_opts *o,
                      const double *b, double *u, pst_solve_result *r)
{
    pst_krylov *s = NULL;
    char err[PST_ERRLEN] = "";
    memset(u, 0, A->n * sizeof *u);
    int st = pst_krylov_create_linop(&s, A, M, o, err);
    if (st != PST_OK) {
        fprintf(stderr, "create: %s\n", err);
        return st;
    }
    st = pst_krylov_solve(s, b, u, r, err);
    pst_krylov_destroy(s);
    return st;
}

/* ---- tests ---------------------------------------------------------------------------------- */

/* CG, GMRES and BiCGSTAB on the SPD grid, without a preconditioner, with Jacobi from the
 * diagonal and with the user's SGS: converged to the discrete solution; SGS needs fewer
 * iterations than none; a user Jacobi (the same map) gives the library Jacobi's bits. */
static void test_methods(void)
{
    grid g = {64, 1.0, 0, 0};
    pst_linop A = grid_linop(&g), sgs = {A.n, sgs_apply, NULL, &g};
    size_t n = A.n;
    double *ustar = malloc(n * sizeof *ustar), *b = malloc(n * sizeof *b);
    double *u = malloc(n * sizeof *u);
    manufacture(&g, 0, ustar, b);
    static const int solvers[3] = {PST_SOLVER_CG, PST_SOLVER_GMRES, PST_SOLVER_BICGSTAB};
    static const char *const pname[3] = {"none", "Jacobi", "user SGS"};
    for (int s = 0; s < 3; ++s) {
        int it[3];
        for (int p = 0; p < 3; ++p) {
            pst_solve_opts o = opts(solvers[s], p == 1 ? PST_PREC_JACOBI : PST_PREC_NONE);
            pst_solve_result r;
            CHECK_INT(solve_once(&A, p == 2 ? &sgs : NULL, &o, b, u, &r), PST_OK);
            CHECK_INT(r.stop, PST_STOP_CONVERGED);
            CHECK_INT(r.solver, solvers[s]);
            CHECK(r.converged && r.rel_residual <= 1e-10);
            CHECK(true_residual(&g, b, u, n) <= 2e-10);
            double e = rel_err(u, ustar, n);
            CHECK(e < 1e-6);
            it[p] = r.iterations;
            printf("user grid n = %zu, %-8s %-8s: %4d iterations, error %.2e\n", n,
                   method_name[solvers[s]], pname[p], r.iterations, e);
            pst_solve_result_free(&r);
        }
        CHECK(it[2] < it[0]);
    }
    free(ustar), free(b), free(u);
}

/* Two solves bit for bit: solution, iterations, stop, message and history. */
static int same_result(const pst_solve_result *a, const double *ua, const pst_solve_result *b,
                       const double *ub, size_t n)
{
    return a->iterations == b->iterations && a->stop == b->stop &&
           a->rel_residual == b->rel_residual && strcmp(a->message, b->message) == 0 &&
           a->nhistory == b->nhistory &&
           memcmp(a->history, b->history, (size_t)a->nhistory * sizeof(double)) == 0 &&
           memcmp(ua, ub, n * sizeof *ua) == 0;
}

/* One handle, three right-hand sides and initial guesses: each solve gives the bits of a fresh
 * handle's, the Jacobi diagonal is set up once, and 1 and 2 threads agree bit for bit. */
static void test_reuse_and_threads(void)
{
    grid g = {64, 1.0, 0, 0};
    pst_linop A = grid_linop(&g), sgs = {A.n, sgs_apply, NULL, &g};
    size_t n = A.n;
    double *ustar = malloc(n * sizeof *ustar), *b = malloc(n * sizeof *b);
    double *u = malloc(n * sizeof *u), *u2 = malloc(n * sizeof *u2);
    static const int solvers[3] = {PST_SOLVER_CG, PST_SOLVER_GMRES, PST_SOLVER_BICGSTAB};
    int nt = omp_get_max_threads();
    for (int s = 0; s < 3; ++s) {
        pst_solve_opts o = opts(solvers[s], PST_PREC_JACOBI);
        o.restart = 20;
        pst_krylov *h = NULL;
        char err[PST_ERRLEN] = "";
        CHECK_INT(pst_krylov_create_linop(&h, &A, s == 1 ? &sgs : NULL, &o, err), PST_OK);
        for (int rhs = 0; rhs < 3; ++rhs) {
            manufacture(&g, rhs, ustar, b);
            pst_solve_result r1, r2, rf;
            for (size_t i = 0; i < n; ++i)
                u[i] = u2[i] = 0.01 * rhs * (double)(i % 7);
            omp_set_num_threads(1);
            CHECK_INT(pst_krylov_solve(h, b, u, &r1, err), PST_OK);
            omp_set_num_threads(2);
            CHECK_INT(pst_krylov_solve(h, b, u2, &r2, err), PST_OK);
            CHECK(same_result(&r1, u, &r2, u2, n));
            for (size_t i = 0; i < n; ++i)
                u2[i] = 0.01 * rhs * (double)(i % 7);
            pst_krylov *fresh = NULL;
            CHECK_INT(pst_krylov_create_linop(&fresh, &A, s == 1 ? &sgs : NULL, &o, err), PST_OK);
            CHECK_INT(pst_krylov_solve(fresh, b, u2, &rf, err), PST_OK);
            pst_krylov_destroy(fresh);
            CHECK(same_result(&r1, u, &rf, u2, n));
            CHECK(rel_err(u, ustar, n) < 1e-6);
            pst_solve_result_free(&r1), pst_solve_result_free(&r2), pst_solve_result_free(&rf);
        }
        pst_krylov_stats st;
        pst_krylov_get_stats(h, &st);
        CHECK_INT(st.solves, 6);
        CHECK_INT(st.precond_setups, s == 1 ? 0 : 1); /* a user M needs no set-up */
        CHECK_INT(st.user_precond, s == 1);
        CHECK_INT(st.solver, solvers[s]);
        CHECK_INT(st.n, n);
        pst_krylov_destroy(h);
    }
    omp_set_num_threads(nt);
    free(ustar), free(b), free(u), free(u2);
}

/* 1 and 2 threads bit for bit on a grid of 101 x 101 = 10201 rows: five reduction blocks, the
 * last one partial and ending off the partial sums' stride. */
static void test_threads_partial_block(void)
{
    grid g = {101, 1.0, 0, 0};
    pst_linop A = grid_linop(&g);
    size_t n = A.n;
    double *ustar = malloc(n * sizeof *ustar), *b = malloc(n * sizeof *b);
    double *u1 = malloc(n * sizeof *u1), *u2 = malloc(n * sizeof *u2);
    manufacture(&g, 1, ustar, b);
    int nt = omp_get_max_threads();
    for (int s = PST_SOLVER_CG; s <= PST_SOLVER_BICGSTAB; ++s) {
        pst_solve_opts o = opts(s, PST_PREC_JACOBI);
        o.rtol = 1e-8; /* GMRES(50) needs ~1000 iterations: many restarts to compare */
        pst_solve_result r1, r2;
        omp_set_num_threads(1);
        CHECK_INT(solve_once(&A, NULL, &o, b, u1, &r1), PST_OK);
        omp_set_num_threads(2);
        CHECK_INT(solve_once(&A, NULL, &o, b, u2, &r2), PST_OK);
        CHECK(same_result(&r1, u1, &r2, u2, n));
        CHECK(true_residual(&g, b, u1, n) <= 2e-8);
        printf("n = %zu, %-8s Jacobi: %d iterations, 1 and 2 threads %s\n", n, method_name[s],
               r1.iterations, same_result(&r1, u1, &r2, u2, n) ? "identical" : "DIFFER");
        pst_solve_result_free(&r1), pst_solve_result_free(&r2);
    }
    omp_set_num_threads(nt);
    free(ustar), free(b), free(u1), free(u2);
}

/* y = d .* x: a diagonal operator. */
typedef struct {
    size_t n;
    const double *d;
} diagonal;

static void diagonal_apply(void *ctx, const double *x, double *y)
{
    const diagonal *D = ctx;
    for (size_t i = 0; i < D->n; ++i)
        y[i] = D->d[i] * x[i];
}

/* GMRES through the internal workspace on A = diag(d), b_i = 1 + 0.3 sin(1.7 i), from x = 0:
 * the iterations, the second passes, the true residual, and the worst |V_i . V_l - delta_il|
 * over the last cycle's normalised basis vectors V_1 .. V_{j-1} (V_0 holds the final residual
 * on return, V_j is not normalised when the cycle converged). x is returned in `x`. */
static double gmres_orthogonality(const diagonal *D, int restart, double rtol, double *x,
                                  int *iterations, int *second_passes, double *rel_residual)
{
    size_t n = D->n;
    pst_linop A = {n, diagonal_apply, NULL, (void *)D};
    char message[PST_ERRLEN] = "";
    pst_ksp k = {.A = &A, .n = n, .max_iter = 1000, .restart = restart, .message = message};
    double *b = malloc(n * sizeof *b), *y = malloc(n * sizeof *y);
    CHECK_INT(pst_ksp_alloc(&k, PST_SOLVER_GMRES, NULL), PST_OK);
    for (size_t i = 0; i < n; ++i) {
        b[i] = 1 + 0.3 * sin(1.7 * (double)i);
        x[i] = 0;
    }
    k.b = b, k.x = x;
    k.bnorm = sqrt(pst_ksp_dot(&k, b, b));
    k.target = rtol * k.bnorm;
    CHECK_INT(pst_ksp_gmres(&k), PST_OK);
    int last = k.iterations < restart ? k.iterations : restart;
    double worst = 0, num = 0;
    for (int i = 1; i < last; ++i)
        for (int l = i; l < last; ++l)
            worst = fmax(worst, fabs(pst_ksp_dot(&k, k.vec[i], k.vec[l]) - (i == l)));
    diagonal_apply((void *)D, x, y);
    for (size_t i = 0; i < n; ++i)
        num += (b[i] - y[i]) * (b[i] - y[i]);
    *iterations = k.iterations;
    *second_passes = k.reorthogonalised;
    *rel_residual = sqrt(num) / k.bnorm;
    printf("GMRES(%d) on 4 clusters of width 1e-9: %s; %d second passes, basis orthogonal to "
           "%.2e\n", restart, message, k.reorthogonalised, worst);
    pst_ksp_free(&k);
    free(b), free(y);
    return worst;
}

/* Eigenvalues in 4 clusters of relative width 1e-9: after 4 Arnoldi steps A M^-1 V_j lies in
 * the basis up to 1e-9 of its norm, the single pass cancels 9 digits and leaves a basis
 * orthogonal only to ~1e-5; the second pass it triggers restores orthogonality to rounding.
 * The solve converges to the true residual and gives the same bits for 1 and 2 threads. */
static void test_gmres_reorthogonalisation(void)
{
    size_t n = 10003;
    double *d = malloc(n * sizeof *d), *x1 = malloc(n * sizeof *x1), *x2 = malloc(n * sizeof *x2);
    for (size_t i = 0; i < n; ++i)
        d[i] = (double)(1 + i % 4) * (1 + 1e-9 * (double)i / (double)n);
    diagonal D = {n, d};
    int nt = omp_get_max_threads(), it1, it2, sp1, sp2;
    double res1, res2;
    omp_set_num_threads(1);
    double orth = gmres_orthogonality(&D, 40, 1e-12, x1, &it1, &sp1, &res1);
    omp_set_num_threads(2);
    gmres_orthogonality(&D, 40, 1e-12, x2, &it2, &sp2, &res2);
    omp_set_num_threads(nt);
    CHECK(sp1 >= 1);
    CHECK(orth < 1e-12);
    CHECK(res1 <= 1e-12);
    CHECK(it1 == it2 && sp1 == sp2 && res1 == res2 && memcmp(x1, x2, n * sizeof *x1) == 0);
    free(d), free(x1), free(x2);
}

/* The reason of a solve of A u = b (b = 1) from u = 0 with the given solver and restart. */
static int stop_of(const pst_linop *A, const pst_linop *M, int solver, int restart, int max_iter,
                   pst_solve_result *r)
{
    double *b = malloc(A->n * sizeof *b), *u = malloc(A->n * sizeof *u);
    for (size_t i = 0; i < A->n; ++i)
        b[i] = 1.0;
    pst_solve_opts o = opts(solver, PST_PREC_NONE);
    o.restart = restart;
    o.max_iter = max_iter;
    int st = solve_once(A, M, &o, b, u, r);
    int finite = 1;
    for (size_t i = 0; i < A->n; ++i)
        finite &= isfinite(u[i]);
    CHECK(finite); /* u is the last finite iterate on every exit */
    free(b), free(u);
    printf("%-9s stop %-15s: %s\n", method_name[solver], pst_stop_reason_name(r->stop),
           r->message);
    pst_solve_result_free(r);
    return st;
}

/* Every reason that can be provoked, for each method where it exists. */
static void test_stop_reasons(void)
{
    size_t n = 4096;
    grid g = {64, 1.0, 0, 0}, neg = {64, -1.0, 0, 0};
    pst_linop A = grid_linop(&g), N = grid_linop(&neg);
    pst_linop rot = {n, rotation_apply, NULL, &n}, zero = {n, zero_apply, NULL, &n};
    pst_solve_result r;
    for (int s = PST_SOLVER_CG; s <= PST_SOLVER_BICGSTAB; ++s) {
        /* the iteration limit */
        CHECK_INT(stop_of(&A, NULL, s, 50, 5, &r), PST_ENUMERIC);
        CHECK_INT(r.stop, PST_STOP_ITERATION_LIMIT);
        CHECK(r.iterations == 5 && strstr(r.message, "iteration limit 5"));
        /* an overflow from the third apply on: the last finite iterate is kept */
        grid bad = {64, 1.0, 0, 3};
        pst_linop B = grid_linop(&bad);
        CHECK_INT(stop_of(&B, NULL, s, 50, 100, &r), PST_ENUMERIC);
        CHECK_INT(r.stop, PST_STOP_NON_FINITE);
        CHECK(strstr(r.message, "non-finite") != NULL);
        /* a non-finite first residual */
        bad = (grid){64, 1.0, 0, 1};
        CHECK_INT(stop_of(&B, NULL, s, 50, 100, &r), PST_ENUMERIC);
        CHECK_INT(r.stop, PST_STOP_NON_FINITE);
        CHECK_INT(r.iterations, 0);
    }
    /* breakdowns: CG on a negative definite operator (p.Ap < 0) and on a rotation (p.Ap = 0);
     * BiCGSTAB on the rotation ((r^, A p) = 0); GMRES with a preconditioner that returns 0 */
    CHECK_INT(stop_of(&N, NULL, PST_SOLVER_CG, 50, 100, &r), PST_ENUMERIC);
    CHECK_INT(r.stop, PST_STOP_BREAKDOWN);
    CHECK(strstr(r.message, "p.Ap <= 0") != NULL);
    CHECK_INT(stop_of(&rot, NULL, PST_SOLVER_CG, 50, 100, &r), PST_ENUMERIC);
    CHECK_INT(r.stop, PST_STOP_BREAKDOWN);
    CHECK_INT(stop_of(&rot, NULL, PST_SOLVER_BICGSTAB, 50, 100, &r), PST_ENUMERIC);
    CHECK_INT(r.stop, PST_STOP_BREAKDOWN);
    CHECK(strstr(r.message, "(r^, A p) ~ 0") != NULL);
    CHECK_INT(stop_of(&A, &zero, PST_SOLVER_GMRES, 50, 100, &r), PST_ENUMERIC);
    CHECK_INT(r.stop, PST_STOP_BREAKDOWN);
    /* stagnation: GMRES(1) on the rotation makes no progress and would repeat itself, after one
     * iteration instead of 100; GMRES(2) solves it */
    CHECK_INT(stop_of(&rot, NULL, PST_SOLVER_GMRES, 1, 100, &r), PST_ENUMERIC);
    CHECK_INT(r.stop, PST_STOP_STAGNATION);
    CHECK_INT(r.iterations, 1);
    CHECK_NEAR(r.rel_residual, 1.0, 1e-15);
    CHECK_INT(stop_of(&rot, NULL, PST_SOLVER_GMRES, 2, 100, &r), PST_OK);
    CHECK_INT(r.stop, PST_STOP_CONVERGED);
    /* b = 0: converged without iterating */
    double *b = calloc(n, sizeof *b), *u = malloc(n * sizeof *u);
    pst_solve_opts o = opts(PST_SOLVER_GMRES, PST_PREC_NONE);
    CHECK_INT(solve_once(&A, NULL, &o, b, u, &r), PST_OK);
    CHECK(r.stop == PST_STOP_CONVERGED && r.iterations == 0);
    CHECK(strcmp(r.message, "b = 0: u = 0") == 0);
    pst_solve_result_free(&r);
    free(b), free(u);
    CHECK(strcmp(pst_stop_reason_name(PST_STOP_STAGNATION), "stagnation") == 0);
    CHECK(strcmp(pst_stop_reason_name(99), "unknown") == 0);
}

/* Bad input: clear errors, no handle. */
static void test_bad_input(void)
{
    grid g = {8, 1.0, 0, 0};
    pst_linop A = grid_linop(&g), M = {A.n, sgs_apply, NULL, &g};
    pst_krylov *s = (pst_krylov *)&g; /* overwritten with NULL on every failure */
    char err[PST_ERRLEN] = "";
    pst_linop empty = A;
    empty.n = 0;
    CHECK_INT(pst_krylov_create_linop(&s, &empty, NULL, NULL, err), PST_EINVAL);
    CHECK(s == NULL && strstr(err, "n = 0") != NULL);
    pst_linop noapply = A;
    noapply.apply = NULL;
    CHECK_INT(pst_krylov_create_linop(&s, &noapply, NULL, NULL, err), PST_EINVAL);
    CHECK(strstr(err, "apply is NULL") != NULL);
    CHECK_INT(pst_krylov_create_linop(&s, NULL, NULL, NULL, err), PST_EINVAL);
    CHECK(strstr(err, "no operator") != NULL);
    pst_linop small = M;
    small.n = A.n - 1;
    CHECK_INT(pst_krylov_create_linop(&s, &A, &small, NULL, err), PST_EINVAL);
    CHECK(strstr(err, "must match") != NULL);
    printf("mismatch: %s\n", err);
    pst_solve_opts o = opts(PST_SOLVER_GMRES, PST_PREC_AMG);
    CHECK_INT(pst_krylov_create_linop(&s, &A, NULL, &o, err), PST_EINVAL);
    CHECK(strstr(err, "engine operator") != NULL);
    pst_linop nodiag = A;
    nodiag.diagonal = NULL;
    o = opts(PST_SOLVER_GMRES, PST_PREC_JACOBI);
    CHECK_INT(pst_krylov_create_linop(&s, &nodiag, NULL, &o, err), PST_EINVAL);
    CHECK(strstr(err, "diagonal is NULL") != NULL);
    nodiag.diagonal = failing_diagonal;
    CHECK_INT(pst_krylov_create_linop(&s, &nodiag, NULL, &o, err), PST_ENUMERIC);
    CHECK(strstr(err, "diagonal failed") != NULL);
    o.rtol = 2;
    CHECK_INT(pst_krylov_create_linop(&s, &A, NULL, &o, err), PST_EINVAL);
    CHECK(strstr(err, "rtol") != NULL);
    /* a good handle, bad solves */
    CHECK_INT(pst_krylov_create_linop(&s, &A, &M, NULL, err), PST_OK);
    double *b = calloc(A.n, sizeof *b), *u = calloc(A.n, sizeof *u);
    pst_solve_result r;
    CHECK_INT(pst_krylov_solve(s, NULL, u, &r, err), PST_EINVAL);
    CHECK(r.stop == PST_STOP_NONE && strstr(r.message, "needs a handle, b and u"));
    u[3] = INFINITY;
    CHECK_INT(pst_krylov_solve(s, b, u, &r, err), PST_EINPUT);
    CHECK(strstr(err, "u[3] is not finite") != NULL);
    CHECK_INT(pst_krylov_solve(NULL, b, u, NULL, err), PST_EINVAL);
    pst_krylov_stats st;
    pst_krylov_get_stats(s, &st);
    CHECK_INT(st.solves, 0);
    pst_krylov_destroy(s);
    pst_krylov_destroy(NULL);
    free(b), free(u);
}

/* An engine operator through pst_op_linop, solved as a user operator (its Dirichlet rows are
 * the identity, so the system is the same): it agrees with pst_solve to the tolerance; and
 * pst_op_linop's refusals. */
static void test_engine_linop(void)
{
    pst_cloud *c = test_lattice(2, 0.0, 1.0, 1.0 / 30, 1.2, 0.3, 3, 1);
    pst_nlist *nl = test_nlist(c, 2.0);
    pst_op *op = test_op(c, nl, "lv", PST_GRAD_G1, 0);
    size_t n = pst_cloud_size(c);
    const uint8_t *kind = pst_cloud_kinds_const(c);
    double *b = malloc(n * sizeof *b), *u1 = calloc(n, sizeof *u1), *u2 = calloc(n, sizeof *u2);
    for (size_t i = 0; i < n; ++i)
        b[i] = kind[i] == PST_DIRICHLET ? 0.5 : 1.0;
    pst_linop L;
    char err[PST_ERRLEN] = "";
    CHECK_INT(pst_op_linop(op, 1, &L, err), PST_EINVAL);
    CHECK(strstr(err, "pst_op_store") != NULL);
    CHECK_INT(pst_op_linop(NULL, 0, &L, err), PST_EINVAL);
    CHECK_INT(pst_op_store(op), PST_OK);
    for (int stored = 0; stored <= 1; ++stored) {
        memset(u1, 0, n * sizeof *u1);
        CHECK_INT(pst_op_linop(op, stored, &L, err), PST_OK);
        CHECK_INT(L.n, n);
        pst_solve_opts o = opts(PST_SOLVER_GMRES, PST_PREC_JACOBI);
        o.stored = stored;
        pst_solve_result r1, r2;
        CHECK_INT(pst_solve(op, b, u1, &o, &r1, err), PST_OK);
        CHECK_INT(solve_once(&L, NULL, &o, b, u2, &r2), PST_OK);
        double d = rel_err(u2, u1, n);
        printf("lv through pst_op_linop (stored %d): %d iterations (pst_solve %d), rel diff %.2e\n",
               stored, r2.iterations, r1.iterations, d);
        CHECK(d < 1e-8);
        pst_solve_result_free(&r1), pst_solve_result_free(&r2);
    }
    free(b), free(u1), free(u2);
    pst_op_destroy(op);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
}

int main(void)
{
    test_bad_input();
    test_methods();
    test_reuse_and_threads();
    test_threads_partial_block();
    test_gmres_reorthogonalisation();
    test_stop_reasons();
    test_engine_linop();
    return check_summary("test_krylov");
}
