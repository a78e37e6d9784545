/* The solver (pst_solve, docs/solving.md): manufactured Poisson solutions on jittered clouds
 * with a Dirichlet boundary layer converge at second order (QSFDI eq. 15) for the QSFDI family
 * and the LV family in 2D and 3D; CG on the symmetrised Brookshaw / corrected-Brookshaw system
 * agrees with GMRES; BiCGSTAB converges; the two apply paths give the same iterates; 1 and 2
 * threads give the same bits; failures (iteration limit, no Dirichlet row, CG on a
 * nonsymmetric scheme, bad options) are clear statuses with finite u; a mixed Dirichlet /
 * Neumann problem converges to the manufactured solution. icspm converges at second order where
 * its Poisson operator is stable (h = 0.9 s0, K <= 0.2 in 2D, K <= 0.1 in 3D); at the QSFDI
 * family's K = 0.35, h = 1.2 s0 it is not, and the solver says so (docs/schemes/icspm.md). The
 * reusable solver (pst_krylov) on engine operators gives the bits of pst_solve. */
#include "check.h"
#include "pstencil.h"
#include "support.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

/* 2D: QSFDI eq. 13. 3D: a plane wave of the same kind. */
static double u2(const double *x) { return sin(6 * x[0] + 8 * x[1]); }
static double lap2(const double *x) { return -100 * sin(6 * x[0] + 8 * x[1]); }
static double u3(const double *x) { return sin(2 * x[0] + 3 * x[1] + 4 * x[2]); }
static double lap3(const double *x) { return -29 * sin(2 * x[0] + 3 * x[1] + 4 * x[2]); }
/* The Neumann problem: a gentler wave, because the flux rows (LV eq. 100) are first order. */
static double un(const double *x) { return 2 + sin(1.5 * x[0] + 2 * x[1]); }

typedef struct {
    pst_cloud *c;
    pst_nlist *nl;
    pst_op *op;
    double *b, *exact, *u;
    size_t n;
} problem;

/* The unit square / cube, jitter K, Dirichlet boundary layer; b = the Laplacian at interior
 * particles and the value at Dirichlet ones. h = h_ratio s0 (quintic schemes, support 3h; the
 * cubic LV family, 2h). */
static problem make_h(int dim, double s0, const char *scheme, double K, double h_ratio,
                      uint64_t seed)
{
    problem p;
    p.c = test_lattice(dim, 0.0, 1.0, s0, h_ratio, K, seed, 1);
    double support = pst_kernel_support(pst_scheme_default_kernel(scheme));
    if (pst_cloud_morton_sort(p.c, support * h_ratio * s0, NULL) != PST_OK)
        exit(1);
    p.nl = test_nlist(p.c, support);
    p.op = test_op(p.c, p.nl, scheme, PST_GRAD_G1, 0);
    p.n = pst_cloud_size(p.c);
    p.exact = test_field(p.c, dim == 2 ? u2 : u3);
    p.b = test_field(p.c, dim == 2 ? lap2 : lap3);
    p.u = calloc(p.n, sizeof *p.u);
    const uint8_t *kind = pst_cloud_kinds_const(p.c);
    for (size_t i = 0; i < p.n; ++i)
        if (kind[i] == PST_DIRICHLET)
            p.b[i] = p.exact[i];
    return p;
}

/* h = 1.2 s0, the tests' default. */
static problem make(int dim, double s0, const char *scheme, double K, uint64_t seed)
{
    return make_h(dim, s0, scheme, K, 1.2, seed);
}

static void destroy(problem *p)
{
    pst_op_destroy(p->op);
    pst_nlist_destroy(p->nl);
    pst_cloud_destroy(p->c);
    free(p->b);
    free(p->exact);
    free(p->u);
}

/* QSFDI eq. 15: ||u - u_exact|| / ||u_exact|| over the interior (unknown) particles. */
static double error_eq15(const problem *p, const double *u)
{
    const uint8_t *kind = pst_cloud_kinds_const(p->c);
    double num = 0, den = 0;
    for (size_t i = 0; i < p->n; ++i) {
        if (kind[i] != PST_INTERIOR)
            continue;
        num += (u[i] - p->exact[i]) * (u[i] - p->exact[i]);
        den += p->exact[i] * p->exact[i];
    }
    return sqrt(num / den);
}

static int all_finite(const double *u, size_t n)
{
    for (size_t i = 0; i < n; ++i)
        if (!isfinite(u[i]))
            return 0;
    return 1;
}

static double max_rel_diff(const double *a, const double *b, size_t n)
{
    double d = 0, m = 0;
    for (size_t i = 0; i < n; ++i) {
        d = fmax(d, fabs(a[i] - b[i]));
        m = fmax(m, fabs(b[i]));
    }
    return d / m;
}

static pst_solve_opts opts(int solver)
{
    pst_solve_opts o;
    pst_solve_defaults(&o);
    o.solver = solver;
    o.rtol = 1e-10;
    o.stored = 1;
    return o;
}

/* Convergence of the solution error with GMRES + Jacobi to 1e-10. The QSFDI family is run at
 * K = 0.35; the Lukyanov-Vuik schemes at the paper's perturbation (+-10 %, K = 0.1): their
 * normalisation tr(Gamma^-1)/n is exact only where Gamma is isotropic, so on strongly
 * disordered clouds at fixed h/s0 the error levels off (measured and printed below at
 * K = 0.35, LV Theorems 2-3: error ~ dx^omega / h). icspm is not stable at K = 0.35,
 * h = 1.2 s0: test_icspm below. */
static void test_convergence(int dim, const double *s0, int m)
{
    static const char *const schemes[] = {"qsfdi", "lpmps", "lsmps", "lv", "schwaiger", "lv"};
    static const double jitter[] = {0.35, 0.35, 0.35, 0.1, 0.1, 0.35};
    for (int k = 0; k < 6; ++k) {
        double e[4];
        int iters[4];
        for (int r = 0; r < m; ++r) {
            problem p = make(dim, s0[r], schemes[k], jitter[k], 3);
            pst_op_store(p.op);
            pst_solve_opts o = opts(PST_SOLVER_GMRES);
            pst_solve_result res;
            char err[PST_ERRLEN];
            int st = pst_solve(p.op, p.b, p.u, &o, &res, err);
            CHECK_INT(st, PST_OK);
            CHECK(res.converged && res.rel_residual <= 1e-10);
            e[r] = error_eq15(&p, p.u);
            iters[r] = res.iterations;
            destroy(&p);
        }
        double sl = test_slope(s0, e, m);
        printf("%dD %-9s K = %.2f eq. 15 error:", dim, schemes[k], jitter[k]);
        for (int r = 0; r < m; ++r)
            printf(" %.3e (%d it)", e[r], iters[r]);
        printf("  slope %.2f%s\n", sl, k == 5 ? " (measured, not asserted)" : "");
        if (k < 5) {
            CHECK(sl >= 1.8);
            CHECK(e[m - 1] < (dim == 2 ? 3e-2 : 1e-1));
        }
    }
}

/* Interior rows whose diagonal is >= 0: a Laplacian row must have a negative diagonal, and
 * e_i^T L e_i >= 0 puts L's field of values into the right half-plane. */
static size_t rows_nonneg_diagonal(const problem *p)
{
    double *d = malloc(p->n * sizeof *d);
    CHECK_INT(pst_op_diagonal(p->op, d), PST_OK);
    const uint8_t *kind = pst_cloud_kinds_const(p->c);
    size_t bad = 0;
    for (size_t i = 0; i < p->n; ++i)
        bad += kind[i] == PST_INTERIOR && !(d[i] < 0);
    free(d);
    return bad;
}

/* icspm (docs/schemes/icspm.md, "Poisson problems"). Its Laplacian is a kernel-derivative
 * stencil whose checkerboard response is weak (test_cspm's lattice symbol) and shrinks fast
 * with h/s0, so jitter and boundary truncation push eigenvalues into the right half-plane.
 * 1. Where it is stable, h = 0.9 s0 and K = 0.2 (2D) / 0.1 (3D): GMRES(50) + Jacobi to 1e-10,
 *    slope >= 1.8, and no interior row with a non-negative diagonal.
 * 2. Where it is not, the QSFDI family's K = 0.35 at h = 1.2 s0 (s0 = 1/20, 361 unknowns):
 *    full GMRES (restart 400 >= unknowns) solves the discrete system to 1e-10 and its solution
 *    is still wrong by tens of per cent, against qsfdi's few per cent on the same cloud with
 *    the same solver: the operator, not the solver, fails. GMRES(50) stops with PST_ENUMERIC
 *    at the iteration limit (a clear status, finite u), not with a wrong "converged". */
static void test_icspm(void)
{
    const double s2[3] = {1.0 / 20, 1.0 / 40, 1.0 / 80}, s3[3] = {1.0 / 6, 1.0 / 9, 1.0 / 12};
    for (int dim = 2; dim <= 3; ++dim) {
        const double *s0 = dim == 2 ? s2 : s3;
        const double K = dim == 2 ? 0.2 : 0.1;
        double e[3];
        int iters[3];
        for (int r = 0; r < 3; ++r) {
            problem p = make_h(dim, s0[r], "icspm", K, 0.9, 3);
            CHECK_INT(rows_nonneg_diagonal(&p), 0);
            pst_op_store(p.op);
            pst_solve_opts o = opts(PST_SOLVER_GMRES);
            pst_solve_result res;
            CHECK_INT(pst_solve(p.op, p.b, p.u, &o, &res, NULL), PST_OK);
            CHECK(res.converged && res.rel_residual <= 1e-10);
            e[r] = error_eq15(&p, p.u);
            iters[r] = res.iterations;
            destroy(&p);
        }
        double sl = test_slope(s0, e, 3);
        printf("%dD icspm     K = %.2f h = 0.9 s0 eq. 15 error: %.3e (%d it) %.3e (%d it) "
               "%.3e (%d it)  slope %.2f\n",
               dim, K, e[0], iters[0], e[1], iters[1], e[2], iters[2], sl);
        CHECK(sl >= 1.8);
        CHECK(e[2] < (dim == 2 ? 1e-2 : 5e-2));
    }

    double err[2];
    static const char *const cmp[2] = {"icspm", "qsfdi"};
    for (int k = 0; k < 2; ++k) {
        problem p = make(2, 1.0 / 20, cmp[k], 0.35, 3);
        pst_op_store(p.op);
        pst_solve_opts o = opts(PST_SOLVER_GMRES);
        o.restart = 400;
        o.max_iter = 400;
        pst_solve_result res;
        CHECK_INT(pst_solve(p.op, p.b, p.u, &o, &res, NULL), PST_OK);
        CHECK(res.converged && res.rel_residual <= 1e-10);
        err[k] = error_eq15(&p, p.u);
        size_t bad = rows_nonneg_diagonal(&p);
        printf("2D %-9s K = 0.35 h = 1.2 s0, s0 = 1/20, full GMRES: %d it, eq. 15 error %.3e, "
               "%zu interior rows with diagonal >= 0\n",
               cmp[k], res.iterations, err[k], bad);
        if (k == 0) {
            CHECK(bad > 0);
            /* restarted GMRES: a clear non-convergence status */
            memset(p.u, 0, p.n * sizeof *p.u);
            o = opts(PST_SOLVER_GMRES);
            o.max_iter = 1000;
            char msg[PST_ERRLEN];
            CHECK_INT(pst_solve(p.op, p.b, p.u, &o, &res, msg), PST_ENUMERIC);
            CHECK(!res.converged && res.iterations == 1000 && res.rel_residual > 1e-6);
            CHECK(all_finite(p.u, p.n) && strstr(res.message, "iteration limit") != NULL);
            printf("2D icspm     K = 0.35 h = 1.2 s0, GMRES(50): %s\n", res.message);
        } else {
            CHECK_INT(bad, 0);
        }
        destroy(&p);
    }
    CHECK(err[0] > 0.2 && err[1] < 0.05);
}

/* CG on brookshaw and cb: converges, is the AUTO choice, agrees with GMRES. */
static void test_cg(void)
{
    static const char *const schemes[] = {"brookshaw", "cb"};
    for (int k = 0; k < 2; ++k) {
        problem p = make(2, 1.0 / 40, schemes[k], 0.35, 5);
        pst_op_store(p.op);
        pst_solve_opts o = opts(PST_SOLVER_AUTO);
        pst_solve_result rc, rg;
        CHECK_INT(pst_solve(p.op, p.b, p.u, &o, &rc, NULL), PST_OK);
        CHECK_INT(rc.solver, PST_SOLVER_CG);
        CHECK_INT(rc.stop, PST_STOP_CONVERGED);
        double *ug = calloc(p.n, sizeof *ug);
        o.solver = PST_SOLVER_GMRES;
        CHECK_INT(pst_solve(p.op, p.b, ug, &o, &rg, NULL), PST_OK);
        double d = max_rel_diff(p.u, ug, p.n);
        printf("%-9s CG %d it, GMRES %d it, max rel diff %.2e, error %.3e; %s\n", schemes[k],
               rc.iterations, rg.iterations, d, error_eq15(&p, p.u), rc.message);
        CHECK(d <= 1e-8);
        CHECK(rc.rel_residual <= 1e-10);
        /* without a preconditioner too */
        o.solver = PST_SOLVER_CG;
        o.precond = PST_PREC_NONE;
        memset(ug, 0, p.n * sizeof *ug);
        CHECK_INT(pst_solve(p.op, p.b, ug, &o, &rg, NULL), PST_OK);
        CHECK(max_rel_diff(p.u, ug, p.n) <= 1e-8);
        free(ug);
        destroy(&p);
    }
}

static void test_bicgstab(void)
{
    problem p = make(2, 1.0 / 40, "lv", 0.35, 5);
    pst_op_store(p.op);
    pst_solve_opts o = opts(PST_SOLVER_BICGSTAB);
    pst_solve_result r;
    CHECK_INT(pst_solve(p.op, p.b, p.u, &o, &r, NULL), PST_OK);
    double *ug = calloc(p.n, sizeof *ug);
    o.solver = PST_SOLVER_GMRES;
    pst_solve_result rg;
    CHECK_INT(pst_solve(p.op, p.b, ug, &o, &rg, NULL), PST_OK);
    printf("lv BiCGSTAB %d it (GMRES %d it), rel residual %.2e, diff to GMRES %.2e\n",
           r.iterations, rg.iterations, r.rel_residual, max_rel_diff(p.u, ug, p.n));
    CHECK(r.converged && r.rel_residual <= 1e-10);
    CHECK(max_rel_diff(p.u, ug, p.n) <= 1e-8);
    free(ug);
    destroy(&p);
}

/* Matrix-free and stored applies: the same iterations, solutions within 1e-12. */
static void test_apply_paths(void)
{
    static const char *const schemes[] = {"qsfdi", "lv", "cb"};
    static const int solvers[] = {PST_SOLVER_GMRES, PST_SOLVER_BICGSTAB, PST_SOLVER_CG};
    for (int k = 0; k < 3; ++k) {
        problem p = make(2, 1.0 / 30, schemes[k], 0.35, 9);
        pst_solve_opts o = opts(solvers[k]);
        o.stored = 1;
        pst_solve_result r1, r2;
        CHECK_INT(pst_solve(p.op, p.b, p.u, &o, &r1, NULL), PST_EINVAL); /* not stored yet */
        CHECK(strstr(r1.message, "pst_op_store") != NULL);
        pst_op_store(p.op);
        CHECK_INT(pst_solve(p.op, p.b, p.u, &o, &r1, NULL), PST_OK);
        double *uf = calloc(p.n, sizeof *uf);
        o.stored = 0;
        CHECK_INT(pst_solve(p.op, p.b, uf, &o, &r2, NULL), PST_OK);
        double d = max_rel_diff(uf, p.u, p.n);
        printf("%-9s stored %d it, matrix-free %d it, max rel diff %.2e\n", schemes[k],
               r1.iterations, r2.iterations, d);
        CHECK_INT(r1.iterations, r2.iterations);
        /* The two paths' rows differ by rounding (the stored apply sums in SIMD partial sums);
         * the solver amplifies that by the condition number (lv: 5e-11 measured), which stays
         * far below the solve's own tolerance. */
        CHECK(d <= 1e-9);
        free(uf);
        destroy(&p);
    }
}

/* 1 and 2 threads: the same bits and iteration counts, for each method. */
static void test_thread_counts(void)
{
    static const char *const schemes[] = {"lsmps", "lv", "brookshaw"};
    static const int solvers[] = {PST_SOLVER_GMRES, PST_SOLVER_BICGSTAB, PST_SOLVER_CG};
    for (int k = 0; k < 3; ++k) {
        problem p = make(2, 1.0 / 30, schemes[k], 0.35, 11);
        pst_solve_opts o = opts(solvers[k]);
        o.stored = 0;
        o.history = 1;
        pst_solve_result r1, r2;
        double *u1 = calloc(p.n, sizeof *u1);
        omp_set_num_threads(1);
        CHECK_INT(pst_solve(p.op, p.b, u1, &o, &r1, NULL), PST_OK);
        omp_set_num_threads(2);
        CHECK_INT(pst_solve(p.op, p.b, p.u, &o, &r2, NULL), PST_OK);
        CHECK_INT(r1.iterations, r2.iterations);
        CHECK(memcmp(u1, p.u, p.n * sizeof *u1) == 0);
        CHECK(r1.rel_residual == r2.rel_residual);
        /* the history: initial residual, then one estimate per iteration */
        CHECK_INT(r1.nhistory, r1.iterations + 1);
        CHECK(r1.history && r1.history[0] > 0.1 && r1.history[r1.nhistory - 1] <= 1e-10);
        CHECK(r1.nhistory == r2.nhistory &&
              memcmp(r1.history, r2.history, (size_t)r1.nhistory * sizeof(double)) == 0);
        pst_solve_result_free(&r1);
        pst_solve_result_free(&r2);
        CHECK(r1.history == NULL && r1.nhistory == 0);
        free(u1);
        destroy(&p);
    }
}

/* Failures: clear statuses, finite u. */
static void test_failures(void)
{
    problem p = make(2, 1.0 / 30, "lv", 0.35, 13);
    pst_solve_opts o = opts(PST_SOLVER_GMRES);
    o.stored = 0;
    pst_solve_result r;
    char err[PST_ERRLEN];
    /* an impossible tolerance with a tiny iteration limit */
    o.rtol = 1e-300;
    o.max_iter = 5;
    CHECK_INT(pst_solve(p.op, p.b, p.u, &o, &r, err), PST_ENUMERIC);
    CHECK(r.converged == 0 && r.iterations == 5 && all_finite(p.u, p.n));
    CHECK(strstr(r.message, "iteration limit 5") && strstr(r.message, "relative residual"));
    CHECK_INT(r.stop, PST_STOP_ITERATION_LIMIT);
    CHECK(r.rel_residual > 0 && r.rel_residual < 1);
    printf("limit: %s\n", r.message);
    for (int s = PST_SOLVER_BICGSTAB; s <= PST_SOLVER_BICGSTAB; ++s) {
        o.solver = s;
        CHECK_INT(pst_solve(p.op, p.b, p.u, &o, &r, err), PST_ENUMERIC);
        CHECK(r.converged == 0 && all_finite(p.u, p.n) && strstr(r.message, "residual"));
        CHECK_INT(r.stop, PST_STOP_ITERATION_LIMIT);
    }
    /* CG on a nonsymmetric scheme */
    o = opts(PST_SOLVER_CG);
    o.stored = 0;
    CHECK_INT(pst_solve(p.op, p.b, p.u, &o, &r, err), PST_EINVAL);
    CHECK(strstr(err, "CG needs a symmetrisable operator") != NULL);
    CHECK(r.stop == PST_STOP_NONE && r.solver == PST_SOLVER_CG && r.iterations == 0);
    printf("CG on lv: %s\n", err);
    /* bad options */
    o = opts(PST_SOLVER_GMRES);
    o.rtol = 0;
    CHECK_INT(pst_solve(p.op, p.b, p.u, &o, &r, err), PST_EINVAL);
    o = opts(PST_SOLVER_GMRES);
    o.restart = 0;
    CHECK_INT(pst_solve(p.op, p.b, p.u, &o, &r, err), PST_EINVAL);
    o = opts(7);
    CHECK_INT(pst_solve(p.op, p.b, p.u, &o, &r, err), PST_EINVAL);
    /* non-finite b */
    o = opts(PST_SOLVER_GMRES);
    o.stored = 0;
    double keep = p.b[p.n / 2];
    p.b[p.n / 2] = NAN;
    CHECK_INT(pst_solve(p.op, p.b, p.u, &o, &r, err), PST_EINPUT);
    p.b[p.n / 2] = keep;
    /* b = 0: u = u_D = 0 */
    double *zero = calloc(p.n, sizeof *zero);
    for (size_t i = 0; i < p.n; ++i)
        p.u[i] = 1.0;
    CHECK_INT(pst_solve(p.op, zero, p.u, &o, &r, err), PST_OK);
    CHECK(strcmp(r.message, "b = 0: u = u_D") == 0 && r.iterations == 0);
    CHECK_INT(r.stop, PST_STOP_CONVERGED);
    CHECK(memcmp(p.u, zero, p.n * sizeof *zero) == 0);
    free(zero);
    /* NULL result and options are allowed */
    CHECK_INT(pst_solve(p.op, p.b, p.u, NULL, NULL, NULL), PST_OK);
    CHECK(error_eq15(&p, p.u) < 3e-2);
    destroy(&p);

    /* no Dirichlet row: interior only, then Neumann only */
    pst_cloud *c = test_lattice(2, 0.0, 1.0, 0.1, 1.2, 0.3, 1, 0);
    pst_nlist *nl = test_nlist(c, 2.0);
    pst_op *op = test_op(c, nl, "lv", PST_GRAD_G1, 0);
    size_t n = pst_cloud_size(c);
    double *b = test_field(c, lap2), *u = calloc(n, sizeof *u);
    CHECK_INT(pst_solve(op, b, u, NULL, &r, err), PST_EINVAL);
    CHECK(strstr(err, "up to a constant") && strstr(err, "Dirichlet"));
    CHECK_INT(r.stop, PST_STOP_NONE);
    printf("singular: %s\n", err);
    pst_op_destroy(op);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
    c = test_lattice(2, 0.0, 1.0, 0.1, 1.2, 0.3, 1, 1);
    test_make_neumann(c, 1);
    nl = test_nlist(c, 2.0);
    op = test_op(c, nl, "lv", PST_GRAD_G1, 0);
    CHECK_INT(pst_solve(op, b, u, NULL, &r, err), PST_EINVAL);
    pst_op_destroy(op);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
    free(b);
    free(u);
}

/* Dirichlet on x = 0, Neumann n . grad u = exact flux on the other sides (corners touching
 * x = 0 stay Dirichlet), lv with GMRES. */
static double neumann_error(double s0, int *iters)
{
    pst_cloud *c = test_lattice(2, 0.0, 1.0, s0, 1.2, 0.35, 17, 1);
    size_t n = pst_cloud_size(c);
    uint8_t *kind = pst_cloud_kinds(c);
    const double *x = pst_cloud_coord_const(c, 0), *y = pst_cloud_coord_const(c, 1);
    const double *nx = pst_cloud_normal(c, 0), *ny = pst_cloud_normal(c, 1);
    for (size_t i = 0; i < n; ++i)
        if (kind[i] == PST_DIRICHLET && x[i] > 1e-12)
            kind[i] = PST_NEUMANN;
    pst_nlist *nl = test_nlist(c, 2.0);
    pst_op *op = test_op(c, nl, "lv", PST_GRAD_G1, 0);
    double *b = malloc(n * sizeof *b), *u = calloc(n, sizeof *u);
    double *exact = test_field(c, un);
    for (size_t i = 0; i < n; ++i) {
        double p[3] = {x[i], y[i], 0}, a = 1.5 * x[i] + 2 * y[i];
        b[i] = kind[i] == PST_DIRICHLET ? un(p)
               : kind[i] == PST_NEUMANN ? cos(a) * (1.5 * nx[i] + 2 * ny[i])
                                        : -6.25 * sin(a);
    }
    pst_solve_opts o = opts(PST_SOLVER_AUTO);
    o.stored = 0;
    pst_solve_result r;
    char err[PST_ERRLEN];
    int st = pst_solve(op, b, u, &o, &r, err);
    CHECK_INT(st, PST_OK);
    CHECK_INT(r.solver, PST_SOLVER_GMRES);
    *iters = r.iterations;
    double num = 0, den = 0;
    for (size_t i = 0; i < n; ++i)
        if (kind[i] == PST_INTERIOR) {
            num += (u[i] - exact[i]) * (u[i] - exact[i]);
            den += exact[i] * exact[i];
        }
    free(b);
    free(u);
    free(exact);
    pst_op_destroy(op);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
    return sqrt(num / den);
}

static void test_neumann(void)
{
    const double s0[2] = {1.0 / 20, 1.0 / 40};
    double e[2];
    int it[2];
    for (int r = 0; r < 2; ++r)
        e[r] = neumann_error(s0[r], &it[r]);
    printf("lv mixed Dirichlet/Neumann eq. 15 error: %.3e (%d it), %.3e (%d it), slope %.2f\n",
           e[0], it[0], e[1], it[1], test_slope(s0, e, 2));
    CHECK(e[1] < 4e-2);
    CHECK(e[1] < e[0]);
}

/* Two solves bit for bit: solution, iterations, stop, message and history. */
static int same_bits(const pst_solve_result *a, const double *ua, const pst_solve_result *b,
                     const double *ub, size_t n)
{
    return a->iterations == b->iterations && a->stop == b->stop && a->solver == b->solver &&
           a->rel_residual == b->rel_residual && strcmp(a->message, b->message) == 0 &&
           a->nhistory == b->nhistory &&
           memcmp(a->history, b->history, (size_t)a->nhistory * sizeof(double)) == 0 &&
           memcmp(ua, ub, n * sizeof *ua) == 0;
}

/* The reusable solver on engine operators, one handle per method (AUTO: CG with its scaling
 * on brookshaw; GMRES and BiCGSTAB on lv): three right-hand sides and initial guesses each,
 * alternating 1 and 2 threads, give the bits of fresh pst_solve calls; the Jacobi diagonal is
 * set up once; a stored handle whose Dirichlet values change still eliminates them. */
static void test_handle(void)
{
    static const char *const schemes[] = {"brookshaw", "lv", "lv"};
    static const int solvers[] = {PST_SOLVER_AUTO, PST_SOLVER_GMRES, PST_SOLVER_BICGSTAB};
    int nt = omp_get_max_threads();
    for (int k = 0; k < 3; ++k) {
        problem p = make(2, 1.0 / 30, schemes[k], 0.35, 19);
        pst_op_store(p.op);
        pst_solve_opts o = opts(solvers[k]);
        o.history = 1;
        pst_krylov *s = NULL;
        char err[PST_ERRLEN] = "";
        CHECK_INT(pst_krylov_create(&s, p.op, &o, err), PST_OK);
        double *b = malloc(p.n * sizeof *b), *uf = malloc(p.n * sizeof *uf);
        for (int rhs = 0; rhs < 3; ++rhs) {
            for (size_t i = 0; i < p.n; ++i) {
                b[i] = p.b[i] * (1 + 0.5 * rhs);
                p.u[i] = uf[i] = 0.1 * rhs;
            }
            pst_solve_result r, rf;
            omp_set_num_threads(rhs == 1 ? 1 : 2);
            CHECK_INT(pst_krylov_solve(s, b, p.u, &r, err), PST_OK);
            omp_set_num_threads(rhs == 1 ? 2 : 1);
            CHECK_INT(pst_solve(p.op, b, uf, &o, &rf, err), PST_OK);
            CHECK(same_bits(&r, p.u, &rf, uf, p.n));
            CHECK(r.stop == PST_STOP_CONVERGED && r.rel_residual <= 1e-10);
            pst_solve_result_free(&r), pst_solve_result_free(&rf);
        }
        pst_krylov_stats st;
        pst_krylov_get_stats(s, &st);
        printf("%-9s handle: %s, %d solves, %d preconditioner set-up\n", schemes[k],
               st.solver == PST_SOLVER_CG ? "CG" : st.solver == PST_SOLVER_GMRES ? "GMRES"
                                                                                 : "BiCGSTAB",
               st.solves, st.precond_setups);
        CHECK_INT(st.solver, k == 0 ? PST_SOLVER_CG : solvers[k]);
        CHECK(st.solves == 3 && st.precond_setups == 1 && st.precond == PST_PREC_JACOBI);
        CHECK(st.n == p.n && !st.user_precond);
        pst_krylov_destroy(s);
        free(b), free(uf);
        destroy(&p);
    }
    omp_set_num_threads(nt);
    /* refusals of the create call */
    problem p = make(2, 1.0 / 10, "lv", 0.35, 19);
    pst_krylov *s = NULL;
    char err[PST_ERRLEN] = "";
    pst_solve_opts o = opts(PST_SOLVER_CG);
    o.stored = 0;
    CHECK_INT(pst_krylov_create(&s, p.op, &o, err), PST_EINVAL);
    CHECK(s == NULL && strstr(err, "CG needs a symmetrisable operator") != NULL);
    o = opts(PST_SOLVER_GMRES);
    CHECK_INT(pst_krylov_create(&s, p.op, &o, err), PST_EINVAL); /* stored, not stored yet */
    CHECK(strstr(err, "pst_op_store") != NULL);
    s = (pst_krylov *)&p; /* a stale value, cleared by every failing create */
    CHECK_INT(pst_krylov_create(&s, NULL, NULL, err), PST_EINVAL);
    CHECK(s == NULL && strstr(err, "needs an operator") != NULL);
    destroy(&p);
}

int main(void)
{
    double t0 = omp_get_wtime();
    test_failures();
    test_handle();
    test_cg();
    test_bicgstab();
    test_apply_paths();
    test_thread_counts();
    test_neumann();
    const double s2[3] = {1.0 / 20, 1.0 / 40, 1.0 / 80};
    test_convergence(2, s2, 3);
    const double s3[3] = {1.0 / 6, 1.0 / 9, 1.0 / 12};
    test_convergence(3, s3, 3);
    test_icspm();
    printf("test_solve: %.1f s\n", omp_get_wtime() - t0);
    return check_summary("test_solve");
}
