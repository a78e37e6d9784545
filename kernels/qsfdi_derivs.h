/* QSFDI's one-off derivatives (kernels/qsfdi_derivs.c, compiled once per ISA level): the
 * scheme's gradient and hessian hooks (operator.h), each calling the copy of the CPU's level
 * (src/core/isa.h, PST_LEVEL_ENTRY). Internal. */
#ifndef PSTENCIL_QSFDI_DERIVS_H
#define PSTENCIL_QSFDI_DERIVS_H

#include "isa.h"
#include "operator.h"

/* The gradient of u at every particle into grad[0..D), u read from op->xyzu. */
PST_LEVEL_ENTRY_VOID(pst_qsfdi_gradient,
                     (const pst_op *op, const double *u, double *const grad[3]),
                     (op, u, grad))

/* The Hessian of u at every particle into hess (xx yy [zz] xy [xz yz]), u read from
 * op->xyzu. */
PST_LEVEL_ENTRY_VOID(pst_qsfdi_hessian, (const pst_op *op, const double *u, double *const hess[6]),
                     (op, u, hess))

#endif /* PSTENCIL_QSFDI_DERIVS_H */
