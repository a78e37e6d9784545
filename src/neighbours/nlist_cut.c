/* A neighbour list cut to a fraction of its radius (nlist_layout.h): the sparse stencil of the
 * AMG proxy (docs/solving.md, "The AMG matrix"). From a whole list: two passes over the rows,
 * count then fill, each row written by one thread at offsets fixed by the count. From a half
 * list (cut_half): the cut's upper pairs the same way, then their transpose in one serial pass
 * in increasing row order, so that every row comes out as the whole list's cut would give it.
 * Identical for every thread count. Bound by the pair distances (a few flops per pair) over one
 * read of the list. */
#include "check.h"
#include "cloud_layout.h"
#include "nlist_layout.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The cut rule of pair (i, j): d_ij < cut * support * (h_i + h_j) / 2, written with squares
 * (d_ij through the periodic faces as the list's). */
static int within(const pst_cloud *c, double reach, size_t i, size_t j)
{
    double d2 = 0;
    for (int d = 0; d < c->dim; ++d) {
        double P = c->periodic[d] ? c->box_hi[d] - c->box_lo[d] : 0; /* minimum image */
        double t = pst_min_image(c->x[d][j] - c->x[d][i], P, P > 0 ? 0.5 * P : INFINITY);
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

/* An empty cut list of n rows with nl's support and the combined cut (offsets allocated). */
static pst_nlist *new_cut_list(const pst_nlist *nl, double cut)
{
    pst_nlist *cl = calloc(1, sizeof *cl);
    if (!cl)
        return NULL;
    cl->offset = pst_calloc(nl->n + 1, sizeof *cl->offset);
    if (!cl->offset) {
        free(cl);
        return NULL;
    }
    cl->n = nl->n;
    cl->support = nl->support;
    cl->cut = cut * nl->cut;
    cl->from_csr = nl->from_csr; /* still the caller's pairs, not the rule's */
    return cl;
}

static int cut_whole(pst_nlist *cl, const pst_cloud *c, const pst_nlist *nl, double reach,
                     size_t *full_rows, char *err)
{
    const size_t n = nl->n;
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
    PST_CHECK(!cl->index, PST_ENOMEM, err, "cannot allocate a cut neighbour list of %lld pairs",
              (long long)cl->offset[n]);
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; ++i) {
        int fallback;
        cut_row(c, nl, reach, i, cl->index + cl->offset[i], &fallback);
    }
    *full_rows = full;
    return PST_OK;
}

/* ---- from a half list ---------------------------------------------------------------------- */

/* The upper pairs of half row i within the cut, written to out unless it is NULL. Returns
 * their number. */
static int64_t cut_upper(const pst_cloud *c, const pst_nlist *hl, double reach, size_t i,
                         uint32_t *out)
{
    int64_t k = 0;
    for (int64_t q = hl->offset[i]; q < hl->offset[i + 1]; ++q)
        if (within(c, reach, i, hl->index[q])) {
            if (out)
                out[k] = hl->index[q];
            k++;
        }
    return k;
}

/* Rows with no pair in the cut but a non-empty whole row (the fallback): fb[i] = 1, their whole
 * lower counts in low[] (0 before: no cut pair points at them). One serial pass over the half
 * list, made only when such a row may exist. Returns their number. */
static size_t mark_fallback_rows(const pst_nlist *hl, const int64_t *up, uint32_t *low,
                                 uint8_t *fb)
{
    const size_t n = hl->n;
    size_t empty = 0;
    for (size_t i = 0; i < n; ++i) {
        fb[i] = up[i + 1] == up[i] && low[i] == 0;
        empty += fb[i];
    }
    if (empty == 0)
        return 0;
    for (size_t i = 0; i < n; ++i)
        for (int64_t q = hl->offset[i]; q < hl->offset[i + 1]; ++q)
            low[hl->index[q]] += fb[hl->index[q]];
    size_t full = 0;
    for (size_t i = 0; i < n; ++i) {
        fb[i] = fb[i] && (low[i] > 0 || hl->offset[i + 1] > hl->offset[i]);
        full += fb[i];
    }
    return full;
}

/* The lower parts of the rows, in increasing order of the lower neighbour: from the cut's
 * upper pairs U, and for the fallback rows from the whole half list. low[] becomes the count
 * written so far (the upper parts follow it). Serial: a few scattered writes per pair of the
 * cut. */
static void fill_lower(pst_nlist *cl, const pst_nlist *hl, const int64_t *up, const uint32_t *U,
                       uint32_t *low, const uint8_t *fb, size_t full)
{
    const size_t n = hl->n;
    memset(low, 0, n * sizeof *low);
    for (size_t i = 0; i < n; ++i)
        for (int64_t q = up[i]; q < up[i + 1]; ++q)
            cl->index[cl->offset[U[q]] + low[U[q]]++] = (uint32_t)i;
    for (size_t i = 0; full && i < n; ++i)
        for (int64_t q = hl->offset[i]; q < hl->offset[i + 1]; ++q)
            if (fb[hl->index[q]])
                cl->index[cl->offset[hl->index[q]] + low[hl->index[q]]++] = (uint32_t)i;
}

/* The whole list's cut of the half list hl into cl (n rows, offsets zero), reach = cut * support. */
static int cut_half(pst_nlist *cl, const pst_cloud *c, const pst_nlist *hl, double reach,
                    size_t *full_rows, char *err)
{
    const size_t n = hl->n;
    int64_t *up = pst_calloc(n + 1, sizeof *up);
    uint32_t *low = pst_calloc(n + 1, sizeof *low), *U = NULL;
    uint8_t *fb = pst_alloc(n + 1);
    int st = PST_OK;
    PST_CHECK_GOTO(!up || !low || !fb, st, PST_ENOMEM, done, err,
                   "cannot allocate the cut of a half list of %zu rows", n);
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; ++i)
        up[i + 1] = cut_upper(c, hl, reach, i, NULL);
    for (size_t i = 0; i < n; ++i)
        up[i + 1] += up[i];
    U = pst_alloc(((size_t)up[n] + 1) * sizeof *U);
    PST_CHECK_GOTO(!U, st, PST_ENOMEM, done, err, "cannot allocate the cut of a half list");
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; ++i)
        cut_upper(c, hl, reach, i, U + up[i]);
    for (int64_t q = 0; q < up[n]; ++q)
        low[U[q]]++;
    size_t full = mark_fallback_rows(hl, up, low, fb);
    for (size_t i = 0; i < n; ++i)
        cl->offset[i + 1] = cl->offset[i] + low[i] +
                            (fb[i] ? hl->offset[i + 1] - hl->offset[i] : up[i + 1] - up[i]);
    cl->index = pst_alloc(((size_t)cl->offset[n] + 1) * sizeof *cl->index);
    PST_CHECK_GOTO(!cl->index, st, PST_ENOMEM, done, err,
                   "cannot allocate a cut neighbour list of %lld pairs", (long long)cl->offset[n]);
    fill_lower(cl, hl, up, U, low, fb, full);
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; ++i) {
        const uint32_t *from = fb[i] ? hl->index + hl->offset[i] : U + up[i];
        int64_t len = fb[i] ? hl->offset[i + 1] - hl->offset[i] : up[i + 1] - up[i];
        memcpy(cl->index + cl->offset[i] + low[i], from, (size_t)len * sizeof *from);
    }
    *full_rows = full;

done:
    pst_free(up);
    pst_free(low);
    pst_free(U);
    pst_free(fb);
    return st;
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
    pst_nlist *cl = new_cut_list(nl, cut);
    PST_CHECK_ALLOC(cl, err, "cannot allocate a cut neighbour list of %zu rows", nl->n);
    const double reach = cut * nl->support;
    int st = nl->half ? cut_half(cl, c, nl, reach, full_rows, err)
                      : cut_whole(cl, c, nl, reach, full_rows, err);
    if (st != PST_OK) {
        pst_nlist_destroy(cl);
        return st;
    }
    *out = cl;
    return PST_OK;
}
