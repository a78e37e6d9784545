/* The CSPM family's matrix-free rows in lanes (kernels/cspm_lanes.c, compiled once per ISA
 * level): the schemes' apply hook (operator.h), calling the copy of the CPU's level
 * (src/core/isa.h, PST_LEVEL_ENTRY). Internal. */
#ifndef PSTENCIL_CSPM_LANES_H
#define PSTENCIL_CSPM_LANES_H

#include "isa.h"
#include "operator.h"

/* The matrix-free apply y = A u, u read from op->xyzu (pst_op_apply packs it). */
PST_LEVEL_ENTRY_VOID(pst_cs_apply, (const pst_op *op, const double *u, double *y), (op, u, y))

#endif /* PSTENCIL_CSPM_LANES_H */
