/* pstencil: Error norms. Part of the public API; include <pstencil.h>. */
#ifndef PSTENCIL_PUBLIC_NORMS_H
#define PSTENCIL_PUBLIC_NORMS_H

#include "pstencil/cloud.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------------------------------------------ */
/* Error norms                                                                                */
/* ------------------------------------------------------------------------------------------ */

/* The papers' error norms (docs/norms.md), e = approx - exact over the particles of a region:
 *   REL_L2              ||e||_2 / ||exact||_2                              QSFDI eqs. 14, 15
 *   QSFDI11             sqrt(sum V (e / exact)^2)      (as printed)         QSFDI eq. 11
 *   QSFDI11_NORMALISED  sqrt(sum V (e / exact)^2 / sum V)
 *   LV78                sqrt(sum V e^2 / sum V)        (absolute)           LV eq. 78
 *   LV95                sqrt(sum V (e / exact)^2 / sum V)                   LV eq. 95
 *   MAX_ABS             max |e|;   MAX_REL  max |e| / max |exact|
 * For vector values (ncomp > 1: gradients, Hessians) e and exact are Euclidean lengths per
 * particle. */
typedef enum {
    PST_NORM_UNKNOWN = -1, /* what pst_norm_from_name returns for an unknown name */
    PST_NORM_REL_L2 = 0,
    PST_NORM_QSFDI11,
    PST_NORM_QSFDI11_NORMALISED,
    PST_NORM_LV78,
    PST_NORM_LV95,
    PST_NORM_MAX_ABS,
    PST_NORM_MAX_REL,
    PST_NNORMS
} pst_norm;

/* The norm's name ("rel_l2", "qsfdi11", ...; NULL when out of range) and its inverse
 * (PST_NORM_UNKNOWN for an unknown name). */
const char *pst_norm_name(int norm);
pst_norm pst_norm_from_name(const char *name);

/* One norm of approx[a][i] - exact[a][i] (a < ncomp <= 6) over the particles with mask[i] != 0
 * (every particle when mask is NULL), in the cloud's order. Errors, with the reason in err:
 * PST_EINVAL (bad norm or ncomp, empty region), PST_ENUMERIC (a non-finite value; a
 * pointwise-relative norm where the exact value is 0; a relative norm whose exact values are all
 * 0). The result never is NaN. */
int pst_error_norm(const pst_cloud *c, int ncomp, const double *const *approx,
                   const double *const *exact, const uint8_t *mask, int norm, double *out,
                   char *err);
/* The same over n values at points that are not particles (unit volumes; no mask). */
int pst_error_norm_points(size_t n, int ncomp, const double *const *approx,
                          const double *const *exact, int norm, double *out, char *err);

#ifdef __cplusplus
}
#endif

#endif /* PSTENCIL_PUBLIC_NORMS_H */
