/* The layout behind the opaque pst_nlist handle, and the neighbours of arbitrary points. Private
 * to the library (seen through internal.h). */
#ifndef PSTENCIL_NLIST_LAYOUT_H
#define PSTENCIL_NLIST_LAYOUT_H

#include "pstencil.h"

struct pst_nlist {
    size_t n;
    double support;      /* radius in units of h the list was built with */
    int64_t *offset;     /* n + 1 */
    uint32_t *index;     /* offset[n] */
};

/* Neighbours of arbitrary points (points.c, for interpolation): for each of the m points
 * (pts[d][k], d < dim) the particles of c with |x - p| < radius, as CSR: off (m + 1 entries)
 * and idx, each row increasing. Free both with pst_free. PST_ENOMEM (message in err). */
int pst_points_neighbours(const pst_cloud *c, const double *const pts[3], size_t m,
                          double radius, int64_t **off, uint32_t **idx, char *err);

#endif
