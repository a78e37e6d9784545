/* pstencil: Outward normals estimated from the cloud. Part of the public API; include
 * <pstencil.h>. */
#ifndef PSTENCIL_PUBLIC_NORMALS_H
#define PSTENCIL_PUBLIC_NORMALS_H

#include "pstencil/cloud.h"
#include "pstencil/kernel.h"
#include "pstencil/neighbours.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Outward unit normals of the particles `select` names (n bytes in cloud order, nonzero =
 * estimate; NULL = every particle whose kind is not interior), for a cloud whose file gives
 * none. The Shepard sum S(x) = sum_j V_j W(|x - x_j|, h) falls off across a free surface, so
 * its gradient at particle i, sum_j V_j W'(r_ij, h_i) (x_i - x_j) / r_ij over the neighbours
 * with r_ij < support h_i, points into the cloud: n_i is minus it, normalised (docs/
 * boundaries.md, with its measured accuracy on a sphere). `nl` is the cloud's full neighbour
 * list (pst_nlist_build) of a radius at least pst_kernel_support(kernel) h_i. A particle whose
 * gradient is below 1e-10 of sum_j V_j |W'(r_ij, h_i)| (no neighbours, or neighbours
 * balanced all round: not on a surface) is degenerate: its normal is set to zero and counted
 * in *degenerate (may be NULL). Rows not selected are not written. normal[d] (d < dim) holds n
 * doubles each. Deterministic and independent of the thread count. PST_EINVAL for a half
 * list, a list of another cloud or a NULL array. */
int pst_normals_estimate(const pst_cloud *c, const pst_nlist *nl, pst_kernel kernel,
                         const uint8_t *select, double *const normal[3], size_t *degenerate,
                         char *err);

#ifdef __cplusplus
}
#endif

#endif /* PSTENCIL_PUBLIC_NORMALS_H */
