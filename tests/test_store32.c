/* Stored weights in float (pst_op_store_with PST_STORE_FLOAT, docs/operators.md): for the
 * QSFDI family, lv, cb and a wide-pattern mixed scheme in 2D and 3D, with Dirichlet and
 * Neumann rows, the float apply agrees with the double one row by row to the weights' rounding,
 * gives the same bits for 1 and 2 threads (store and apply), keeps the double diagonal, drives
 * a solve to the double store's answer, and every request that does not apply is refused. */
#include "check.h"
#include "pstencil.h"
#include "support.h"

#include <float.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

static double wave(const double *x) { return sin(3 * x[0] + 2 * x[1] - x[2]) + x[0] * x[1]; }

static pst_cloud *cloud_of(int dim)
{
    pst_cloud *c = dim == 2 ? test_lattice(2, 0, 1, 1.0 / 41, 1.2, 0.3, 5, 1)
                            : test_lattice(3, 0, 1, 1.0 / 13, 1.2, 0.3, 5, 1);
    test_make_neumann(c, 7);
    return c;
}

static pst_op *stored(const pst_cloud *c, const pst_nlist *nl, const char *scheme, int prec,
                      int threads)
{
    pst_op *op = test_op(c, nl, scheme, PST_GRAD_G1, 0);
    pst_op_store_opts so;
    pst_op_store_defaults(&so);
    CHECK_INT(so.precision, PST_STORE_DOUBLE);
    so.precision = prec;
    int saved = omp_get_max_threads();
    omp_set_num_threads(threads);
    char err[PST_ERRLEN] = "";
    CHECK_INT(pst_op_store_with(op, &so, err), PST_OK);
    omp_set_num_threads(saved);
    CHECK_INT(pst_op_store_precision(op), prec);
    return op;
}

/* |y32 - y64| <= 2^-24 sum_J |w_IJ| |u_J - u_I| per row (the weights' rounding; the sums'
 * own rounding is far below), from the double store's assembled rows. */
static void check_rows(const pst_op *op64, const double *u, const double *y64,
                       const double *y32, const uint8_t *kind, size_t n)
{
    pst_csr a;
    CHECK_INT(pst_op_assemble(op64, &a), PST_OK);
    double worst = 0, maxdiff = 0, maxy = 0;
    size_t dirichlet_differ = 0;
    for (size_t i = 0; i < n; ++i) {
        double s = 0;
        for (int64_t k = a.rowptr[i]; k < a.rowptr[i + 1]; ++k)
            if (a.col[k] != i)
                s += fabs(a.val[k]) * fabs(u[a.col[k]] - u[i]);
        double d = fabs(y32[i] - y64[i]);
        if (kind[i] == PST_DIRICHLET)
            dirichlet_differ += y32[i] != y64[i];
        else if (s > 0)
            worst = fmax(worst, d / s);
        maxdiff = fmax(maxdiff, d);
        maxy = fmax(maxy, fabs(y64[i]));
    }
    CHECK_INT(dirichlet_differ, 0);
    CHECK(worst <= 0x1p-24 * 1.01);
    CHECK(maxdiff > 0); /* the weights were rounded */
    CHECK(maxdiff <= 1e-5 * maxy);
    pst_csr_free(&a);
}

static void check_scheme(const char *scheme, int dim)
{
    pst_cloud *c = cloud_of(dim);
    size_t n = pst_cloud_size(c);
    pst_nlist *nl = test_nlist(c, pst_kernel_support(pst_scheme_default_kernel(scheme)));
    pst_op *op64 = stored(c, nl, scheme, PST_STORE_DOUBLE, 2);
    pst_op *op32a = stored(c, nl, scheme, PST_STORE_FLOAT, 1);
    pst_op *op32b = stored(c, nl, scheme, PST_STORE_FLOAT, 2);
    double *u = test_field(c, wave);
    double *y64 = malloc(n * sizeof *y64), *y[4], *d64 = malloc(n * sizeof *d64),
           *d32 = malloc(n * sizeof *d32);
    CHECK_INT(pst_op_apply_stored(op64, u, y64), PST_OK);
    int saved = omp_get_max_threads();
    for (int k = 0; k < 4; ++k) { /* stores of 1 and 2 threads, applies of 1 and 2 threads */
        y[k] = malloc(n * sizeof *y[k]);
        omp_set_num_threads(1 + k % 2);
        CHECK_INT(pst_op_apply_stored(k < 2 ? op32a : op32b, u, y[k]), PST_OK);
    }
    omp_set_num_threads(saved);
    for (int k = 1; k < 4; ++k)
        CHECK(memcmp(y[0], y[k], n * sizeof *y[0]) == 0);
    check_rows(op64, u, y64, y[0], pst_cloud_kinds_const(c), n);
    /* the diagonal is the double rows' whatever the store */
    CHECK_INT(pst_op_diagonal(op64, d64), PST_OK);
    CHECK_INT(pst_op_diagonal(op32a, d32), PST_OK);
    CHECK(memcmp(d64, d32, n * sizeof *d64) == 0);
    for (int k = 0; k < 4; ++k)
        free(y[k]);
    free(y64);
    free(d64);
    free(d32);
    free(u);
    pst_op_destroy(op64);
    pst_op_destroy(op32a);
    pst_op_destroy(op32b);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
}

/* GMRES + Jacobi on the float store: converged, close to the double store's solution. */
static void check_solve(void)
{
    pst_cloud *c = test_lattice(2, 0, 1, 1.0 / 41, 1.2, 0.3, 5, 1);
    size_t n = pst_cloud_size(c);
    pst_nlist *nl = test_nlist(c, 3.0);
    pst_op *op[2] = {stored(c, nl, "qsfdi", PST_STORE_DOUBLE, 2),
                     stored(c, nl, "qsfdi", PST_STORE_FLOAT, 2)};
    double *b = test_field(c, wave), *u[2] = {calloc(n, sizeof(double)), calloc(n, sizeof(double))};
    pst_solve_opts so;
    pst_solve_defaults(&so);
    so.solver = PST_SOLVER_GMRES;
    so.stored = 1;
    so.rtol = 1e-10;
    int it[2];
    for (int p = 0; p < 2; ++p) {
        pst_solve_result r = {0};
        char err[PST_ERRLEN] = "";
        CHECK_INT(pst_solve(op[p], b, u[p], &so, &r, err), PST_OK);
        CHECK(r.converged);
        it[p] = r.iterations;
        pst_solve_result_free(&r);
    }
    CHECK(abs(it[0] - it[1]) <= 2);
    double num = 0, den = 0;
    for (size_t i = 0; i < n; ++i) {
        num += (u[1][i] - u[0][i]) * (u[1][i] - u[0][i]);
        den += u[0][i] * u[0][i];
    }
    CHECK(sqrt(num / den) < 1e-5);
    for (int p = 0; p < 2; ++p) {
        free(u[p]);
        pst_op_destroy(op[p]);
    }
    free(b);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
}

static void check_refusals(void)
{
    pst_cloud *c = test_lattice(2, 0, 1, 1.0 / 21, 1.2, 0.3, 5, 1);
    size_t n = pst_cloud_size(c);
    pst_nlist *nl = test_nlist(c, 2.0);
    char err[PST_ERRLEN] = "";
    pst_op_store_opts f = {.precision = PST_STORE_FLOAT}, bad = {.precision = 7};
    double *u = test_field(c, wave), *y = malloc(n * sizeof *y);

    pst_op *op = test_op(c, nl, "lv", PST_GRAD_G1, 0);
    CHECK_INT(pst_op_store_precision(op), -1);
    CHECK_INT(pst_op_apply_stored(op, u, y), PST_EINVAL);
    CHECK_INT(pst_op_store_with(NULL, &f, err), PST_EINVAL);
    CHECK_INT(pst_op_store_with(op, &bad, err), PST_EINVAL);
    CHECK(strstr(err, "precision") != NULL);
    CHECK_INT(pst_op_store_with(op, &f, err), PST_OK);
    CHECK_INT(pst_op_store_with(op, &f, err), PST_OK); /* the same again: nothing to do */
    err[0] = '\0';
    CHECK_INT(pst_op_store(op), PST_EINVAL);
    CHECK_INT(pst_op_store_with(op, NULL, err), PST_EINVAL);
    CHECK(strstr(err, "already stored in float") != NULL);
    CHECK_INT(pst_op_store_precision(op), PST_STORE_FLOAT);
    pst_linop L;
    CHECK_INT(pst_op_linop(op, 1, &L, err), PST_OK);
    pst_nlist *half = NULL;
    CHECK_INT(pst_nlist_halve(&half, nl, err), PST_OK);
    CHECK_INT(pst_op_use_half_list(op, half, err), PST_EINVAL);
    pst_op_destroy(op);

    op = test_op(c, nl, "lv", PST_GRAD_G1, 0); /* float after double */
    CHECK_INT(pst_op_store(op), PST_OK);
    CHECK_INT(pst_op_store_with(op, &f, err), PST_EINVAL);
    CHECK(strstr(err, "already stored in double") != NULL);
    double *yd = malloc(n * sizeof *yd);
    CHECK_INT(pst_op_apply_stored(op, u, yd), PST_OK);
    pst_op_drop_store(op); /* then float: matrix-free in between */
    CHECK_INT(pst_op_store_precision(op), PST_STORE_NONE);
    CHECK_INT(pst_op_apply_stored(op, u, y), PST_EINVAL);
    pst_op_drop_store(op);
    pst_op_drop_store(NULL);
    CHECK_INT(pst_op_store_with(op, &f, err), PST_OK);
    CHECK_INT(pst_op_apply_stored(op, u, y), PST_OK);
    double moved = 0, size = 0;
    for (size_t i = 0; i < n; ++i) {
        moved = fmax(moved, fabs(y[i] - yd[i]));
        size = fmax(size, fabs(yd[i]));
    }
    CHECK(moved > 0 && moved <= 1e-6 * size); /* the float weights, not the double ones */
    free(yd);
    pst_op_destroy(op);

    op = test_op(c, nl, "lv", PST_GRAD_G1, 0); /* on a half list */
    CHECK_INT(pst_op_use_half_list(op, half, err), PST_OK);
    CHECK_INT(pst_op_store_with(op, &f, err), PST_EINVAL);
    CHECK(strstr(err, "half list") != NULL);
    pst_op_destroy(op);

    pst_op_opts o; /* qsfdi's derivatives skip the rows when asked (laplacian = 0) */
    pst_op_defaults(&o);
    o.scheme = "qsfdi";
    o.laplacian = 0;
    pst_nlist *nl3 = test_nlist(c, 3.0);
    op = test_op_of(c, nl3, &o);
    CHECK_INT(pst_op_has_rows(op), 0);
    CHECK_INT(pst_op_store_with(op, &f, err), PST_EINVAL);
    CHECK(strstr(err, "without rows") != NULL);
    pst_op_destroy(op);
    pst_nlist_destroy(nl3);

    /* spacing 1e-21: weights ~ 1/h^2 ~ 1e42 overflow float; the double store still serves */
    pst_cloud *tiny = test_lattice(2, 0, 20e-21, 1e-21, 1.2, 0.3, 5, 1);
    pst_nlist *tnl = test_nlist(tiny, 2.0);
    op = test_op(tiny, tnl, "lv", PST_GRAD_G1, 0);
    CHECK_INT(pst_op_store_with(op, &f, err), PST_ENUMERIC);
    CHECK(strstr(err, "outside the range float keeps") != NULL);
    CHECK_INT(pst_op_store_precision(op), -1);
    CHECK_INT(pst_op_store(op), PST_OK);
    pst_op_destroy(op);
    pst_nlist_destroy(tnl);
    pst_cloud_destroy(tiny);

    pst_nlist_destroy(half);
    free(u);
    free(y);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
}

int main(void)
{
    static const char *const schemes[] = {"qsfdi", "lpmps", "lsmps", "lv", "cb", "mixed1"};
    for (int dim = 2; dim <= 3; ++dim)
        for (size_t k = 0; k < sizeof schemes / sizeof *schemes; ++k)
            check_scheme(schemes[k], dim);
    check_solve();
    check_refusals();
    return check_summary("test_store32");
}
