/* The layout behind the opaque pst_nlist handle, and the neighbours of arbitrary points. Private
 * to the library (seen through internal.h). */
#ifndef PSTENCIL_NLIST_LAYOUT_H
#define PSTENCIL_NLIST_LAYOUT_H

#include "pstencil.h"

struct pst_nlist {
    size_t n;
    double support;      /* radius in units of h the list was built with */
    double cut;          /* fraction of that radius the pairs lie within: 1 for a built list,
                            < 1 for a cut one (pst_nlist_cut)                               */
    int half;            /* 1: row i holds only its neighbours j > i (pst_nlist_halve)      */
    int from_csr;        /* 1: the pairs are the caller's (pst_nlist_from_csr), which only
                            pst_nlist_set_csr replaces; pst_nlist_update refuses the list    */
    int64_t *offset;     /* n + 1 */
    uint32_t *index;     /* offset[n] */
    struct pst_verlet *verlet; /* the skin list and the state pst_nlist_update reads, or NULL
                                  (nlist_update.c)                                         */
};

/* A list's Verlet state (nlist_update.c): freed, and the bytes it holds (the wide list, the
 * kept positions, the list's index at its capacity) for a cloud of n particles. */
void pst_verlet_free(struct pst_verlet *v);
size_t pst_verlet_bytes(const struct pst_verlet *v, size_t n);

/* The checks of a build on the cloud c at radius support (units of h): finite positions, h in
 * range, a representable radius. PST_EINVAL, PST_EINPUT (message in err, particle by id). */
int pst_nlist_check_cloud(const pst_cloud *c, double support, char *err);

/* The points a search of radius `radius` around them accepts (points.c, for interpolation):
 * finite coordinates pts[d][k] (d < dim, k < m); along a periodic axis of c, inside the box and
 * a radius below half the period. PST_EINPUT (message in err, the point by index). */
int pst_points_check(const pst_cloud *c, const double *const pts[3], size_t m, double radius,
                     char *err);

/* Neighbours of arbitrary points (points.c, for interpolation): for each of the m points
 * (pts[d][k], d < dim) the particles of c with |x - p| < radius, as CSR: off (m + 1 entries)
 * and idx, each row increasing; the points as pst_points_check accepts them (PST_EINPUT). Free
 * both with pst_free. PST_ENOMEM (message in err). */
int pst_points_neighbours(const pst_cloud *c, const double *const pts[3], size_t m,
                          double radius, int64_t **off, uint32_t **idx, char *err);

/* The pairs of nl (a list of cloud c, whole or half) that lie within a fraction of their radius:
 * d_ij < cut * support * (h_i + h_j) / 2, a symmetric rule, so the cut list is symmetric. A row
 * left with no pair keeps all of nl's (a documented fallback: an operator row with no neighbour
 * would have a zero diagonal); *full_rows counts them. The cut list keeps nl's support (an
 * operator built on it sees the kernel cut at that radius) and records the cut. 0 < cut <= 1.
 * The cut list is always whole: from a half list it is the one the whole list would give, entry
 * for entry (so cut = 1 restores the whole list). PST_EINVAL, PST_ENOMEM (message in err).
 * Identical for every thread count. */
int pst_nlist_cut(pst_nlist **out, const pst_cloud *c, const pst_nlist *nl, double cut,
                  size_t *full_rows, char *err);

/* nl takes fresh's pairs (its offsets and index, which it frees first) and fresh is destroyed:
 * a list rebuilt or replaced behind the handle operators hold. */
void pst_nlist_adopt(pst_nlist *nl, pst_nlist *fresh);

#endif
