/* The layout behind the opaque pst_cloud handle and the cloud helpers the library's other layers
 * use. Private to the library (seen through internal.h). */
#ifndef PSTENCIL_CLOUD_LAYOUT_H
#define PSTENCIL_CLOUD_LAYOUT_H

#include "pstencil.h"

struct pst_cloud {
    int dim;
    size_t n;
    double *x[3];        /* positions, x[d] for d < dim; NULL above                         */
    double *V;           /* volumes                                                          */
    double h_uniform;    /* > 0 when h is uniform; then h == NULL                            */
    double *h;           /* per-particle smoothing length, or NULL                           */
    uint8_t *kind;       /* pst_kind                                                         */
    double *normal[3];   /* outward normals, normal[d] for d < dim                           */
    int mob_ncomp;       /* 0 (m = 1), 1 (scalar) or dim (diagonal tensor)                   */
    double *mob[3];      /* mobility components                                              */
    int64_t *id;         /* original input index                                             */
    size_t nfields;
    char (*field_name)[PST_MAX_NAME];
    double **field;
};

/* Find two particles at the same coordinates: returns 1 with their indices a < b (the first
 * such pair in lexicographic position order), 0 when all positions differ, PST_ENOMEM. */
int pst_cloud_find_duplicate(const pst_cloud *c, size_t *a, size_t *b);

/* The whole-cloud checks of pst_cloud_validate that the readers' per-value checks cannot make:
 * a finite extent along every axis, a non-zero normal on every Neumann particle. PST_EINPUT
 * with the axis or the particle (by id) in err. */
int pst_cloud_check_extent_normals(const pst_cloud *c, char *err);

/* h of particle i whatever the layout. */
static inline double pst_cloud_h_at(const pst_cloud *c, size_t i)
{
    return c->h ? c->h[i] : c->h_uniform;
}

#endif
