/* Operator refresh (pst_op_refresh) after the particles moved and the list was updated: for
 * every scheme, 2D and 3D, the refreshed operator gives an operator created afresh bit for bit
 * (matrix-free apply, stored apply when it was stored, gradient, row status) in the scheme data
 * it kept (every entry written again); refusals (a half list) and a failed refresh (degenerate
 * rows refused) leave an operator that every call refuses. */
#include "check.h"
#include "support.h"

#include "operator.h" /* op->data: the scheme data a refresh keeps */
#include "pstencil.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static double field(const double *x) { return sin(2 * x[0] + x[1]) + cos(3 * x[2] - x[1]); }

/* Move every particle by a smooth swirl of at most 0.15 s0. */
static void swirl(pst_cloud *c, double s0)
{
    double *x = pst_cloud_coord(c, 0), *y = pst_cloud_coord(c, 1);
    for (size_t i = 0; i < pst_cloud_size(c); ++i) {
        double vx = sin(3 * y[i]) * cos(2 * x[i]), vy = -cos(3 * x[i]) * sin(2 * y[i]);
        x[i] += 0.1 * s0 * vx;
        y[i] += 0.1 * s0 * vy;
    }
}

/* 1 when a and b hold the same n doubles, bit for bit. */
static int same(const double *a, const double *b, size_t n)
{
    return memcmp(a, b, n * sizeof *a) == 0;
}

/* One scheme in one dimension: create, move, update, refresh; against a fresh operator. */
static int refreshed_equals_fresh(const char *scheme, int dim, int stored)
{
    double s0 = dim == 3 ? 1.0 / 9 : 1.0 / 24;
    pst_cloud *c = test_lattice(dim, 0, 1, s0, 1.3, 0.3, 21, 1);
    double support = pst_kernel_support(pst_scheme_default_kernel(scheme));
    pst_cloud_morton_sort(c, (support + 0.4) * 1.3 * s0, NULL);
    pst_nlist *nl = NULL;
    char err[PST_ERRLEN] = "";
    CHECK(pst_nlist_build_skin(&nl, c, support, 0.4, err) == PST_OK);
    pst_op_opts o;
    pst_op_defaults(&o);
    o.scheme = scheme;
    pst_op *op = NULL;
    CHECK(pst_op_create(&op, c, nl, &o, err) == PST_OK);
    if (stored)
        CHECK(pst_op_store(op) == PST_OK);
    size_t n = pst_cloud_size(c);
    double *g[3], *gf[3];
    double *y = malloc(n * sizeof *y), *yf = malloc(n * sizeof *yf);
    double *ys = malloc(n * sizeof *ys), *ysf = malloc(n * sizeof *ysf);
    for (int a = 0; a < 3; ++a) {
        g[a] = calloc(n, sizeof *g[a]);
        gf[a] = calloc(n, sizeof *gf[a]);
    }
    int ok = 1, kept_weights = 0;
    for (int step = 0; step < 3; ++step) {
        swirl(c, s0);
        pst_nlist_update_info info;
        CHECK(pst_nlist_update(nl, c, &info, err) == PST_OK);
        const void *data = op->data, *w = op->w ? (const void *)op->w : (const void *)op->w32;
        CHECK(pst_op_refresh(op, err) == PST_OK);
        CHECK(op->data == data); /* the scheme's data and its arrays reused, not allocated */
        kept_weights += stored && w == (op->w ? (const void *)op->w : (const void *)op->w32);
        pst_nlist *fl = test_nlist(c, support);
        pst_op *fresh = test_op_of(c, fl, &o);
        double *u = test_field(c, field);
        CHECK(pst_op_apply(op, u, y) == PST_OK && pst_op_apply(fresh, u, yf) == PST_OK);
        ok &= same(y, yf, n);
        if (stored) {
            CHECK(pst_op_store(fresh) == PST_OK);
            CHECK(pst_op_apply_stored(op, u, ys) == PST_OK);
            CHECK(pst_op_apply_stored(fresh, u, ysf) == PST_OK);
            ok &= same(ys, ysf, n);
        }
        if (pst_scheme_supports(scheme, PST_SUPPORTS_GRADIENT)) {
            CHECK(pst_op_gradient(op, u, g) == PST_OK && pst_op_gradient(fresh, u, gf) == PST_OK);
            for (int a = 0; a < dim; ++a)
                ok &= same(g[a], gf[a], n);
        }
        ok &= memcmp(pst_op_status(op), pst_op_status(fresh), n) == 0;
        free(u);
        pst_op_destroy(fresh);
        pst_nlist_destroy(fl);
    }
    for (int a = 0; a < 3; ++a) {
        free(g[a]);
        free(gf[a]);
    }
    free(y);
    free(yf);
    free(ys);
    free(ysf);
    pst_op_destroy(op);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
    /* the stored weights' array is kept by the refreshes whose pattern fits it (the first
     * refresh grows it by an eighth) */
    return ok && (!stored || kept_weights >= 1);
}

static void test_every_scheme(void)
{
    for (int k = 0; k < pst_scheme_count(); ++k) {
        const char *name = pst_scheme_name(k);
        for (int dim = 2; dim <= 3; ++dim) {
            int ok = refreshed_equals_fresh(name, dim, k % 2);
            if (!ok)
                fprintf(stderr, "refresh differs from a fresh operator: %s %dD\n", name, dim);
            CHECK(ok);
        }
    }
}

/* A half-list operator is refused; a refresh that fails (degenerate rows refused after the
 * neighbours of a particle were moved onto one line) leaves an operator every call refuses. */
static void test_refusals(void)
{
    double s0 = 1.0 / 24;
    pst_cloud *c = test_lattice(2, 0, 1, s0, 1.3, 0.3, 4, 1);
    pst_nlist *nl = NULL, *half = NULL;
    char err[PST_ERRLEN] = "";
    CHECK(pst_nlist_build_skin(&nl, c, 3.0, 0.4, err) == PST_OK);
    pst_op_opts o;
    pst_op_defaults(&o);
    o.scheme = "lv";
    o.on_degenerate = PST_DEGENERATE_REFUSE;
    pst_op *op = test_op_of(c, nl, &o), *halved = test_op_of(c, nl, &o);
    CHECK(pst_nlist_halve(&half, nl, err) == PST_OK);
    CHECK(pst_op_use_half_list(halved, half, err) == PST_OK);
    CHECK(pst_op_refresh(halved, err) == PST_EINVAL && strstr(err, "half list"));
    /* the particles within 3 h of the centre onto the line y = 0.5 */
    double *x = pst_cloud_coord(c, 0), *y = pst_cloud_coord(c, 1);
    size_t n = pst_cloud_size(c);
    for (size_t i = 0; i < n; ++i)
        if (hypot(x[i] - 0.5, y[i] - 0.5) < 3 * 1.3 * s0)
            y[i] = 0.5;
    CHECK(pst_nlist_update(nl, c, NULL, err) == PST_OK);
    CHECK(pst_op_refresh(op, err) == PST_ENUMERIC && strstr(err, "degenerate"));
    double *u = calloc(n, sizeof *u), *out = calloc(n, sizeof *out);
    double *g[3] = {out, out, out};
    CHECK(pst_op_apply(op, u, out) == PST_EINVAL);
    CHECK(pst_op_apply_stored(op, u, out) == PST_EINVAL);
    CHECK(pst_op_gradient(op, u, g) == PST_EINVAL);
    CHECK(pst_op_diagonal(op, out) != PST_OK);
    free(u);
    free(out);
    pst_op_destroy(halved);
    pst_op_destroy(op);
    pst_nlist_destroy(half);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
}

int main(void)
{
    test_every_scheme();
    test_refusals();
    return check_summary("test_op_refresh");
}
