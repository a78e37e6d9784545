/* Solver refresh (pst_krylov_refresh) after the particles moved, the list was updated and the
 * operator refreshed: with Jacobi (GMRES, CG's symmetric scaling, fix_mean in a periodic box)
 * the refreshed handle solves bit for bit as a handle created afresh; with AMG the hierarchy is
 * kept or set up again by the amg_reuse rule and the solves still converge to the fresh
 * answer; a user operator's Jacobi diagonal taken again; the refusals, and a failed refresh
 * that makes every solve refuse the handle. */
#include "check.h"
#include "support.h"

#include "pstencil.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Move the particles that are not Dirichlet by a smooth swirl of at most 0.1 s0 (folded back
 * into a periodic box). */
static void swirl(pst_cloud *c, double s0)
{
    double *x = pst_cloud_coord(c, 0), *y = pst_cloud_coord(c, 1);
    const uint8_t *kind = pst_cloud_kinds(c);
    for (size_t i = 0; i < pst_cloud_size(c); ++i) {
        if (kind[i] == PST_DIRICHLET)
            continue;
        x[i] += 0.1 * s0 * sin(3 * y[i]) * cos(2 * x[i]);
        y[i] -= 0.1 * s0 * cos(3 * x[i]) * sin(2 * y[i]);
    }
    pst_cloud_wrap(c);
}

/* b: a source inside, boundary values on Dirichlet rows. */
static double *rhs(const pst_cloud *c)
{
    size_t n = pst_cloud_size(c);
    double *b = malloc(n * sizeof *b);
    for (size_t i = 0; i < n; ++i) {
        double x[3];
        test_position(c, i, x);
        b[i] = pst_cloud_kinds_const(c)[i] == PST_DIRICHLET ? x[0] * x[1]
                                                            : sin(6.283185307179586 * x[0]);
    }
    return b;
}

/* Three moves of a cloud with a handle refreshed after each, against a handle created afresh
 * on the refreshed operator. amg: compare to 1e-8 (a kept hierarchy differs from a new one)
 * instead of bit for bit. */
static void moves(pst_cloud *c, double s0, const char *scheme, const pst_solve_opts *o,
                  int amg, int expect_setups)
{
    char err[PST_ERRLEN] = "";
    double support = pst_kernel_support(pst_scheme_default_kernel(scheme));
    pst_nlist *nl = NULL;
    CHECK(pst_nlist_build_skin(&nl, c, support, 0.4, err) == PST_OK);
    pst_op *op = test_op(c, nl, scheme, PST_GRAD_G1, 0);
    if (o->stored)
        CHECK(pst_op_store(op) == PST_OK);
    pst_krylov *s = NULL;
    CHECK(pst_krylov_create(&s, op, o, err) == PST_OK);
    size_t n = pst_cloud_size(c);
    double *u = calloc(n, sizeof *u), *uf = calloc(n, sizeof *uf);
    int same = 1;
    double worst = 0;
    for (int step = 0; step < 3; ++step) {
        swirl(c, s0);
        CHECK(pst_nlist_update(nl, c, NULL, err) == PST_OK);
        CHECK(pst_op_refresh(op, err) == PST_OK);
        CHECK(pst_krylov_refresh(s, err) == PST_OK);
        double *b = rhs(c);
        memset(u, 0, n * sizeof *u);
        memset(uf, 0, n * sizeof *uf);
        pst_solve_result r, rf;
        CHECK(pst_krylov_solve(s, b, u, &r, err) == PST_OK);
        CHECK(pst_solve(op, b, uf, o, &rf, err) == PST_OK);
        same &= memcmp(u, uf, n * sizeof *u) == 0 && r.iterations == rf.iterations;
        double scale = 0;
        for (size_t i = 0; i < n; ++i) {
            worst = fmax(worst, fabs(u[i] - uf[i]));
            scale = fmax(scale, fabs(uf[i]));
        }
        worst /= scale > 0 ? scale : 1;
        free(b);
    }
    if (amg)
        CHECK(worst < 1e-8);
    else
        CHECK(same);
    pst_krylov_stats st;
    pst_krylov_get_stats(s, &st);
    CHECK_INT(st.refreshes, 3);
    CHECK_INT(st.precond_setups, expect_setups);
    if (!amg || st.precond_setups != expect_setups)
        printf("%s: refreshed = fresh %s (worst %.2g), %d set-ups, %d AMG reuses\n", scheme,
               same ? "bit for bit" : "to rounding", worst, st.precond_setups, st.amg_reuses);
    pst_krylov_destroy(s);
    pst_op_destroy(op);
    pst_nlist_destroy(nl);
    free(u);
    free(uf);
}

static void test_jacobi(void)
{
    pst_solve_opts o;
    pst_solve_defaults(&o);
    double s0 = 1.0 / 24;
    pst_cloud *c = test_lattice(2, 0, 1, s0, 1.3, 0.3, 5, 1);
    moves(c, s0, "qsfdi", &o, 0, 4); /* GMRES, Jacobi set up at creation and each refresh */
    o.stored = 1;
    moves(c, s0, "lsmps", &o, 0, 4);
    o.stored = 0;
    moves(c, s0, "brookshaw", &o, 0, 4); /* CG with its scaling recomputed */
    pst_cloud_destroy(c);

    /* a periodic box without Dirichlet rows: fix_mean's constant recomputed */
    pst_lattice_opts lo;
    pst_lattice_defaults(&lo);
    lo.s0 = s0;
    lo.h_ratio = 1.3;
    lo.jitter = 0.3;
    lo.periodic[0] = lo.periodic[1] = 1;
    pst_cloud *p = test_lattice_of(&lo);
    o.fix_mean = 1;
    moves(p, s0, "qsfdi", &o, 0, 4);
    pst_cloud_destroy(p);
}

static void test_amg(void)
{
    if (!pst_have_amg())
        return;
    test_mpi_init();
    pst_solve_opts o;
    pst_solve_defaults(&o);
    o.precond = PST_PREC_AMG;
    double s0 = 1.0 / 24;
    pst_cloud *c = test_lattice(2, 0, 1, s0, 1.3, 0.3, 5, 1);
    o.amg_reuse = 2; /* kept for two refreshes, set up again at the third */
    moves(c, s0, "qsfdi", &o, 1, 2);
    o.amg_reuse = 0; /* set up at every refresh */
    moves(c, s0, "qsfdi", &o, 1, 4);
    pst_cloud_destroy(c);
}

/* A user operator diag(d) whose values change behind the same apply. */
static double diag_scale = 1;
static void diag_apply(void *ctx, const double *x, double *y)
{
    size_t n = *(const size_t *)ctx;
    for (size_t i = 0; i < n; ++i)
        y[i] = diag_scale * (1.0 + (double)i) * x[i] + (i > 0 ? 0.1 * x[i - 1] : 0.0);
}
static int diag_diagonal(void *ctx, double *d)
{
    size_t n = *(const size_t *)ctx;
    for (size_t i = 0; i < n; ++i)
        d[i] = diag_scale * (1.0 + (double)i);
    return PST_OK;
}

/* A user operator's handle: the refreshed Jacobi diagonal gives a fresh handle's solve. */
static void test_user_operator(void)
{
    char err[PST_ERRLEN] = "";
    CHECK(pst_krylov_refresh(NULL, err) == PST_EINVAL);
    size_t n = 50;
    pst_linop A = {.n = n, .apply = diag_apply, .diagonal = diag_diagonal, .ctx = &n};
    pst_solve_opts o;
    pst_solve_defaults(&o);
    o.rtol = 1e-3; /* a few iterations, where the preconditioner shows in the bits */
    pst_krylov *s = NULL, *fresh = NULL;
    CHECK(pst_krylov_create_linop(&s, &A, NULL, &o, err) == PST_OK);
    double b[50], u[50] = {0}, uf[50] = {0};
    for (size_t i = 0; i < n; ++i)
        b[i] = sin((double)i);
    diag_scale = 1e3;
    CHECK(pst_krylov_refresh(s, err) == PST_OK);
    CHECK(pst_krylov_create_linop(&fresh, &A, NULL, &o, err) == PST_OK);
    CHECK(pst_krylov_solve(s, b, u, NULL, err) == PST_OK);
    CHECK(pst_krylov_solve(fresh, b, uf, NULL, err) == PST_OK);
    CHECK(memcmp(u, uf, sizeof u) == 0);
    pst_krylov_stats st;
    pst_krylov_get_stats(s, &st);
    CHECK(st.refreshes == 1 && st.precond_setups == 2);
    diag_scale = 1;
    pst_krylov_destroy(s);
    pst_krylov_destroy(fresh);
}

static void test_refusals(void)
{
    char err[PST_ERRLEN] = "";
    pst_solve_opts o;
    pst_krylov *s = NULL;
    double s0 = 1.0 / 24;
    pst_cloud *c = test_lattice(2, 0, 1, s0, 1.3, 0.3, 4, 1);
    pst_nlist *nl = NULL;
    CHECK(pst_nlist_build_skin(&nl, c, 3.0, 0.4, err) == PST_OK);
    pst_op_opts oo;
    pst_op_defaults(&oo);
    oo.scheme = "lv";
    oo.on_degenerate = PST_DEGENERATE_REFUSE;
    pst_op *op = test_op_of(c, nl, &oo);
    pst_solve_defaults(&o);
    o.amg_reuse = -1;
    CHECK(pst_krylov_create(&s, op, &o, err) == PST_EINVAL);
    CHECK(strstr(err, "amg_reuse") != NULL);
    pst_solve_defaults(&o);
    CHECK(pst_krylov_create(&s, op, &o, err) == PST_OK);
    /* a failed operator refresh (the particles near the centre moved onto one line, their
     * rows refused): the solver refresh refuses, and so does every solve until a refresh
     * succeeds */
    size_t n = pst_cloud_size(c);
    double *y = pst_cloud_coord(c, 1), *x = pst_cloud_coord(c, 0);
    double *keep = malloc(n * sizeof *keep);
    memcpy(keep, y, n * sizeof *keep);
    for (size_t i = 0; i < n; ++i)
        if (hypot(x[i] - 0.5, y[i] - 0.5) < 3 * 1.3 * s0)
            y[i] = 0.5;
    CHECK(pst_nlist_update(nl, c, NULL, err) == PST_OK);
    CHECK(pst_op_refresh(op, err) == PST_ENUMERIC);
    CHECK(pst_krylov_refresh(s, err) == PST_EINVAL);
    CHECK(strstr(err, "no rows") != NULL);
    double *b = rhs(c), *u = calloc(n, sizeof *u);
    CHECK(pst_krylov_solve(s, b, u, NULL, err) == PST_EINVAL);
    CHECK(strstr(err, "last refresh failed") != NULL);
    memcpy(y, keep, n * sizeof *keep);
    CHECK(pst_nlist_update(nl, c, NULL, err) == PST_OK);
    CHECK(pst_op_refresh(op, err) == PST_OK);
    CHECK(pst_krylov_refresh(s, err) == PST_OK);
    CHECK(pst_krylov_solve(s, b, u, NULL, err) == PST_OK);
    free(keep);
    free(b);
    free(u);
    pst_krylov_destroy(s);
    pst_op_destroy(op);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
}

int main(void)
{
    test_jacobi();
    test_amg();
    test_user_operator();
    test_refusals();
    return check_summary("test_krylov_refresh");
}
