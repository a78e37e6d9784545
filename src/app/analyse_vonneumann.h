/* Von Neumann growth factors of an operator (LV §4.3, eqs. 81-83; docs/stability.md):
 *     lambda_j(k) = 1 + tau s0^2 e^{-i k.r_j} (L[e^{i k.r}])_j
 * for every unknown row j (interior and Neumann particles; a Neumann row, an outward flux
 * n.grad u in L, enters with the inward-flux sign -n.grad u, the sign of a Laplacian row) and
 * every wave vector k of the set
 *     k = (pi / s0) (a, b[, c]) / N,   a, b, c in 0..N,   k != 0.
 * tau is dimensionless: the time step (or Richardson step) is tau s0^2, so on the 5-point
 * Laplacian the checkerboard gives lambda = 1 - 8 tau (exactly -1 at the paper's tau = 0.25). */
#ifndef PSTENCIL_ANALYSE_VONNEUMANN_H
#define PSTENCIL_ANALYSE_VONNEUMANN_H

#include "pstencil.h"

#include <stddef.h>
#include <stdint.h>

/* |lambda| above 1 + this is growth. */
#define PST_VN_TOL 1e-12

typedef struct {
    int dim;
    double tau, s0;            /* as given                                                     */
    int waves;                 /* N                                                            */
    size_t nk;                 /* wave vectors: (N+1)^dim - 1                                  */
    double *k;                 /* 3 nk: kx, ky, kz of wave vector q at k[3q..3q+2] (kz 0 in 2D) */
    size_t rows;               /* unknown rows                                                 */
    size_t *particle;          /* rows: the cloud index of each unknown row                     */
    int64_t *id;               /* rows: its input id (pst_cloud_ids)                            */
    uint8_t *adjacent;         /* rows: 1 when boundary-adjacent (see below)                    */
    double *re, *im;           /* nk * rows: lambda of row r for wave q at [q * rows + r]       */
    double max_abs;            /* max |lambda| over every (row, k)                              */
    size_t over;               /* (row, k) pairs with |lambda| > 1 + PST_VN_TOL                 */
    double over_fraction;      /* over / (rows * nk)                                            */
    size_t particles_over;     /* rows with |lambda| > 1 + PST_VN_TOL for some k                */
    size_t particles_over_adjacent; /* ... of them boundary-adjacent                            */
    size_t adjacent_rows;      /* boundary-adjacent rows in all                                 */
} pst_vonneumann;

/* The growth factors of op (built on cloud c with list nl) for time-step factor tau > 0 and
 * N = waves >= 1, with lattice spacing s0 > 0. L is real, so L[e^{ik.r}] = L[cos] + i L[sin]:
 * two matrix-free applies per k over every particle (Dirichlet particles carry the wave too).
 * A row is boundary-adjacent when it is a Neumann particle or has a Dirichlet or Neumann
 * particle in its neighbour list. Errors with the reason in err: PST_EINVAL (bad tau, waves or
 * s0; no unknown rows), PST_ENOMEM, PST_ENUMERIC (a non-finite apply). vn is zeroed first and
 * is safe to free after any failure. */
int pst_vonneumann_compute(const pst_cloud *c, const pst_nlist *nl, const pst_op *op, double s0,
                           double tau, int waves, pst_vonneumann *vn, char *err, size_t errlen);
/* Free the arrays of vn and zero it (a zeroed or failed one is fine). */
void pst_vonneumann_free(pst_vonneumann *vn);

/* The mean over particles of the distance to the nearest neighbour in nl (particles without
 * neighbours are skipped): the spacing of a cloud that has none (a file). 0 when no particle
 * has a neighbour. */
double pst_mean_nearest_distance(const pst_cloud *c, const pst_nlist *nl);

/* DIR/vonneumann.csv: "k,kx,ky,kz,id,re,im,abs", one line per (k, row), all or nothing. */
int pst_vonneumann_write_csv(const pst_vonneumann *vn, const char *path, char *err,
                             size_t errlen);
/* DIR/vonneumann.png: every lambda in the complex plane with the unit circle, the ones
 * outside it highlighted (gnuplot; PST_EIO when it is missing or fails). */
int pst_vonneumann_plot(const pst_vonneumann *vn, const char *path, const char *title,
                        char *err, size_t errlen);

#endif
