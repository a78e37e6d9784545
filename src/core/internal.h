/* Internal definitions shared by the library's translation units: the layouts behind the
 * opaque handles, aligned allocation and error-message helpers. Not installed. */
#ifndef PSTENCIL_INTERNAL_H
#define PSTENCIL_INTERNAL_H

#include "pstencil.h"

#include <stdarg.h>
#include <stdio.h>

/* Every hot array is 64-byte aligned (one cache line, one AVX-512 vector). */
#define PST_ALIGN 64

/* Allocate `bytes` (rounded up to PST_ALIGN) aligned to PST_ALIGN; NULL on failure or when the
 * size overflows. Free with pst_free. A zero-byte request returns a valid, freeable pointer. */
void *pst_alloc(size_t bytes);
/* Same, zero-filled. */
void *pst_calloc(size_t count, size_t size);
void pst_free(void *p);

/* Write a formatted message into an error buffer of PST_ERRLEN bytes (NULL is ignored). */
void pst_set_err(char *err, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

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

struct pst_nlist {
    size_t n;
    double support;      /* radius in units of h the list was built with */
    int64_t *offset;     /* n + 1 */
    uint32_t *index;     /* offset[n] */
};

/* Find two particles at the same coordinates: returns 1 with their indices a < b (the first
 * such pair in lexicographic position order), 0 when all positions differ, PST_ENOMEM. */
int pst_cloud_find_duplicate(const pst_cloud *c, size_t *a, size_t *b);

/* h of particle i whatever the layout. */
static inline double pst_cloud_h_at(const pst_cloud *c, size_t i)
{
    return c->h ? c->h[i] : c->h_uniform;
}

/* Neighbours of arbitrary points (src/points.c, for interpolation): for each of the m points
 * (pts[d][k], d < dim) the particles of c with |x - p| < radius, as CSR: off (m + 1 entries)
 * and idx, each row increasing. Free both with pst_free. PST_ENOMEM (message in err). */
int pst_points_neighbours(const pst_cloud *c, const double *const pts[3], size_t m,
                          double radius, int64_t **off, uint32_t **idx, char *err);

#endif
