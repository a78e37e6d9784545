/* QSFDI's matrix-free rows in lanes (kernels/qsfdi_lanes.c, compiled once per ISA level):
 * the scheme's apply and half_rows hooks (operator.h), each calling the copy of the CPU's
 * level (src/core/isa.h, PST_LEVEL_ENTRY). Internal. */
#ifndef PSTENCIL_QSFDI_LANES_H
#define PSTENCIL_QSFDI_LANES_H

#include "isa.h"
#include "operator.h"

/* The matrix-free apply y = A u, u read from op->xyzu (pst_op_apply packs it). */
PST_LEVEL_ENTRY_VOID(pst_qs_apply, (const pst_op *op, const double *u, double *y),
                     (op, u, y))

/* Rows [i0, i1) of the half list (off, idx) added into y (operator.h, half_rows). */
PST_LEVEL_ENTRY_VOID(pst_qs_half_rows,
                     (const pst_op *op, const int64_t *off, const uint32_t *idx, size_t i0,
                      size_t i1, const double *u, double *y),
                     (op, off, idx, i0, i1, u, y))

#endif /* PSTENCIL_QSFDI_LANES_H */
