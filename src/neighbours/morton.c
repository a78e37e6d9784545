/* Morton (Z-order) keys and the cloud's Morton sort: keys of the cell coordinates, a parallel
 * stable LSD radix sort, one permutation of every field (docs/neighbours.md). */
#include "cells.h"
#include "check.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>

/* Spread the low bits of v (those of `keep`) apart: each step doubles the gaps, shifting by
 * shift[k] and keeping mask[k]. */
static inline uint64_t spread(uint64_t v, uint64_t keep, const int shift[5],
                              const uint64_t mask[5])
{
    v &= keep;
    for (int k = 0; k < 5; ++k)
        v = (v | v << shift[k]) & mask[k];
    return v;
}

/* The low 21 bits of v to every third bit (bit k goes to bit 3k). */
static uint64_t spread3(uint64_t v)
{
    static const int shift[5] = {32, 16, 8, 4, 2};
    static const uint64_t mask[5] = {0x001f00000000ffffULL, 0x001f0000ff0000ffULL,
                                     0x100f00f00f00f00fULL, 0x10c30c30c30c30c3ULL,
                                     0x1249249249249249ULL};
    return spread(v, 0x1fffff, shift, mask);
}

/* The 32 bits of v to every second bit. */
static uint64_t spread2(uint64_t v)
{
    static const int shift[5] = {16, 8, 4, 2, 1};
    static const uint64_t mask[5] = {0x0000ffff0000ffffULL, 0x00ff00ff00ff00ffULL,
                                     0x0f0f0f0f0f0f0f0fULL, 0x3333333333333333ULL,
                                     0x5555555555555555ULL};
    return spread(v, 0xffffffffULL, shift, mask);
}

uint64_t pst_morton_key(int dim, uint32_t ix, uint32_t iy, uint32_t iz)
{
    if (dim == 3)
        return spread3(ix) | spread3(iy) << 1 | spread3(iz) << 2;
    return spread2(ix) | spread2(iy) << 1;
}

#define RADIX_BITS 8
#define RADIX 256

/* Stable LSD radix sort of (key, val) by key, 8-bit digits. Only digits in which the keys
 * differ get a pass (`varying`: the bits in which some key differs from another). Each pass splits the input into `chunks`
 * fixed ranges with a histogram each, so the (unique, stable) result does not depend on the
 * thread count. Returns the buffers holding the sorted data through *key / *val. */
static void radix_sort(uint64_t **key, uint32_t **val, uint64_t **kbuf, uint32_t **vbuf,
                       size_t n, uint64_t varying, size_t chunks, size_t (*hist)[RADIX])
{
    uint64_t *k0 = *key, *k1 = *kbuf;
    uint32_t *v0 = *val, *v1 = *vbuf;
    for (int shift = 0; shift < 64; shift += RADIX_BITS) {
        if (!((varying >> shift) & (RADIX - 1)))
            continue;
#pragma omp parallel
        {
#pragma omp for schedule(static)
            for (size_t t = 0; t < chunks; ++t) {
                size_t *h = hist[t];
                for (int b = 0; b < RADIX; ++b)
                    h[b] = 0;
                for (size_t i = t * n / chunks; i < (t + 1) * n / chunks; ++i)
                    ++h[(k0[i] >> shift) & (RADIX - 1)];
            }
#pragma omp single
            {
                size_t s = 0;
                for (int b = 0; b < RADIX; ++b)
                    for (size_t t = 0; t < chunks; ++t) {
                        size_t v = hist[t][b];
                        hist[t][b] = s;
                        s += v;
                    }
            }
#pragma omp for schedule(static)
            for (size_t t = 0; t < chunks; ++t) {
                size_t *h = hist[t];
                for (size_t i = t * n / chunks; i < (t + 1) * n / chunks; ++i) {
                    size_t dst = h[(k0[i] >> shift) & (RADIX - 1)]++;
                    k1[dst] = k0[i];
                    v1[dst] = v0[i];
                }
            }
        }
        uint64_t *kt = k0;
        k0 = k1;
        k1 = kt;
        uint32_t *vt = v0;
        v0 = v1;
        v1 = vt;
    }
    *key = k0;
    *val = v0;
    *kbuf = k1;
    *vbuf = v1;
}

int pst_cloud_morton_sort(pst_cloud *c, double cell, char *err)
{
    PST_CHECK(!(cell > 0) || !isfinite(cell), PST_EINVAL, err,
              "Morton sort: cell size must be finite and > 0 (got %g)", cell);
    PST_TRY(pst_cloud_check_owned(c, "Morton sort", err));
    size_t n = c->n;
    int dim = c->dim;
    if (n < 2)
        return PST_OK;
    double lo[3], hi[3];
    pst_cloud_bbox(c, lo, hi);
    for (int d = 0; d < dim; ++d) {
        PST_CHECK(!isfinite(lo[d]) || !isfinite(hi[d]), PST_EINPUT, err,
                  "Morton sort: coordinates are not finite");
        PST_CHECK(!isfinite(hi[d] - lo[d]), PST_EINPUT, err,
                  "Morton sort: the cloud spans [%g, %g] along axis %d, too wide (the extent "
                  "overflows a double)",
                  lo[d], hi[d], d);
    }
    /* A key holds 21 (3D) or 32 (2D) bits per axis: coarsen the cells by doubling (which keeps
     * them nested with the finer grid) until the box fits. With a finite extent this ends
     * before the exponent range does (about 2100 doublings); the bound makes sure of it. */
    double maxcells = dim == 3 ? 2097152.0 : 4294967295.0; /* 2D: the count fits uint32 */
    double inv = 1.0 / cell;
    int fits = 0;
    for (int k = 0; k < PST_MAX_DOUBLINGS && !fits; ++k) {
        fits = isfinite(inv);
        for (int d = 0; d < dim; ++d)
            fits = fits && floor((hi[d] - lo[d]) * inv) + 1.0 <= maxcells;
        if (!fits) {
            cell *= 2.0;
            inv = 1.0 / cell;
        }
    }
    PST_CHECK(!fits, PST_EINPUT, err, "Morton sort: no cell size fits the cloud's extent");
    uint32_t dims[3] = {1, 1, 1};
    for (int d = 0; d < dim; ++d)
        dims[d] = (uint32_t)floor((hi[d] - lo[d]) * inv) + 1u;

    size_t chunks = (size_t)omp_get_max_threads();
    uint64_t *key = pst_alloc(n * sizeof *key), *kbuf = pst_alloc(n * sizeof *kbuf);
    uint32_t *perm = pst_alloc(n * sizeof *perm), *vbuf = pst_alloc(n * sizeof *vbuf);
    size_t(*hist)[RADIX] = pst_alloc(chunks * sizeof *hist);
    if (!key || !kbuf || !perm || !vbuf || !hist) {
        pst_free(key);
        pst_free(kbuf);
        pst_free(perm);
        pst_free(vbuf);
        pst_free(hist);
        pst_set_err(err, "Morton sort: cannot allocate %zu keys", n);
        return PST_ENOMEM;
    }
    /* Digits equal in every key need no pass: collect the bits in which some key differs
     * from particle 0's. */
    const double *x = c->x[0], *y = c->x[1], *z = c->x[2];
    uint64_t diff = 0;
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; ++i) {
        uint32_t ix = pst_cell_coord(x[i], lo[0], inv, dims[0]);
        uint32_t iy = pst_cell_coord(y[i], lo[1], inv, dims[1]);
        uint32_t iz = dim == 3 ? pst_cell_coord(z[i], lo[2], inv, dims[2]) : 0;
        key[i] = pst_morton_key(dim, ix, iy, iz);
        perm[i] = (uint32_t)i;
    }
    uint64_t k0 = key[0];
#pragma omp parallel for schedule(static) reduction(| : diff)
    for (size_t i = 0; i < n; ++i)
        diff |= key[i] ^ k0;
    radix_sort(&key, &perm, &kbuf, &vbuf, n, diff, chunks, hist);
    int status = pst_cloud_permute(c, perm, NULL);
    pst_free(key);
    pst_free(kbuf);
    pst_free(perm);
    pst_free(vbuf);
    pst_free(hist);
    return status;
}
