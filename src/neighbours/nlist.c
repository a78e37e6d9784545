/* CSR neighbour lists (choice 1, docs/choices.md): j is a neighbour of i iff j != i and
 *     d2 < R_ij^2,  d2 = dx*dx + dy*dy (+ dz*dz),  dx = x_j - x_i (double),
 *     R_ij = support*(h_i + h_j)/2  (uniform h: support*h).
 * Both the rule and its evaluation are symmetric in i and j, so the list is symmetric.
 *
 * Algorithm (docs/neighbours.md): bin the particles into cells of edge >= R_max/CELL_DIV, laid
 * out in Morton order (cells.c), copy positions into that slot order, then two lock-free passes
 * over the cells, both symmetric: every pair of slots p < q is tested once, by the thread that
 * owns p. Count: the hit is credited to both rows in the thread's per-slot counters; exclusive
 * scan into int64 offsets and, per slot, into per-thread write cursors (thread u writes row s
 * after threads 0..u-1); fill: the hit writes q into row p and p into row q through the thread's
 * cursors. A thread owns whole cells, a static partition balanced by particle count; every entry
 * goes to a fixed place, so the list is identical for any thread count.
 *
 * Periodic axes (docs/periodic.md): the distance tests take the minimum image of each offset,
 * and a cell's candidates along such an axis wrap around the box: the cells the reach covers
 * past a face are those at the other face, their bounds shifted by the period so that the
 * pruning sees the image. Where the images of the reach overlap (a period of a few cells)
 * the axis's cells are taken once each, unpruned: with the period above twice the radius only
 * the minimum image of a pair can be within it, so no pair is counted twice.
 *
 * Row order: row s receives, in this order, the lower neighbours p < s (in increasing slot
 * order: thread u's before thread u+1's, each thread's in its processing order) and then the
 * upper ones (candidate cells in increasing slot order, increasing inside each). So rows are
 * sorted by slot, which is the cloud order when the cloud is Morton-sorted with cell =
 * support*h_max or a power-of-two fraction of it (the slot order is then the identity);
 * otherwise each row is sorted afterwards by a natural merge sort of its runs. */
#include "cells.h"
#include "check.h"
#include "isa.h"
#include "nlist_rule.h"
#include "tally.h"

#include <float.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

/* Cell edge = R_max / CELL_DIV. 1 (27/9 cells) measured faster than 2 (125/25 cells, pruned
 * per particle): docs/neighbours.md has the numbers. */
#define CELL_DIV 1

#define SCAN_BLOCKS 64
#define FILL_BLOCK 64
/* Slots a pass handles between two counts of a progress hook (pst_nlist_build_with). */
#define PROGRESS_SLOTS 4096

/* A candidate cell: its slots in the cell-ordered copy and its box widened by the rounding
 * margin. */
typedef struct {
    uint32_t a, b;
    double lo[3], hi[3];
} cand;

typedef struct {
    int dim;
    const pst_cells *g;
    const double *x[3]; /* positions in cell order (x[2] = NULL in 2D)        */
    const double *h;    /* per-particle h in cell order, or NULL (uniform)    */
    const uint32_t *pid;/* cloud index of every cell-order slot (g->order)    */
    double halfs;       /* support/2                                          */
    double huni, hmax;
    double r2uni;       /* (support*h)^2 for uniform h                        */
    double margin;      /* bound on the rounding of positions vs cell bounds  */
    pst_image im;       /* the periodic box (im.any = 0: none)                */
    double blo[3], bhi[3]; /* its bounds on the periodic axes                 */
    const int64_t *offset; /* fill pass: the row offsets (by cloud index)     */
    uint32_t *index;       /* fill pass: the list                             */
    pst_tally *tally;      /* the progress hook's counter, or NULL            */
} ctx;

/* Largest distance at which particle p (a cell-order slot) can have a neighbour, inflated so
 * that rounding in d2 and in the cell coordinates can never lose one (cell_coord is monotone). */
static inline double reach(const ctx *k, size_t p)
{
    double hp = k->h ? k->h[p] : k->huni;
    return k->halfs * (hp + k->hmax) * (1.0 + 64 * DBL_EPSILON) + k->margin;
}

/* Candidate cells of the cell of rank r: every non-empty cell within the reach of one of its
 * particles (through the periodic faces too), sorted by slot. Returns their number. */
static size_t cell_candidates(const ctx *k, size_t r, cand *out)
{
    const pst_cells *g = k->g;
    double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    for (int d = 0; d < k->dim; ++d) {
        lo[d] = INFINITY;
        hi[d] = -INFINITY;
    }
    for (size_t p = g->start[r]; p < g->start[r + 1]; ++p) {
        double rp = reach(k, p);
        for (int d = 0; d < k->dim; ++d) {
            lo[d] = fmin(lo[d], k->x[d][p] - rp);
            hi[d] = fmax(hi[d], k->x[d][p] + rp);
        }
    }
    pst_cell_run runs[3][3];
    int nr[3];
    pst_cell_box_runs(g, &k->im, k->blo, k->bhi, lo, hi, runs, nr);
    size_t m = 0;
    PST_FOR_EACH_CELL(runs, nr, rx, ry, rz, ix, iy, iz) {
        size_t rc = g->rank[((size_t)iz * g->dims[1] + iy) * g->dims[0] + ix];
        uint32_t a = g->start[rc], b = g->start[rc + 1];
        if (a == b)
            continue;
        cand e = {.a = a, .b = b};
        const uint32_t ic[3] = {ix, iy, iz};
        const pst_cell_run *ar[3] = {&runs[0][rx], &runs[1][ry], &runs[2][rz]};
        for (int d = 0; d < 3; ++d) {
            double c0 = g->lo[d] + ic[d] * g->size + ar[d]->shift;
            double c1 = g->lo[d] + (ic[d] + 1.0) * g->size + ar[d]->shift;
            int used = d < k->dim && ar[d]->prune;
            e.lo[d] = used ? c0 - k->margin : d < k->dim ? -INFINITY : 0;
            e.hi[d] = used ? c1 + k->margin : d < k->dim ? INFINITY : 0;
        }
        size_t j = m++;
        for (; j > 0 && out[j - 1].a > e.a; --j)
            out[j] = out[j - 1];
        out[j] = e;
    }
    return m;
}

/* The hot loops: slot p (at xp, smoothing length hi, cloud index self) against the slots
 * [a, b), all after p. Count: `cur` is the thread's per-slot counter. Fill: `cur` is the
 * thread's per-slot write cursor (relative to the row's offset) and `row` the next entry of
 * row p. Returns the hits. The distance tests stream contiguous slot ranges of the SoA copy and
 * are branch-free, so they vectorise; a cell's ranges stay in L1/L2 across its particles. With
 * cells of edge R_max the tests per neighbour are ~4.9 (3D) and ~2.6 (2D) after the
 * per-particle box pruning (expected volumes of the visited cells over the ball's, uniform
 * density), halved by testing each pair once. */
static inline __attribute__((always_inline)) size_t
scan_range(const ctx *k, int dim, int varh, int per, int fill, size_t a, size_t b,
           const double *xp, double hi, uint32_t *restrict cur, uint32_t *row, uint32_t self)
{
    double xi[3] = {xp[0], xp[1], xp[2]}; /* in registers: no aliasing with the outputs */
    const double *restrict X = k->x[0], *restrict Y = k->x[1], *restrict Z = k->x[2];
    const double *restrict H = k->h;
    const uint32_t *restrict pid = k->pid;
    double halfs = k->halfs, r2u = k->r2uni;
    const pst_image im = k->im;
    if (!fill) {
        /* count: bound by the flops and compare latency of the distance tests (vectorised,
         * AVX-512 under dispatch: about a quarter of the 3D scene's 1.6 s of user time at 1
         * thread, the fill most of the rest); each hit is credited to q here and to p by the
         * caller */
        size_t cnt = 0;
        for (size_t q = a; q < b; ++q) {
            size_t hit = pair_hit(X, Y, Z, H, xi, hi, halfs, r2u, dim, varh, per, &im, q);
            cnt += hit;
            cur[q] += (uint32_t)hit;
        }
        return cnt;
    }
    const int64_t *restrict offset = k->offset;
    uint32_t *index = k->index;
    size_t w = 0;
    uint64_t hit[FILL_BLOCK];
    uint32_t qs[FILL_BLOCK];
    for (size_t q0 = a; q0 < b; q0 += FILL_BLOCK) {
        size_t len = b - q0 < FILL_BLOCK ? b - q0 : FILL_BLOCK;
        /* fill, tests: the same vectorised tests as the count, into a block of 0/1 flags */
        for (size_t e = 0; e < len; ++e) {
            hit[e] = pair_hit(X, Y, Z, H, xi, hi, halfs, r2u, dim, varh, per, &im, q0 + e);
        }
        /* fill, compaction: branch-free list of the hit slots (bound by the chain of adds on m,
         * one per flag) */
        size_t m = 0;
        for (size_t e = 0; e < len; ++e) {
            qs[m] = (uint32_t)(q0 + e);
            m += hit[e];
        }
        /* fill, writes: q into row p and p into row q; bound by the stores into the index
         * array (first touch of its pages, the rows of the candidate cells in L2): with the
         * compaction, 44 % of the passes' samples (docs/neighbours.md) */
        for (size_t j = 0; j < m; ++j) {
            uint32_t q = qs[j], i = pid[q];
            row[w++] = i;
            index[offset[i] + cur[q]++] = self;
        }
    }
    return w;
}

/* The neighbours of slot p in later slots: counted (credited to both rows in `cur`) or
 * written (row p from `row` on, row q through `cur`). Returns their number. */
static inline __attribute__((always_inline)) size_t
particle_row(const ctx *k, int dim, int varh, int per, int fill, size_t p, const cand *cl,
             size_t m, uint32_t *restrict cur, uint32_t *row)
{
    double xi[3] = {k->x[0][p], k->x[1][p], dim == 3 ? k->x[2][p] : 0};
    double hi = varh ? k->h[p] : k->huni;
    double r = reach(k, p), r2 = r * r;
    uint32_t self = k->pid[p];
    size_t w = 0;
    for (size_t e = 0; e < m; ++e) {
        const cand *c = &cl[e];
        if (c->b <= p + 1)
            continue;
        double g2 = 0;
        for (int d = 0; d < dim; ++d) {
            double gl = c->lo[d] - xi[d], gh = xi[d] - c->hi[d];
            double gap = gl > gh ? gl : gh;
            gap = gap > 0 ? gap : 0;
            g2 += gap * gap;
        }
        if (g2 >= r2)
            continue;
        size_t a = c->a > p ? c->a : p + 1;
        w += scan_range(k, dim, varh, per, fill, a, c->b, xi, hi, cur, fill ? row + w : NULL,
                        self);
    }
    return w;
}

/* Sort a row of distinct indices by merging its natural runs pairwise; tmp has len entries.
 * An already sorted row costs one scan. */
static void sort_row(uint32_t *row, uint32_t *tmp, size_t len)
{
    uint32_t *src = row, *dst = tmp;
    for (;;) {
        size_t i = 0, runs = 0;
        while (i < len) {
            size_t m = i + 1;
            while (m < len && src[m - 1] < src[m])
                ++m;
            size_t e = m;
            if (m < len)
                for (e = m + 1; e < len && src[e - 1] < src[e];)
                    ++e;
            size_t u = i, v = m, o = i;
            while (u < m && v < e)
                dst[o++] = src[u] < src[v] ? src[u++] : src[v++];
            while (u < m)
                dst[o++] = src[u++];
            while (v < e)
                dst[o++] = src[v++];
            ++runs;
            i = e;
        }
        uint32_t *t = src;
        src = dst;
        dst = t;
        if (runs <= 1)
            break;
    }
    if (src != row)
        memcpy(row, src, len * sizeof *row);
}

/* The count pass (k->index == NULL) or the fill pass over the cells of ranks [c0, c1), with
 * the thread's counters / cursors `cur`, dispatched to a specialised instance of the loops;
 * compiled per ISA (AVX-512 tests: 1.78x less user time than the generic build's, 3D). */
PST_ISA_DISPATCH static void pass(const ctx *k, size_t c0, size_t c1, cand *cl, uint32_t *cur)
{
    const pst_cells *g = k->g;
    int fill = k->index != NULL, varh = k->h != NULL, per = k->im.any;
    size_t counted = g->start[c0]; /* the slots before it are counted: one test per cell */
    for (size_t r = c0; r < c1; ++r) {
        if (k->tally && g->start[r] - counted >= PROGRESS_SLOTS) {
            pst_tally_add(k->tally, g->start[r] - counted);
            counted = g->start[r];
        }
        if (g->start[r] == g->start[r + 1])
            continue;
        size_t m = cell_candidates(k, r, cl);
        for (size_t p = g->start[r]; p < g->start[r + 1]; ++p) {
            /* fill: row p's own part starts after this thread's writes of lower neighbours */
            uint32_t *row = fill ? k->index + k->offset[k->pid[p]] + cur[p] : NULL;
            size_t len;
#define ROW(D, V, P, F) particle_row(k, D, V, P, F, p, cl, m, cur, row)
#define ROWS(D, V) (per ? (fill ? ROW(D, V, 1, 1) : ROW(D, V, 1, 0))                            \
                        : (fill ? ROW(D, V, 0, 1) : ROW(D, V, 0, 0)))
            if (k->dim == 3)
                len = varh ? ROWS(3, 1) : ROWS(3, 0);
            else
                len = varh ? ROWS(2, 1) : ROWS(2, 0);
#undef ROWS
#undef ROW
            cur[p] += (uint32_t)len;
        }
    }
    pst_tally_add(k->tally, g->start[c1] - counted);
}

/* First cell (rank) whose particles start at or after slot `pos`. */
static size_t first_cell(const pst_cells *g, size_t pos)
{
    size_t lo = 0, hi = g->ncells;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (g->start[mid] < pos)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

/* The smoothing lengths a list accepts: the kernels scale as h^-dim and their second
 * derivatives as h^-(dim+2), which leave a double's range outside about 1e+-60 in 3D. */
#define PST_H_MIN 1e-60
#define PST_H_MAX 1e60

static int h_in_range(double h)
{
    return h >= PST_H_MIN && h <= PST_H_MAX; /* false for NaN */
}

int pst_nlist_check_cloud(const pst_cloud *c, double support, char *err)
{
    PST_CHECK(!(support > 0) || !isfinite(support), PST_EINVAL, err,
              "neighbour list: support must be finite and > 0 (got %g)", support);
    size_t n = c->n, bad_h = n, bad_x = n;
    PST_CHECK(!c->h && !h_in_range(c->h_uniform), PST_EINPUT, err,
              "neighbour list: smoothing length h = %g must be in [%g, %g]", c->h_uniform,
              PST_H_MIN, PST_H_MAX);
#pragma omp parallel for schedule(static) reduction(min : bad_h, bad_x)
    for (size_t i = 0; i < n; ++i) {
        if (c->h && !h_in_range(c->h[i]))
            bad_h = i < bad_h ? i : bad_h;
        for (int d = 0; d < c->dim; ++d)
            if (!isfinite(c->x[d][i]))
                bad_x = i < bad_x ? i : bad_x;
    }
    PST_CHECK(bad_h < n, PST_EINPUT, err,
              "neighbour list: particle %lld: smoothing length h = %g must be in [%g, %g]",
              (long long)c->id[bad_h], c->h[bad_h], PST_H_MIN, PST_H_MAX);
    PST_CHECK(bad_x < n, PST_EINPUT, err,
              "neighbour list: particle %lld: a coordinate is not finite",
              (long long)c->id[bad_x]);
    double hmax = pst_cloud_h_max(c), rmax = support * hmax;
    PST_CHECK(!isfinite(rmax * rmax) || !isfinite(2 * hmax), PST_EINVAL, err,
              "neighbour list: support radius %g * %g is too large", support, hmax);
    PST_TRY(pst_cloud_check_box(c, err));
    for (int d = 0; d < c->dim; ++d) {
        double P = c->box_hi[d] - c->box_lo[d];
        PST_CHECK(c->periodic[d] && !(2 * rmax < P), PST_EINPUT, err,
                  "neighbour list: the period %g along %c must exceed twice the neighbour "
                  "radius %g * h_max %g = %g (a pair would have two images within reach)",
                  P, "xyz"[d], support, hmax, rmax);
    }
    return PST_OK;
}

/* A list of n rows: its offsets, zero when n < 2 (with the index: no pairs), else unset (the
 * build writes every one, in parallel). */
static int new_list(pst_nlist **out, size_t n, double support, char *err)
{
    pst_nlist *nl = calloc(1, sizeof *nl);
    if (nl)
        nl->offset = n < 2 ? pst_calloc(n + 1, sizeof *nl->offset)
                           : pst_alloc((n + 1) * sizeof *nl->offset);
    if (nl && n < 2)
        nl->index = pst_alloc(0);
    if (!nl || !nl->offset || (n < 2 && !nl->index)) {
        pst_nlist_destroy(nl);
        pst_set_err(err, "neighbour list: cannot allocate the offsets of %zu rows", n);
        return PST_ENOMEM;
    }
    nl->n = n;
    nl->support = support;
    nl->cut = 1;
    *out = nl;
    return PST_OK;
}

/* The search context over the cell-ordered copy, and the rounding margin of the cell bounds. */
static ctx search_ctx(const pst_cloud *c, const pst_cells *g, double *copy, double support,
                      double hmax)
{
    size_t n = c->n;
    int dim = c->dim;
    ctx k = {.dim = dim, .g = g, .pid = g->order, .halfs = 0.5 * support, .hmax = hmax};
    for (int d = 0; d < dim; ++d)
        k.x[d] = copy + (size_t)d * n;
    k.h = c->h ? copy + (size_t)dim * n : NULL;
    k.huni = c->h ? 0 : c->h_uniform;
    k.r2uni = (support * k.huni) * (support * k.huni);
    double maxabs = 0, span = 0;
    for (int d = 0; d < dim; ++d) {
        double ext = (g->dims[d] + 1.0) * g->size;
        maxabs = fmax(maxabs, fabs(g->lo[d]) + ext);
        span = fmax(span, ext);
    }
    k.im = pst_cloud_image(c);
    double period = 0;
    for (int d = 0; d < dim; ++d) {
        k.blo[d] = c->box_lo[d];
        k.bhi[d] = c->box_hi[d];
        period = fmax(period, k.im.P[d]);
    }
    /* a minimum image rounds once more, by an ulp of the period */
    k.margin = 64 * DBL_EPSILON * (maxabs + span + period);
    return k;
}

/* Bound on the candidate cells of one cell: the reach spans at most this many per axis. */
static size_t max_candidates(const ctx *k, double support)
{
    const pst_cells *g = k->g;
    double rmax = support * k->hmax * (1.0 + 64 * DBL_EPSILON) + k->margin;
    size_t maxcand = 1;
    for (int d = 0; d < k->dim; ++d) {
        /* a periodic axis splits the reach into up to three runs: two more partial cells */
        double per_axis = floor((2 * rmax + g->size) * g->inv) + 3 + 2 * (k->im.P[d] > 0);
        maxcand *= per_axis < g->dims[d] ? (size_t)per_axis : g->dims[d];
    }
    return maxcand;
}

/* Row lengths offset[i + 1] into row offsets offset[i], in fixed blocks (called by every
 * thread of the region); offset[n] keeps the last row's length. */
static void scan_offsets(int64_t *offset, int64_t *bsum, size_t n)
{
#pragma omp for schedule(static)
    for (size_t b = 0; b < SCAN_BLOCKS; ++b) {
        int64_t s = 0;
        for (size_t i = b * n / SCAN_BLOCKS; i < (b + 1) * n / SCAN_BLOCKS; ++i)
            s += offset[i + 1];
        bsum[b] = s;
    }
#pragma omp single
    pst_exclusive_scan(bsum, SCAN_BLOCKS); /* no overflow: n < 2^32 rows of < 2^32 entries */
#pragma omp for schedule(static)
    for (size_t b = 0; b < SCAN_BLOCKS; ++b) {
        int64_t s = bsum[b];
        for (size_t i = b * n / SCAN_BLOCKS; i < (b + 1) * n / SCAN_BLOCKS; ++i) {
            int64_t v = offset[i + 1];
            offset[i] = s;
            s += v;
        }
    }
}

/* The list's index for the pairs the offsets count, and the merge buffers for the rows of a
 * cloud not in slot order (tmp, nth rows of L + 1). */
static int alloc_index(pst_nlist *nl, int identity, size_t L, int nth, uint32_t **tmp,
                       char *err)
{
    size_t n = nl->n;
    int64_t pairs = nl->offset[n - 1] + nl->offset[n]; /* offset[n]: the last row's count */
    nl->offset[n] = pairs;
    PST_CHECK((uint64_t)pairs > SIZE_MAX / sizeof(uint32_t), PST_ENOMEM, err,
              "neighbour list: %lld pairs overflow the address space", (long long)pairs);
    nl->index = pst_alloc((size_t)pairs * sizeof *nl->index);
    if (!identity)
        *tmp = pst_alloc((size_t)nth * (L + 1) * sizeof **tmp);
    PST_CHECK(!nl->index || (!identity && !*tmp), PST_ENOMEM, err,
              "neighbour list: cannot allocate %lld pairs (%.3g GB)", (long long)pairs,
              (double)pairs * 4e-9);
    return PST_OK;
}

/* The buffers of a build: the cell-ordered copy, the candidate cells of every thread, the
 * per-thread per-slot counters, the scan's block sums and the merge buffers. */
typedef struct {
    double *copy;
    cand *cl;
    uint32_t *cnts, *tmp;
    int64_t *bsum;
} build_buffers;

/* Count, scan and fill the list of n >= 2 rows, in one parallel region, so that the fill runs
 * with the same threads and cell partition as the count its cursors come from. */
static int fill_list(pst_nlist *nl, const pst_cloud *c, ctx *k, build_buffers *bb,
                     size_t maxcand, char *err)
{
    const pst_cells *g = k->g;
    size_t n = c->n, L = 0; /* the longest row */
    int dim = c->dim, varh = c->h != NULL, nth = omp_get_max_threads(), status = PST_OK;
    int identity = 1; /* slot order == cloud order: rows come out sorted */
#pragma omp parallel
    {
        int t = omp_get_thread_num(), nt = omp_get_num_threads();
#pragma omp for schedule(static) reduction(&& : identity)
        for (size_t p = 0; p < n; ++p) {
            uint32_t i = g->order[p];
            identity = identity && i == p;
            for (int d = 0; d < dim; ++d)
                bb->copy[(size_t)d * n + p] = c->x[d][i];
            if (varh)
                bb->copy[(size_t)dim * n + p] = c->h[i];
        }
        size_t c0 = first_cell(g, (size_t)t * n / (size_t)nt);
        size_t c1 = t + 1 == nt ? g->ncells : first_cell(g, (size_t)(t + 1) * n / (size_t)nt);
        uint32_t *cur = bb->cnts + (size_t)t * n;
        for (int u = t; u < nth; u += nt) /* zeroed in parallel, not by one thread before */
            memset(bb->cnts + (size_t)u * n, 0, n * sizeof *bb->cnts);
        pass(k, c0, c1, bb->cl + (size_t)t * maxcand, cur);
#pragma omp barrier
        /* row lengths; thread u's counts of a row become its cursor: the sum of the counts of
         * threads 0..u-1 */
#pragma omp for schedule(static) reduction(max : L)
        for (size_t p = 0; p < n; ++p) {
            size_t len = 0;
            for (int u = 0; u < nth; ++u) {
                uint32_t v = bb->cnts[(size_t)u * n + p];
                bb->cnts[(size_t)u * n + p] = (uint32_t)len;
                len += v;
            }
            nl->offset[(size_t)g->order[p] + 1] = (int64_t)len;
            L = len > L ? len : L;
        }
        scan_offsets(nl->offset, bb->bsum, n);
#pragma omp single
        {
            status = alloc_index(nl, identity, L, nth, &bb->tmp, err);
            k->offset = nl->offset;
            k->index = nl->index;
        } /* implicit barrier: status, k and tmp are seen by every thread */
        if (status == PST_OK) {
            pass(k, c0, c1, bb->cl + (size_t)t * maxcand, cur);
            if (!identity) {
#pragma omp barrier
#pragma omp for schedule(dynamic, 4096)
                for (size_t i = 0; i < n; ++i)
                    sort_row(nl->index + nl->offset[i], bb->tmp + (size_t)t * (L + 1),
                             (size_t)(nl->offset[i + 1] - nl->offset[i]));
            }
        }
    }
    return status;
}

int pst_nlist_build(pst_nlist **out, const pst_cloud *c, double support, char *err)
{
    return pst_nlist_build_with(out, c, support, NULL, err);
}

int pst_nlist_build_with(pst_nlist **out, const pst_cloud *c, double support,
                         const pst_progress *progress, char *err)
{
    *out = NULL;
    PST_TRY(pst_nlist_check_cloud(c, support, err));
    size_t n = c->n;
    pst_nlist *nl = NULL;
    PST_TRY(new_list(&nl, n, support, err));
    if (n < 2) {
        pst_tally tally;
        pst_tally_finish(pst_tally_start(&tally, progress, 2 * (uint64_t)n));
        *out = nl;
        return PST_OK;
    }
    double hmax = pst_cloud_h_max(c);
    pst_cells g;
    int status = pst_cells_build(&g, c, support * hmax / CELL_DIV, err);
    if (status != PST_OK) {
        pst_nlist_destroy(nl);
        return status;
    }
    int nth = omp_get_max_threads();
    build_buffers bb = {.copy = pst_alloc(n * (size_t)(c->dim + (c->h != NULL)) * sizeof(double)),
                        .cnts = pst_alloc((size_t)nth * n * sizeof(uint32_t)),
                        .bsum = calloc(SCAN_BLOCKS, sizeof(int64_t))};
    if (!bb.copy || !bb.cnts || !bb.bsum) {
        status = PST_ENOMEM;
        pst_set_err(err, "neighbour list: cannot allocate the cell-ordered copy of %zu "
                         "particles", n);
    } else {
        ctx k = search_ctx(c, &g, bb.copy, support, hmax);
        pst_tally tally; /* two passes over every slot: the count and the fill */
        k.tally = pst_tally_start(&tally, progress, 2 * (uint64_t)n);
        size_t maxcand = max_candidates(&k, support);
        bb.cl = pst_alloc((size_t)nth * maxcand * sizeof *bb.cl);
        if (!bb.cl) {
            status = PST_ENOMEM;
            pst_set_err(err, "neighbour list: cannot allocate %d x %zu candidate cells", nth,
                        maxcand);
        } else {
            status = fill_list(nl, c, &k, &bb, maxcand, err);
            if (status == PST_OK)
                pst_tally_finish(k.tally);
        }
    }
    pst_free(bb.cl);
    pst_free(bb.tmp);
    pst_free(bb.copy);
    pst_free(bb.cnts);
    free(bb.bsum);
    pst_cells_free(&g);
    if (status != PST_OK) {
        pst_nlist_destroy(nl);
        return status;
    }
    *out = nl;
    return PST_OK;
}

void pst_nlist_adopt(pst_nlist *nl, pst_nlist *fresh)
{
    pst_free(nl->offset);
    pst_free(nl->index);
    nl->offset = fresh->offset;
    nl->index = fresh->index;
    fresh->offset = NULL;
    fresh->index = NULL;
    pst_nlist_destroy(fresh);
}

void pst_nlist_destroy(pst_nlist *nl)
{
    if (!nl)
        return;
    pst_free(nl->offset);
    pst_free(nl->index);
    pst_verlet_free(nl->verlet);
    free(nl);
}

size_t pst_nlist_rows(const pst_nlist *nl) { return nl->n; }
double pst_nlist_support(const pst_nlist *nl) { return nl->support; }
const int64_t *pst_nlist_offsets(const pst_nlist *nl) { return nl->offset; }
const uint32_t *pst_nlist_indices(const pst_nlist *nl) { return nl->index; }
int64_t pst_nlist_pairs(const pst_nlist *nl) { return nl->offset[nl->n]; }

void pst_nlist_get_stats(const pst_nlist *nl, pst_nlist_stats *s)
{
    size_t n = nl->n;
    int64_t mn = n ? INT64_MAX : 0, mx = 0;
    size_t isolated = 0;
#pragma omp parallel for schedule(static) reduction(min : mn) reduction(max : mx)              \
    reduction(+ : isolated)
    for (size_t i = 0; i < n; ++i) {
        int64_t len = nl->offset[i + 1] - nl->offset[i];
        mn = len < mn ? len : mn;
        mx = len > mx ? len : mx;
        isolated += len == 0;
    }
    s->pairs = nl->offset[n];
    s->min = mn;
    s->max = mx;
    s->mean = n ? (double)s->pairs / (double)n : 0.0;
    s->isolated = isolated;
    /* a Verlet list's index holds its capacity, counted with the wide list and the positions
     * it keeps */
    s->bytes = sizeof *nl + (n + 1) * sizeof *nl->offset +
               (nl->verlet ? pst_verlet_bytes(nl->verlet, n)
                           : (size_t)s->pairs * sizeof *nl->index);
}
