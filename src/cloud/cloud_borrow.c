/* Borrowed clouds (docs/embedding.md, "The host code's own data"): a cloud that reads a host
 * code's own structure-of-arrays particle data in place. The borrowed pointers go straight
 * into the layout, so every kernel reads them as it reads a cloud's own arrays; the
 * PST_BORROW_* bits record which arrays are the caller's, for destroy and the setters (never
 * freed) and for permute (refused: reordering would reorder the caller's data under it). */
#include "check.h"
#include "cloud_layout.h"

#include <math.h>
#include <stdlib.h>

/* The argument checks of pst_cloud_borrow. */
static int check_arrays(int dim, size_t n, const pst_cloud_arrays *a, char *err)
{
    PST_CHECK(dim != 2 && dim != 3, PST_EINVAL, err, "borrowed cloud: dim must be 2 or 3 (got %d)",
              dim);
    PST_CHECK(n > (size_t)UINT32_MAX, PST_EINVAL, err, /* neighbour indices are 32-bit */
              "borrowed cloud: %zu particles exceed the 32-bit index limit", n);
    PST_CHECK(!a, PST_EINVAL, err, "borrowed cloud: the arrays must not be NULL");
    int normals = 0;
    for (int d = 0; d < dim; ++d) {
        PST_CHECK(!a->x[d], PST_EINVAL, err, "borrowed cloud: positions along %c are NULL",
                  "xyz"[d]);
        normals += a->normal[d] != NULL;
    }
    PST_CHECK(!a->V, PST_EINVAL, err, "borrowed cloud: the volumes V are NULL");
    PST_CHECK(normals != 0 && normals != dim, PST_EINVAL, err,
              "borrowed cloud: normals given along %d of %d axes (all or none)", normals, dim);
    PST_CHECK(!a->h && (!(a->h_uniform > 0) || !isfinite(a->h_uniform)), PST_EINVAL, err,
              "borrowed cloud: without a per-particle h the uniform h must be finite and > 0 "
              "(got %g)",
              a->h_uniform);
    PST_CHECK(a->mob_ncomp != 0 && a->mob_ncomp != 1 && a->mob_ncomp != dim, PST_EINVAL, err,
              "borrowed cloud: mobility has 0, 1 or %d components (got %d)", dim, a->mob_ncomp);
    for (int k = 0; k < a->mob_ncomp; ++k)
        PST_CHECK(!a->mob[k], PST_EINVAL, err, "borrowed cloud: mobility component %d is NULL",
                  k);
    return PST_OK;
}

int pst_cloud_borrow(pst_cloud **out, int dim, size_t n, const pst_cloud_arrays *a, char *err)
{
    *out = NULL;
    PST_TRY(check_arrays(dim, n, a, err));
    pst_cloud *c = calloc(1, sizeof *c);
    PST_CHECK_ALLOC(c, err, "borrowed cloud: out of memory");
    c->dim = dim;
    c->n = n;
    c->borrowed = PST_BORROW_X | PST_BORROW_V;
    for (int d = 0; d < dim; ++d)
        c->x[d] = a->x[d];
    c->V = a->V;
    c->h = a->h;
    c->h_uniform = a->h ? 0 : a->h_uniform;
    c->borrowed |= a->h ? PST_BORROW_H : 0;
    c->kind = a->kind;
    c->borrowed |= a->kind ? PST_BORROW_KIND : 0;
    if (a->normal[0]) {
        for (int d = 0; d < dim; ++d)
            c->normal[d] = a->normal[d];
        c->borrowed |= PST_BORROW_NORMAL;
    }
    c->mob_ncomp = a->mob_ncomp;
    for (int k = 0; k < a->mob_ncomp; ++k)
        c->mob[k] = a->mob[k];
    c->borrowed |= a->mob_ncomp ? PST_BORROW_MOB : 0;
    if (pst_cloud_alloc_missing(c) != PST_OK) {
        pst_cloud_destroy(c);
        pst_set_err(err, "borrowed cloud: out of memory for the arrays of %zu particles", n);
        return PST_ENOMEM;
    }
    *out = c;
    return PST_OK;
}

int pst_cloud_is_borrowed(const pst_cloud *c) { return c->borrowed != 0; }

int pst_cloud_check_owned(const pst_cloud *c, const char *what, char *err)
{
    PST_CHECK(c->borrowed, PST_EINVAL, err,
              "%s: the cloud borrows the caller's arrays (pst_cloud_borrow) and is never "
              "reordered; its results are in the caller's order",
              what);
    return PST_OK;
}
