/* The upper half of a neighbour list (pst_nlist_halve, docs/neighbours.md): row i keeps its
 * neighbours j > i, so each pair is stored once, for the matrix-free apply of the largest
 * clouds (src/operator/operator_half.c). Rows are increasing, so the kept part of a row is its
 * tail after the first j > i. Count, scan, copy: bound by one read of the list and one write
 * of half of it. */
#include "check.h"
#include "nlist_layout.h"

#include <stdlib.h>
#include <string.h>

/* The first entry of row i above i (a binary search: the row is increasing). */
static int64_t upper_start(const pst_nlist *nl, size_t i)
{
    int64_t lo = nl->offset[i], hi = nl->offset[i + 1];
    while (lo < hi) {
        int64_t mid = lo + (hi - lo) / 2;
        if (nl->index[mid] > i)
            hi = mid;
        else
            lo = mid + 1;
    }
    return lo;
}

int pst_nlist_halve(pst_nlist **out, const pst_nlist *nl, char *err)
{
    *out = NULL;
    PST_CHECK(nl->half, PST_EINVAL, err, "the neighbour list is already a half list");
    const size_t n = nl->n;
    pst_nlist *hl = calloc(1, sizeof *hl);
    if (hl)
        hl->offset = pst_alloc((n + 1) * sizeof *hl->offset);
    int st = PST_OK;
    PST_CHECK_GOTO(!hl || !hl->offset, st, PST_ENOMEM, fail, err,
                   "cannot allocate a half neighbour list of %zu rows", n);
    hl->n = n;
    hl->support = nl->support;
    hl->cut = nl->cut;
    hl->half = 1;
    hl->offset[0] = 0;
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; ++i)
        hl->offset[i + 1] = nl->offset[i + 1] - upper_start(nl, i);
    for (size_t i = 0; i < n; ++i)
        hl->offset[i + 1] += hl->offset[i];
    hl->index = pst_alloc(((size_t)hl->offset[n] + 1) * sizeof *hl->index);
    PST_CHECK_GOTO(!hl->index, st, PST_ENOMEM, fail, err,
                   "cannot allocate a half neighbour list of %lld pairs",
                   (long long)hl->offset[n]);
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; ++i)
        memcpy(hl->index + hl->offset[i], nl->index + upper_start(nl, i),
               (size_t)(hl->offset[i + 1] - hl->offset[i]) * sizeof *hl->index);
    *out = hl;
    return PST_OK;

fail:
    pst_nlist_destroy(hl);
    return st;
}

int pst_nlist_is_half(const pst_nlist *nl) { return nl->half; }
