/* The Lukyanov–Vuik boundary-value problems of §5.1 and §5.2 (docs/lv-tables.md)
 * and the SPE10 comparison of §5.3, shared by tests/test_lv_bvp.c,
 * tests/test_spe10_tpfa.c and bench/lv_tables.c.
 *
 * Geometry: the unit square (L = H = 1; the paper does not give L, H), the cell-centred layout
 * of pst_cloud_cell_centred with n cells per side (DoF = n^2 interior particles, one per cell)
 * and one face particle at the centre of every boundary cell face; V = (1/n)^2 everywhere,
 * h = f / n. A perturbed cloud moves every interior particle by K delta / n per coordinate with
 * K = 0.1 * 1.001 (our reading of "10 % of h_max = 1.001", docs/lv-tables.md), face particles
 * stay put.
 *
 * Boundary data use the paper's side numbering: psi[0] = psi1 on y = 0, psi[1] = psi2 on
 * x = L, psi[2] = psi3 on y = H, psi[3] = psi4 on x = 0. */
#ifndef PSTENCIL_TEST_LV_PROBLEMS_H
#define PSTENCIL_TEST_LV_PROBLEMS_H

#include "pstencil.h"

#include <stddef.h>
#include <stdint.h>

/* Perturbation amplitude of the random tables, in units of the spacing. */
#define LV_JITTER (0.1 * 1.001)

/* The paper's psi values of §5.2: psi1 = 150, psi2 = 90, psi3 = 150, psi4 = 200. The paper
 * gives none for §5.1; we use the same ones there (one sign, so u > 0 and eq. 95 is finite). */
extern const double lv_psi[4];

typedef enum {
    LV_DIRICHLET_ALL = 1, /* §5.1: every face particle Dirichlet, exact (96)               */
    LV_MIXED = 2          /* §5.2: Dirichlet on y = 0, Neumann elsewhere, exact (98)       */
} lv_problem;

/* One problem instance: cloud, list, right-hand side and the exact values at the particles. */
typedef struct {
    pst_cloud *cloud;
    pst_nlist *nlist;
    double *b;        /* right-hand side of pst_solve (interior 0, Dirichlet value, Neumann g_N) */
    double *exact;    /* exact solution at every particle (face particles: the boundary value
                         on Dirichlet faces, the series on Neumann faces)                      */
    size_t n;         /* particles                                                              */
    size_t ninterior; /* interior particles (= cells = DoF)                                     */
} lv_case;

/* Build the §5.1 or §5.2 problem on n x n cells with h = f / n and perturbation amplitude
 * `jitter` (0 for the uniform tables, LV_JITTER for the random ones) from `seed`. Returns
 * PST_OK or the library's status with the reason in err. */
int lv_case_build(lv_case *pc, lv_problem prob, int n, double f, double jitter, uint64_t seed,
                  char *err);
void lv_case_free(lv_case *pc);

/* Exact solutions on the unit square. (96) with its psi3 term corrected, summed in closed form
 * (the odd-n sine series of e^{-n pi y} is (2/pi) atan(sin(pi x) / sinh(pi y))) plus a
 * remainder that converges like e^{-n pi}; nterms > 0 instead sums the first nterms odd terms
 * of the printed series directly (the paper's truncated evaluation, with its Gibbs ripple). */
double lv_exact96(double x, double y, const double psi[4], int nterms);
/* (98) with sin(lambda_n y) (the printed sinh is a typo), summed until the terms are below
 * 1e-17 of psi (at most 2e6 terms). */
double lv_exact98(double x, double y, const double psi[4]);

/* Error (95): the relative discrete L2 error over the interior particles,
 * [sum V_K ((u_K - u_h,K) / u_K)^2 / sum V_J]^(1/2). */
double lv_error95(const pst_cloud *c, const double *exact, const double *uh);

/* Solve the case with `scheme` (cubic kernel, G1) on its stored weights: GMRES(50) + Jacobi,
 * rtol 1e-10, max 20000 iterations, starting from 0. iters (may be NULL) receives the iterations. Returns the
 * status of pst_solve / pst_op_create with the reason in err. */
int lv_solve_scheme(const lv_case *pc, const char *scheme, double *uh, int *iters, char *err);

/* The same discrete solution by a dense LU of the assembled matrix (LAPACKE_dgesv): a
 * solver-independent cross-check for small clouds (n <= 4000). */
int lv_solve_dense(const pst_op *op, const double *b, double *uh, char *err);
/* The same for an assembled (possibly edited) matrix a, n <= 4000. */
int lv_solve_dense_csr(const pst_csr *a, const double *b, double *uh, char *err);

/* Least-squares slope of log2(err) against log2(1/side) over m levels: the convergence rate
 * in powers of h (DoF x 4 = h / 2). */
double lv_fit_rate(const int *sides, const double *err, int m);

/* The TPFA reference (tpfa_ref.h) on the same problem and n x n cells (the paper's MPFA
 * column: MPFA = TPFA on uniform grids): error (95) over the cell centres. Returns 0 or -1
 * with the reason in err. */
int lv_tpfa_error(lv_problem prob, int n, double *e95, char *err);

/* SPE10 §5.3: the cell-centred cloud of nx x ny (x nz) cells of spacing 1/nx on
 * [0,1] x [0, ny/nx] (x [0, nz/nx]), mobility diag(Kx, Ky[, Kz]) of the grid cell holding each
 * particle, Dirichlet u = 1 on y = 0 and u = 0 on y = ymax, no-flow Neumann (g_N = 0) on
 * every other face. The grid is mapped cell for cell (square cells: docs/spe10.md "aspect
 * ratio"). h = f / nx. b receives the right-hand side (caller frees). Interior particles come
 * first, in the grid's cell order (pst_cloud_cell_centred). */
int lv_spe10_case(const pst_perm_grid *g, double f, pst_cloud **c, pst_nlist **nl, double **b,
                  char *err);

/* Stack layers 84 (l = 0) and 85 (l = 1) of the GEOS files into one nx x ny x 2 grid (arrays
 * from malloc: free g->k[c] with free()). */
int lv_spe10_stack_84_85(pst_perm_grid *g, const char *permx_path, int ni, int nj, char *err);

#endif
