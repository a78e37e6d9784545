/* The half-list apply (pst_op_use_half_list, docs/operators.md): for every scheme that has one,
 * in 2D and 3D, with Dirichlet and Neumann rows, uniform and per-particle h and (LV family) a
 * rough scalar or tensor mobility and the gradients G1-G4, it agrees with the whole-list apply
 * to rounding, gives the same bits for 1 and 2 threads, keeps the whole-list diagonal, refuses
 * what needs whole rows, and an AMG solve on it takes the whole list's iterations to the same
 * answer (AUTO on the Brookshaw proxy where the scheme's own matrix would need whole rows). */
#include "check.h"
#include "pstencil.h"
#include "support.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

static double wave(const double *x) { return sin(3 * x[0] + 2 * x[1] - x[2]) + x[0] * x[1]; }

/* mobility: its components (0: none), TENSOR: a diagonal tensor, one per dimension. */
enum { TENSOR = -1 };

typedef struct {
    const char *scheme;
    int variant, mobility, mean, gradient; /* mean: pst_mobility_mean; gradient 0: G1 */
} scheme_case;

/* The LV family's G1 rows go in lanes with any mobility, under either pair mean, with one h
 * or h per particle (kernels/lv_half_lanes.c); the gradients G2-G4 in chunks, and the Neumann
 * rows of every gradient (kernels/lv_half_rows.c, half_row_t). */
static const scheme_case cases[] = {
    {"qsfdi", 0, 0, 0, 0},
    {"lpmps", 0, 0, 0, 0},
    {"lsmps", 0, 0, 0, 0},
    {"lsmps", 1, 0, 0, 0},
    {"lv", 0, 0, 0, 0},
    {"lv", 0, 1, 0, 0},
    {"lv", 0, 1, PST_MEAN_HARMONIC, 0},
    {"lv", 0, TENSOR, 0, 0},
    {"lv", 0, TENSOR, PST_MEAN_HARMONIC, 0},
    {"lv", 0, 1, 0, PST_GRAD_G2},
    {"lv", 0, 1, PST_MEAN_HARMONIC, PST_GRAD_G3},
    {"lv", 0, TENSOR, 0, PST_GRAD_G4},
    {"cb", 0, 0, 0, 0},
    {"brookshaw", 0, 1, 0, 0},
    {"schwaiger", 0, 0, 0, 0}};

/* A jittered lattice with a Dirichlet layer, every 7th boundary particle Neumann, with per-
 * particle h (+-10 %) when vary_h; more than one block of rows (2048) in both dimensions. */
static pst_cloud *cloud_of(int dim, int vary_h)
{
    pst_cloud *c = dim == 2 ? test_lattice(2, 0, 1, 1.0 / 79, 1.2, 0.3, 11, 1)
                            : test_lattice(3, 0, 1, 1.0 / 17, 1.2, 0.3, 11, 1);
    test_make_neumann(c, 7);
    if (vary_h) {
        double *h = pst_cloud_h_per_particle(c);
        for (size_t i = 0; i < pst_cloud_size(c); ++i)
            h[i] *= 0.9 + 0.2 * (double)((i * 2654435761u) % 97) / 96.0;
    }
    return c;
}

static double max_abs_diff(const double *a, const double *b, size_t n, double *scale)
{
    double d = 0, s = 0;
    for (size_t i = 0; i < n; ++i) {
        d = fmax(d, fabs(a[i] - b[i]));
        s = fmax(s, fabs(b[i]));
    }
    *scale = s;
    return d;
}

/* One scheme on one cloud: whole against half, 1 against 2 threads, the diagonal. */
static void check_case(const scheme_case *sc, int dim, int vary_h)
{
    pst_cloud *c = cloud_of(dim, vary_h);
    if (sc->mobility)
        test_rough_mobility(c, sc->mobility == TENSOR ? dim : sc->mobility);
    size_t n = pst_cloud_size(c);
    double support = pst_kernel_support(pst_scheme_default_kernel(sc->scheme));
    pst_nlist *nl = test_nlist(c, support), *half = NULL;
    pst_op_opts o;
    pst_op_defaults(&o);
    o.scheme = sc->scheme;
    o.gradient = sc->gradient ? sc->gradient : PST_GRAD_G1;
    o.variant = sc->variant;
    o.mobility_mean = sc->mean;
    pst_op *op = test_op_of(c, nl, &o);
    double *u = test_field(c, wave), *yw = malloc(n * sizeof *yw), *y1 = malloc(n * sizeof *y1),
           *y2 = malloc(n * sizeof *y2), *dw = malloc(n * sizeof *dw),
           *dh = malloc(n * sizeof *dh);
    CHECK_INT(pst_op_apply(op, u, yw), PST_OK);
    CHECK_INT(pst_op_diagonal(op, dw), PST_OK);
    CHECK_INT(pst_nlist_halve(&half, nl, NULL), PST_OK);
    CHECK(2 * pst_nlist_pairs(half) == pst_nlist_pairs(nl) && pst_nlist_is_half(half));
    int64_t pattern = pst_op_pattern_pairs(op);
    char err[PST_ERRLEN] = "";
    CHECK_INT(pst_op_use_half_list(op, half, err), PST_OK);
    pst_nlist_destroy(nl); /* the operator no longer reads it */
    CHECK(pst_op_half_colours(op) >= 2 && pst_op_half_colours(op) <= 64);
    CHECK(pst_op_pattern_pairs(op) == pattern);
    int saved = omp_get_max_threads();
    omp_set_num_threads(1);
    CHECK_INT(pst_op_apply(op, u, y1), PST_OK);
    omp_set_num_threads(2);
    CHECK_INT(pst_op_apply(op, u, y2), PST_OK);
    omp_set_num_threads(saved);
    CHECK(memcmp(y1, y2, n * sizeof *y1) == 0);
    double scale, d = max_abs_diff(y1, yw, n, &scale);
    CHECK(d <= 1e-12 * scale);
    if (!(d <= 1e-12 * scale))
        fprintf(stderr,
                "  %s (variant %d, mobility %d, gradient %d) %dD vary_h %d: half vs whole "
                "%.3g of %.3g\n",
                sc->scheme, sc->variant, sc->mobility, sc->gradient, dim, vary_h, d, scale);
    CHECK_INT(pst_op_diagonal(op, dh), PST_OK);
    CHECK(memcmp(dh, dw, n * sizeof *dh) == 0);
    pst_op_destroy(op);
    pst_nlist_destroy(half);
    pst_cloud_destroy(c);
    free(u);
    free(yw);
    free(y1);
    free(y2);
    free(dw);
    free(dh);
}

static void test_agreement(void)
{
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k)
        for (int dim = 2; dim <= 3; ++dim)
            for (int vary_h = 0; vary_h <= 1; ++vary_h)
                check_case(&cases[k], dim, vary_h);
}

/* What needs whole rows is refused, with a message where the call takes one. */
static void test_refusals(void)
{
    pst_cloud *c = test_lattice(2, 0, 1, 0.05, 1.2, 0.3, 3, 1);
    size_t n = pst_cloud_size(c);
    pst_nlist *nl = test_nlist(c, 3.0), *half = NULL, *other = NULL;
    CHECK_INT(pst_nlist_halve(&half, nl, NULL), PST_OK);
    char err[PST_ERRLEN] = "";
    CHECK_INT(pst_nlist_halve(&other, half, err), PST_EINVAL);
    CHECK(other == NULL && strstr(err, "half") != NULL);
    pst_op_opts o;
    pst_op_defaults(&o);
    o.scheme = "qsfdi";
    pst_op *op = NULL;
    err[0] = 0;
    CHECK_INT(pst_op_create(&op, c, half, &o, err), PST_EINVAL);
    CHECK(op == NULL && strstr(err, "whole") != NULL);
    /* no half-list apply: cspm */
    pst_op *cspm = test_op(c, nl, "cspm", PST_GRAD_G1, 0);
    err[0] = 0;
    CHECK_INT(pst_op_use_half_list(cspm, half, err), PST_EINVAL);
    CHECK(strstr(err, "cspm") != NULL && !pst_scheme_supports("cspm", PST_SUPPORTS_HALF_LIST));
    CHECK(pst_scheme_supports("qsfdi", PST_SUPPORTS_HALF_LIST));
    pst_op_destroy(cspm);
    /* a list that is not the operator's half */
    pst_op *qs = test_op(c, nl, "qsfdi", PST_GRAD_G1, 0);
    err[0] = 0;
    CHECK_INT(pst_op_use_half_list(qs, nl, err), PST_EINVAL);
    CHECK(strstr(err, "half") != NULL);
    CHECK_INT(pst_op_use_half_list(qs, half, NULL), PST_OK);
    CHECK_INT(pst_op_use_half_list(qs, half, NULL), PST_EINVAL);
    double *u = calloc(n, sizeof *u), *g[3] = {calloc(n, sizeof(double)),
                                               calloc(n, sizeof(double)), NULL};
    CHECK_INT(pst_op_store(qs), PST_EINVAL);
    CHECK_INT(pst_op_apply_stored(qs, u, g[0]), PST_EINVAL);
    pst_csr a;
    CHECK_INT(pst_op_assemble(qs, &a), PST_EINVAL);
    pst_op_audit au;
    CHECK_INT(pst_op_audit_rows(qs, &au), PST_EINVAL);
    CHECK_INT(pst_op_gradient(qs, u, g), PST_EINVAL);
    pst_op_destroy(qs);
    /* stored weights: the half list would only be slower */
    qs = test_op(c, nl, "qsfdi", PST_GRAD_G1, 0);
    CHECK_INT(pst_op_store(qs), PST_OK);
    CHECK_INT(pst_op_use_half_list(qs, half, err), PST_EINVAL);
    pst_op_destroy(qs);
    free(u);
    free(g[0]);
    free(g[1]);
    pst_nlist_destroy(half);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
}

/* A 3D qsfdi Poisson solve, GMRES + AMG (the Brookshaw proxy within 1.6 h, and the whole list,
 * both built from the half list) and GMRES + Jacobi: the half-list operator takes the whole
 * list's iterations, to the same answer. */
static void test_solves(void)
{
    if (!pst_have_amg())
        return;
    pst_cloud *c = test_lattice(3, 0, 1, 1.0 / 15, 1.2, 0.3, 5, 1);
    size_t n = pst_cloud_size(c);
    pst_nlist *nl = test_nlist(c, 3.0), *half = NULL;
    CHECK_INT(pst_nlist_halve(&half, nl, NULL), PST_OK);
    pst_op *whole = test_op(c, nl, "qsfdi", PST_GRAD_G1, 0);
    pst_op *op = test_op(c, nl, "qsfdi", PST_GRAD_G1, 0);
    CHECK_INT(pst_op_use_half_list(op, half, NULL), PST_OK);
    double *b = test_field(c, wave), *uw = calloc(n, sizeof *uw), *uh = calloc(n, sizeof *uh);
    const int precond[3] = {PST_PREC_AMG, PST_PREC_AMG, PST_PREC_JACOBI};
    const double radius[3] = {-1, 0, -1};
    for (int k = 0; k < 3; ++k) {
        pst_solve_opts so;
        pst_solve_defaults(&so);
        so.precond = precond[k];
        so.amg_radius = radius[k];
        so.rtol = 1e-10;
        pst_solve_result rw, rh;
        memset(uw, 0, n * sizeof *uw);
        memset(uh, 0, n * sizeof *uh);
        CHECK_INT(pst_solve(whole, b, uw, &so, &rw, NULL), PST_OK);
        CHECK_INT(pst_solve(op, b, uh, &so, &rh, NULL), PST_OK);
        CHECK_INT(rh.iterations, rw.iterations);
        double scale, d = max_abs_diff(uh, uw, n, &scale);
        CHECK(d <= 1e-8 * scale);
        pst_solve_result_free(&rw);
        pst_solve_result_free(&rh);
    }
    pst_op_destroy(op);
    pst_op_destroy(whole);
    pst_nlist_destroy(half);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
    free(b);
    free(uw);
    free(uh);
}

/* lsmps names its own AMG matrix, which needs whole rows: on a half list AUTO takes the
 * Brookshaw proxy (amg_own 0) and converges; asking for the own matrix is refused clearly. */
static void test_auto_source(void)
{
    if (!pst_have_amg())
        return;
    pst_cloud *c = test_lattice(2, 0, 1, 1.0 / 40, 1.2, 0.3, 9, 1);
    size_t n = pst_cloud_size(c);
    pst_nlist *nl = test_nlist(c, 3.0), *half = NULL;
    CHECK_INT(pst_nlist_halve(&half, nl, NULL), PST_OK);
    pst_op *op = test_op(c, nl, "lsmps", PST_GRAD_G1, 0);
    CHECK_INT(pst_op_use_half_list(op, half, NULL), PST_OK);
    pst_solve_opts so;
    pst_solve_defaults(&so);
    so.precond = PST_PREC_AMG;
    so.max_iter = 1000;
    pst_krylov *k = NULL;
    CHECK_INT(pst_krylov_create(&k, op, &so, NULL), PST_OK);
    pst_krylov_stats st;
    pst_krylov_get_stats(k, &st);
    CHECK_INT(st.amg_own, 0);
    double *b = test_field(c, wave), *u = calloc(n, sizeof *u);
    pst_solve_result r;
    CHECK_INT(pst_krylov_solve(k, b, u, &r, NULL), PST_OK);
    pst_solve_result_free(&r);
    pst_krylov_destroy(k);
    so.amg_source = PST_AMG_OWN;
    char err[PST_ERRLEN] = "";
    k = NULL;
    CHECK_INT(pst_krylov_create(&k, op, &so, err), PST_EINVAL);
    CHECK(k == NULL && strstr(err, "half list") != NULL);
    pst_op_destroy(op);
    pst_nlist_destroy(half);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
    free(b);
    free(u);
}

int main(void)
{
    if (pst_have_amg())
        test_mpi_init(); /* the AMG solves need MPI */
    test_agreement();
    test_refusals();
    test_solves();
    test_auto_source();
    return check_summary("test_half");
}
