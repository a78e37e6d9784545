/* The mixed schemes' stored pattern (kernels/mixed.c): a stored row composes two sweeps, so its
 * columns are the neighbours of the neighbours (~1500 per row in 3D). Built only when the
 * operator layer asks for it (stored weights, assembly, diagonal, audit), never by the
 * precompute. */
#include "check.h"
#include "mixed.h"

#include <omp.h>

/* In-place sort of a short row of column indices: insertion sort below 16, else quicksort on
 * the median of three. Bound by the comparisons, ~log2(len) per entry. */
static void sort_u32(uint32_t *a, int64_t n)
{
    while (n > 16) {
        uint32_t x = a[0], y = a[n / 2], z = a[n - 1];
        uint32_t piv = x < y ? (y < z ? y : (x < z ? z : x)) : (x < z ? x : (y < z ? z : y));
        int64_t lo = 0, hi = n - 1;
        while (lo <= hi) {
            while (a[lo] < piv)
                ++lo;
            while (a[hi] > piv)
                --hi;
            if (lo <= hi) {
                uint32_t t = a[lo];
                a[lo++] = a[hi];
                a[hi--] = t;
            }
        }
        if (hi + 1 < n - lo) { /* recurse on the smaller part, loop on the larger */
            sort_u32(a, hi + 1);
            a += lo;
            n -= lo;
        } else {
            sort_u32(a + lo, n - lo);
            n = hi + 1;
        }
    }
    for (int64_t r = 1; r < n; ++r) {
        uint32_t v = a[r];
        int64_t s = r;
        for (; s > 0 && a[s - 1] > v; --s)
            a[s] = a[s - 1];
        a[s] = v;
    }
}

/* The columns of row i of the pattern, N(i) and N(j) for j in N(i), without i, unsorted; with
 * out == NULL only counted. mark[] (one per thread) holds the last row that took a column. */
static int64_t ring2(const mx_ctx *k, size_t i, uint32_t *mark, uint32_t *out)
{
    const int64_t *off = k->c.off;
    const uint32_t *idx = k->c.idx;
    int64_t c = 0;
    mark[i] = (uint32_t)i;
    for (int64_t e = off[i]; e < off[i + 1]; ++e) {
        uint32_t j = idx[e];
        if (mark[j] != i) {
            mark[j] = (uint32_t)i;
            if (out)
                out[c] = j;
            ++c;
        }
        for (int64_t f = off[j]; f < off[j + 1]; ++f) {
            uint32_t l = idx[f];
            if (mark[l] != i) {
                mark[l] = (uint32_t)i;
                if (out)
                    out[c] = l;
                ++c;
            }
        }
    }
    return c;
}

/* Every thread's marker array reset (i < n <= UINT32_MAX never equals the reset value). */
static void reset_marks(uint32_t *marks, size_t len)
{
    for (size_t t = 0; t < len; ++t)
        marks[t] = UINT32_MAX;
}

/* The wide_pattern hook: the neighbours-of-neighbours pattern, a counting pass and (with pidx)
 * a filling pass, so memory stays one copy of it. Bound by the |N|^2 gathers of mark[] per row,
 * then the sort. Nothing is left allocated on failure. */
int pst_mx_wide_pattern(const pst_op *op, int64_t **poff, uint32_t **pidx, char *err)
{
    mx_ctx k = make_ctx(op);
    size_t n = op->n, nm = (size_t)omp_get_max_threads() * n;
    uint32_t *marks = pst_alloc(nm * sizeof *marks), *idx = NULL;
    int64_t *off = pst_alloc((n + 1) * sizeof *off);
    int st = PST_OK;
    PST_CHECK_GOTO(!marks || !off, st, PST_ENOMEM, fail, err,
                   "%s: cannot allocate the stencil pattern of %zu particles", op->scheme->name,
                   n);
    reset_marks(marks, nm);
    off[0] = 0;
#pragma omp parallel
    {
        uint32_t *mark = marks + (size_t)omp_get_thread_num() * n;
#pragma omp for schedule(dynamic, 256)
        for (size_t i = 0; i < n; ++i)
            off[i + 1] = ring2(&k, i, mark, NULL);
    }
    for (size_t i = 0; i < n; ++i)
        off[i + 1] += off[i];
    if (pidx) {
        idx = pst_alloc((size_t)off[n] * sizeof *idx);
        PST_CHECK_GOTO(!idx, st, PST_ENOMEM, fail, err,
                       "%s: cannot allocate the stencil pattern (%lld entries)",
                       op->scheme->name, (long long)off[n]);
        reset_marks(marks, nm);
#pragma omp parallel
        {
            uint32_t *mark = marks + (size_t)omp_get_thread_num() * n;
#pragma omp for schedule(dynamic, 256)
            for (size_t i = 0; i < n; ++i) {
                ring2(&k, i, mark, idx + off[i]);
                sort_u32(idx + off[i], off[i + 1] - off[i]);
            }
        }
        *pidx = idx;
    }
    pst_free(marks);
    *poff = off;
    return PST_OK;
fail:
    pst_free(marks);
    pst_free(off);
    return st;
}
