/* The weighted-least-squares engine (kernels/wls.c, wls_rows.c, wls_points.c), shared by
 * lsmps (types A and B, LDL^T), lpmps (which supplies only its block factorisation) and qsfdi
 * (which uses the vectorised moment sums). Internal. */
#ifndef PSTENCIL_WLS_H
#define PSTENCIL_WLS_H

#include "isa.h"
#include "kernel_common.h"
#include "operator.h"

/* Factor the moment matrix M of a row (nb unknowns) into fac; returns a condition estimate
 * (INFINITY when singular). Solve M x = b in place with that factor. */
typedef double (*wls_factor_fn)(int dim, int nb, const double *M, double *fac);
typedef void (*wls_solve_fn)(int dim, int nb, const double *M, const double *fac, double *b);

/* Precompute a quadric WLS operator (typeB: with the constant) with the given factorisation. */
int pst_wls_precompute(pst_op *op, int typeB, wls_factor_fn factor, wls_solve_fn solve,
                       char *err);
int pst_wls_min_neighbours(int dim);
/* The rows (kernels/wls_rows.c, compiled once per ISA level: each of these calls the copy of
 * the CPU's level, src/core/isa.h): the matrix-free apply, one row's weights, the half-list
 * rows. */
PST_LEVEL_ENTRY_VOID(pst_wls_apply, (const pst_op *op, const double *u, double *y),
                     (op, u, y))
PST_LEVEL_ENTRY_VOID(pst_wls_emit_row, (const pst_op *op, size_t i, double *w), (op, i, w))
PST_LEVEL_ENTRY_VOID(pst_wls_half_rows,
                     (const pst_op *op, const int64_t *off, const uint32_t *idx, size_t i0,
                      size_t i1, const double *u, double *y),
                     (op, off, idx, i0, i1, u, y))
void pst_wls_gradient(const pst_op *op, const double *u, double *const grad[3]);
void pst_wls_hessian(const pst_op *op, const double *u, double *const hess[6]);
int pst_wls_interpolate(const pst_op *op, const double *const pts[3], size_t m,
                        const double *u, double *value, double *lap, size_t *fallbacks,
                        char *err);
void pst_wls_free(void *p);
/* A flat neighbourhood (pst_op_check_flat_rows): row i becomes the radial row (or empty). */
void pst_wls_degrade(pst_op *op, size_t i);

/* s[.] += sum_c w_c m(r_c) over the monomials m of degree deg (1 to 4), graded lexicographic
 * order; r holds x, y[, z] at stride `stride`, n pairs. Vectorised reduction loops. */
void pst_wls_msums(int dim, int deg, int n, const double *r, int stride, const double *w,
                   double *s);

/* The fields of a WLS scheme's table other than its name, description and precompute. */
#define PST_WLS_FALLBACK                                                                       \
    "quadric fit: too few neighbours or singular -> linear-exact reduced fit -> radial row -> " \
    "zero row; flat neighbours off the particle -> radial row"
#define PST_WLS_ENTRY_POINTS                                                                   \
    .fallback = PST_WLS_FALLBACK, .default_kernel = PST_KERNEL_QUINTIC, .degree = 2,          \
    .degree_lattice = 2,                                                                       \
    .min_neighbours = pst_wls_min_neighbours, .apply = pst_wls_apply, .lanes = 1,              \
    .half_rows = pst_wls_half_rows,                                                            \
    .emit_row = pst_wls_emit_row, .gradient = pst_wls_gradient, .hessian = pst_wls_hessian,    \
    .interpolate = pst_wls_interpolate, .degrade = pst_wls_degrade, .free_data = pst_wls_free, \
    .data_bytes = {49, 81} /* lam: nb doubles (6 / 10 with type B) and a level byte */

#endif
