/* Progress hooks (pst_progress): the counts a hook sees never go back and reach the total, the
 * hook is never entered twice at once, from 1 and 2 threads, and every result is the same, bit
 * for bit, with and without a hook: the neighbour list, every family's precompute (through its
 * apply), the gradient, the Hessian and the interpolation. */
#include "check.h"
#include "pstencil.h"
#include "support.h"

#include <omp.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    long calls;
    uint64_t last, total;
    int went_back, inside_twice;
    atomic_int inside;
} recorder;

static void record(void *user, uint64_t done, uint64_t total)
{
    recorder *r = user;
    if (atomic_fetch_add(&r->inside, 1) != 0)
        r->inside_twice = 1;
    if (r->calls > 0 && (done < r->last || total != r->total))
        r->went_back = 1;
    r->calls++;
    r->last = done;
    r->total = total;
    atomic_fetch_sub(&r->inside, 1);
}

static pst_progress hook_of(recorder *r)
{
    memset(r, 0, sizeof *r);
    atomic_init(&r->inside, 0);
    return (pst_progress){record, r};
}

/* What every call with a hook must show: the total, reached, in more than one report when
 * the work has more than one chunk, never backwards, never two at once. */
static void check_reports(const recorder *r, uint64_t total, long min_calls)
{
    CHECK_INT(r->total, total);
    CHECK_INT(r->last, total);
    CHECK(r->calls >= min_calls);
    CHECK(!r->went_back);
    CHECK(!r->inside_twice);
}

static double smooth(const double *x) { return x[0] * x[0] * x[1] + 0.5 * x[1] - x[0]; }

static void check_list(const pst_cloud *c)
{
    pst_nlist *plain = test_nlist(c, 2.0), *hooked = NULL;
    recorder r;
    pst_progress p = hook_of(&r);
    CHECK_INT(pst_nlist_build_with(&hooked, c, 2.0, &p, NULL), PST_OK);
    size_t n = pst_cloud_size(c);
    check_reports(&r, 2 * (uint64_t)n, 3);
    CHECK_INT(pst_nlist_pairs(hooked), pst_nlist_pairs(plain));
    CHECK(memcmp(pst_nlist_offsets(hooked), pst_nlist_offsets(plain),
                 (n + 1) * sizeof(int64_t)) == 0);
    CHECK(memcmp(pst_nlist_indices(hooked), pst_nlist_indices(plain),
                 (size_t)pst_nlist_pairs(plain) * sizeof(uint32_t)) == 0);
    pst_nlist_destroy(hooked);
    pst_nlist_destroy(plain);
}

/* Outputs of a derivative call (ncomp arrays of n values) of op with and without its hook. */
static void check_derivative(pst_op *op, const double *u, size_t n, int ncomp, int hessian)
{
    double *with[6] = {NULL}, *without[6] = {NULL};
    for (int a = 0; a < ncomp; ++a) {
        with[a] = calloc(n, sizeof(double));
        without[a] = calloc(n, sizeof(double));
    }
    recorder r;
    pst_progress p = hook_of(&r);
    pst_op_set_progress(op, &p);
    int st = hessian ? pst_op_hessian(op, u, with) : pst_op_gradient(op, u, with);
    CHECK_INT(st, PST_OK);
    check_reports(&r, n, 2);
    pst_op_set_progress(op, NULL);
    st = hessian ? pst_op_hessian(op, u, without) : pst_op_gradient(op, u, without);
    CHECK_INT(st, PST_OK);
    CHECK_INT(r.last, n); /* the hook removed: nothing more reported */
    for (int a = 0; a < ncomp; ++a) {
        CHECK(memcmp(with[a], without[a], n * sizeof(double)) == 0);
        free(with[a]);
        free(without[a]);
    }
}

static void check_interpolation(pst_op *op, const double *u)
{
    enum { M = 3000 };
    double *pts[3], *v[2], *l[2];
    for (int d = 0; d < 3; ++d)
        pts[d] = malloc(M * sizeof(double));
    for (size_t q = 0; q < M; ++q)
        for (int d = 0; d < 3; ++d)
            pts[d][q] = d < 2 ? 0.05 + 0.9 * test_rnd() : 0.0;
    size_t fb[2];
    recorder r;
    pst_progress p = hook_of(&r);
    for (int pass = 0; pass < 2; ++pass) {
        v[pass] = malloc(M * sizeof(double));
        l[pass] = malloc(M * sizeof(double));
        pst_op_set_progress(op, pass == 0 ? &p : NULL);
        CHECK_INT(pst_op_interpolate(op, (const double *const *)pts, M, u, v[pass], l[pass],
                                     &fb[pass], NULL),
                  PST_OK);
    }
    check_reports(&r, M, 2);
    CHECK_INT(fb[0], fb[1]);
    CHECK(memcmp(v[0], v[1], M * sizeof(double)) == 0);
    CHECK(memcmp(l[0], l[1], M * sizeof(double)) == 0);
    for (int pass = 0; pass < 2; ++pass) {
        free(v[pass]);
        free(l[pass]);
    }
    for (int d = 0; d < 3; ++d)
        free(pts[d]);
}

/* One scheme: the precompute with a hook reports its rows and gives the rows of the one
 * without (their applies agree bit for bit); then its derivative calls. */
static void check_scheme(const pst_cloud *c, const pst_nlist *nl, const char *scheme)
{
    size_t n = pst_cloud_size(c);
    pst_op_opts o;
    pst_op_defaults(&o);
    o.scheme = scheme;
    pst_op *plain = test_op_of(c, nl, &o);
    recorder r;
    o.progress = hook_of(&r);
    pst_op *hooked = test_op_of(c, nl, &o);
    check_reports(&r, n, 2);
    double *u = test_field(c, smooth), *y0 = calloc(n, sizeof(double)),
           *y1 = calloc(n, sizeof(double));
    CHECK_INT(pst_op_apply(plain, u, y0), PST_OK);
    CHECK_INT(pst_op_apply(hooked, u, y1), PST_OK);
    CHECK(memcmp(y0, y1, n * sizeof(double)) == 0);
    CHECK_INT(r.last, n); /* the apply reports nothing */
    if (pst_scheme_supports(scheme, PST_SUPPORTS_GRADIENT))
        check_derivative(hooked, u, n, 2, 0);
    if (pst_scheme_supports(scheme, PST_SUPPORTS_HESSIAN))
        check_derivative(hooked, u, n, 3, 1);
    if (pst_scheme_supports(scheme, PST_SUPPORTS_INTERPOLATE))
        check_interpolation(hooked, u);
    free(u);
    free(y0);
    free(y1);
    pst_op_destroy(hooked);
    pst_op_destroy(plain);
}

int main(void)
{
    static const char *const schemes[] = {"brookshaw", "lv",    "cspm",  "icspm", "qsfdi",
                                          "lsmps",     "lpmps", "mixed2"};
    test_rng_seed(7);
    /* 121 x 121 particles: more than one block (8192 rows) of the blocked precomputes */
    pst_cloud *c = test_lattice(2, 0.0, 1.0, 1.0 / 120, 1.3, 0.2, 3, 0);
    char err[PST_ERRLEN];
    CHECK_INT(pst_cloud_morton_sort(c, 2.0 * 1.3 / 120, err), PST_OK);
    for (int threads = 1; threads <= 2; ++threads) {
        omp_set_num_threads(threads);
        check_list(c);
        pst_nlist *nl = test_nlist(c, 3.0);
        for (size_t s = 0; s < sizeof schemes / sizeof *schemes; ++s)
            check_scheme(c, nl, schemes[s]);
        pst_nlist_destroy(nl);
    }
    /* a hook with no fn is no hook */
    pst_nlist *nl = NULL;
    pst_progress none = {NULL, NULL};
    CHECK_INT(pst_nlist_build_with(&nl, c, 2.0, &none, NULL), PST_OK);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
    return check_summary("test_progress");
}
