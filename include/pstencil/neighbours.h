/* pstencil: Morton order and neighbour lists. Part of the public API; include <pstencil.h>. */
#ifndef PSTENCIL_PUBLIC_NEIGHBOURS_H
#define PSTENCIL_PUBLIC_NEIGHBOURS_H

#include "pstencil/cloud.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------------------------------------------ */
/* Morton order and neighbour lists                                                           */
/* ------------------------------------------------------------------------------------------ */

/* Sort the cloud along a Morton (Z-order) curve of cells of size `cell` (> 0): 64-bit keys,
 * 21 bits per axis in 3D and 32 in 2D (coarser cells are used when the box needs more), a
 * parallel LSD radix sort, and one permutation applied to every field. The ids keep the input
 * order (pst_cloud_to_input_order). PST_EINVAL for a bad cell and for a borrowed cloud
 * (pst_cloud_borrow), which is never reordered. */
int pst_cloud_morton_sort(pst_cloud *c, double cell, char *err);

/* Morton key of integer cell coordinates (3D: 21 bits per axis; 2D: 32 bits per axis, iz
 * ignored). */
uint64_t pst_morton_key(int dim, uint32_t ix, uint32_t iy, uint32_t iz);

typedef struct pst_nlist pst_nlist;

/* Build the CSR neighbour list of choice 1 (docs/choices.md): j is a neighbour of i iff j != i and
 * |x_j - x_i| < support * (h_i + h_j)/2 (strict), with `support` the kernel's support radius
 * in units of h (pst_kernel_support). Rows are sorted by neighbour index. Works on any order
 * of the cloud; a Morton-sorted cloud is faster. In a periodic cloud (pst_cloud_set_periodic)
 * x_j - x_i is the minimum image along the periodic axes: positions must lie in the box and
 * each period must exceed 2 support h_max, so that a pair has one image within reach
 * (PST_EINPUT otherwise, with the numbers in err). */
int pst_nlist_build(pst_nlist **out, const pst_cloud *c, double support, char *err);

/* pst_nlist_build with a progress hook (pstencil/core.h; NULL or a NULL fn: none). The work
 * is two passes over the particles, the count and the fill, so total = 2 n; the list is the
 * same, bit for bit, with or without the hook. */
int pst_nlist_build_with(pst_nlist **out, const pst_cloud *c, double support,
                         const pst_progress *progress, char *err);

void pst_nlist_destroy(pst_nlist *nl);

/* Rows: the neighbours of particle i are index[offset[i] .. offset[i+1]). */
size_t pst_nlist_rows(const pst_nlist *nl);
const int64_t *pst_nlist_offsets(const pst_nlist *nl);   /* rows + 1 entries */
const uint32_t *pst_nlist_indices(const pst_nlist *nl);
int64_t pst_nlist_pairs(const pst_nlist *nl);  /* total entries (each pair twice; once in a
                                                   half list)                                 */

/* The upper half of a list: row i keeps its neighbours j > i, in increasing order, so each
 * pair is stored once (8 bytes per row + 4 per pair instead of 8 per pair). It serves the
 * matrix-free apply of the largest clouds (pst_op_use_half_list) and the AMG proxy built from
 * it; operators cannot be created on it (their precompute reads whole rows). nl is unchanged;
 * destroy it when nothing else reads it. The same for every thread count. PST_EINVAL (nl is
 * already half), PST_ENOMEM (message in err). */
int pst_nlist_halve(pst_nlist **out, const pst_nlist *nl, char *err);

/* 1 when nl is a half list (pst_nlist_halve), else 0. */
int pst_nlist_is_half(const pst_nlist *nl);

/* The support (radius in units of h) the list was built with. */
double pst_nlist_support(const pst_nlist *nl);

/* ------------------------------------------------------------------------------------------ */
/* Lists from the host code (docs/neighbours.md, "Lists from the host code")                  */
/* ------------------------------------------------------------------------------------------ */

/* Optional checks of pst_nlist_from_csr and pst_nlist_set_csr (bits of `flags`). With both the
 * list is, entry for entry, the one pst_nlist_build would give. */
enum {
    PST_CSR_CHECK_RADIUS = 1,  /* every pair within support * (h_i + h_j) / 2, the build's rule
                                  (minimum images in a periodic box): O(pairs)              */
    PST_CSR_CHECK_COMPLETE = 2 /* every pair of that rule present: builds the library's list
                                  once to compare (its time and memory)                     */
};

/* A whole list of the cloud c (rows = pst_cloud_size(c)) from the caller's CSR: the neighbours
 * of particle i are index[offset[i] .. offset[i+1]); offset has n + 1 entries. The pairs are
 * copied: the caller's arrays may be freed or changed once this returns. `support` is the
 * radius in units of h the caller's list covers (pst_op_create needs it to cover the kernel's,
 * pst_kernel_support). Always checked, PST_EINPUT with the first offending row (and entry) in
 * err: offset[0] = 0, offsets non-decreasing, no row longer than n - 1, every index < n, no
 * self pair, every row strictly increasing (sorted, no repeats), and symmetry (j in row i <=>
 * i in row j), which the operators, pst_nlist_halve and the AMG proxy rely on. The cloud gets
 * the checks of a build (finite positions, h in range, periodic periods above twice the
 * radius). Without PST_CSR_CHECK_RADIUS a pair beyond the rule's radius is kept: with a
 * uniform h the kernels give it zero weight, but it still counts as a neighbour (row status
 * "too few") and as an entry of stored weights and assembled matrices; with per-particle h a
 * scheme weighing by h_I alone may weigh it (docs/neighbours.md). Without
 * PST_CSR_CHECK_COMPLETE a list that misses pairs of the rule silently gives another
 * discretisation. The list works with every
 * reader of lists (pst_op_create, the solves, pst_nlist_halve, pst_nlist_get_stats);
 * pst_nlist_update refuses it (the library cannot know the caller's rule): after the
 * particles move, pass the new pairs to pst_nlist_set_csr. index may be NULL when offset[n]
 * is 0. PST_EINVAL (a NULL argument, unknown flags, a bad support), PST_EINPUT, PST_ENOMEM. */
int pst_nlist_from_csr(pst_nlist **out, const pst_cloud *c, double support,
                       const int64_t *offset, const uint32_t *index, int flags, char *err);

/* Replace the pairs of nl, a list made by pst_nlist_from_csr, by the caller's new CSR for the
 * cloud c (same size), with the checks and the copy of pst_nlist_from_csr and nl's support:
 * the host code's step after its particles moved, before pst_op_refresh of the operators
 * built on nl. The handle stays valid; its offsets and indices move (read them again). On
 * failure nl is unchanged. PST_EINVAL (a list not from pst_nlist_from_csr, a half or cut list,
 * a cloud of another size), and the errors of pst_nlist_from_csr. */
int pst_nlist_set_csr(pst_nlist *nl, const pst_cloud *c, const int64_t *offset,
                      const uint32_t *index, int flags, char *err);

/* ------------------------------------------------------------------------------------------ */
/* Moving particles: Verlet lists (docs/neighbours.md, "Moving particles")                    */
/* ------------------------------------------------------------------------------------------ */

/* pst_nlist_build, and beside the list a wide one of radius (support + skin) * (h_i + h_j) / 2
 * with the positions and h it was built from, for pst_nlist_update. skin is in units of h, in
 * [0, support]; 0 gives a plain list, which every update builds again. The list itself is the
 * one pst_nlist_build gives, entry for entry. PST_EINVAL, PST_EINPUT, PST_ENOMEM. */
int pst_nlist_build_skin(pst_nlist **out, const pst_cloud *c, double support, double skin,
                         char *err);

/* What an update did. */
typedef struct {
    int rebuilt;              /* 1: the wide list was built again (or the whole list, skin 0) */
    double moved;             /* largest displacement since the wide list's build             */
    double grown;             /* largest growth of an h since then (0 if none grew)          */
    double budget;            /* the rebuild rule's bound on 2 moved + support * grown       */
    int64_t pairs;            /* entries of the updated list                                  */
    uint64_t rebuilds, filters; /* wide builds and filter passes so far (skin > 0)            */
} pst_nlist_update_info;

/* Bring nl up to date with the cloud c after its positions or h changed in place (the same
 * particles: c is the cloud nl was built on, or one of the same size and order). With a skin,
 * when 2 moved + support * grown <= skin * min h (h as at the wide build, less a rounding
 * allowance) the list is the wide list's pairs filtered by the true radius, an O(pairs) pass;
 * otherwise, or when the cloud was permuted (pst_cloud_permute, pst_cloud_morton_sort) or its
 * periodic box changed since, the wide list is built again. In a periodic box a displacement
 * is its minimum image, so particles folded back by pst_cloud_wrap count as moved by their
 * step. Either way the result is, entry for entry, the list
 * pst_nlist_build would give now, for every thread count. Without a skin: a fresh build. The
 * list's handle stays valid; its offsets and indices may move (read them again). Operators
 * built on nl must be refreshed (pst_op_refresh) before their next use. info may be NULL.
 * PST_EINVAL (a half or cut list, a list of the caller's pairs (pst_nlist_from_csr: use
 * pst_nlist_set_csr), a cloud of another size), PST_EINPUT (a non-finite position, h out of
 * range), PST_ENOMEM; on failure nl is unusable until an update succeeds. */
int pst_nlist_update(pst_nlist *nl, const pst_cloud *c, pst_nlist_update_info *info, char *err);

/* The skin a list keeps for its updates (0 for a plain list). */
double pst_nlist_skin(const pst_nlist *nl);

/* Statistics of a list. */
typedef struct {
    int64_t pairs;             /* stored entries                                  */
    int64_t min, max;          /* neighbours per particle                         */
    double mean;
    size_t isolated;           /* particles with no neighbour                     */
    size_t bytes;              /* memory held by the list                         */
} pst_nlist_stats;
void pst_nlist_get_stats(const pst_nlist *nl, pst_nlist_stats *s);

#ifdef __cplusplus
}
#endif

#endif /* PSTENCIL_PUBLIC_NEIGHBOURS_H */
