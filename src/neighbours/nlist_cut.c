/* A neighbour list cut to a fraction of its radius (nlist_layout.h): the sparse stencil of the
 * AMG proxy (docs/solving.md, "The AMG matrix"). Two passes over the rows, count then fill,
 * each row written by one thread at offsets fixed by the count: identical for every thread
 * count. Bound by the pair distances (a few flops per pair) over one read of the list. */
#include "check.h"
#include "cloud_layout.h"
#include "nlist_layout.h"

#include <math.h>
#include <stdlib.h>

/* The cut rule of pair (i, j): d_ij < cut * support * (h_i + h_j) / 2, written with squares. */
static int within(const pst_cloud *c, double reach, size_t i, size_t j)
{
    double d2 = 0;
    for (int d = 0; d < c->dim; ++d) {
        double t = c->x[d][j] - c->x[d][i];
        d2 += t * t;
    }
    double r = reach * 0.5 * (pst_cloud_h_at(c, i) + pst_cloud_h_at(c, j));
    return d2 < r * r;
}

/* Row i's pairs within the cut, written to out when it is not NULL; a row with none keeps all
 * of its pairs (the fallback, *fallback = 1). Returns the row's length. */
static int64_t cut_row(const pst_cloud *c, const pst_nlist *nl, double reach, size_t i,
                       uint32_t *out, int *fallback)
{
    *fallback = 0;
    int64_t lo = nl->offset[i], hi = nl->offset[i + 1], k = 0;
    for (int64_t q = lo; q < hi; ++q)
        if (within(c, reach, i, nl->index[q])) {
            if (out)
                out[k] = nl->index[q];
            k++;
        }
    if (k > 0 || hi == lo)
        return k;
    *fallback = 1;
    for (int64_t q = lo; out && q < hi; ++q)
        out[q - lo] = nl->index[q];
    return hi - lo;
}

int pst_nlist_cut(pst_nlist **out, const pst_cloud *c, const pst_nlist *nl, double cut,
                  size_t *full_rows, char *err)
{
    *out = NULL;
    *full_rows = 0;
    PST_CHECK(!(cut > 0 && cut <= 1), PST_EINVAL, err,
              "the cut of a neighbour list must lie in (0, 1] (got %g)", cut);
    PST_CHECK(nl->n != c->n, PST_EINVAL, err,
              "the neighbour list has %zu rows, the cloud %zu particles", nl->n, c->n);
    const size_t n = nl->n;
    const double reach = cut * nl->support;
    pst_nlist *cl = calloc(1, sizeof *cl);
    if (cl)
        cl->offset = pst_alloc((n + 1) * sizeof *cl->offset);
    int st = PST_OK;
    PST_CHECK_GOTO(!cl || !cl->offset, st, PST_ENOMEM, fail, err,
                   "cannot allocate a cut neighbour list of %zu rows", n);
    cl->n = n;
    cl->support = nl->support;
    cl->cut = cut * nl->cut;
    size_t full = 0;
#pragma omp parallel for schedule(static) reduction(+ : full)
    for (size_t i = 0; i < n; ++i) {
        int fallback;
        cl->offset[i + 1] = cut_row(c, nl, reach, i, NULL, &fallback);
        full += (size_t)fallback;
    }
    cl->offset[0] = 0;
    for (size_t i = 0; i < n; ++i)
        cl->offset[i + 1] += cl->offset[i];
    cl->index = pst_alloc(((size_t)cl->offset[n] + 1) * sizeof *cl->index);
    PST_CHECK_GOTO(!cl->index, st, PST_ENOMEM, fail, err,
                   "cannot allocate a cut neighbour list of %lld pairs", (long long)cl->offset[n]);
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; ++i) {
        int fallback;
        cut_row(c, nl, reach, i, cl->index + cl->offset[i], &fallback);
    }
    *full_rows = full;
    *out = cl;
    return PST_OK;

fail:
    pst_nlist_destroy(cl);
    return st;
}
