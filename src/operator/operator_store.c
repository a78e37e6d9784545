/* The stored weights and the stored apply, in double (8 bytes per pattern entry) or in float
 * (4 bytes, pst_op_store_with). Either store serves pst_op_apply_stored and the solves that
 * take the stored path; the diagonal, assembly and audits always use the rows' double weights
 * (the double store, or emit_row). docs/operators.md, "Stored weights in float". */
#include "operator.h"
#include "check.h"
#include "isa.h"
#include "lanes8.h"

#include <float.h>
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <string.h>

int pst_op_has_store(const pst_op *op) { return op->w || op->w32; }

pst_store_precision pst_op_store_precision(const pst_op *op)
{
    return op->w ? PST_STORE_DOUBLE : op->w32 ? PST_STORE_FLOAT : PST_STORE_NONE;
}

void pst_op_store_defaults(pst_op_store_opts *o) { o->precision = PST_STORE_DOUBLE; }

/* The stored weights need the pattern for as long as they live: a wide one is built into op. */
static int own_pattern(pst_op *op)
{
    if (op->poff)
        return PST_OK;
    PST_TRY(op->scheme->wide_pattern(op, &op->own_poff, &op->own_pidx, NULL));
    op->poff = op->own_poff;
    op->pidx = op->own_pidx;
    return PST_OK;
}

static void drop_own_pattern(pst_op *op)
{
    if (!op->own_poff)
        return;
    pst_free(op->own_poff);
    pst_free(op->own_pidx);
    op->own_poff = NULL;
    op->own_pidx = NULL;
    op->poff = NULL;
    op->pidx = NULL;
}

void pst_op_drop_store(pst_op *op)
{
    if (!op)
        return;
    pst_free(op->w);
    pst_free(op->w32);
    pst_free(op->spare_w);
    op->w = NULL;
    op->w32 = NULL;
    op->spare_w = NULL;
    op->spare_bytes = op->w_bytes = 0;
    drop_own_pattern(op);
}

void pst_op_park_store(pst_op *op)
{
    void *w = op->w ? (void *)op->w : (void *)op->w32;
    if (w) {
        pst_free(op->spare_w);
        op->spare_w = w;
        op->spare_bytes = op->w_bytes;
    }
    op->w = NULL;
    op->w32 = NULL;
    op->w_bytes = 0;
    drop_own_pattern(op);
}

/* The array of `entries` weights of `size` bytes: a refresh's parked one while it holds them
 * (its pages touched already); else a new one, exactly the size on a first store (the memory
 * the planner counts), an eighth more on a refresh, so that a moving cloud's next patterns
 * fit. Its size into op->w_bytes; NULL when out of memory. */
static void *weights(pst_op *op, int64_t entries, size_t size)
{
    size_t need = (size_t)entries * size;
    void *w = op->spare_w;
    if (w && op->spare_bytes >= need) {
        op->w_bytes = op->spare_bytes;
    } else {
        op->w_bytes = w ? need + need / 8 : need;
        pst_free(w);
        w = pst_alloc(op->w_bytes);
    }
    op->spare_w = NULL;
    op->spare_bytes = 0;
    return w;
}

static int store_double(pst_op *op)
{
    const int64_t *off = op->poff;
    double *w = weights(op, off[op->n], sizeof *w);
    if (!w)
        return PST_ENOMEM;
    const uint8_t *kind = op->kind;
#pragma omp parallel for schedule(dynamic, 256)
    for (size_t i = 0; i < op->n; ++i) {
        if (kind[i] == PST_DIRICHLET)
            memset(w + off[i], 0, (size_t)(off[i + 1] - off[i]) * sizeof *w);
        else
            op->scheme->emit_row(op, i, w + off[i]);
    }
    op->w = w;
    return PST_OK;
}

/* Float keeps a row to 2^-24 of its largest weight when that weight is in
 * [FLOAT_ROW_MIN, FLT_MAX]: weights far below it may round to subnormals or zero (absolute
 * error <= 2^-150, under 2^-48 of the row's largest), which the bound covers. */
#define FLOAT_ROW_MIN 0x1p-102

static int row_fits_float(const double *w, size_t len)
{
    double m = 0;
    for (size_t k = 0; k < len; ++k)
        m = fmax(m, fabs(w[k]));
    return m == 0 || (m >= FLOAT_ROW_MIN && m <= FLT_MAX);
}

static double row_largest(const double *w, size_t len)
{
    double m = 0;
    for (size_t k = 0; k < len; ++k)
        m = fabs(w[k]) > fabs(m) ? w[k] : m;
    return m;
}

/* Each row emitted in double into a per-thread buffer, rounded to float; the first row (lowest
 * index, the same for every thread count) whose largest weight float cannot hold to 2^-24
 * refuses the store. */
static int store_float(pst_op *op, char *err)
{
    const int64_t *off = op->poff;
    int64_t longest = 0;
    for (size_t i = 0; i < op->n; ++i)
        longest = off[i + 1] - off[i] > longest ? off[i + 1] - off[i] : longest;
    float *w = weights(op, off[op->n], sizeof *w);
    double *scratch = pst_alloc((size_t)omp_get_max_threads() * ((size_t)longest + 1) *
                                sizeof *scratch);
    if (!w || !scratch) {
        pst_free(w);
        pst_free(scratch);
        pst_set_err(err, "cannot allocate the float weights (%lld entries)",
                    (long long)off[op->n]);
        return PST_ENOMEM;
    }
    const uint8_t *kind = op->kind;
    size_t bad = SIZE_MAX;
    double bad_value = 0;
#pragma omp parallel
    {
        double *buf = scratch + (size_t)omp_get_thread_num() * ((size_t)longest + 1);
#pragma omp for schedule(dynamic, 256) reduction(min : bad)
        for (size_t i = 0; i < op->n; ++i) {
            size_t len = (size_t)(off[i + 1] - off[i]);
            if (kind[i] == PST_DIRICHLET) {
                memset(w + off[i], 0, len * sizeof *w);
                continue;
            }
            op->scheme->emit_row(op, i, buf);
            if (!row_fits_float(buf, len) && i < bad)
                bad = i;
            for (size_t k = 0; k < len; ++k)
                w[off[i] + (int64_t)k] = (float)buf[k];
        }
    }
    if (bad != SIZE_MAX) {
        op->scheme->emit_row(op, bad, scratch);
        bad_value = row_largest(scratch, (size_t)(off[bad + 1] - off[bad]));
    }
    pst_free(scratch);
    if (bad != SIZE_MAX) {
        pst_free(w);
        pst_set_err(err,
                    "row %zu's largest weight %.3e is outside the range float keeps to 2^-24 "
                    "[%.3e, %.3e]: store in double (or rescale the coordinates)",
                    bad, bad_value, FLOAT_ROW_MIN, (double)FLT_MAX);
        return PST_ENUMERIC;
    }
    op->w32 = w;
    return PST_OK;
}

int pst_op_store_with(pst_op *op, const pst_op_store_opts *o, char *err)
{
    pst_op_store_opts d;
    if (!o) {
        pst_op_store_defaults(&d);
        o = &d;
    }
    PST_CHECK(!op, PST_EINVAL, err, "pst_op_store_with needs an operator");
    PST_CHECK(o->precision != PST_STORE_DOUBLE && o->precision != PST_STORE_FLOAT, PST_EINVAL,
              err, "unknown store precision %d (PST_STORE_DOUBLE or PST_STORE_FLOAT)",
              o->precision);
    PST_CHECK(!op->rows, PST_EINVAL, err,
              "the operator was built without rows (laplacian = 0): there are no weights");
    PST_CHECK(op->half, PST_EINVAL, err,
              "the operator uses a half list (pst_op_use_half_list): it keeps no pattern to "
              "store weights in");
    int have = pst_op_store_precision(op);
    if (have == o->precision)
        return PST_OK;
    PST_CHECK(have >= 0, PST_EINVAL, err,
              "the weights are already stored in %s: one store per operator",
              have == PST_STORE_DOUBLE ? "double" : "float");
    int st = own_pattern(op);
    PST_CHECK(st != PST_OK, st, err, "cannot build the rows' pattern");
    st = o->precision == PST_STORE_DOUBLE ? store_double(op) : store_float(op, err);
    if (st == PST_ENOMEM && o->precision == PST_STORE_DOUBLE)
        pst_set_err(err, "cannot allocate the weights (%lld entries)", (long long)op->poff[op->n]);
    if (st != PST_OK)
        drop_own_pattern(op); /* a caller that goes on matrix-free gets its memory back */
    return st;
}

int pst_op_store(pst_op *op) { return pst_op_store_with(op, NULL, NULL); }

/* The weights of the 8 pattern entries from k as two halves (double weights wd, or float wf
 * widened exactly). */
static inline __attribute__((always_inline)) void
block_weights(int single, const double *wd, const float *wf, int64_t k, pst_v4 *lo, pst_v4 *hi)
{
    if (single) {
        pst_v4_widen_halves(wf + k, lo, hi);
    } else {
        memcpy(lo, wd + k, sizeof *lo);
        memcpy(hi, wd + k + 4, sizeof *hi);
    }
}

/* w_IJ (u_J - u_I) of the 4 pattern entries from k with weights w, uiv = u_I in every lane. */
static inline __attribute__((always_inline)) pst_v4
half_terms(pst_v4 w, const uint32_t *idx, const double *u, int64_t k, pst_v4 uiv)
{
    return w * (pst_v4_gather(u, idx + k) - uiv);
}

/* The row's partial sums, lanes 0-3 and 4-7 of a block of 8 (src/core/lanes8.h, "Half
 * vectors": as one pst_v8 they lived on the stack in the AVX2 clone). */
typedef struct {
    pst_v4 lo, hi;
} row_sums;

/* sums + the block of 8 entries from k. */
static inline __attribute__((always_inline)) row_sums
add_block(row_sums a, int single, const double *wd, const float *wf, const uint32_t *idx,
          const double *u, int64_t k, pst_v4 uiv)
{
    pst_v4 wlo, whi;
    block_weights(single, wd, wf, k, &wlo, &whi);
    a.lo += half_terms(wlo, idx, u, k, uiv);
    a.hi += half_terms(whi, idx, u, k + 4, uiv);
    return a;
}

/* sums + the block of 8 entries from k in its lanes l with from + l < len (len in every
 * lane): the lanes past the row's end add nothing. */
static inline __attribute__((always_inline)) row_sums
add_block_below(row_sums a, int single, const double *wd, const float *wf,
                const uint32_t *idx, const double *u, int64_t k, pst_v4 uiv, double from,
                pst_v4 len)
{
    pst_v4 wlo, whi;
    block_weights(single, wd, wf, k, &wlo, &whi);
    a.lo = pst_v4_add_below(a.lo, half_terms(wlo, idx, u, k, uiv), from, len);
    a.hi = pst_v4_add_below(a.hi, half_terms(whi, idx, u, k + 4, uiv), from + 4, len);
    return a;
}

/* Rows of at most this many pairs (three blocks) are always taken as three blocks of 8. */
#define SHORT_ROW (3 * PST_LANES)

/* Rows [i0, i1) of the stored apply from the double weights wd or, with single, the float
 * weights wf (a float weight is widened exactly, so the float store differs only by its
 * weights' rounding, 2^-24 relative); end = off[n], the pattern's length. 8 pairs at a time
 * in two halves of 4 (src/core/lanes8.h): the weights as vector loads, u_J as element loads,
 * times u_J - u_I into 8 partial sums, neighbour c in lane c mod 8, the lanes combined in
 * pst_v8_sum's order, so the sum is the same for every ISA and thread count. The row's last
 * pairs (fewer than 8) are one more block of 8 whose lanes past the row's end (the next row's
 * entries) are kept out of the sums by a select: the same bits as adding the last pairs one by
 * one, which only the pattern's last row still does (no 8 entries after it). A short row
 * (<= SHORT_ROW pairs: the ~17-pair 2D rows of the LV family) is always three such blocks, so
 * that its loop has one trip count: with rows of 13 to 22 pairs the exit of the loop over full
 * blocks was unpredictable, which cost more than the loads of the lanes past the row (2D lv:
 * 6-17 % off the apply; bench/README.md, "short rows as three blocks").
 * Bound: per-core loads (8 index loads, 8 element loads merged into vectors, the weights'
 * loads per 8 pairs), near the memory's bandwidth: beside a triad of the same bytes
 * (bench_stored, 2026-12-07, 2 threads) 0.93-1.04 for the 3D rows of qsfdi, lpmps and lsmps,
 * 0.85-0.95 for lv's, 0.83-1.05 for most 2D runs; at 1 thread 0.85-0.92 for the 3D quintic
 * rows, 0.5-0.84 for the shorter ones, whose row is mostly its own instructions. Dirichlet
 * rows (their stored weights are zeros) are the identity and skip the stream: a boundary
 * layer is 6 % of the rows of a 100^3 cloud and 17 % of a 33^3 one. */
static inline __attribute__((always_inline)) void
stored_rows(const int64_t *off, const uint32_t *idx, int single, const double *wd,
            const float *wf, const uint8_t *kind, const double *u, double *y, size_t i0,
            size_t i1, int64_t end)
{
    for (size_t i = i0; i < i1; ++i) {
        if (kind[i] == PST_DIRICHLET) {
            y[i] = u[i];
            continue;
        }
        const double ui = u[i];
        const pst_v4 uiv = pst_v4_splat(ui);
        row_sums acc = {pst_v4_splat(0.0), pst_v4_splat(0.0)};
        int64_t k = off[i], len = off[i + 1] - k;
        if (len <= SHORT_ROW && k + SHORT_ROW <= end) {
            const pst_v4 lenv = pst_v4_splat((double)len);
            for (int b = 0; b < SHORT_ROW; b += PST_LANES)
                acc = add_block_below(acc, single, wd, wf, idx, u, k + b, uiv, b, lenv);
        } else {
            for (; k + PST_LANES <= off[i + 1]; k += PST_LANES)
                acc = add_block(acc, single, wd, wf, idx, u, k, uiv);
            int64_t rest = off[i + 1] - k;
            if (rest > 0 && k + PST_LANES <= end) {
                acc = add_block_below(acc, single, wd, wf, idx, u, k, uiv, 0,
                                      pst_v4_splat((double)rest));
            } else {
                for (int l = 0; k < off[i + 1]; ++k, ++l) {
                    double t = (single ? (double)wf[k] : wd[k]) * (u[idx[k]] - ui);
                    if (l < 4)
                        acc.lo[l] += t;
                    else
                        acc.hi[l - 4] += t;
                }
            }
        }
        y[i] = pst_v4_sum_halves(acc.lo, acc.hi);
    }
}

PST_ISA_DISPATCH static void rows_double(const int64_t *off, const uint32_t *idx,
                                         const double *w, const uint8_t *kind, const double *u,
                                         double *y, size_t i0, size_t i1, size_t n)
{
    stored_rows(off, idx, 0, w, NULL, kind, u, y, i0, i1, off[n]);
}

PST_ISA_DISPATCH static void rows_float(const int64_t *off, const uint32_t *idx, const float *w,
                                        const uint8_t *kind, const double *u, double *y,
                                        size_t i0, size_t i1, size_t n)
{
    stored_rows(off, idx, 1, NULL, w, kind, u, y, i0, i1, off[n]);
}

#define STORED_BLOCK 1024 /* rows per call of a worker: its dispatch costs < 0.1 % of a block */

/* Stored apply, y_I = sum_J w_IJ (u_J - u_I): the matrix-free apply's weights, so the two
 * paths agree to rounding. Per pair 8 bytes of weight (4 in float) + 4 of index streamed, u_J
 * gathered (Morton order keeps it in cache); about 12 (8) bytes and 3 flops. */
int pst_op_apply_stored(const pst_op *op, const double *u, double *y)
{
    if (!pst_op_has_store(op))
        return PST_EINVAL;
    double t0 = omp_get_wtime();
    size_t nb = (op->n + STORED_BLOCK - 1) / STORED_BLOCK;
#pragma omp parallel for schedule(static)
    for (size_t b = 0; b < nb; ++b) {
        size_t i0 = b * STORED_BLOCK, i1 = i0 + STORED_BLOCK < op->n ? i0 + STORED_BLOCK : op->n;
        if (op->w)
            rows_double(op->poff, op->pidx, op->w, op->kind, u, y, i0, i1, op->n);
        else
            rows_float(op->poff, op->pidx, op->w32, op->kind, u, y, i0, i1, op->n);
    }
    pst_op_record_apply(op, t0);
    return PST_OK;
}
