/* The neighbour rule of choice 1 (docs/choices.md) as one inline test, shared by the list's
 * build (nlist.c) and its Verlet update (nlist_update.c) so that both decide every pair bit for
 * bit alike. Private to src/neighbours. */
#ifndef PSTENCIL_NLIST_RULE_H
#define PSTENCIL_NLIST_RULE_H

#include "cloud_layout.h"

#include <stddef.h>
#include <stdint.h>
#include <string.h>

/* d2 < r2 as the sign bit of d2 - r2: equal for non-NaN d2 and finite r2 (the difference of
 * two distinct doubles is never 0 and rounding keeps its sign; d2 = r2 gives +0). Unlike the
 * compare, it vectorises into an integer count on baseline x86-64 (SSE2) and needs no
 * unordered-compare fix-up in the scalar compaction. */
static inline size_t closer(double d2, double r2)
{
    double diff = d2 - r2;
    uint64_t bits;
    memcpy(&bits, &diff, sizeof bits);
    return (size_t)(bits >> 63);
}

/* The neighbour test of slot q against the particle at xi with smoothing length hi (choice 1,
 * docs/choices.md): the build's count and fill passes and the Verlet filter agree bit for
 * bit. per: the offsets are minimum images in the box `im` (a constant in the instantiations:
 * a cloud that is not periodic runs the loop it ran before). */
static inline __attribute__((always_inline)) size_t
pair_hit(const double *restrict X, const double *restrict Y, const double *restrict Z,
         const double *restrict H, const double xi[3], double hi, double halfs, double r2u,
         int dim, int varh, int per, const pst_image *im, size_t q)
{
    double dx = X[q] - xi[0], dy = Y[q] - xi[1];
    if (per) {
        dx = pst_min_image(dx, im->P[0], im->hP[0]);
        dy = pst_min_image(dy, im->P[1], im->hP[1]);
    }
    double d2 = dx * dx + dy * dy;
    if (dim == 3) {
        double dz = Z[q] - xi[2];
        if (per)
            dz = pst_min_image(dz, im->P[2], im->hP[2]);
        d2 += dz * dz;
    }
    double r2 = r2u;
    if (varh) {
        double r = halfs * (hi + H[q]);
        r2 = r * r;
    }
    return closer(d2, r2);
}

#endif
