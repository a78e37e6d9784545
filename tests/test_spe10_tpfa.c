/* The TPFA finite-volume reference (tpfa_ref.c) on its own, then LV §5.3 (spec lukyanov_vuik
 * §7.9): SPE10 layer 85, 60 x 60, one particle per cell, M = diag(Kx, Ky), u = 1 at y = 0 and
 * u = 0 at y = 1, no flow on the x faces, `lv` against TPFA on the same grid; and the 3D
 * 60 x 60 x 2 stack of layers 84 and 85 (not the paper's 60^3 block: docs/spe10.md).
 * docs/lv-tables.md explains the bounds. */
#include "check.h"
#include "lv_problems.h"
#include "pstencil.h"
#include "tpfa_ref.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef PSTENCIL_SHARED_DIR
#error "PSTENCIL_SHARED_DIR must name the shared/ directory (tests/CMakeLists.txt)"
#endif
#define GEOS_X PSTENCIL_SHARED_DIR "/data/spe10/geos_layers84_85/permx.geos"

static double linear(void *ctx, int side, const double x[3])
{
    (void)ctx;
    (void)side;
    return 1.0 + 2.0 * x[0] - 3.0 * x[1] + 0.5 * x[2];
}

/* A linear field is exact for constant K (2D and 3D, any side lengths), and the boundary
 * fluxes balance. */
static void test_tpfa_linear(void)
{
    char err[256];
    for (int dim = 2; dim <= 3; ++dim) {
        const int n[3] = {7, 5, dim == 3 ? 4 : 1};
        size_t nc = (size_t)n[0] * n[1] * n[2];
        double *k = malloc(nc * sizeof *k), *u = malloc(nc * sizeof *u);
        for (size_t c = 0; c < nc; ++c)
            k[c] = 2.5;
        tpfa_problem p = {.dim = dim, .n = {n[0], n[1], n[2]}, .d = {0.1, 0.2, 0.3},
                          .lo = {1, -1, 0.5}, .k = {k, k, k}, .value_fn = linear};
        for (int s = 0; s < 2 * dim; ++s)
            p.bc_kind[s] = TPFA_DIRICHLET;
        CHECK(tpfa_solve(&p, u, err, sizeof err) == 0);
        double worst = 0;
        for (size_t c = 0; c < nc; ++c) {
            double x[3] = {p.lo[0] + ((double)(c % 7) + 0.5) * 0.1,
                           p.lo[1] + ((double)(c / 7 % 5) + 0.5) * 0.2,
                           p.lo[2] + ((double)(c / 35) + 0.5) * 0.3};
            if (dim == 2)
                x[2] = 0;
            worst = fmax(worst, fabs(u[c] - linear(NULL, 0, x)));
        }
        CHECK(worst < 1e-12);
        double net = 0;
        for (int s = 0; s < 2 * dim; ++s)
            net += tpfa_side_flux(&p, u, s);
        CHECK(fabs(net) < 1e-11);
        /* x = 0 outward flux of u = ... + 2x is -K 2 times the face area */
        double area = dim == 3 ? 0.2 * 5 * 0.3 * 4 : 0.2 * 5;
        CHECK_NEAR(tpfa_side_flux(&p, u, 0), -2.5 * 2 * area, 1e-11);
        free(k);
        free(u);
    }
}

/* Layered K (constant along x, varying along y) with u = 1 at y = 0, u = 0 at y = 1 and no
 * flow on the x faces: the flux is 1 / sum(dy / K_j) (the harmonic mean) and u is the
 * piecewise-linear exact solution at the cell centres. */
static void test_tpfa_layered(void)
{
    char err[256];
    const int nx = 4, ny = 6;
    const double kl[6] = {1, 100, 0.01, 5, 1e4, 0.3};
    double *kx = malloc(nx * ny * sizeof *kx), *ky = malloc(nx * ny * sizeof *ky),
           *u = malloc(nx * ny * sizeof *u);
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
            kx[i + nx * j] = 7 * kl[j]; /* any Kx: no flow along x */
            ky[i + nx * j] = kl[j];
        }
    const double dy = 1.0 / ny, dx = 0.25;
    tpfa_problem p = {.dim = 2, .n = {nx, ny, 1}, .d = {dx, dy, 1}, .k = {kx, ky, NULL},
                      .bc_kind = {TPFA_FLUX, TPFA_FLUX, TPFA_DIRICHLET, TPFA_DIRICHLET},
                      .bc_value = {0, 0, 1, 0}};
    CHECK(tpfa_solve(&p, u, err, sizeof err) == 0);
    double r = 0;
    for (int j = 0; j < ny; ++j)
        r += dy / kl[j];
    double q = 1.0 / r; /* flux per unit width from y = 0 to y = 1 */
    /* outward n . K grad u: -q on the outlet y = 1, +q on the inlet y = 0 */
    CHECK_NEAR(tpfa_side_flux(&p, u, 3), -q * nx * dx, 1e-11 * q);
    CHECK_NEAR(tpfa_side_flux(&p, u, 2), q * nx * dx, 1e-11 * q);
    double worst = 0, drop = 0; /* exact: u drops by q dy/(2K) over each half cell */
    for (int j = 0; j < ny; ++j) {
        double uc = 1 - (drop + q * dy / (2 * kl[j]));
        drop += q * dy / kl[j];
        for (int i = 0; i < nx; ++i)
            worst = fmax(worst, fabs(u[i + nx * j] - uc));
    }
    CHECK(worst < 1e-12);
    p.bc_kind[2] = p.bc_kind[3] = TPFA_FLUX; /* no Dirichlet side: singular, refused */
    CHECK(tpfa_solve(&p, u, err, sizeof err) == -1);
    free(kx);
    free(ky);
    free(u);
}

/* lv on the SPE10 case against TPFA at the cell centres: max |u_lv - u_tpfa| / |u_tpfa| and
 * max |u_lv - u_tpfa| (the drop is 1, so the latter is relative to it). */
static void compare(const pst_perm_grid *g, double f, double *maxrel, double *maxabs, int *iters,
                    double *resid)
{
    char err[PST_ERRLEN];
    pst_cloud *c = NULL;
    pst_nlist *nl = NULL;
    double *b = NULL;
    *maxrel = *maxabs = INFINITY;
    int st = lv_spe10_case(g, f, &c, &nl, &b, err);
    CHECK(st == PST_OK);
    if (st != PST_OK) {
        fprintf(stderr, "spe10 case: %s\n", err);
        return;
    }
    size_t np = pst_cloud_size(c), nc = (size_t)g->nx * g->ny * g->nz;
    pst_op_opts oo;
    pst_op_defaults(&oo);
    oo.scheme = "lv";
    pst_op *op = NULL;
    CHECK(pst_op_create(&op, c, nl, &oo, err) == PST_OK);
    pst_solve_opts so;
    pst_solve_defaults(&so);
    so.solver = PST_SOLVER_GMRES;
    /* Jacobi-GMRES stalls near 1e-9 on the 4.4e6 contrast; BoomerAMG on the Brookshaw
     * M-matrix of the same cloud and mobility does not */
    so.precond = PST_PREC_AMG;
    so.amg_source = PST_AMG_BROOKSHAW;
    so.rtol = 1e-10;
    so.max_iter = 2000;
    pst_solve_result r;
    memset(&r, 0, sizeof r);
    double *u = calloc(np, sizeof *u), *t = malloc(nc * sizeof *t);
    st = pst_solve(op, b, u, &so, &r, err);
    *iters = r.iterations;
    *resid = r.rel_residual;
    if (st == PST_ENUMERIC && np <= 4000) {
        st = lv_solve_dense(op, b, u, err); /* small: a dense LU instead (iters = -1) */
        *iters = -1;
        *resid = 0;
    }
    /* the 3D stack (too big for the dense LU) is accepted at a stalled residual below 1e-7:
     * the differences measured are 1e-1 */
    CHECK(st == PST_OK || (st == PST_ENUMERIC && *resid < 1e-7));
    if (st != PST_OK)
        fprintf(stderr, "spe10 solve: %s\n", err);
    pst_solve_result_free(&r);
    tpfa_problem p = {.dim = g->nz > 1 ? 3 : 2, .n = {g->nx, g->ny, g->nz},
                      .d = {1.0 / g->nx, 1.0 / g->nx, 1.0 / g->nx},
                      .k = {g->k[0], g->k[1], g->k[2]},
                      .bc_kind = {TPFA_FLUX, TPFA_FLUX, TPFA_DIRICHLET, TPFA_DIRICHLET, TPFA_FLUX, TPFA_FLUX},
                      .bc_value = {0, 0, 1, 0, 0, 0}};
    CHECK(tpfa_solve(&p, t, err, PST_ERRLEN) == 0);
    /* interior particles come first, in the grid's cell order (pst_cloud_cell_centred) */
    double wr = 0, wa = 0;
    for (size_t k = 0; k < nc; ++k) {
        wa = fmax(wa, fabs(u[k] - t[k]));
        wr = fmax(wr, fabs(u[k] - t[k]) / fabs(t[k]));
    }
    *maxrel = wr;
    *maxabs = wa;
    free(u);
    free(t);
    free(b);
    pst_op_destroy(op);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
}

static void test_spe10(void)
{
    char err[PST_ERRLEN];
    pst_perm_grid g;
    int st = pst_spe10_read(&g, GEOS_X, 85, 0, 0, 60, 60, err);
    CHECK(st == PST_OK);
    if (st != PST_OK) {
        fprintf(stderr, "%s\n", err);
        return;
    }
    double rel, abs_, res;
    int it;
    /* The comparison machinery on a homogeneous K (same cloud, same BCs): u = 1 - y is exact
     * for both, so the difference is the solvers' alone. */
    pst_perm_grid h = g;
    double *one = malloc(3600 * sizeof *one);
    for (int k = 0; k < 3600; ++k)
        one[k] = 1;
    h.k[0] = h.k[1] = h.k[2] = one;
    compare(&h, 0.6006, &rel, &abs_, &it, &res);
    printf("homogeneous K, lv f = 0.6006: max rel diff vs TPFA %.3e, max abs %.3e\n", rel, abs_);
    CHECK(abs_ < 1e-8);
    free(one);

    const double fs[2] = {0.6006, 1.2012};
    for (int k = 0; k < 2; ++k) {
        compare(&g, fs[k], &rel, &abs_, &it, &res);
        printf("SPE10 layer 85 60x60, lv f = %.4f: max rel diff vs TPFA %.3e, max abs %.3e "
               "(iterations %d, -1 = dense LU; paper: 6e-4)\n", fs[k], rel, abs_, it);
        /* measured 0.145 (f = 0.6006) and 0.228 (f = 1.2012): lv's arithmetic mobility mean
         * against TPFA's harmonic one on a 4.4e6 contrast; docs/lv-tables.md */
        CHECK(abs_ < (k == 0 ? 0.2 : 0.3));
        CHECK(abs_ > 0.05); /* the difference is real, not 0.06 %: tell us if that changes */
    }
    pst_perm_grid_free(&g);
    pst_perm_grid g3;
    st = lv_spe10_stack_84_85(&g3, GEOS_X, 60, 60, err);
    CHECK(st == PST_OK);
    if (st == PST_OK) {
        compare(&g3, 0.6006, &rel, &abs_, &it, &res);
        printf("SPE10 layers 84+85 60x60x2, lv f = 0.6006: max rel diff vs TPFA %.3e, max abs "
               "%.3e (iterations %d, residual %.1e)\n", rel, abs_, it, res);
        CHECK(abs_ < 0.25); /* measured 0.194 */
        for (int c = 0; c < 3; ++c)
            free(g3.k[c]);
    } else {
        fprintf(stderr, "%s\n", err);
    }
}

int main(void)
{
    test_tpfa_linear();
    test_tpfa_layered();
    test_spe10();
    return check_summary("test_spe10_tpfa");
}
