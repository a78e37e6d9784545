/* Cell grid: a dense uniform grid over the bounding box and a parallel counting sort of the
 * particles into it (DualSPHysics' PreSort/BeginCell, made parallel with per-chunk histograms),
 * the cells laid out in Morton order. The counting sort is stable, so its output is unique and
 * the same for any thread count. */
#include "cells.h"
#include "check.h"

#include <math.h>
#include <omp.h>
#include <string.h>

/* Cell counts are scanned in this many fixed blocks, whatever the thread count. */
#define SCAN_BLOCKS 64

void pst_cells_free(pst_cells *g)
{
    pst_free(g->rank);
    pst_free(g->start);
    pst_free(g->order);
    g->rank = g->start = g->order = NULL;
}

/* Choose the cell size: min_size doubled until the grid is small enough. Doubling (rather
 * than any other growth) keeps the grid nested with Morton cells of the same base size.
 * PST_EINPUT (message in err) for a cell size or an extent that is not finite. */
static int choose_grid(pst_cells *g, const double hi[3], size_t n, double min_size, char *err)
{
    PST_CHECK(!(min_size > 0) || !isfinite(min_size), PST_EINPUT, err,
              "cell grid: the cell size (support times h) must be finite and > 0 (got %g)",
              min_size);
    for (int d = 0; d < g->dim; ++d)
        PST_CHECK(!isfinite(hi[d] - g->lo[d]), PST_EINPUT, err,
                  "cell grid: the cloud spans [%g, %g] along axis %d, too wide (the extent "
                  "overflows a double)",
                  g->lo[d], hi[d], d);
    double limit = fmin(8.0 * (double)n + 1024.0, (double)UINT32_MAX - 1); /* ranks: uint32 */
    double size = min_size;
    for (int k = 0; k < PST_MAX_DOUBLINGS; ++k) {
        double inv = 1.0 / size, total = 1.0;
        int fits = isfinite(inv);
        for (int d = 0; d < g->dim; ++d) {
            double nd = floor((hi[d] - g->lo[d]) * inv) + 1.0;
            fits = fits && nd < (double)UINT32_MAX;
            total *= nd;
        }
        if (fits && total <= limit) {
            g->size = size;
            g->inv = inv;
            g->ncells = 1;
            for (int d = 0; d < 3; ++d) {
                g->dims[d] = d < g->dim ? (uint32_t)(floor((hi[d] - g->lo[d]) * inv) + 1.0) : 1;
                g->ncells *= g->dims[d];
            }
            return PST_OK;
        }
        size *= 2.0;
    }
    pst_set_err(err, "cell grid: no cell size fits the cloud's extent");
    return PST_EINPUT;
}

/* Number the cells of the 2^level cube with lower corner (x, y, z) in Morton order: children
 * in key order (x bit lowest, then y, then z, as pst_morton_key), cells outside the grid
 * skipped; cellat[r] = the cell of rank r. Serial, a few ns per cell: the recursion's inner
 * nodes are fewer than the cells plus `level` per boundary. */
static void morton_number(pst_cells *g, uint32_t *cellat, uint32_t *next, int level, uint64_t x,
                          uint64_t y, uint64_t z)
{
    int nchild = 1 << g->dim; /* unused axes have one cell */
    uint64_t half = (uint64_t)1 << (level - 1);
    for (int ch = 0; ch < nchild; ++ch) {
        uint64_t cx = x + (ch & 1) * half, cy = y + (ch >> 1 & 1) * half;
        uint64_t cz = z + (ch >> 2 & 1) * half;
        if (cx >= g->dims[0] || cy >= g->dims[1] || cz >= g->dims[2])
            continue;
        if (level > 1) {
            morton_number(g, cellat, next, level - 1, cx, cy, cz);
            continue;
        }
        size_t c = ((size_t)cz * g->dims[1] + cy) * g->dims[0] + cx;
        g->rank[c] = *next;
        cellat[(*next)++] = (uint32_t)c;
    }
}

static size_t cell_of(const pst_cells *g, const pst_cloud *c, size_t i)
{
    size_t cell = 0;
    for (int d = g->dim - 1; d >= 0; --d)
        cell = cell * g->dims[d] + pst_cell_coord(c->x[d][i], g->lo[d], g->inv, g->dims[d]);
    return cell;
}

int pst_cells_build(pst_cells *g, const pst_cloud *c, double min_size, char *err)
{
    memset(g, 0, sizeof *g);
    g->dim = c->dim;
    size_t n = c->n;
    double hi[3];
    pst_cloud_bbox(c, g->lo, hi);
    PST_TRY(choose_grid(g, hi, n, min_size, err));
    size_t nc = g->ncells;

    /* Chunks of particles, each with its own histogram; capped so that the histograms stay
     * within ~4 words per particle when the grid is large compared with n. */
    size_t chunks = (size_t)omp_get_max_threads();
    size_t cap = 4 * (n + 1024) / nc;
    chunks = chunks < cap ? chunks : cap;
    chunks = chunks ? chunks : 1;

    g->rank = pst_alloc(nc * sizeof *g->rank);
    g->start = pst_alloc((nc + 1) * sizeof *g->start);
    g->order = pst_alloc(n * sizeof *g->order);
    uint32_t *cellat = pst_alloc(nc * sizeof *cellat);
    uint32_t *cell = pst_alloc(n * sizeof *cell);
    uint32_t *hist = pst_calloc(chunks * nc, sizeof *hist);
    if (!g->rank || !g->start || !g->order || !cellat || !cell || !hist) {
        pst_set_err(err, "cell grid: cannot allocate %zu cells for %zu particles", nc, n);
        pst_free(cellat);
        pst_free(cell);
        pst_free(hist);
        pst_cells_free(g);
        return PST_ENOMEM;
    }
    int level = 1; /* the grid fits in a cube of 2^level cells per axis */
    for (int d = 0; d < 3; ++d)
        while (((uint64_t)1 << level) < g->dims[d])
            ++level;
    uint32_t next = 0;
    morton_number(g, cellat, &next, level, 0, 0, 0);
    int64_t blocksum[SCAN_BLOCKS + 1];

#pragma omp parallel
    {
        /* count */
#pragma omp for schedule(static)
        for (size_t t = 0; t < chunks; ++t) {
            uint32_t *h = hist + t * nc;
            for (size_t i = t * n / chunks; i < (t + 1) * n / chunks; ++i) {
                cell[i] = (uint32_t)cell_of(g, c, i);
                ++h[cell[i]];
            }
        }
        /* scan, cell-major in Morton order then chunk: chunk t's particles of a cell follow
         * chunk t-1's */
#pragma omp for schedule(static)
        for (size_t b = 0; b < SCAN_BLOCKS; ++b) {
            uint32_t s = 0;
            for (size_t r = b * nc / SCAN_BLOCKS; r < (b + 1) * nc / SCAN_BLOCKS; ++r)
                for (size_t t = 0; t < chunks; ++t)
                    s += hist[t * nc + cellat[r]];
            blocksum[b] = s;
        }
#pragma omp single
        pst_exclusive_scan(blocksum, SCAN_BLOCKS); /* n < 2^32: every sum fits a uint32_t */
#pragma omp for schedule(static)
        for (size_t b = 0; b < SCAN_BLOCKS; ++b) {
            uint32_t s = (uint32_t)blocksum[b];
            for (size_t r = b * nc / SCAN_BLOCKS; r < (b + 1) * nc / SCAN_BLOCKS; ++r) {
                size_t k = cellat[r];
                g->start[r] = s;
                for (size_t t = 0; t < chunks; ++t) {
                    uint32_t v = hist[t * nc + k];
                    hist[t * nc + k] = s;
                    s += v;
                }
            }
        }
        /* scatter, in input order inside each chunk: stable */
#pragma omp for schedule(static)
        for (size_t t = 0; t < chunks; ++t) {
            uint32_t *h = hist + t * nc;
            for (size_t i = t * n / chunks; i < (t + 1) * n / chunks; ++i)
                g->order[h[cell[i]]++] = (uint32_t)i;
        }
    }
    g->start[nc] = (uint32_t)n;
    pst_free(cellat);
    pst_free(cell);
    pst_free(hist);
    return PST_OK;
}
