/* The matrix-free rows in lanes (kernels/lanes.h, docs/operators.md "Matrix-free rows in lanes"):
 * for qsfdi, lpmps, lsmps, the CSPM and the LV families the matrix-free apply takes 8 pairs at a
 * time from the packed (x, y, z, u) rows and sums in the stored apply's 8 lanes, so the two
 * applies give the same numbers, row by row, not only to rounding. Checked in 2D and 3D with
 * Dirichlet and Neumann rows, uniform and per-particle h, the LV gradient variants, mobilities and
 * kernels (the LV rows in lanes beside its chunk rows; the CSPM rows, whose emission takes its
 * chunks), rows of every length modulo 8 (the last block padded, or read past the row) and rows
 * longer than a chunk (256 neighbours); a second apply with another u repacks u; an operator whose
 * rows were skipped refuses the apply. */
#include "check.h"
#include "pstencil.h"
#include "support.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static double wave(const double *x) { return sin(3 * x[0] + 2 * x[1] - x[2]) + x[0] * x[1]; }
static double bump(const double *x) { return exp(-x[0] * x[0] - 2 * x[1]) + x[2]; }

/* Rows of the apply and the stored apply that differ (== on doubles: -0 and +0 are equal),
 * and the row lengths modulo 8 seen, as a bit set. */
static size_t differing(const pst_op *op, const pst_nlist *nl, const double *u, size_t n,
                        unsigned *tails)
{
    double *y = malloc(n * sizeof *y), *ys = malloc(n * sizeof *ys);
    CHECK_INT(pst_op_apply(op, u, y), PST_OK);
    CHECK_INT(pst_op_apply_stored(op, u, ys), PST_OK);
    const int64_t *off = pst_nlist_offsets(nl);
    size_t bad = 0;
    for (size_t i = 0; i < n; ++i) {
        bad += !(y[i] == ys[i]);
        *tails |= 1u << ((off[i + 1] - off[i]) % 8);
    }
    free(y);
    free(ys);
    return bad;
}

/* One operator: stored in double, then both applies for two fields. */
static void check_op(const pst_cloud *c, const pst_nlist *nl, const pst_op_opts *o,
                     unsigned *tails)
{
    pst_op *op = test_op_of(c, nl, o);
    CHECK_INT(pst_op_store(op), PST_OK);
    size_t n = pst_cloud_size(c);
    double *u = test_field(c, wave), *v = test_field(c, bump);
    size_t bad = differing(op, nl, u, n, tails) + differing(op, nl, v, n, tails);
    if (bad)
        printf("  %s %dD gradient %d: %zu rows differ\n", o->scheme, pst_cloud_dim(c),
               o->gradient, bad);
    CHECK_INT(bad, 0);
    free(u);
    free(v);
    pst_op_destroy(op);
}

static void check_schemes(int dim, int per_particle_h)
{
    pst_cloud *c = test_lane_cloud(dim, per_particle_h);
    unsigned tails = 0;
    const char *quadric[] = {"qsfdi", "lpmps", "lsmps", "cspm", "icspm", "csph2g"};
    pst_nlist *wide = test_nlist(c, 3.0 * 1.2); /* the quintic support, with h's spread */
    for (int s = 0; s < 6; ++s) {
        pst_op_opts o;
        pst_op_defaults(&o);
        o.scheme = quadric[s];
        check_op(c, wide, &o, &tails);
    }
    const char *lv[] = {"brookshaw", "cb", "schwaiger", "lv"};
    pst_nlist *nl = test_nlist(c, 2.0 * 1.2); /* the cubic spline's */
    /* the LV and CSPM rows in lanes have an instantiation per kernel: the other three */
    for (int K = PST_KERNEL_QUINTIC; K <= PST_KERNEL_WENDLAND_C4; ++K)
        for (int s = 0; s < 2; ++s) {
            pst_op_opts o;
            pst_op_defaults(&o);
            o.scheme = s ? "cspm" : "lv";
            o.kernel = (pst_kernel)K;
            check_op(c, K == PST_KERNEL_QUINTIC ? wide : nl, &o, &tails);
        }
    pst_nlist_destroy(wide);
    for (int s = 0; s < 4; ++s)
        for (int g = PST_GRAD_G1; g <= PST_GRAD_G4; ++g) {
            pst_op_opts o;
            pst_op_defaults(&o);
            o.scheme = lv[s];
            o.gradient = g;
            check_op(c, nl, &o, &tails);
        }
    for (int ncomp = 1; ncomp <= dim; ncomp += dim - 1) { /* scalar, then diagonal tensor */
        test_rough_mobility(c, ncomp);
        for (int mean = PST_MEAN_ARITHMETIC; mean <= PST_MEAN_HARMONIC; ++mean) {
            pst_op_opts o;
            pst_op_defaults(&o);
            o.scheme = "lv";
            o.mobility_mean = mean;
            check_op(c, nl, &o, &tails);
        }
    }
    CHECK_INT(tails, 0xffu); /* every row length modulo 8 occurred */
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
}

/* Rows longer than a chunk: h = 3.2 s0 gives ~540 neighbours per row with the cubic support
 * in 3D. */
static void check_long_rows(void)
{
    pst_cloud *c = test_lattice(3, 0, 1, 1.0 / 11, 3.2, 0.3, 3, 1);
    pst_nlist *nl = test_nlist(c, 2.0);
    pst_nlist_stats st;
    pst_nlist_get_stats(nl, &st);
    CHECK(st.max > 2 * 256);
    unsigned tails = 0;
    const char *schemes[] = {"lv", "qsfdi", "cspm"};
    for (int s = 0; s < 3; ++s) {
        pst_op_opts o;
        pst_op_defaults(&o);
        o.scheme = schemes[s];
        o.kernel = PST_KERNEL_CUBIC;
        check_op(c, nl, &o, &tails);
    }
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
}

/* Without rows there is nothing to apply, and nothing is packed. */
static void check_no_rows(void)
{
    pst_cloud *c = test_lattice(2, 0, 1, 1.0 / 21, 1.3, 0.3, 3, 0);
    pst_nlist *nl = test_nlist(c, 3.0);
    pst_op_opts o;
    pst_op_defaults(&o);
    o.laplacian = 0;
    pst_op *op = test_op_of(c, nl, &o);
    size_t n = pst_cloud_size(c);
    double *u = test_field(c, wave), *y = malloc(n * sizeof *y);
    CHECK_INT(pst_op_apply(op, u, y), PST_EINVAL);
    free(u);
    free(y);
    pst_op_destroy(op);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
}

int main(void)
{
    for (int dim = 2; dim <= 3; ++dim)
        for (int h = 0; h <= 1; ++h)
            check_schemes(dim, h);
    check_long_rows();
    check_no_rows();
    return check_summary("test_lanes");
}
