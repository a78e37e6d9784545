/* The layout behind the opaque pst_cloud handle and the cloud helpers the library's other layers
 * use. Private to the library (seen through internal.h). */
#ifndef PSTENCIL_CLOUD_LAYOUT_H
#define PSTENCIL_CLOUD_LAYOUT_H

#include "min_image.h"
#include "pstencil.h"

#include <math.h>

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
    uint64_t permutations; /* pst_cloud_permute calls so far: a list kept for an update
                              (pst_nlist_update) notices a reordered cloud                    */
    uint8_t periodic[3];   /* axis d is periodic (pst_cloud_set_periodic)                      */
    double box_lo[3], box_hi[3]; /* the periodic box along the periodic axes                 */
    size_t nfields;
    char (*field_name)[PST_MAX_NAME];
    double **field;
    unsigned borrowed;     /* PST_BORROW_* bits: the arrays the caller owns (pst_cloud_borrow),
                              which the cloud never frees and never reorders                 */
};

/* The arrays of a borrowed cloud that belong to the caller, one bit per group. */
enum {
    PST_BORROW_X = 1,      /* x[d], d < dim      */
    PST_BORROW_V = 2,
    PST_BORROW_H = 4,
    PST_BORROW_KIND = 8,
    PST_BORROW_NORMAL = 16, /* normal[d], d < dim */
    PST_BORROW_MOB = 32     /* mob[k], k < ncomp  */
};

/* Allocate every array of c that is still NULL (positions, normals, V, kinds, ids) at its
 * pst_cloud_create default; h and mobility stay as they are. PST_ENOMEM when an allocation
 * fails (what was allocated stays, for pst_cloud_destroy). */
int pst_cloud_alloc_missing(pst_cloud *c);

/* PST_EINVAL (message in err, starting with `what`) when c borrows the caller's arrays
 * (pst_cloud_borrow): such a cloud is never reordered. */
int pst_cloud_check_owned(const pst_cloud *c, const char *what, char *err);

/* Find two particles at the same coordinates: returns 1 with their indices a < b (the first
 * such pair in lexicographic position order), 0 when all positions differ, PST_ENOMEM. */
int pst_cloud_find_duplicate(const pst_cloud *c, size_t *a, size_t *b);

/* The first name of names[0..n) that an earlier one repeats: returns 1 with *again its index
 * and *first the earliest index with that name (*again the smallest such repeat, as a scan in
 * order would find), 0 when all differ, PST_ENOMEM. O(n log n). */
int pst_find_repeated_name(const char *const *names, size_t n, size_t *first, size_t *again);

/* pst_cloud_add_field for names[0..n) at once, data[k] (may be NULL) the k-th new array:
 * every name checked (PST_EINVAL for an invalid one or one that repeats an existing field or
 * an earlier name) before anything is added, then the arrays grown once. On PST_ENOMEM the
 * fields allocated so far stay in the cloud. */
int pst_cloud_add_fields(pst_cloud *c, const char *const *names, size_t n, double **data,
                         char *err);

/* The whole-cloud checks of pst_cloud_validate that the readers' per-value checks cannot make:
 * a finite extent along every axis, a non-zero normal on every Neumann particle. PST_EINPUT
 * with the axis or the particle (by id) in err. */
int pst_cloud_check_extent_normals(const pst_cloud *c, char *err);

/* The pair geometry of a periodic box (docs/periodic.md): per axis the period P and P/2, or
 * P = 0 and P/2 = infinity on an axis that is not periodic. any: some axis is periodic. */
typedef struct {
    double P[3], hP[3];
    int any;
} pst_image;

static inline pst_image pst_cloud_image(const pst_cloud *c)
{
    pst_image m = {.any = 0};
    for (int d = 0; d < 3; ++d) {
        int per = d < c->dim && c->periodic[d];
        m.P[d] = per ? c->box_hi[d] - c->box_lo[d] : 0.0;
        m.hP[d] = per ? 0.5 * m.P[d] : INFINITY;
        m.any |= per;
    }
    return m;
}

/* PST_EINPUT (the particle and the box in err) when a position along a periodic axis lies
 * outside [lo, hi). */
int pst_cloud_check_box(const pst_cloud *c, char *err);

/* h of particle i whatever the layout. */
static inline double pst_cloud_h_at(const pst_cloud *c, size_t i)
{
    return c->h ? c->h[i] : c->h_uniform;
}

#endif
