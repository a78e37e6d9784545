/* The host code's own data (docs/embedding.md, "The host code's own data"): a cloud that
 * borrows the caller's arrays gives a copied cloud's operators bit for bit, in the caller's
 * order, also after the caller moves its particles in place (update and refresh); it is never
 * reordered, never frees or writes the caller's arrays; a list from the caller's CSR gives the
 * built list's operators, halves and solves bit for bit, and each malformed CSR is refused with
 * its code and the offending row; 1 and 2 threads agree. */
#include "check.h"
#include "support.h"

#include "pstencil.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

static double field(const double *x) { return sin(2 * x[0] + x[1]) + cos(3 * x[2] - x[1]); }

/* A host code's particle arrays, all inside one allocation at offsets past its start, so that
 * a free() of any of them by the library would be caught (an invalid free), and a read after
 * the cloud's destroy too under the sanitizer (a use after free). */
typedef struct {
    int dim;
    size_t n;
    char *block;
    pst_cloud_arrays a;
} host;

/* The host's copy of src (positions, V, kinds), with a per-particle h varying by 10 %, every
 * fifth Dirichlet particle Neumann with a radial normal, and a scalar mobility when mob. */
static host host_from(const pst_cloud *src, int mob)
{
    int dim = pst_cloud_dim(src);
    size_t n = pst_cloud_size(src);
    host hs = {.dim = dim, .n = n};
    size_t arrays = 2 * (size_t)dim + 3; /* x, normal, V, h, mobility */
    hs.block = malloc(64 + arrays * n * sizeof(double) + n);
    double *next = (double *)(hs.block + 64);
    for (int d = 0; d < dim; ++d) {
        hs.a.x[d] = next;
        hs.a.normal[d] = next + n;
        next += 2 * n;
    }
    hs.a.V = next;
    hs.a.h = next + n;
    hs.a.mob[0] = next + 2 * n;
    hs.a.mob_ncomp = mob;
    hs.a.kind = (uint8_t *)(next + 3 * n);
    for (size_t i = 0; i < n; ++i) {
        double r2 = 0;
        for (int d = 0; d < dim; ++d) {
            hs.a.x[d][i] = pst_cloud_coord_const(src, d)[i];
            r2 += (hs.a.x[d][i] - 0.5) * (hs.a.x[d][i] - 0.5);
        }
        hs.a.V[i] = pst_cloud_volume_const(src)[i];
        hs.a.h[i] = pst_cloud_h_uniform(src) * (1 + 0.1 * sin(7 * hs.a.x[0][i]));
        hs.a.mob[0][i] = 1.5 + sin(5 * hs.a.x[1][i]);
        uint8_t k = pst_cloud_kinds_const(src)[i];
        hs.a.kind[i] = k == PST_DIRICHLET && i % 5 == 0 ? PST_NEUMANN : k;
        for (int d = 0; d < dim; ++d)
            hs.a.normal[d][i] =
                hs.a.kind[i] == PST_NEUMANN ? (hs.a.x[d][i] - 0.5) / sqrt(r2) : 0.0;
    }
    return hs;
}

static pst_cloud *borrow(const host *hs)
{
    pst_cloud *c = NULL;
    char err[PST_ERRLEN] = "";
    int st = pst_cloud_borrow(&c, hs->dim, hs->n, &hs->a, err);
    if (st != PST_OK) {
        fprintf(stderr, "borrow: %s\n", err);
        exit(1);
    }
    return c;
}

/* A cloud of its own holding the host's current values. */
static pst_cloud *copy_of(const host *hs)
{
    pst_cloud *c = NULL;
    if (pst_cloud_create(&c, hs->dim, hs->n, NULL) != PST_OK ||
        (hs->a.mob_ncomp && pst_cloud_set_mobility(c, 1, NULL) != PST_OK))
        exit(1);
    size_t bytes = hs->n * sizeof(double);
    for (int d = 0; d < hs->dim; ++d) {
        memcpy(pst_cloud_coord(c, d), hs->a.x[d], bytes);
        memcpy(pst_cloud_normal(c, d), hs->a.normal[d], bytes);
    }
    memcpy(pst_cloud_volume(c), hs->a.V, bytes);
    memcpy(pst_cloud_h_per_particle(c), hs->a.h, bytes);
    memcpy(pst_cloud_kinds(c), hs->a.kind, hs->n);
    if (hs->a.mob_ncomp)
        memcpy(pst_cloud_mobility(c, 0), hs->a.mob[0], bytes);
    return c;
}

/* Move every particle by a smooth swirl of at most 0.1 s0, in the host's arrays. */
static void swirl(host *hs, double s0)
{
    double *x = hs->a.x[0], *y = hs->a.x[1];
    for (size_t i = 0; i < hs->n; ++i) {
        double vx = sin(3 * y[i]) * cos(2 * x[i]), vy = -cos(3 * x[i]) * sin(2 * y[i]);
        x[i] += 0.1 * s0 * vx;
        y[i] += 0.1 * s0 * vy;
    }
}

static int same(const void *a, const void *b, size_t bytes) { return memcmp(a, b, bytes) == 0; }

/* The outputs of an operator on u: apply, gradient (zeros when unsupported), stored apply. */
typedef struct {
    double *y, *ys, *g[3];
} outputs;

static outputs run_op(pst_op *op, const double *u, size_t n)
{
    outputs o = {.y = calloc(n, sizeof(double)), .ys = calloc(n, sizeof(double))};
    for (int a = 0; a < 3; ++a)
        o.g[a] = calloc(n, sizeof(double));
    CHECK(pst_op_apply(op, u, o.y) == PST_OK);
    if (pst_scheme_supports(pst_op_scheme(op), PST_SUPPORTS_GRADIENT))
        CHECK(pst_op_gradient(op, u, o.g) == PST_OK);
    CHECK(pst_op_store(op) == PST_OK && pst_op_apply_stored(op, u, o.ys) == PST_OK);
    return o;
}

static int same_outputs(const outputs *a, const outputs *b, size_t n)
{
    size_t bytes = n * sizeof(double);
    int ok = same(a->y, b->y, bytes) && same(a->ys, b->ys, bytes);
    for (int k = 0; k < 3; ++k)
        ok = ok && same(a->g[k], b->g[k], bytes);
    return ok;
}

static void free_outputs(outputs *o)
{
    free(o->y);
    free(o->ys);
    for (int a = 0; a < 3; ++a)
        free(o->g[a]);
}

/* Operator outputs of `scheme` on cloud c with list nl. */
static outputs outputs_of(const pst_cloud *c, const pst_nlist *nl, const char *scheme)
{
    pst_op *op = test_op(c, nl, scheme, PST_GRAD_G1, 0);
    double *u = test_field(c, field);
    outputs o = run_op(op, u, pst_cloud_size(c));
    free(u);
    pst_op_destroy(op);
    return o;
}

/* The caller's copy of a list's CSR (malloc'ed; the caller frees both). */
static void csr_of(const pst_nlist *nl, int64_t **off, uint32_t **idx)
{
    size_t n = pst_nlist_rows(nl);
    int64_t pairs = pst_nlist_pairs(nl);
    *off = malloc((n + 1) * sizeof **off);
    *idx = malloc(((size_t)pairs + 1) * sizeof **idx);
    memcpy(*off, pst_nlist_offsets(nl), (n + 1) * sizeof **off);
    memcpy(*idx, pst_nlist_indices(nl), (size_t)pairs * sizeof **idx);
}

static pst_nlist *from_csr_of(const pst_cloud *c, const pst_nlist *built, double support,
                              int flags)
{
    int64_t *off;
    uint32_t *idx;
    csr_of(built, &off, &idx);
    pst_nlist *nl = NULL;
    char err[PST_ERRLEN] = "";
    int st = pst_nlist_from_csr(&nl, c, support, off, idx, flags, err);
    if (st != PST_OK)
        fprintf(stderr, "from_csr: %s\n", err);
    CHECK(st == PST_OK);
    free(off);
    free(idx);
    return nl;
}

static const char *const schemes[] = {"qsfdi", "lv", "lsmps", "brookshaw"};

/* A borrowed cloud against a copied one with the same values: the same list and the same
 * apply, gradient and stored apply, bit for bit; against a Morton-sorted copy, the same
 * results scattered back to input order (to rounding: the sorted rows sum in another order). */
static void test_borrowed_equals_copied(void)
{
    for (int dim = 2; dim <= 3; ++dim) {
        double s0 = dim == 3 ? 1.0 / 8 : 1.0 / 20;
        pst_cloud *lat = test_lattice(dim, 0, 1, s0, 1.3, 0.3, 5, 1);
        for (size_t k = 0; k < sizeof schemes / sizeof *schemes; ++k) {
            const char *scheme = schemes[k];
            host hs = host_from(lat, pst_scheme_supports(scheme, PST_SUPPORTS_MOBILITY));
            pst_cloud *cb = borrow(&hs), *cc = copy_of(&hs);
            char err[PST_ERRLEN] = "";
            CHECK(pst_cloud_validate(cb, err) == PST_OK);
            CHECK(pst_cloud_is_borrowed(cb) && !pst_cloud_is_borrowed(cc));
            double support = pst_kernel_support(pst_scheme_default_kernel(scheme));
            pst_nlist *nb = test_nlist(cb, support), *nc = test_nlist(cc, support);
            size_t n = hs.n;
            CHECK(pst_nlist_pairs(nb) == pst_nlist_pairs(nc));
            CHECK(same(pst_nlist_indices(nb), pst_nlist_indices(nc),
                       (size_t)pst_nlist_pairs(nb) * sizeof(uint32_t)));
            outputs ob = outputs_of(cb, nb, scheme), oc = outputs_of(cc, nc, scheme);
            int ok = same_outputs(&ob, &oc, n);
            if (!ok)
                fprintf(stderr, "borrowed differs from copied: %s %dD\n", scheme, dim);
            CHECK(ok);
            /* the library's usual order, then back: the borrowed results are in input order */
            pst_cloud *cm = copy_of(&hs);
            CHECK(pst_cloud_morton_sort(cm, support * 1.5 * s0, err) == PST_OK);
            pst_nlist *nm = test_nlist(cm, support);
            outputs om = outputs_of(cm, nm, scheme);
            double *back = malloc(n * sizeof *back), worst = 0, scale = 0;
            pst_cloud_to_input_order(cm, om.y, back);
            for (size_t i = 0; i < n; ++i) {
                worst = fmax(worst, fabs(back[i] - ob.y[i]));
                scale = fmax(scale, fabs(ob.y[i]));
            }
            CHECK(worst <= 1e-10 * scale);
            free(back);
            free_outputs(&om);
            free_outputs(&ob);
            free_outputs(&oc);
            pst_nlist_destroy(nm);
            pst_nlist_destroy(nb);
            pst_nlist_destroy(nc);
            pst_cloud_destroy(cm);
            pst_cloud_destroy(cb);
            pst_cloud_destroy(cc);
            free(hs.block);
        }
        pst_cloud_destroy(lat);
    }
}

/* The host's step: move its arrays in place, then pst_nlist_update (a Verlet list) or
 * pst_nlist_set_csr (its own list) and pst_op_refresh: the operator of a fresh copy, fresh
 * list, fresh build, bit for bit. */
static void test_moved_in_place(void)
{
    for (int dim = 2; dim <= 3; ++dim) {
        double s0 = dim == 3 ? 1.0 / 8 : 1.0 / 20;
        pst_cloud *lat = test_lattice(dim, 0, 1, s0, 1.3, 0.3, 9, 1);
        const char *scheme = dim == 2 ? "lv" : "qsfdi";
        host hs = host_from(lat, pst_scheme_supports(scheme, PST_SUPPORTS_MOBILITY));
        pst_cloud *cb = borrow(&hs);
        double support = pst_kernel_support(pst_scheme_default_kernel(scheme));
        pst_nlist *verlet = NULL;
        char err[PST_ERRLEN] = "";
        CHECK(pst_nlist_build_skin(&verlet, cb, support, 0.4, err) == PST_OK);
        pst_nlist *first = test_nlist(cb, support);
        pst_nlist *own = from_csr_of(cb, first, support, 0);
        pst_nlist_destroy(first);
        CHECK(pst_nlist_update(own, cb, NULL, err) == PST_EINVAL &&
              strstr(err, "pst_nlist_set_csr"));
        pst_op *opv = test_op(cb, verlet, scheme, PST_GRAD_G1, 0);
        pst_op *opo = test_op(cb, own, scheme, PST_GRAD_G1, 0);
        for (int step = 0; step < 3; ++step) {
            swirl(&hs, s0);
            pst_cloud *cc = copy_of(&hs);
            pst_nlist *nc = test_nlist(cc, support);
            int64_t *off;
            uint32_t *idx;
            csr_of(nc, &off, &idx);
            CHECK(pst_nlist_update(verlet, cb, NULL, err) == PST_OK);
            CHECK(pst_nlist_set_csr(own, cb, off, idx, PST_CSR_CHECK_RADIUS, err) == PST_OK);
            free(off);
            free(idx);
            CHECK(pst_op_refresh(opv, err) == PST_OK && pst_op_refresh(opo, err) == PST_OK);
            double *u = test_field(cb, field);
            outputs ov = run_op(opv, u, hs.n), oo = run_op(opo, u, hs.n);
            outputs of = outputs_of(cc, nc, scheme);
            CHECK(same_outputs(&ov, &of, hs.n));
            CHECK(same_outputs(&oo, &of, hs.n));
            free(u);
            free_outputs(&ov);
            free_outputs(&oo);
            free_outputs(&of);
            pst_nlist_destroy(nc);
            pst_cloud_destroy(cc);
        }
        pst_op_destroy(opv);
        pst_op_destroy(opo);
        pst_nlist_destroy(verlet);
        pst_nlist_destroy(own);
        pst_cloud_destroy(cb);
        free(hs.block);
        pst_cloud_destroy(lat);
    }
}

/* Ownership: the accessors give the caller's arrays; setters let them go without freeing
 * them; permute and Morton sort refuse the cloud and leave it; wrap folds the caller's
 * positions; validate reports a bad value in the caller's array; destroy frees none of them
 * (the arrays are written after it, then freed by their owner). Bad arguments. */
static void test_ownership(void)
{
    pst_cloud *lat = test_lattice(2, 0, 1, 0.1, 1.3, 0.2, 3, 1);
    host hs = host_from(lat, 1);
    size_t n = hs.n, bytes = n * sizeof(double);
    double *h_saved = malloc(bytes), *x_saved = malloc(bytes), *m_saved = malloc(bytes);
    memcpy(h_saved, hs.a.h, bytes);
    memcpy(x_saved, hs.a.x[0], bytes);
    memcpy(m_saved, hs.a.mob[0], bytes);
    pst_cloud *cb = borrow(&hs);
    char err[PST_ERRLEN] = "";
    CHECK(pst_cloud_coord(cb, 1) == hs.a.x[1] && pst_cloud_volume(cb) == hs.a.V);
    CHECK(pst_cloud_normal(cb, 0) == hs.a.normal[0] && pst_cloud_kinds(cb) == hs.a.kind);
    CHECK(pst_cloud_h_array(cb) == hs.a.h && pst_cloud_mobility(cb, 0) == hs.a.mob[0]);
    uint32_t *perm = malloc(n * sizeof *perm);
    for (size_t i = 0; i < n; ++i)
        perm[i] = (uint32_t)(n - 1 - i);
    CHECK(pst_cloud_permute(cb, perm, err) == PST_EINVAL && strstr(err, "borrows"));
    CHECK(pst_cloud_morton_sort(cb, 0.2, err) == PST_EINVAL && strstr(err, "borrows"));
    CHECK(same(hs.a.x[0], x_saved, bytes));
    free(perm);
    CHECK(pst_cloud_set_h_uniform(cb, 0.13, err) == PST_OK);
    CHECK(pst_cloud_h_array(cb) == NULL && same(hs.a.h, h_saved, bytes));
    double *h = pst_cloud_h_per_particle(cb);
    CHECK(h && h != hs.a.h && h[0] == 0.13);
    CHECK(pst_cloud_set_mobility(cb, 1, err) == PST_OK);
    CHECK(pst_cloud_mobility(cb, 0) != hs.a.mob[0] && pst_cloud_mobility(cb, 0)[3] == 1.0);
    CHECK(same(hs.a.mob[0], m_saved, bytes));
    CHECK(pst_cloud_set_mobility(cb, 0, err) == PST_OK);
    /* validate reads the caller's values */
    hs.a.V[7] = -1;
    CHECK(pst_cloud_validate(cb, err) == PST_EINPUT && strstr(err, "particle 7:"));
    hs.a.V[7] = 0.01;
    CHECK(pst_cloud_validate(cb, err) == PST_OK);
    /* wrap writes the caller's positions, as documented */
    int per[3] = {1, 0, 0};
    double lo[3] = {-0.05, 0, 0}, hi[3] = {1.05, 0, 0};
    CHECK(pst_cloud_set_periodic(cb, per, lo, hi, err) == PST_OK);
    hs.a.x[0][4] = 1.25;
    pst_cloud_wrap(cb);
    CHECK_NEAR(hs.a.x[0][4], 0.15, 1e-12);
    pst_cloud_destroy(cb);
    for (int d = 0; d < 2; ++d)
        for (size_t i = 0; i < n; ++i)
            hs.a.x[d][i] = hs.a.normal[d][i] = hs.a.V[i] = hs.a.h[i] = hs.a.mob[0][i] = 1;
    memset(hs.a.kind, 0, n);
    free(hs.block);

    /* bad arguments: PST_EINVAL and no cloud */
    host bad = host_from(lat, 0);
    pst_cloud *c = (pst_cloud *)&bad;
    CHECK(pst_cloud_borrow(&c, 2, n, NULL, err) == PST_EINVAL && c == NULL);
    CHECK(pst_cloud_borrow(&c, 4, n, &bad.a, err) == PST_EINVAL && strstr(err, "dim"));
    pst_cloud_arrays a = bad.a;
    a.x[1] = NULL;
    CHECK(pst_cloud_borrow(&c, 2, n, &a, err) == PST_EINVAL && strstr(err, "along y"));
    a = bad.a;
    a.V = NULL;
    CHECK(pst_cloud_borrow(&c, 2, n, &a, err) == PST_EINVAL && strstr(err, "volumes"));
    a = bad.a;
    a.normal[1] = NULL;
    CHECK(pst_cloud_borrow(&c, 2, n, &a, err) == PST_EINVAL && strstr(err, "normals"));
    a = bad.a;
    a.h = NULL;
    a.h_uniform = 0;
    CHECK(pst_cloud_borrow(&c, 2, n, &a, err) == PST_EINVAL && strstr(err, "uniform h"));
    a = bad.a;
    a.mob_ncomp = 3;
    CHECK(pst_cloud_borrow(&c, 2, n, &a, err) == PST_EINVAL && strstr(err, "mobility"));
    a = bad.a;
    a.mob_ncomp = 2;
    a.mob[1] = NULL;
    CHECK(pst_cloud_borrow(&c, 2, n, &a, err) == PST_EINVAL && strstr(err, "component 1"));
    CHECK(pst_cloud_borrow(&c, 2, (size_t)UINT32_MAX + 1, &bad.a, err) == PST_EINVAL);
    /* only positions and volumes: the rest is the cloud's own, at its defaults */
    a = (pst_cloud_arrays){.x = {bad.a.x[0], bad.a.x[1]}, .V = bad.a.V, .h_uniform = 0.13};
    CHECK(pst_cloud_borrow(&c, 2, n, &a, err) == PST_OK);
    CHECK(pst_cloud_kinds(c)[0] == PST_INTERIOR && pst_cloud_normal(c, 0)[0] == 0);
    CHECK(pst_cloud_h_uniform(c) == 0.13 && pst_cloud_ids(c)[n - 1] == (int64_t)(n - 1));
    pst_cloud_destroy(c);
    free(bad.block);
    free(h_saved);
    free(x_saved);
    free(m_saved);
    pst_cloud_destroy(lat);
}

/* A solve of L u = b (GMRES; Jacobi, or AMG when hypre is there) into u, from u = 0. */
static int solve(const pst_op *op, const double *b, double *u, size_t n, int precond)
{
    pst_solve_opts so;
    pst_solve_defaults(&so);
    so.solver = PST_SOLVER_GMRES;
    so.precond = precond;
    pst_solve_result r;
    char err[PST_ERRLEN] = "";
    memset(u, 0, n * sizeof *u);
    int st = pst_solve(op, b, u, &so, &r, err);
    if (st != PST_OK)
        fprintf(stderr, "solve: %s\n", err);
    pst_solve_result_free(&r);
    return st == PST_OK ? r.iterations : -1;
}

/* A CSR equal to the built list: the same list, halves, stats, operators and solves, bit for
 * bit. A wider list is taken (and refused by PST_CSR_CHECK_RADIUS); a narrower one is refused
 * by PST_CSR_CHECK_COMPLETE. */
static void test_csr_equals_built(void)
{
    for (int dim = 2; dim <= 3; ++dim) {
        double s0 = dim == 3 ? 1.0 / 8 : 1.0 / 20;
        pst_cloud *c = test_lattice(dim, 0, 1, s0, 1.3, 0.3, 11, 1);
        const char *scheme = "qsfdi";
        double support = pst_kernel_support(pst_scheme_default_kernel(scheme));
        pst_nlist *built = test_nlist(c, support);
        pst_nlist *own = from_csr_of(c, built, support,
                                     PST_CSR_CHECK_RADIUS | PST_CSR_CHECK_COMPLETE);
        size_t n = pst_cloud_size(c);
        CHECK(!pst_nlist_is_half(own) && pst_nlist_support(own) == support);
        CHECK(same(pst_nlist_offsets(own), pst_nlist_offsets(built), (n + 1) * sizeof(int64_t)));
        pst_nlist_stats sa, sb;
        pst_nlist_get_stats(own, &sa);
        pst_nlist_get_stats(built, &sb);
        CHECK(same(&sa, &sb, sizeof sa));
        pst_nlist *ha = NULL, *hb = NULL;
        char err[PST_ERRLEN] = "";
        CHECK(pst_nlist_halve(&ha, own, err) == PST_OK);
        CHECK(pst_nlist_halve(&hb, built, err) == PST_OK);
        CHECK(pst_nlist_pairs(ha) == pst_nlist_pairs(hb) &&
              same(pst_nlist_indices(ha), pst_nlist_indices(hb),
                   (size_t)pst_nlist_pairs(ha) * sizeof(uint32_t)));
        outputs oa = outputs_of(c, own, scheme), ob = outputs_of(c, built, scheme);
        CHECK(same_outputs(&oa, &ob, n));
        free_outputs(&oa);
        free_outputs(&ob);
        pst_op *opa = test_op(c, own, scheme, PST_GRAD_G1, 0);
        pst_op *opb = test_op(c, built, scheme, PST_GRAD_G1, 0);
        double *b = test_field(c, field);
        double *ua = malloc(n * sizeof *ua), *ub = malloc(n * sizeof *ub);
        int precond = pst_have_amg() ? PST_PREC_AMG : PST_PREC_JACOBI;
        int ia = solve(opa, b, ua, n, precond), ib = solve(opb, b, ub, n, precond);
        CHECK(ia > 0 && ia == ib && same(ua, ub, n * sizeof *ua));
        free(b);
        free(ua);
        free(ub);
        pst_op_destroy(opa);
        pst_op_destroy(opb);
        /* wider and narrower lists */
        pst_nlist *wide = test_nlist(c, 1.25 * support), *narrow = test_nlist(c, 0.8 * support);
        int64_t *off;
        uint32_t *idx;
        pst_nlist *nl = NULL;
        csr_of(wide, &off, &idx);
        CHECK(pst_nlist_from_csr(&nl, c, support, off, idx, PST_CSR_CHECK_RADIUS, err) ==
                  PST_EINPUT &&
              nl == NULL && strstr(err, "beyond the support"));
        CHECK(pst_nlist_from_csr(&nl, c, support, off, idx, PST_CSR_CHECK_COMPLETE, err) ==
              PST_OK);
        /* uniform h: the extra pairs get zero kernel weight, the rows are the built list's */
        pst_op *opw = test_op(c, nl, scheme, PST_GRAD_G1, 0);
        pst_op *opn = test_op(c, built, scheme, PST_GRAD_G1, 0);
        double *u = test_field(c, field), *y = malloc(n * sizeof *y), *yn = malloc(n * sizeof *yn);
        CHECK(pst_op_apply(opw, u, y) == PST_OK && pst_op_apply(opn, u, yn) == PST_OK);
        double worst = 0, scale = 0;
        for (size_t i = 0; i < n; ++i) {
            worst = fmax(worst, fabs(y[i] - yn[i]));
            scale = fmax(scale, fabs(yn[i]));
        }
        CHECK(worst <= 1e-10 * scale);
        free(u);
        free(y);
        free(yn);
        pst_op_destroy(opw);
        pst_op_destroy(opn);
        pst_nlist_destroy(nl);
        free(off);
        free(idx);
        csr_of(narrow, &off, &idx);
        CHECK(pst_nlist_from_csr(&nl, c, support, off, idx, PST_CSR_CHECK_COMPLETE, err) ==
                  PST_EINPUT &&
              strstr(err, "lacks"));
        CHECK(pst_nlist_from_csr(&nl, c, support, off, idx, PST_CSR_CHECK_RADIUS, err) == PST_OK);
        pst_nlist_destroy(nl);
        free(off);
        free(idx);
        pst_nlist_destroy(wide);
        pst_nlist_destroy(narrow);
        pst_nlist_destroy(ha);
        pst_nlist_destroy(hb);
        pst_nlist_destroy(own);
        pst_nlist_destroy(built);
        pst_cloud_destroy(c);
    }
}

/* One malformed CSR: the code, and err holding `expect`. */
static void expect_refusal(const pst_cloud *c, const int64_t *off, const uint32_t *idx,
                           int code, const char *expect, const char *what)
{
    pst_nlist *nl = (pst_nlist *)off;
    char err[PST_ERRLEN] = "";
    int st = pst_nlist_from_csr(&nl, c, 2.0, off, idx, 0, err);
    int ok = st == code && nl == NULL && strstr(err, expect);
    if (!ok)
        fprintf(stderr, "%s: status %d, message '%s' (expected '%s')\n", what, st, err, expect);
    CHECK(ok);
}

/* Each malformed CSR is refused with its code and the first offending row; the refusal is the
 * same for 1 and 2 threads; a failed pst_nlist_set_csr leaves the list as it was. */
static void test_csr_refusals(void)
{
    pst_cloud *c = test_lattice(2, 0, 1, 1.0 / 7, 1.3, 0.2, 2, 0);
    pst_nlist *built = test_nlist(c, 2.0);
    size_t n = pst_cloud_size(c), r = 10;
    int64_t *off0, *off;
    uint32_t *idx0, *idx;
    csr_of(built, &off0, &idx0);
    csr_of(built, &off, &idx);
    size_t pairs = (size_t)off0[n], row_bytes = (n + 1) * sizeof *off;
    CHECK(off0[r + 1] - off0[r] >= 3);
    char expect[64];
#define RESET() (memcpy(off, off0, row_bytes), memcpy(idx, idx0, pairs * sizeof *idx))
    int64_t a = off0[r];
    RESET();
    uint32_t t = idx[a];
    idx[a] = idx[a + 1];
    idx[a + 1] = t;
    snprintf(expect, sizeof expect, "row %zu, entry 1", r);
    expect_refusal(c, off, idx, PST_EINPUT, expect, "unsorted row");
    RESET();
    idx[a + 1] = idx[a];
    expect_refusal(c, off, idx, PST_EINPUT, expect, "repeated index");
    RESET();
    idx[a] = (uint32_t)r;
    snprintf(expect, sizeof expect, "row %zu, entry 0: the particle itself", r);
    expect_refusal(c, off, idx, PST_EINPUT, expect, "self pair");
    RESET();
    idx[off0[r + 1] - 1] = (uint32_t)n;
    snprintf(expect, sizeof expect, "row %zu, entry %lld: index %zu out of range", r,
             (long long)(off0[r + 1] - 1 - a), n);
    expect_refusal(c, off, idx, PST_EINPUT, expect, "index out of range");
    RESET();
    idx[a] = UINT32_MAX;
    expect_refusal(c, off, idx, PST_EINPUT, "out of range", "index 2^32 - 1");
    RESET();
    off[0] = 1;
    expect_refusal(c, off, idx, PST_EINPUT, "offset[0] = 1", "offset[0] not 0");
    RESET();
    off[r + 1] = off[r] - 1;
    snprintf(expect, sizeof expect, "row %zu: offset[%zu]", r, r + 1);
    expect_refusal(c, off, idx, PST_EINPUT, expect, "decreasing offsets");
    RESET();
    off[n] = off[n - 1] + (int64_t)n;
    snprintf(expect, sizeof expect, "row %zu has %zu entries", n - 1,
             (size_t)(off[n] - off[n - 1]));
    expect_refusal(c, off, idx, PST_EINPUT, expect, "row too long");
    /* asymmetric: row r without its first neighbour j, row j still holding r */
    RESET();
    uint32_t j = idx0[a];
    memmove(idx + a, idx + a + 1, (pairs - (size_t)a - 1) * sizeof *idx);
    for (size_t i = r + 1; i <= n; ++i)
        off[i] -= 1;
    snprintf(expect, sizeof expect, "row %u, entry", j);
    for (int threads = 1; threads <= 2; ++threads) {
        omp_set_num_threads(threads);
        expect_refusal(c, off, idx, PST_EINPUT, expect, "asymmetric");
        expect_refusal(c, off, idx, PST_EINPUT, "symmetric", "asymmetric");
    }
    /* bad arguments */
    RESET();
    pst_nlist *nl = NULL;
    char err[PST_ERRLEN] = "";
    CHECK(pst_nlist_from_csr(&nl, c, 2.0, NULL, idx, 0, err) == PST_EINVAL);
    CHECK(pst_nlist_from_csr(&nl, c, 2.0, off, NULL, 0, err) == PST_EINVAL);
    CHECK(pst_nlist_from_csr(&nl, c, 2.0, off, idx, 4, err) == PST_EINVAL);
    CHECK(pst_nlist_from_csr(&nl, c, 0.0, off, idx, 0, err) == PST_EINVAL);
    CHECK(pst_nlist_set_csr(built, c, off, idx, 0, err) == PST_EINVAL &&
          strstr(err, "pst_nlist_from_csr"));
    /* a failed replacement leaves the list */
    CHECK(pst_nlist_from_csr(&nl, c, 2.0, off, idx, 0, err) == PST_OK);
    idx[a] = (uint32_t)r;
    CHECK(pst_nlist_set_csr(nl, c, off, idx, 0, err) == PST_EINPUT);
    CHECK(same(pst_nlist_offsets(nl), off0, row_bytes) &&
          same(pst_nlist_indices(nl), idx0, pairs * sizeof *idx));
    pst_nlist_destroy(nl);
    /* a list of one particle: no pairs, no indices */
    pst_cloud *one = NULL;
    int64_t off1[2] = {0, 0};
    CHECK(pst_cloud_create(&one, 2, 1, err) == PST_OK);
    CHECK(pst_nlist_from_csr(&nl, one, 2.0, off1, NULL, 0, err) == PST_OK &&
          pst_nlist_pairs(nl) == 0);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(one);
#undef RESET
    free(off0);
    free(idx0);
    free(off);
    free(idx);
    pst_nlist_destroy(built);
    pst_cloud_destroy(c);
}

/* A borrowed cloud with a list from the caller's CSR: every output the same for 1 and 2
 * threads. */
static void test_one_and_two_threads(void)
{
    pst_cloud *lat = test_lattice(3, 0, 1, 1.0 / 8, 1.3, 0.3, 17, 1);
    host hs = host_from(lat, 1);
    outputs o[2];
    for (int t = 0; t < 2; ++t) {
        omp_set_num_threads(t + 1);
        pst_cloud *cb = borrow(&hs);
        pst_nlist *built = test_nlist(cb, 2.0);
        pst_nlist *own = from_csr_of(cb, built, 2.0, PST_CSR_CHECK_RADIUS);
        o[t] = outputs_of(cb, own, "lv");
        pst_nlist_destroy(own);
        pst_nlist_destroy(built);
        pst_cloud_destroy(cb);
    }
    CHECK(same_outputs(&o[0], &o[1], hs.n));
    free_outputs(&o[0]);
    free_outputs(&o[1]);
    free(hs.block);
    pst_cloud_destroy(lat);
}

int main(void)
{
    test_mpi_init();
    test_borrowed_equals_copied();
    test_moved_in_place();
    test_ownership();
    test_csr_equals_built();
    test_csr_refusals();
    test_one_and_two_threads();
    return check_summary("test_host_data");
}
