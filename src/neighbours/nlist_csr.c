/* Neighbour lists from the caller's CSR (docs/neighbours.md, "Lists from the host code"): a
 * host code that keeps its own lists hands them over instead of a build. The pairs are copied
 * into a list of the library's layout, so the caller's arrays may be freed or rewritten at
 * once and every reader (operators, halve, cut, stats) sees an ordinary list.
 *
 * Everything the readers assume is checked, because a malformed list would make them read out
 * of bounds or silently give another scheme: offsets that start at 0 and never decrease, rows
 * strictly increasing (sorted, no repeats) of indices < n other than the row's own, and
 * symmetry (j in row i <=> i in row j), which the operators' two-point form, the half list and
 * the AMG proxy need. Row checks run in parallel and report the smallest offending row, found
 * again serially for its message, so the error is the same for every thread count. Symmetry is
 * a binary search of i in row j for every entry: O(pairs log row), no extra memory. */
#include "check.h"
#include "nlist_layout.h"
#include "nlist_rule.h"

#include <stdlib.h>
#include <string.h>

/* Offsets: n + 1 entries from 0, non-decreasing, no row longer than n - 1 (a row of distinct
 * indices other than its own), so the total is at most n (n - 1) and fits an int64. */
static int check_offsets(const int64_t *off, size_t n, char *err)
{
    PST_CHECK(off[0] != 0, PST_EINPUT, err, "neighbour CSR: offset[0] = %lld, must be 0",
              (long long)off[0]);
    for (size_t i = 0; i < n; ++i) {
        PST_CHECK(off[i + 1] < off[i], PST_EINPUT, err,
                  "neighbour CSR: row %zu: offset[%zu] = %lld is below offset[%zu] = %lld "
                  "(offsets must not decrease)",
                  i, i + 1, (long long)off[i + 1], i, (long long)off[i]);
        PST_CHECK((uint64_t)(off[i + 1] - off[i]) > (n ? n - 1 : 0), PST_EINPUT, err,
                  "neighbour CSR: row %zu has %lld entries, more than the %zu other particles",
                  i, (long long)(off[i + 1] - off[i]), n ? n - 1 : 0);
    }
    return PST_OK;
}

/* Row i's own checks: every index < n, not i, and larger than the one before. */
static int check_row(const pst_nlist *nl, size_t i, char *err)
{
    const uint32_t *row = nl->index + nl->offset[i];
    int64_t len = nl->offset[i + 1] - nl->offset[i];
    for (int64_t k = 0; k < len; ++k) {
        PST_CHECK(row[k] >= nl->n, PST_EINPUT, err,
                  "neighbour CSR: row %zu, entry %lld: index %u out of range (n = %zu)", i,
                  (long long)k, row[k], nl->n);
        PST_CHECK(row[k] == i, PST_EINPUT, err,
                  "neighbour CSR: row %zu, entry %lld: the particle itself (no self pairs)", i,
                  (long long)k);
        PST_CHECK(k > 0 && row[k] == row[k - 1], PST_EINPUT, err,
                  "neighbour CSR: row %zu, entry %lld: index %u repeated", i, (long long)k,
                  row[k]);
        PST_CHECK(k > 0 && row[k] < row[k - 1], PST_EINPUT, err,
                  "neighbour CSR: row %zu, entry %lld: index %u after %u (rows must be sorted "
                  "increasing)",
                  i, (long long)k, row[k], row[k - 1]);
    }
    return PST_OK;
}

/* 1 when the sorted row j holds i. */
static int row_has(const pst_nlist *nl, size_t j, uint32_t i)
{
    int64_t lo = nl->offset[j], hi = nl->offset[j + 1];
    while (lo < hi) {
        int64_t mid = lo + (hi - lo) / 2;
        if (nl->index[mid] < i)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < nl->offset[j + 1] && nl->index[lo] == i;
}

/* Row i's symmetry: i is in the row of every j of row i (rows already checked). */
static int check_symmetric(const pst_nlist *nl, size_t i, char *err)
{
    for (int64_t q = nl->offset[i]; q < nl->offset[i + 1]; ++q)
        PST_CHECK(!row_has(nl, nl->index[q], (uint32_t)i), PST_EINPUT, err,
                  "neighbour CSR: row %zu, entry %lld: %u is a neighbour of %zu but %zu is not "
                  "one of %u (the list must be symmetric)",
                  i, (long long)(q - nl->offset[i]), nl->index[q], i, i, nl->index[q]);
    return PST_OK;
}

/* Row i's radius (PST_CSR_CHECK_RADIUS): every pair within support (h_i + h_j) / 2, decided by
 * the build's own test (nlist_rule.h), bit for bit. */
static int check_radius(const pst_nlist *nl, const pst_cloud *c, size_t i, char *err)
{
    const pst_image im = pst_cloud_image(c);
    double xi[3] = {c->x[0][i], c->x[1][i], c->dim == 3 ? c->x[2][i] : 0};
    double hi = pst_cloud_h_at(c, i), halfs = 0.5 * nl->support;
    double r2u = (nl->support * c->h_uniform) * (nl->support * c->h_uniform);
    for (int64_t q = nl->offset[i]; q < nl->offset[i + 1]; ++q)
        PST_CHECK(!pair_hit(c->x[0], c->x[1], c->x[2], c->h, xi, hi, halfs, r2u, c->dim,
                            c->h != NULL, im.any, &im, nl->index[q]),
                  PST_EINPUT, err,
                  "neighbour CSR: row %zu, entry %lld: %u lies beyond the support radius "
                  "%g (h_i + h_j) / 2",
                  i, (long long)(q - nl->offset[i]), nl->index[q], nl->support);
    return PST_OK;
}

enum { CHECK_ROW, CHECK_SYMMETRIC, CHECK_RADIUS };

/* One check over every row: the smallest failing row, checked again with err for its
 * message. */
static int check_rows(const pst_nlist *nl, const pst_cloud *c, int which, char *err)
{
    size_t n = nl->n, bad = n;
#pragma omp parallel for schedule(dynamic, 1024) reduction(min : bad)
    for (size_t i = 0; i < n; ++i) {
        int st = which == CHECK_ROW         ? check_row(nl, i, NULL)
                 : which == CHECK_SYMMETRIC ? check_symmetric(nl, i, NULL)
                                            : check_radius(nl, c, i, NULL);
        bad = st != PST_OK && i < bad ? i : bad;
    }
    if (bad == n)
        return PST_OK;
    return which == CHECK_ROW         ? check_row(nl, bad, err)
           : which == CHECK_SYMMETRIC ? check_symmetric(nl, bad, err)
                                      : check_radius(nl, c, bad, err);
}

/* PST_CSR_CHECK_COMPLETE: every pair of the build's rule is in nl (both rows sorted). */
static int check_complete(const pst_nlist *nl, const pst_cloud *c, char *err)
{
    pst_nlist *built = NULL;
    PST_TRY(pst_nlist_build(&built, c, nl->support, err));
    size_t n = nl->n, bad = n;
#pragma omp parallel for schedule(dynamic, 1024) reduction(min : bad)
    for (size_t i = 0; i < n; ++i) {
        int64_t q = nl->offset[i];
        for (int64_t p = built->offset[i]; p < built->offset[i + 1] && bad > i; ++p) {
            while (q < nl->offset[i + 1] && nl->index[q] < built->index[p])
                ++q;
            if (q == nl->offset[i + 1] || nl->index[q] != built->index[p])
                bad = i;
        }
    }
    uint32_t missing = 0;
    for (int64_t p = bad < n ? built->offset[bad] : 0; bad < n; ++p)
        if (!row_has(nl, bad, built->index[p])) {
            missing = built->index[p];
            break;
        }
    pst_nlist_destroy(built);
    PST_CHECK(bad < n, PST_EINPUT, err,
              "neighbour CSR: row %zu lacks %u, which lies within the support radius %g "
              "(h_i + h_j) / 2",
              bad, missing, nl->support);
    return PST_OK;
}

/* The validated copy of the caller's CSR as a list of c's n rows. */
static int csr_list(pst_nlist **out, const pst_cloud *c, double support, const int64_t *offset,
                    const uint32_t *index, int flags, char *err)
{
    *out = NULL;
    PST_CHECK(!c || !offset, PST_EINVAL, err, "neighbour CSR: the cloud and the offsets must "
                                              "not be NULL");
    PST_CHECK(flags & ~(PST_CSR_CHECK_RADIUS | PST_CSR_CHECK_COMPLETE), PST_EINVAL, err,
              "neighbour CSR: unknown flags 0x%x", (unsigned)flags);
    PST_TRY(pst_nlist_check_cloud(c, support, err));
    size_t n = c->n;
    PST_TRY(check_offsets(offset, n, err));
    int64_t pairs = offset[n];
    PST_CHECK(pairs > 0 && !index, PST_EINVAL, err,
              "neighbour CSR: %lld pairs but the indices are NULL", (long long)pairs);
    PST_CHECK((uint64_t)pairs > SIZE_MAX / sizeof(uint32_t), PST_ENOMEM, err,
              "neighbour CSR: %lld pairs overflow the address space", (long long)pairs);
    pst_nlist *nl = calloc(1, sizeof *nl);
    if (nl) {
        nl->offset = pst_alloc((n + 1) * sizeof *nl->offset);
        nl->index = pst_alloc((size_t)pairs * sizeof *nl->index);
    }
    if (!nl || !nl->offset || !nl->index) {
        pst_nlist_destroy(nl);
        pst_set_err(err, "neighbour CSR: cannot allocate %zu rows and %lld pairs", n,
                    (long long)pairs);
        return PST_ENOMEM;
    }
    nl->n = n;
    nl->support = support;
    nl->cut = 1;
    nl->from_csr = 1;
    memcpy(nl->offset, offset, (n + 1) * sizeof *nl->offset);
    if (pairs > 0)
        memcpy(nl->index, index, (size_t)pairs * sizeof *nl->index);
    int st = check_rows(nl, c, CHECK_ROW, err);
    if (st == PST_OK)
        st = check_rows(nl, c, CHECK_SYMMETRIC, err);
    if (st == PST_OK && (flags & PST_CSR_CHECK_RADIUS))
        st = check_rows(nl, c, CHECK_RADIUS, err);
    if (st == PST_OK && (flags & PST_CSR_CHECK_COMPLETE))
        st = check_complete(nl, c, err);
    if (st != PST_OK) {
        pst_nlist_destroy(nl);
        return st;
    }
    *out = nl;
    return PST_OK;
}

int pst_nlist_from_csr(pst_nlist **out, const pst_cloud *c, double support,
                       const int64_t *offset, const uint32_t *index, int flags, char *err)
{
    PST_CHECK(!out, PST_EINVAL, err, "neighbour CSR: out must not be NULL");
    return csr_list(out, c, support, offset, index, flags, err);
}

int pst_nlist_set_csr(pst_nlist *nl, const pst_cloud *c, const int64_t *offset,
                      const uint32_t *index, int flags, char *err)
{
    PST_CHECK(!nl, PST_EINVAL, err, "neighbour CSR: the list must not be NULL");
    PST_CHECK(!nl->from_csr || nl->half || nl->cut != 1, PST_EINVAL, err,
              "neighbour CSR: only a whole list made by pst_nlist_from_csr takes new pairs "
              "(a built list follows its cloud through pst_nlist_update)");
    PST_CHECK(c && c->n != nl->n, PST_EINVAL, err,
              "neighbour CSR: the cloud has %zu particles, the list %zu rows", c->n, nl->n);
    pst_nlist *fresh = NULL;
    PST_TRY(csr_list(&fresh, c, nl->support, offset, index, flags, err));
    pst_nlist_adopt(nl, fresh); /* the handle stays: operators hold it */
    return PST_OK;
}
