/* pstencil: Smoothing kernels. Part of the public API; include <pstencil.h>. */
#ifndef PSTENCIL_PUBLIC_KERNEL_H
#define PSTENCIL_PUBLIC_KERNEL_H

#include "pstencil/core.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------------------------------------------ */
/* Smoothing kernels                                                                          */
/* ------------------------------------------------------------------------------------------ */

/* PST_KERNEL_DEFAULT asks for a scheme's default kernel (pst_op_opts.kernel); PST_KERNEL_UNKNOWN
 * is what the lookups return for an unknown name. Both are -1, never a kernel. */
typedef enum {
    PST_KERNEL_DEFAULT = -1,
    PST_KERNEL_UNKNOWN = -1,
    PST_KERNEL_CUBIC = 0,       /* cubic B-spline, LV eq. 12, support 2h                     */
    PST_KERNEL_QUINTIC = 1,     /* quintic spline, QSFDI eq. 9, support 3h                   */
    PST_KERNEL_WENDLAND_C2 = 2, /* Wendland C2, support 2h                                   */
    PST_KERNEL_WENDLAND_C4 = 3  /* Wendland C4, support 2h                                   */
} pst_kernel;

/* Name ("cubic", "quintic", "wendland_c2", "wendland_c4") and lookup by name
 * (PST_KERNEL_UNKNOWN if unknown). */
const char *pst_kernel_name(pst_kernel k);
pst_kernel pst_kernel_from_name(const char *name);

/* Support radius in units of h (2 or 3). */
double pst_kernel_support(pst_kernel k);

/* Kernel value W(r, h), dW/dr and d2W/dr2 in `dim` = 1, 2 or 3 dimensions, normalised so that
 * the integral of W over R^dim is 1. All three are 0 at and beyond the support radius. */
double pst_kernel_w(pst_kernel k, int dim, double r, double h);
double pst_kernel_dw(pst_kernel k, int dim, double r, double h);
double pst_kernel_d2w(pst_kernel k, int dim, double r, double h);

#ifdef __cplusplus
}
#endif

#endif /* PSTENCIL_PUBLIC_KERNEL_H */
