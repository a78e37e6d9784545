/* The files compiled once per ISA level (src/core/isa.h) give the same bits at every level this
 * CPU runs: pst_isa_level_cap runs the lower levels' copies here, so one dispatched build on an
 * AVX-512 machine checks the blocks of 8, 4 and 2 pairs against each other. Compared per level, by
 * a hash of their bytes: the operator built at that level (its row statuses, after the flatness
 * check), the flatness check's sums of every row, the matrix-free apply on the whole list and on a
 * half list (where the scheme has one), the stored apply, and qsfdi's gradient and Hessian from
 * kept kappas and computed; for qsfdi, lpmps, lsmps, the CSPM family and the LV family (G1 in
 * lanes, G2 in chunks, a tensor mobility), 2D and 3D with Neumann rows, one h and h per particle.
 * Where the build or the CPU has one level only, there is nothing to compare and the test says so. */
#include "check.h"
#include "isa.h"
#include "operator_flat_sums.h"
#include "pstencil.h"
#include "support.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

static double wave(const double *x) { return sin(3 * x[0] + 2 * x[1] - x[2]) + x[0] * x[1]; }

static uint64_t fnv(const void *p, size_t bytes, uint64_t h)
{
    const unsigned char *b = p;
    for (size_t i = 0; i < bytes; ++i)
        h = (h ^ b[i]) * 1099511628211ull;
    return h;
}

/* The hash of what one operator gives at the current level (see the file comment). */
static uint64_t outputs(const pst_cloud *c, const pst_nlist *nl, const pst_op_opts *o)
{
    const size_t n = pst_cloud_size(c);
    double *u = test_field(c, wave), *y = malloc(n * sizeof *y), *d[9];
    uint64_t h = 14695981039346656037ull;
    pst_op *op = test_op_of(c, nl, o);
    h = fnv(pst_op_status(op), n, h);
    CHECK_INT(pst_op_apply(op, u, y), PST_OK);
    h = fnv(y, n * sizeof *y, h);
    for (size_t i = 0; i < n; ++i) {
        double s[PST_FLAT_SUMS];
        pst_flat_sums(op, i, s);
        h = fnv(s, sizeof s, h);
    }
    for (int a = 0; a < 9; ++a)
        d[a] = calloc(n, sizeof *d[a]);
    if (pst_scheme_supports(o->scheme, PST_SUPPORTS_GRADIENT))
        CHECK_INT(pst_op_gradient(op, u, d), PST_OK);
    if (pst_scheme_supports(o->scheme, PST_SUPPORTS_HESSIAN))
        CHECK_INT(pst_op_hessian(op, u, d + 3), PST_OK);
    for (int a = 0; a < 9; ++a) {
        h = fnv(d[a], n * sizeof *d[a], h);
        free(d[a]);
    }
    CHECK_INT(pst_op_store(op), PST_OK);
    CHECK_INT(pst_op_apply_stored(op, u, y), PST_OK);
    h = fnv(y, n * sizeof *y, h);
    pst_op_destroy(op);
    if (pst_scheme_supports(o->scheme, PST_SUPPORTS_HALF_LIST)) {
        pst_nlist *half = NULL;
        char err[512];
        op = test_op_of(c, nl, o);
        CHECK_INT(pst_nlist_halve(&half, nl, err), PST_OK);
        CHECK_INT(pst_op_use_half_list(op, half, err), PST_OK);
        CHECK_INT(pst_op_apply(op, u, y), PST_OK);
        h = fnv(y, n * sizeof *y, h);
        pst_op_destroy(op);
        pst_nlist_destroy(half);
    }
    free(u);
    free(y);
    return h;
}

/* One operator at every level below the CPU's against the CPU's own. */
static void compare_levels(const pst_cloud *c, const pst_nlist *nl, const pst_op_opts *o,
                           int top)
{
    const uint64_t ref = outputs(c, nl, o);
    for (int level = top - 1; level >= 0; --level) {
        CHECK_INT(pst_isa_level_cap(level), level);
        uint64_t h = outputs(c, nl, o);
        if (h != ref)
            printf("  %s %dD G%d keep %d mobility %d: level %d differs from level %d\n",
                   o->scheme, pst_cloud_dim(c), o->gradient, o->keep, pst_cloud_mobility_ncomp(c),
                   level, top);
        CHECK(h == ref);
    }
    CHECK_INT(pst_isa_level_cap(2), top);
}

static void check_cloud(int dim, int per_particle_h, int top)
{
    pst_cloud *c = test_lane_cloud(dim, per_particle_h);
    pst_nlist *wide = test_nlist(c, 3.0 * 1.2), *nl = test_nlist(c, 2.0 * 1.2);
    const char *quadric[] = {"qsfdi", "lpmps", "lsmps"};
    for (int s = 0; s < 3; ++s)
        for (int keep = 0; keep <= (s == 0 ? 3 : 0); keep += 3) {
            pst_op_opts o;
            pst_op_defaults(&o);
            o.scheme = quadric[s];
            o.keep = keep;
            compare_levels(c, wide, &o, top);
        }
    const char *cspm[] = {"cspm", "icspm", "csph2g"};
    for (int s = 0; s < 3; ++s) {
        pst_op_opts o;
        pst_op_defaults(&o);
        o.scheme = cspm[s];
        compare_levels(c, wide, &o, top);
    }
    for (int g = PST_GRAD_G1; g <= PST_GRAD_G2; ++g) {
        pst_op_opts o;
        pst_op_defaults(&o);
        o.scheme = "lv";
        o.gradient = g;
        compare_levels(c, nl, &o, top);
    }
    test_rough_mobility(c, dim); /* a diagonal tensor */
    pst_op_opts o;
    pst_op_defaults(&o);
    o.scheme = "lv";
    compare_levels(c, nl, &o, top);
    pst_nlist_destroy(wide);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
}

int main(void)
{
    const int top = pst_isa_level();
    if (top == 0) {
        printf("test_levels: this build or CPU runs one level only (%s): nothing to compare\n",
               pst_isa());
        return check_summary("test_levels");
    }
    for (int dim = 2; dim <= 3; ++dim)
        for (int h = 0; h <= 1; ++h)
            check_cloud(dim, h, top);
    return check_summary("test_levels");
}
