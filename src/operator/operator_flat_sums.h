/* The sums of the flatness check (src/operator/operator_flat_sums.c, compiled once per ISA
 * level): pst_op_check_flat_rows (operator_flat.c) calls the copy of the CPU's level
 * (src/core/isa.h, PST_LEVEL_ENTRY). Internal. */
#ifndef PSTENCIL_OPERATOR_FLAT_SUMS_H
#define PSTENCIL_OPERATOR_FLAT_SUMS_H

#include "isa.h"
#include "operator.h"

#define PST_FLAT_SUMS 10 /* 1, x (3), x x^T (6, packed upper triangle) */

/* The sums over row i's live neighbours of 1, x and x x^T into s (s[0]; s[1..4): x, y, z;
 * s[4..10): xx, xy, xz, yy, yz, zz), the offsets x = (x_J - x_I) / h_I; in 2D the z entries
 * are 0. A pair is live when it is farther than min_pair_distance h_I and within the kernel
 * support of the larger smoothing length, so that the check never sees fewer neighbours than
 * a scheme does. */
PST_LEVEL_ENTRY_VOID(pst_flat_sums, (const pst_op *op, size_t i, double s[PST_FLAT_SUMS]),
                     (op, i, s))

#endif /* PSTENCIL_OPERATOR_FLAT_SUMS_H */
