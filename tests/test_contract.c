/* The operator contract, checked for every registered scheme (a loop over pst_scheme_count(), so
 * a new scheme is held to it by its registry line alone), in 2D and 3D:
 *   - exactness: the interior rows reproduce the Laplacian of every monomial up to the scheme's
 *     degree (pst_scheme_degree) on a jittered cloud, rows cut by its edge included, and fail at
 *     the next degree (so the table's degree is the highest); on a regular lattice, the rows with
 *     full support reproduce degree_lattice;
 *   - the matrix-free apply, the stored apply and the assembled matrix agree to PATH_TOL, the
 *     diagonal bit for bit;
 *   - 1 and 2 threads give bit-identical operators: apply, status, stored apply, diagonal, and
 *     the gradient and Hessian where the scheme has them;
 *   - Neumann rows reproduce n . grad u of a linear field (schemes of degree >= 1);
 *   - degenerate rows (an isolated particle, a collinear / coplanar neighbourhood) are counted,
 *     finite, and the isolated row is empty;
 *   - options: a neighbour list narrower than the kernel's support, a variant the scheme does
 *     not have and (for a scheme without div(M grad u)) a mobility are refused with a message;
 *     the derivatives a scheme has not are PST_EINVAL.
 * The schemes' own tests (paper tables, convergence orders, oracles) live in their files. */
#include "check.h"
#include "support.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

/* Relative agreement of the two apply paths and the assembled matrix (rounding of one row sum
 * in another order). */
#define PATH_TOL 1e-12
/* Exactness: |L p - lap p| relative to the row's scale sum_j |w_ij (p_j - p_i)| + |lap p|. */
#define EXACT_TOL 1e-9
/* The next degree must miss by more than this (same scale). */
#define INEXACT_MIN 1e-6

/* The monomials of degree k in dim variables: exponents e[m][3]; returns their number. */
static int monomials(int dim, int k, int e[][3])
{
    int m = 0;
    for (int a = k; a >= 0; --a)
        for (int b = k - a; b >= 0; --b) {
            int c = k - a - b;
            if (dim == 2 && c != 0)
                continue;
            e[m][0] = a;
            e[m][1] = b;
            e[m][2] = c;
            ++m;
        }
    return m;
}

static double ipow(double x, int p) { return p < 0 ? 0.0 : p == 0 ? 1.0 : x * ipow(x, p - 1); }

/* The monomial x^e and its Laplacian at x (shifted by 0.3 so that no coordinate is 0). */
static double mono(const int e[3], const double *x)
{
    return ipow(x[0] + 0.3, e[0]) * ipow(x[1] + 0.3, e[1]) * ipow(x[2] + 0.3, e[2]);
}
static double mono_lap(const int e[3], const double *x)
{
    double s = 0;
    for (int a = 0; a < 3; ++a) {
        int f[3] = {e[0], e[1], e[2]};
        f[a] -= 2;
        s += e[a] * (e[a] - 1) * (f[a] < 0 ? 0.0 : mono(f, x));
    }
    return s;
}

/* The worst relative error of op's rows with status ok on the monomials of degree k, over the
 * particles at least `margin` inside [0, 1]^dim (their number into *rows); a is op assembled. */
static double degree_error(const pst_cloud *c, pst_op *op, const pst_csr *a, int k,
                           double margin, size_t *rows)
{
    int dim = pst_cloud_dim(c), e[15][3], nm = monomials(dim, k, e);
    size_t n = pst_cloud_size(c);
    double *u = malloc(n * sizeof *u), *y = malloc(n * sizeof *y), worst = 0;
    *rows = 0;
    for (int m = 0; m < nm; ++m) {
        for (size_t i = 0; i < n; ++i) {
            double x[3];
            test_position(c, i, x);
            u[i] = mono(e[m], x);
        }
        pst_op_apply(op, u, y);
        for (size_t i = 0; i < n; ++i) {
            double x[3];
            test_position(c, i, x);
            if (pst_op_status(op)[i] != PST_ROW_OK || !test_inside(c, i, 0.0, 1.0, margin))
                continue;
            *rows += m == 0;
            double lap = mono_lap(e[m], x), scale = fabs(lap);
            for (int64_t q = a->rowptr[i]; q < a->rowptr[i + 1]; ++q)
                scale += fabs(a->val[q] * (u[a->col[q]] - u[i]));
            worst = fmax(worst, fabs(y[i] - lap) / (scale > 0 ? scale : 1.0));
        }
    }
    free(u);
    free(y);
    return worst;
}

static double support_of(const char *name)
{
    return pst_kernel_support(pst_scheme_default_kernel(name));
}

/* Exactness at the table's degree on a jittered cloud (all rows interior, the edge rows cut)
 * and a miss at the next; degree_lattice on the rows of a regular lattice whose neighbours
 * have full support too (the rows of cspm, csph2g and the mixed schemes read their neighbours'
 * volumes or gradients). */
static void test_exactness(const char *name, int dim)
{
    double s0 = dim == 2 ? 0.1 : 1.0 / 7, R = support_of(name);
    int deg = pst_scheme_degree(name, 0), deg_lat = pst_scheme_degree(name, 1);
    size_t rows;
    pst_cloud *c = test_lattice(dim, 0.0, 1.0, s0, 1.2, 0.3, 7, 0);
    pst_nlist *nl = test_nlist(c, R);
    pst_op *op = test_op(c, nl, name, PST_GRAD_G1, 0);
    pst_csr a;
    CHECK_INT(pst_op_assemble(op, &a), PST_OK);
    double err = 0;
    for (int k = 0; k <= deg; ++k)
        err = fmax(err, degree_error(c, op, &a, k, -1.0, &rows));
    double miss = degree_error(c, op, &a, deg + 1, -1.0, &rows);
    pst_csr_free(&a);
    printf("%-9s %dD: degree %d error %.1e (%zu rows), degree %d error %.1e", name, dim, deg,
           err, rows, deg + 1, miss);
    CHECK(rows > pst_cloud_size(c) / 2);
    CHECK(err <= EXACT_TOL);
    CHECK(miss > INEXACT_MIN);
    pst_op_destroy(op);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);

    double s1 = dim == 2 ? 0.05 : 1.0 / 12, h1 = dim == 2 ? 1.2 : 0.8;
    c = test_lattice(dim, 0.0, 1.0, s1, h1, 0.0, 7, 0);
    nl = test_nlist(c, R);
    op = test_op(c, nl, name, PST_GRAD_G1, 0);
    CHECK_INT(pst_op_assemble(op, &a), PST_OK);
    double lat = 0;
    for (int k = 0; k <= deg_lat; ++k)
        lat = fmax(lat, degree_error(c, op, &a, k, 2.0 * R * h1 * s1 + 1e-9, &rows));
    pst_csr_free(&a);
    printf(", lattice degree %d error %.1e (%zu rows)\n", deg_lat, lat, rows);
    CHECK(rows > 0);
    CHECK(lat <= EXACT_TOL);
    pst_op_destroy(op);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
}

static double smooth(const double *x) { return sin(2.0 * x[0]) * cos(x[1]) + x[2] * x[0]; }
static double linear(const double *x) { return 1.0 + 2.0 * x[0] - 3.0 * x[1] + 0.5 * x[2]; }

/* Stored apply and diagonal of the two operators of t, op1 with 1 thread, op2 with 2. */
static void check_stored_threads(const test_threads *t, const double *u, size_t n)
{
    double *a = malloc(n * sizeof *a), *b = malloc(n * sizeof *b);
    omp_set_num_threads(1);
    CHECK_INT(pst_op_store(t->op1), PST_OK);
    CHECK_INT(pst_op_apply_stored(t->op1, u, a), PST_OK);
    omp_set_num_threads(2);
    CHECK_INT(pst_op_apply_stored(t->op2, u, b), PST_OK);
    CHECK(memcmp(a, b, n * sizeof *a) == 0);
    omp_set_num_threads(1);
    CHECK_INT(pst_op_diagonal(t->op1, a), PST_OK);
    omp_set_num_threads(2);
    CHECK_INT(pst_op_diagonal(t->op2, b), PST_OK);
    CHECK(memcmp(a, b, n * sizeof *a) == 0);
    free(a);
    free(b);
}

/* The worst |row - n . grad u| / max |n . grad u| over the Neumann rows with status ok of a
 * linear u, and their number. */
static double neumann_error(pst_cloud *c, pst_op *op, size_t *count)
{
    size_t n = pst_cloud_size(c);
    int dim = pst_cloud_dim(c);
    const double g[3] = {2.0, -3.0, 0.5};
    double *u = test_field(c, linear), *y = malloc(n * sizeof *y), worst = 0, scale = 0;
    pst_op_apply(op, u, y);
    *count = 0;
    for (size_t i = 0; i < n; ++i) {
        if (pst_cloud_kinds(c)[i] != PST_NEUMANN || pst_op_status(op)[i] != PST_ROW_OK)
            continue;
        double flux = 0;
        for (int a = 0; a < dim; ++a)
            flux += pst_cloud_normal(c, a)[i] * g[a];
        worst = fmax(worst, fabs(y[i] - flux));
        scale = fmax(scale, fabs(flux));
        ++*count;
    }
    free(u);
    free(y);
    return scale > 0 ? worst / scale : worst;
}

/* Apply paths, threads and Neumann rows on a cloud with all three kinds of particle. */
static void test_paths_threads(const char *name, int dim)
{
    pst_cloud *c = test_lattice(dim, 0.0, 1.0, dim == 2 ? 0.05 : 0.125, 1.2, 0.3, 11, 1);
    test_make_neumann(c, 3);
    size_t n = pst_cloud_size(c);
    pst_nlist *nl = test_nlist(c, support_of(name));
    int derivs = pst_scheme_supports(name, PST_SUPPORTS_HESSIAN)    ? 2
                 : pst_scheme_supports(name, PST_SUPPORTS_GRADIENT) ? 1
                                                                     : 0;
    double *u = test_field(c, smooth), *y1 = malloc(n * sizeof *y1), *y2 = malloc(n * sizeof *y2),
           *ys = malloc(n * sizeof *ys);
    test_threads t = test_one_vs_two_threads(c, nl, name, PST_GRAD_G1, 0, u, y1, y2, derivs);
    CHECK(t.same_apply);
    CHECK(t.same_status);
    for (int a = 0; a < 3; ++a)
        CHECK(t.same_grad[a]);
    for (int e = 0; e < 6; ++e)
        CHECK(t.same_hess[e]);
    test_paths p = test_compare_paths(t.op2, u, y2, ys);
    CHECK_INT(p.unstored, PST_EINVAL);
    CHECK_INT(p.store, PST_OK);
    CHECK_INT(p.stored, PST_OK);
    CHECK_INT(p.assemble, PST_OK);
    CHECK_INT(p.diagonal, PST_OK);
    CHECK(p.finite && p.finite_values && p.sorted);
    CHECK(p.worst <= PATH_TOL);
    CHECK(p.worst_csr <= PATH_TOL);
    CHECK(p.worst_diag == 0.0);
    check_stored_threads(&t, u, n);
    size_t nneu = 0;
    double neu = neumann_error(c, t.op2, &nneu);
    printf("%-9s %dD: stored vs free %.1e, csr vs free %.1e, Neumann rows %zu error %.1e\n",
           name, dim, p.worst, p.worst_csr, nneu, neu);
    if (pst_scheme_degree(name, 0) >= 1) {
        CHECK(nneu > 5);
        CHECK(neu <= EXACT_TOL);
    }
    pst_op_destroy(t.op1);
    pst_op_destroy(t.op2);
    free(u);
    free(y1);
    free(y2);
    free(ys);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
}

/* Every value of apply, the stored apply, the gradient and the Hessian (where the scheme has
 * them) finite, and the stored apply equal to the matrix-free one to PATH_TOL. */
static int degenerate_outputs_finite(pst_op *op, int dim, size_t n, const double *u,
                                     const double *y)
{
    double *ys = malloc(n * sizeof *ys), *d[9];
    for (int k = 0; k < 9; ++k)
        d[k] = malloc(n * sizeof *d[k]);
    int ok = pst_op_store(op) == PST_OK && pst_op_apply_stored(op, u, ys) == PST_OK;
    int ng = pst_op_gradient(op, u, d) == PST_OK ? dim : 0;
    int nh = pst_op_hessian(op, u, d + 3) == PST_OK ? dim * (dim + 1) / 2 : 0;
    for (size_t i = 0; i < n; ++i) {
        ok = ok && isfinite(y[i]) && fabs(ys[i] - y[i]) <= PATH_TOL * (fabs(y[i]) + 1);
        for (int k = 0; k < ng; ++k)
            ok = ok && isfinite(d[k][i]);
        for (int k = 0; k < nh; ++k)
            ok = ok && isfinite(d[3 + k][i]);
    }
    for (int k = 0; k < 9; ++k)
        free(d[k]);
    free(ys);
    return ok;
}

/* A line (2D) or a plane (3D) of particles, one isolated particle far away: every output
 * finite (degenerate_outputs_finite), the isolated row too-few-neighbours and empty, the flat
 * rows of a scheme that fits moments (degree >= 1) not ok. */
static void test_degenerate(const char *name, int dim)
{
    size_t n = (dim == 2 ? 11 : 25) + 1;
    pst_cloud *c;
    CHECK_INT(pst_cloud_create(&c, dim, n, NULL), PST_OK);
    size_t m = test_flat_layout(c);
    for (int a = 0; a < dim; ++a)
        pst_cloud_coord(c, a)[m] = 10.0;
    pst_cloud_set_h_uniform(c, 0.1, NULL);
    pst_nlist *nl = test_nlist(c, support_of(name));
    pst_op *op = test_op(c, nl, name, PST_GRAD_G1, 0);
    double *u = malloc(n * sizeof *u), *y = malloc(n * sizeof *y);
    for (size_t i = 0; i < n; ++i)
        u[i] = (double)(i * i);
    CHECK_INT(pst_op_apply(op, u, y), PST_OK);
    CHECK(degenerate_outputs_finite(op, dim, n, u, y));
    CHECK_INT(pst_op_status(op)[m], PST_ROW_TOO_FEW);
    CHECK(y[m] == 0.0);
    size_t counts[PST_ROW_NSTATUS], flat_ok = 0;
    pst_op_status_counts(op, counts);
    for (size_t i = 0; i < m; ++i)
        flat_ok += pst_op_status(op)[i] == PST_ROW_OK;
    CHECK(counts[PST_ROW_TOO_FEW] >= 1);
    if (pst_scheme_degree(name, 0) >= 1)
        CHECK_INT(flat_ok, 0);
    pst_op_destroy(op);
    free(u);
    free(y);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
}

/* An operator of `name` from o (scheme and defaults set here), and its status. */
static int create(pst_op **op, const pst_cloud *c, const pst_nlist *nl, const char *name,
                  int variant, char *err)
{
    pst_op_opts o;
    pst_op_defaults(&o);
    o.scheme = name;
    o.variant = variant;
    *op = NULL;
    return pst_op_create(op, c, nl, &o, err);
}

static void test_options(const char *name, int dim)
{
    pst_cloud *c = test_lattice(dim, 0.0, 1.0, dim == 2 ? 0.1 : 0.25, 1.2, 0.2, 3, 0);
    double R = support_of(name);
    char err[PST_ERRLEN];
    pst_op *op;
    pst_nlist *narrow = test_nlist(c, R - 0.5), *nl = test_nlist(c, R);
    CHECK_INT(create(&op, c, narrow, name, 0, err), PST_EINVAL);
    CHECK(op == NULL && strstr(err, "support") != NULL);
    CHECK_INT(create(&op, c, nl, name, pst_scheme_variants(name), err), PST_EINVAL);
    CHECK(op == NULL && strstr(err, "variant") != NULL);
    for (int v = 0; v < pst_scheme_variants(name); ++v) {
        CHECK_INT(create(&op, c, nl, name, v, err), PST_OK);
        double *d[6] = {NULL}, *u = test_field(c, linear);
        if (!pst_scheme_supports(name, PST_SUPPORTS_GRADIENT))
            CHECK_INT(pst_op_gradient(op, u, d), PST_EINVAL);
        if (!pst_scheme_supports(name, PST_SUPPORTS_HESSIAN))
            CHECK_INT(pst_op_hessian(op, u, d), PST_EINVAL);
        if (!pst_scheme_supports(name, PST_SUPPORTS_INTERPOLATE))
            CHECK_INT(pst_op_interpolate(op, (const double *const *)d, 0, u, NULL, NULL, NULL,
                                         err),
                      PST_EINVAL);
        free(u);
        pst_op_destroy(op);
    }
    if (!pst_scheme_supports(name, PST_SUPPORTS_MOBILITY)) {
        CHECK_INT(pst_cloud_set_mobility(c, 1, NULL), PST_OK);
        CHECK_INT(create(&op, c, nl, name, 0, err), PST_EINVAL);
        CHECK(op == NULL && strstr(err, "mobility") != NULL);
    }
    pst_nlist_destroy(narrow);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
}

int main(void)
{
    CHECK(pst_scheme_count() > 0);
    CHECK_INT(pst_scheme_degree("no such scheme", 0), -1);
    CHECK_INT(pst_scheme_variants("no such scheme"), 0);
    for (int s = 0; s < pst_scheme_count(); ++s) {
        const char *name = pst_scheme_name(s);
        CHECK(pst_scheme_degree(name, 1) >= pst_scheme_degree(name, 0));
        for (int dim = 2; dim <= 3; ++dim) {
            test_exactness(name, dim);
            test_paths_threads(name, dim);
            test_degenerate(name, dim);
            test_options(name, dim);
        }
    }
    return check_summary("test_contract");
}
