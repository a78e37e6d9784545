/* The literal multi-pass QSFDI of the paper with the corrected formulas of
 * docs/schemes/qsfdi.md (Eqs. 16-31), kept as a test oracle for the one-pass moment
 * formulation in kernels/qsfdi.c. */
#ifndef PSTENCIL_QSFDI_ORACLE_H
#define PSTENCIL_QSFDI_ORACLE_H

#include <stddef.h>
#include <stdint.h>

/* Use the paper's printed Gamma_jI (after Eq. 18) instead of the corrected omega4 Pi_j: a
 * negative control that must fail quadratic exactness. */
#define QSFDI_ORACLE_PRINTED_GAMMA 1

/* Weights at the point xi (dim 2 or 3) from the neighbours nb[0..n) of the positions x, with
 * the quintic weight of smoothing length h, in unscaled coordinates: lap[k] = a_Ik (1^T Phi^s)
 * and grad[k*dim + a] = Phi^g_k. Pairs closer than 1e-8 h get 0. Returns 0 when M2c, M2s or
 * M1q is singular. */
int qsfdi_oracle_weights(int dim, const double *const x[3], const double xi[3],
                         const uint32_t *nb, size_t n, double h, int flags, double *lap,
                         double *grad);

#endif
