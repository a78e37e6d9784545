/* The discrete maximum principle of an operator (LV §4.5, Definition 7; docs/stability.md):
 * solve L u = 0 on the interior rows, with the Dirichlet particles holding data g and the
 * Neumann rows the flux of g (0 for the step, n_x for g = x), by dense LU, and count the
 * unknowns outside the boundary range of g. */
#ifndef PSTENCIL_ANALYSE_DMP_H
#define PSTENCIL_ANALYSE_DMP_H

#include "pstencil.h"

#include <stddef.h>

typedef struct {
    double gmin, gmax;   /* the boundary range [min g, max g] over the Dirichlet particles
                            (and the Neumann ones for the linear data, whose flux is not 0)  */
    size_t violations;   /* unknowns below gmin or above gmax by more than 1e-12 * range     */
    double overshoot;    /* the largest excursion outside [gmin, gmax] / range (0: none); the
                            absolute excursion when the range is 0                          */
    double max_err;      /* linear data: max |u - x| over the unknowns; -1 for the step       */
} pst_dmp_case;

typedef struct {
    int applicable;      /* 0: no Dirichlet particles (or no unknowns): nothing solved         */
    int singular;        /* 1: the unknowns' block is singular: no solution, see why           */
    char why[160];       /* the singular finding ("LAPACKE_dgesv: U(3,3) is exactly zero")    */
    size_t unknowns, dirichlet;
    double xmid;         /* the x midpoint of the cloud's bounding box                         */
    pst_dmp_case step;   /* g = 1 where x > xmid, else 0                                       */
    pst_dmp_case linear; /* g = x                                                              */
} pst_dmp;

/* Solve both data sets for the assembled operator a of cloud c (pst_op_assemble, cloud
 * order) with one LAPACKE_dgesv (dense: 8 m^2 bytes for m unknowns). A singular block
 * (dgesv info > 0, or a non-finite solution) is a finding in d, not an error. Errors:
 * PST_ENOMEM, PST_EINVAL (a does not match c), with the reason in err. */
int pst_dmp_check(const pst_cloud *c, const pst_csr *a, pst_dmp *d, char *err, size_t errlen);

#endif
