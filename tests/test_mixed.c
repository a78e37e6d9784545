/* The least-squares mixed schemes (mixed0, mixed1, mixed2; seed 003 Models 3-5): exactness of
 * the nested Laplacian and of div(m grad u) on jittered clouds (K = 0.8), the LS gradient and
 * Hessian, Neumann rows, the two apply paths and the assembled matrix on the neighbours-of-
 * neighbours pattern, which only the paths that read it build, 1 vs 2 threads, degenerate rows
 * and bad options, in 2D and 3D. */
#include "check.h"
#include "operator.h"
#include "pstencil.h"
#include "support.h"

#include <omp.h>
#include <stdlib.h>
#include <string.h>

static const char *const schemes[] = {"mixed0", "mixed1", "mixed2"};
#define NSCHEMES 3

/* A lattice on [0,1]^dim with spacing s0, h = f s0, jitter K. */
static pst_cloud *lattice(int dim, double s0, double f, double K, int boundary_layer)
{
    return test_lattice(dim, 0.0, 1.0, s0, f, K, 11, boundary_layer);
}

static pst_op *make_op(const pst_cloud *c, const pst_nlist *nl, const char *scheme)
{
    return test_op(c, nl, scheme, PST_GRAD_G1, 0);
}

/* Every coordinate at least `margin` inside [0,1]. */
static int inner(const pst_cloud *c, size_t i, double margin)
{
    return test_inside(c, i, 0.0, 1.0, margin);
}

static const double slope[3] = {2.0, -3.0, 0.5};
static double linear(const double *x) { return 1.0 + 2.0 * x[0] - 3.0 * x[1] + 0.5 * x[2]; }
/* a full quadratic; its Laplacian is 2 (1.5 + 0.5 + 1) in 3D, 2 (1.5 + 0.5) in 2D */
static double quad(const double *x)
{
    return 1.5 * x[0] * x[0] + 0.5 * x[1] * x[1] + x[2] * x[2] + 0.7 * x[0] * x[1] -
           0.4 * x[0] * x[2] + 0.3 * x[1] * x[2] + x[0] - x[1];
}
static void quad_grad(const double *x, double g[3])
{
    g[0] = 3.0 * x[0] + 0.7 * x[1] - 0.4 * x[2] + 1.0;
    g[1] = x[1] + 0.7 * x[0] + 0.3 * x[2] - 1.0;
    g[2] = 2.0 * x[2] - 0.4 * x[0] + 0.3 * x[1];
}
/* scalar mobility m = 1 + c . x */
static const double mc[3] = {0.5, -0.3, 0.2};
static double mobility(const double *x) { return 1.0 + mc[0] * x[0] + mc[1] * x[1] + mc[2] * x[2]; }
/* div(m grad quad) = m lap(quad) + grad m . grad quad */
static double div_m_grad_quad(const double *x, int dim)
{
    double g[3], lap = dim == 2 ? 4.0 : 6.0, s = mobility(x) * lap;
    quad_grad(x, g);
    for (int d = 0; d < dim; ++d)
        s += mc[d] * g[d];
    return s;
}

/* The exactness test of one scheme on one cloud: linear u (L u = 0), div(m grad u) with linear
 * m and u (= grad m . grad u), the gradient of linear u, and for mixed2 quadratics (L, div(m
 * grad), gradient, Hessian), at rows with full 2-ring support (margin 6h). Returns the worst
 * quadratic Laplacian error (to compare the schemes). */
static double exactness(pst_cloud *c, const pst_nlist *nl, const char *scheme, double margin)
{
    int dim = pst_cloud_dim(c), quadratic = strcmp(scheme, "mixed2") == 0;
    size_t n = pst_cloud_size(c), used = 0;
    double *u = test_field(c, linear), *q = test_field(c, quad), *y = malloc(n * sizeof *y);
    double *g[3], *hs[6];
    for (int d = 0; d < 3; ++d)
        g[d] = malloc(n * sizeof *g[d]);
    for (int d = 0; d < 6; ++d)
        hs[d] = malloc(n * sizeof *hs[d]);
    pst_op *op = make_op(c, nl, scheme);
    double e_lin = 0, e_grad = 0, e_mob = 0, e_quad = 0, e_qmob = 0, e_qgrad = 0, e_hess = 0;
    pst_op_apply(op, u, y);
    CHECK_INT(pst_op_gradient(op, u, g), PST_OK);
    for (size_t i = 0; i < n; ++i) {
        if (!inner(c, i, margin))
            continue;
        ++used;
        e_lin = fmax(e_lin, fabs(y[i]));
        for (int d = 0; d < dim; ++d)
            e_grad = fmax(e_grad, fabs(g[d][i] - slope[d]));
    }
    pst_op_apply(op, q, y);
    CHECK_INT(pst_op_gradient(op, q, g), PST_OK);
    CHECK_INT(pst_op_hessian(op, q, hs), quadratic ? PST_OK : PST_EINVAL);
    for (size_t i = 0; i < n; ++i) {
        if (!inner(c, i, margin))
            continue;
        double x[3], gq[3];
        test_position(c, i, x);
        quad_grad(x, gq);
        double lap = dim == 2 ? 4.0 : 6.0;
        e_quad = fmax(e_quad, fabs(y[i] - lap) / lap);
        for (int d = 0; d < dim; ++d)
            e_qgrad = fmax(e_qgrad, fabs(g[d][i] - gq[d]));
        if (quadratic) {
            double h2[6] = {3.0, 1.0, 0.7, 0, 0, 0}; /* 2D: xx, yy, xy */
            if (dim == 3) {
                double h3[6] = {3.0, 1.0, 2.0, 0.7, -0.4, 0.3};
                memcpy(h2, h3, sizeof h2);
            }
            for (int k = 0; k < (dim == 2 ? 3 : 6); ++k)
                e_hess = fmax(e_hess, fabs(hs[k][i] - h2[k]));
        }
    }
    pst_op_destroy(op);
    /* heterogeneous scalar mobility m = 1 + c . x */
    pst_cloud_set_mobility(c, 1, NULL);
    double *m = pst_cloud_mobility(c, 0);
    for (size_t i = 0; i < n; ++i) {
        double x[3];
        test_position(c, i, x);
        m[i] = mobility(x);
    }
    op = make_op(c, nl, scheme);
    pst_op_apply(op, u, y);
    double target = 0;
    for (int d = 0; d < dim; ++d)
        target += mc[d] * slope[d];
    for (size_t i = 0; i < n; ++i)
        if (inner(c, i, margin))
            e_mob = fmax(e_mob, fabs(y[i] - target) / fabs(target));
    pst_op_apply(op, q, y);
    for (size_t i = 0; i < n; ++i)
        if (inner(c, i, margin)) {
            double x[3];
            test_position(c, i, x);
            double t = div_m_grad_quad(x, dim);
            e_qmob = fmax(e_qmob, fabs(y[i] - t) / fabs(t));
        }
    pst_op_destroy(op);
    pst_cloud_set_mobility(c, 0, NULL);
    printf("exact %dD %s (%zu rows): linear |Lu| %.2e, grad err %.2e, div(m grad lin) rel %.2e; "
           "quadratic: lap rel %.2e, div(m grad) rel %.2e, grad err %.2e, hessian err %.2e\n",
           dim, scheme, used, e_lin, e_grad, e_mob, e_quad, e_qmob, e_qgrad, e_hess);
    CHECK(used >= (dim == 2 ? 100u : 8u));
    CHECK(e_lin <= 1e-9);
    CHECK(e_grad <= 1e-10);
    CHECK(e_mob <= 1e-9);
    if (quadratic) {
        CHECK(e_quad <= 1e-9);
        CHECK(e_qmob <= 1e-9);
        CHECK(e_qgrad <= 1e-10);
        CHECK(e_hess <= 1e-8);
    } else {
        CHECK(e_qgrad >= 1e-6); /* the linear fit is not exact for quadratics on disorder */
    }
    free(u);
    free(q);
    free(y);
    for (int d = 0; d < 3; ++d)
        free(g[d]);
    for (int d = 0; d < 6; ++d)
        free(hs[d]);
    return e_quad;
}

/* Jittered clouds K = 0.8, h = 1.2 s0 in 2D, 1.0 s0 in 3D (the precompute builds the 2-ring
 * pattern, |N|^2 per row): full support of the nested operator is 2 * 3h from the box. */
static void test_exactness(void)
{
    for (int dim = 2; dim <= 3; ++dim) {
        double s0 = dim == 2 ? 1.0 / 30 : 1.0 / 16, f = dim == 2 ? 1.2 : 1.0;
        pst_cloud *c = lattice(dim, s0, f, 0.8, 0);
        pst_nlist *nl = test_nlist(c, 3.0);
        double eq[NSCHEMES];
        for (int s = 0; s < NSCHEMES; ++s)
            eq[s] = exactness(c, nl, schemes[s], 6.0 * f * s0);
        CHECK(eq[0] >= 1e-4 && eq[1] >= 1e-4); /* linear fits: O(1) truncation on disorder */
        pst_nlist_destroy(nl);
        pst_cloud_destroy(c);
    }
}

/* On a regular lattice the linear fit is centred (odd moments vanish), so mixed0/mixed1 give
 * exact gradients of quadratics and the nested Laplacian is exact for quadratics inside: 2
 * rings (6h) from the box for mixed1, 3 rings (9h) for mixed0, whose volumes V~ (eq. 4) must
 * be uniform on the 2-ring too. */
static void test_regular_lattice(void)
{
    for (int dim = 2; dim <= 3; ++dim) {
        double s0 = dim == 2 ? 1.0 / 30 : 1.0 / 18, f = dim == 2 ? 1.2 : 1.0;
        pst_cloud *c = lattice(dim, s0, f, 0.0, 0);
        pst_nlist *nl = test_nlist(c, 3.0);
        size_t n = pst_cloud_size(c);
        double *q = test_field(c, quad), *y = malloc(n * sizeof *y);
        for (int s = 0; s < 2; ++s) {
            pst_op *op = make_op(c, nl, schemes[s]);
            pst_op_apply(op, q, y);
            double worst = 0, lap = dim == 2 ? 4.0 : 6.0;
            size_t used = 0;
            for (size_t i = 0; i < n; ++i)
                if (inner(c, i, (s == 0 ? 9 : 6) * f * s0 - 1e-9)) {
                    worst = fmax(worst, fabs(y[i] - lap) / lap);
                    ++used;
                }
            printf("lattice %dD %s: lap(quadratic) rel err %.2e over %zu rows\n", dim,
                   schemes[s], worst, used);
            CHECK(used >= 1);
            CHECK(worst <= 1e-10);
            pst_op_destroy(op);
        }
        free(q);
        free(y);
        pst_nlist_destroy(nl);
        pst_cloud_destroy(c);
    }
}

/* Both apply paths, the assembled matrix and the diagonal on the 2-ring pattern, on a cloud
 * with all three kinds and no/scalar/tensor mobility; 1 and 2 threads bit for bit; Neumann rows
 * equal n . M grad u for linear u and constant M. */
static void test_paths_and_threads(void)
{
    for (int dim = 2; dim <= 3; ++dim)
        for (int ncomp = 0; ncomp <= dim; ncomp += (ncomp == 1 ? dim - 1 : 1)) {
            pst_cloud *c = dim == 2 ? lattice(2, 1.0 / 15, 1.2, 0.3, 1)
                                    : lattice(3, 1.0 / 7, 1.0, 0.3, 1);
            const uint8_t *kind = pst_cloud_kinds(c);
            size_t n = pst_cloud_size(c);
            test_make_neumann(c, 3); /* every third boundary particle Neumann */
            test_rough_mobility(c, ncomp);
            pst_nlist *nl = test_nlist(c, 3.0);
            double *u = test_field(c, quad), *ul = test_field(c, linear),
                   *y1 = malloc(n * sizeof *y1), *y2 = malloc(n * sizeof *y2),
                   *y3 = malloc(n * sizeof *y3);
            for (int s = 0; s < NSCHEMES; ++s) {
                test_threads t =
                    test_one_vs_two_threads(c, nl, schemes[s], PST_GRAD_G1, 0, u, y3, y1, 0);
                pst_op *op = t.op2, *op1 = t.op1;
                CHECK(t.same_apply);
                CHECK(t.same_status);
                test_paths p = test_compare_paths(op, u, y1, y2);
                CHECK_INT(p.store, PST_OK);
                CHECK_INT(pst_op_store(op1), PST_OK);
                CHECK_INT(p.stored, PST_OK);
                pst_op_apply_stored(op1, u, y3);
                CHECK(memcmp(y2, y3, n * sizeof *y2) == 0); /* stored weights: 1 vs 2 threads */
                CHECK_INT(p.assemble, PST_OK);
                CHECK_INT(p.diagonal, PST_OK);
                printf("paths %dD %s ncomp %d: pattern %.1f per row (list %.1f), free vs stored "
                       "%.2e, csr vs free %.2e (relative to sum |w u|)\n",
                       dim, schemes[s], ncomp, (double)p.offdiag / (double)n,
                       (double)pst_nlist_pairs(nl) / (double)n, p.worst, p.worst_csr);
                CHECK(p.finite);
                CHECK(p.sorted);
                /* wider than the list */
                CHECK((double)p.offdiag > 1.5 * (double)pst_nlist_pairs(nl));
                CHECK(p.worst <= 1e-13);
                CHECK(p.worst_csr <= 1e-13);
                CHECK(p.worst_diag == 0.0);
                if (ncomp != 1) {
                    /* Neumann rows: n . M grad u for linear u (M constant per particle here
                     * only where the mobility is; use the operator's M at I) */
                    pst_op_apply(op, ul, y1);
                    const uint8_t *st = pst_op_status(op);
                    double wn = 0;
                    for (size_t i = 0; i < n; ++i) {
                        if (kind[i] != PST_NEUMANN || st[i] >= PST_ROW_RANK_DEFICIENT)
                            continue;
                        double flux = 0;
                        for (int d = 0; d < dim; ++d)
                            flux += pst_cloud_normal(c, d)[i] * slope[d] *
                                    (ncomp ? pst_cloud_mobility(c, d)[i] : 1.0);
                        wn = fmax(wn, fabs(y1[i] - flux) / (fabs(flux) + 1));
                    }
                    CHECK(wn <= 1e-10);
                }
                pst_op_destroy(op);
                pst_op_destroy(op1);
            }
            free(u);
            free(ul);
            free(y1);
            free(y2);
            free(y3);
            pst_nlist_destroy(nl);
            pst_cloud_destroy(c);
        }
}

/* 1 when op holds no neighbours-of-neighbours pattern (operator.h's private fields). */
static int no_pattern(const pst_op *op)
{
    return !op->poff && !op->pidx && !op->own_poff && !op->own_pidx;
}

static int same_csr(const pst_csr *a, const pst_csr *b)
{
    size_t nnz = (size_t)a->rowptr[a->n];
    return a->n == b->n && memcmp(a->rowptr, b->rowptr, (a->n + 1) * sizeof *a->rowptr) == 0 &&
           memcmp(a->col, b->col, nnz * sizeof *a->col) == 0 &&
           memcmp(a->val, b->val, nnz * sizeof *a->val) == 0;
}

/* The worst |yb - ya| over the rows relative to sum_j |a_ij u_j|, with ya = a u when NULL; and
 * the worst |a_ii - diag_i| into *diag_err. */
static double worst_rel(const pst_csr *a, const double *u, const double *ya, const double *yb,
                        const double *diag, double *diag_err)
{
    double worst = 0;
    *diag_err = 0;
    for (size_t i = 0; i < a->n; ++i) {
        double sum = 0, mag = 0;
        for (int64_t e = a->rowptr[i]; e < a->rowptr[i + 1]; ++e) {
            sum += a->val[e] * u[a->col[e]];
            mag += fabs(a->val[e] * u[a->col[e]]);
            if (a->col[e] == i)
                *diag_err = fmax(*diag_err, fabs(a->val[e] - diag[i]));
        }
        worst = fmax(worst, fabs(yb[i] - (ya ? ya[i] : sum)) / (mag > 0 ? mag : 1));
    }
    return worst;
}

/* The pattern is built only where it is read: the matrix-free apply, the gradient and the
 * Neumann rows never build it; the pattern count, the assembly and the diagonal build theirs
 * per call and keep none; pst_op_store keeps one. The lazily assembled matrix agrees with the
 * matrix-free apply to rounding, and bit for bit with 2 threads and with the matrix assembled
 * from the stored weights. 2D and 3D, all three kinds, tensor mobility. */
static void test_lazy_pattern(void)
{
    for (int dim = 2; dim <= 3; ++dim) {
        pst_cloud *c = dim == 2 ? lattice(2, 1.0 / 15, 1.2, 0.3, 1)
                                : lattice(3, 1.0 / 7, 1.0, 0.3, 1);
        size_t n = pst_cloud_size(c);
        test_make_neumann(c, 3);
        test_rough_mobility(c, dim);
        pst_nlist *nl = test_nlist(c, 3.0);
        double *u = test_field(c, quad), *y[2], *dg[2], *g[3];
        for (int t = 0; t < 3; ++t) {
            g[t] = malloc(n * sizeof **g);
            if (t < 2) {
                y[t] = malloc(n * sizeof **y);
                dg[t] = malloc(n * sizeof **dg);
            }
        }
        for (int s = 0; s < NSCHEMES; ++s) {
            pst_op *op[2];
            pst_csr a[2], b;
            int64_t pairs[2];
            for (int t = 0; t < 2; ++t) {
                omp_set_num_threads(t + 1);
                op[t] = make_op(c, nl, schemes[s]);
                CHECK_INT(pst_op_apply(op[t], u, y[t]), PST_OK);
                CHECK_INT(pst_op_gradient(op[t], u, g), PST_OK);
                CHECK(no_pattern(op[t]));
                pairs[t] = pst_op_pattern_pairs(op[t]);
                CHECK_INT(pst_op_assemble(op[t], &a[t]), PST_OK);
                CHECK_INT(pst_op_diagonal(op[t], dg[t]), PST_OK);
                CHECK(no_pattern(op[t])); /* the read-only paths keep nothing */
            }
            CHECK(memcmp(y[0], y[1], n * sizeof **y) == 0);
            CHECK(same_csr(&a[0], &a[1]));
            CHECK(memcmp(dg[0], dg[1], n * sizeof **dg) == 0);
            CHECK(pairs[0] == pairs[1] && pairs[0] == a[0].rowptr[n] - (int64_t)n);
            CHECK((double)pairs[0] > 1.5 * (double)pst_nlist_pairs(nl));
            double diag_err, csr_free = worst_rel(&a[0], u, NULL, y[0], dg[0], &diag_err);
            CHECK_INT(pst_op_store(op[1]), PST_OK);
            CHECK(!no_pattern(op[1]));
            CHECK(pst_op_pattern_pairs(op[1]) == pairs[0]);
            CHECK_INT(pst_op_assemble(op[1], &b), PST_OK);
            CHECK(same_csr(&a[0], &b)); /* stored weights = emitted ones, 1 or 2 threads */
            CHECK_INT(pst_op_apply_stored(op[1], u, y[1]), PST_OK);
            double unused, stored_free = worst_rel(&a[0], u, y[0], y[1], dg[0], &unused);
            printf("lazy pattern %dD %s: %.1f per row, csr (no store) vs free %.2e, stored vs "
                   "free %.2e (relative to sum |w u|)\n",
                   dim, schemes[s], (double)pairs[0] / (double)n, csr_free, stored_free);
            CHECK(csr_free <= 1e-13);
            CHECK(stored_free <= 1e-13);
            CHECK(diag_err == 0.0);
            for (int t = 0; t < 2; ++t) {
                pst_csr_free(&a[t]);
                pst_op_destroy(op[t]);
            }
            pst_csr_free(&b);
        }
        for (int t = 0; t < 3; ++t) {
            free(g[t]);
            if (t < 2) {
                free(y[t]);
                free(dg[t]);
            }
        }
        free(u);
        pst_nlist_destroy(nl);
        pst_cloud_destroy(c);
    }
}

/* Degenerate rows: flagged, finite, the isolated row is 0. 2D collinear, 3D coplanar, one
 * isolated particle each; and a 2D particle with 3 neighbours (mixed2: too few for the
 * quadratic fit, the linear fit still gives the exact gradient of linear u). */
static void test_degenerate(void)
{
    for (int dim = 2; dim <= 3; ++dim) {
        size_t n = (dim == 2 ? 11 : 25) + 1;
        pst_cloud *c;
        CHECK_INT(pst_cloud_create(&c, dim, n, NULL), PST_OK);
        size_t nflat = test_flat_layout(c);
        for (int d = 0; d < dim; ++d)
            pst_cloud_coord(c, d)[nflat] = 10.0;
        pst_cloud_set_h_uniform(c, dim == 2 ? 0.12 : 0.08, NULL); /* mixed2 gets >= 5 neighbours */
        pst_nlist *nl = test_nlist(c, 3.0);
        double *u = malloc(n * sizeof *u), *y = malloc(n * sizeof *y), *g[3], *hs[6];
        for (int d = 0; d < 3; ++d)
            g[d] = malloc(n * sizeof *g[d]);
        for (int d = 0; d < 6; ++d)
            hs[d] = malloc(n * sizeof *hs[d]);
        for (size_t i = 0; i < n; ++i)
            u[i] = (double)(i * i);
        for (int s = 0; s < NSCHEMES; ++s) {
            pst_op *op = make_op(c, nl, schemes[s]);
            size_t counts[PST_ROW_NSTATUS];
            pst_op_status_counts(op, counts);
            pst_op_apply(op, u, y);
            pst_op_gradient(op, u, g);
            int finite = 1;
            for (size_t i = 0; i < n; ++i) {
                finite = finite && isfinite(y[i]);
                for (int d = 0; d < dim; ++d)
                    finite = finite && isfinite(g[d][i]);
            }
            if (s == 2) {
                CHECK_INT(pst_op_hessian(op, u, hs), PST_OK);
                for (size_t i = 0; i < n; ++i)
                    for (int k = 0; k < (dim == 2 ? 3 : 6); ++k)
                        finite = finite && hs[k][i] == 0.0; /* no quadratic fit anywhere */
            }
            CHECK(finite);
            CHECK_INT(pst_op_status(op)[nflat], PST_ROW_TOO_FEW);
            CHECK(y[nflat] == 0.0);
            CHECK_INT(counts[PST_ROW_RANK_DEFICIENT] + counts[PST_ROW_TOO_FEW], n);
            CHECK(counts[PST_ROW_RANK_DEFICIENT] > 0);
            CHECK_INT(pst_op_store(op), PST_OK);
            double *y2 = malloc(n * sizeof *y2);
            pst_op_apply_stored(op, u, y2);
            double diff = 0;
            for (size_t i = 0; i < n; ++i)
                diff = fmax(diff, fabs(y[i] - y2[i]) / (fabs(y[i]) + 1));
            CHECK(diff <= 1e-12); /* fallback rows on both paths */
            free(y2);
            printf("degenerate %dD %s: ok %zu, fallback %zu, ill %zu, rank-deficient %zu, too few "
                   "%zu\n",
                   dim, schemes[s], counts[0], counts[1], counts[2], counts[3], counts[4]);
            pst_op_destroy(op);
        }
        free(u);
        free(y);
        for (int d = 0; d < 3; ++d)
            free(g[d]);
        for (int d = 0; d < 6; ++d)
            free(hs[d]);
        pst_nlist_destroy(nl);
        pst_cloud_destroy(c);
    }

    /* particle 0 at the origin with 3 neighbours around it */
    pst_cloud *c;
    CHECK_INT(pst_cloud_create(&c, 2, 4, NULL), PST_OK);
    const double px[4] = {0.0, 0.1, -0.05, 0.02}, py[4] = {0.0, 0.01, 0.08, -0.09};
    for (int i = 0; i < 4; ++i) {
        pst_cloud_coord(c, 0)[i] = px[i];
        pst_cloud_coord(c, 1)[i] = py[i];
    }
    pst_cloud_set_h_uniform(c, 0.1, NULL);
    pst_nlist *nl = test_nlist(c, 3.0);
    pst_op *op = make_op(c, nl, "mixed2");
    double u[4], gx[4], gy[4], *g[3] = {gx, gy, NULL};
    for (int i = 0; i < 4; ++i)
        u[i] = 1.0 + 2.0 * px[i] - 3.0 * py[i];
    pst_op_gradient(op, u, g);
    CHECK_INT(pst_op_status(op)[0], PST_ROW_TOO_FEW);
    CHECK_NEAR(gx[0], 2.0, 1e-12);
    CHECK_NEAR(gy[0], -3.0, 1e-12);
    pst_op_destroy(op);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
}

/* Bad options and hooks the schemes do not have; per-particle h; phase timers. */
static void test_errors_and_options(void)
{
    pst_cloud *c = lattice(2, 1.0 / 20, 1.2, 0.5, 0);
    size_t n = pst_cloud_size(c);
    pst_nlist *nl = test_nlist(c, 3.0);
    pst_op_opts o;
    pst_op *op = NULL;
    char err[PST_ERRLEN];
    pst_op_defaults(&o);
    o.scheme = "mixed1";
    o.rank_tol = 2.0;
    CHECK_INT(pst_op_create(&op, c, nl, &o, err), PST_EINVAL);
    pst_op_defaults(&o);
    o.scheme = "mixed1";
    CHECK_INT(pst_op_create(&op, c, nl, &o, err), PST_OK);
    double t[PST_NPHASES];
    pst_op_phase_times(op, t);
    /* no WEIGHTS phase: the precompute does not build the pattern */
    CHECK(t[PST_PHASE_MOMENTS] > 0 && t[PST_PHASE_INVERSION] > 0 && t[PST_PHASE_WEIGHTS] == 0);
    CHECK(t[PST_PHASE_GEOMETRY] + t[PST_PHASE_MOMENTS] + t[PST_PHASE_INVERSION] +
              t[PST_PHASE_WEIGHTS] <= t[PST_PHASE_PRECOMPUTE]);
    pst_op_destroy(op);

    /* per-particle h (the fit of I uses h_I): still exact for linear u */
    double *h = pst_cloud_h_per_particle(c);
    for (size_t i = 0; i < n; ++i)
        h[i] = (1.1 + 0.3 * (double)(i % 3)) / 20;
    pst_nlist_destroy(nl);
    nl = test_nlist(c, 3.0);
    double *u = test_field(c, linear), *y = malloc(n * sizeof *y);
    for (int s = 0; s < NSCHEMES; ++s) {
        op = make_op(c, nl, schemes[s]);
        pst_op_apply(op, u, y);
        double worst = 0;
        for (size_t i = 0; i < n; ++i)
            worst = fmax(worst, fabs(y[i]));
        printf("per-particle h %s: max |L u| (linear u, every row) %.2e\n", schemes[s], worst);
        CHECK(worst <= 1e-9);
        pst_op_destroy(op);
    }
    free(u);
    free(y);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
}

int main(void)
{
    test_exactness();
    test_regular_lattice();
    test_paths_and_threads();
    test_lazy_pattern();
    test_degenerate();
    test_errors_and_options();
    return check_summary("test_mixed");
}
