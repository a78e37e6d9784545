/* A two-point flux approximation (TPFA) finite-volume reference for -div(K grad u) = 0 on a
 * Cartesian grid of nx x ny (x nz) cells with a diagonal K per cell: the mesh scheme LV
 * compare against (LV eqs. 66-67, MRST's TPFA).
 *
 *   interior face between cells a and b along axis d:  T = A / (d_d/2 / K_a,d + d_d/2 / K_b,d)
 *   (the harmonic face transmissibility), A the face area;
 *   boundary face of cell a:  Dirichlet u = g:      T = A / (d_d/2 / K_a,d), flux T (g - u_a);
 *                             flux  n . K grad u = g (outward):  inflow A g into the cell;
 *                             no flow is flux 0.
 * The matrix is symmetric positive definite when at least one face is Dirichlet; it is stored
 * banded (axes reordered so that the longest axis is the slowest and the half-bandwidth is the
 * product of the other extents) and solved by LAPACKE_dpbsv (Cholesky). */
#ifndef PSTENCIL_TEST_TPFA_REF_H
#define PSTENCIL_TEST_TPFA_REF_H

#include <stddef.h>

typedef enum { TPFA_FLUX = 0, TPFA_DIRICHLET = 1 } tpfa_bc;

typedef struct {
    int dim;              /* 2 or 3                                                        */
    int n[3];             /* cells per axis (n[2] ignored in 2D)                           */
    double d[3];          /* cell size per axis                                            */
    double lo[3];         /* lower corner                                                  */
    const double *k[3];   /* K_d per cell, cell (i, j, l) at i + n0 (j + n1 l)             */
    /* Boundary side s = 2 d + (0 lower, 1 upper face along axis d): kind and value (the
     * Dirichlet value, or the outward flux n . K grad u; 0 with TPFA_FLUX is no flow). When
     * `value_fn` is set it gives the value at face centre x instead of bc_value[s]. */
    int bc_kind[6];
    double bc_value[6];
    double (*value_fn)(void *ctx, int side, const double x[3]);
    void *ctx;
} tpfa_problem;

/* Solve for the cell-centre values u (n0 n1 [n2] values, the cell order above). Returns 0,
 * or -1 with the reason in err (bad input, no Dirichlet face: singular, LAPACK failure,
 * out of memory). */
int tpfa_solve(const tpfa_problem *p, double *u, char *err, size_t errlen);

/* Net outward flux through boundary side s of the solution u (sum over its faces of
 * A n . K grad u, by the same two-point formula). */
double tpfa_side_flux(const tpfa_problem *p, const double *u, int side);

#endif
