/* The matrix-free apply on a half neighbour list (pst_op_use_half_list; docs/operators.md,
 * "The half-list apply"). Each pair (I, J > I) is stored once and visited once: the scheme's
 * half_rows computes both of its weights and writes y_I and y_J. Two threads must never write
 * one y_J at a time, and every y_I must receive its terms in an order that does not depend on
 * the thread count. So the rows are cut into blocks of a fixed size, and the blocks are
 * coloured (greedily, in block order) so that two blocks of one colour write disjoint sets of
 * blocks of y. The colours run one after another, the blocks of a colour in parallel, the rows
 * of a block in order: the order of every sum is fixed by the list alone. */
#include "check.h"
#include "operator.h"

#include <omp.h>
#include <stdlib.h>
#include <string.h>

/* Rows per block: large enough that a 3D block's neighbours reach few other blocks (39 colours
 * at the quintic support, h = 1.2 s0), small enough for about 12 blocks per colour at 10^6 rows
 * and 120 at 10^7 (2 threads need 2; a 16-core machine wants the 10^7 clouds this layout is
 * for). Doubled while the greedy colouring needs more than HALF_COLOURS colours (one bit each in
 * a 64-bit mask). */
#define HALF_BLOCK 2048
#define HALF_COLOURS 64

struct pst_half_schedule {
    size_t block;         /* rows per block                                        */
    size_t nblocks;
    int ncolours;
    size_t *colour_start; /* ncolours + 1 offsets into order                       */
    uint32_t *order;      /* the blocks, by colour, in increasing order inside one */
};

void pst_half_schedule_free(struct pst_half_schedule *h)
{
    if (!h)
        return;
    free(h->colour_start);
    free(h->order);
    free(h);
}

/* The blocks of y that block b writes: its own and those of its rows' neighbours, each once,
 * into out (NULL: count only). seen[] is the calling thread's, stamped with b + 1. */
static size_t block_targets(const int64_t *off, const uint32_t *idx, size_t n, size_t block,
                            size_t b, uint32_t *seen, uint32_t *out)
{
    size_t m = 0;
    seen[b] = (uint32_t)b + 1;
    if (out)
        out[m] = (uint32_t)b;
    m++;
    size_t i1 = (b + 1) * block < n ? (b + 1) * block : n;
    for (int64_t e = off[b * block]; e < off[i1]; ++e) {
        size_t t = idx[e] / block;
        if (seen[t] != (uint32_t)b + 1) {
            seen[t] = (uint32_t)b + 1;
            if (out)
                out[m] = (uint32_t)t;
            m++;
        }
    }
    return m;
}

/* The target sets of every block as CSR (toff, tgt): two threaded passes, count then fill,
 * each block's set in the order its rows reach them. PST_ENOMEM. */
static int all_targets(const int64_t *off, const uint32_t *idx, size_t n, size_t block,
                       size_t nb, size_t **ptoff, uint32_t **ptgt)
{
    size_t *toff = calloc(nb + 1, sizeof *toff);
    uint32_t *seen = calloc((size_t)omp_get_max_threads() * nb, sizeof *seen), *tgt = NULL;
    int st = !toff || !seen ? PST_ENOMEM : PST_OK;
    for (int pass = 0; st == PST_OK && pass < 2; ++pass) {
#pragma omp parallel
        {
            uint32_t *mine = seen + (size_t)omp_get_thread_num() * nb;
#pragma omp for schedule(dynamic, 4)
            for (size_t b = 0; b < nb; ++b) {
                size_t m = block_targets(off, idx, n, block, b, mine, pass ? tgt + toff[b] : NULL);
                if (!pass)
                    toff[b + 1] = m;
            }
        }
        if (!pass) {
            for (size_t b = 0; b < nb; ++b)
                toff[b + 1] += toff[b];
            memset(seen, 0, (size_t)omp_get_max_threads() * nb * sizeof *seen);
            tgt = malloc((toff[nb] + 1) * sizeof *tgt);
            st = tgt ? PST_OK : PST_ENOMEM;
        }
    }
    free(seen);
    if (st != PST_OK) {
        free(toff);
        free(tgt);
        return st;
    }
    *ptoff = toff;
    *ptgt = tgt;
    return PST_OK;
}

/* Greedy colouring in block order: block b takes the lowest colour that no earlier block
 * writing one of b's target blocks has. colour[] gets the colours; returns their number, or
 * HALF_COLOURS + 1 when that is not enough. */
static int colour_blocks(const size_t *toff, const uint32_t *tgt, size_t nb, uint8_t *colour,
                         uint64_t *used)
{
    int ncol = 0;
    memset(used, 0, nb * sizeof *used);
    for (size_t b = 0; b < nb; ++b) {
        uint64_t taken = 0;
        for (size_t e = toff[b]; e < toff[b + 1]; ++e)
            taken |= used[tgt[e]];
        if (taken == UINT64_MAX)
            return HALF_COLOURS + 1;
        int c = __builtin_ctzll(~taken);
        colour[b] = (uint8_t)c;
        for (size_t e = toff[b]; e < toff[b + 1]; ++e)
            used[tgt[e]] |= UINT64_C(1) << c;
        ncol = c + 1 > ncol ? c + 1 : ncol;
    }
    return ncol;
}

/* The schedule of one block size: NULL on allocation failure, ncolours > HALF_COLOURS when the
 * colours did not suffice. */
static struct pst_half_schedule *schedule_of(const pst_nlist *half, size_t block)
{
    const int64_t *off = pst_nlist_offsets(half);
    const uint32_t *idx = pst_nlist_indices(half);
    size_t n = pst_nlist_rows(half), nb = (n + block - 1) / block;
    struct pst_half_schedule *h = calloc(1, sizeof *h);
    size_t *toff = NULL;
    uint32_t *tgt = NULL;
    uint8_t *colour = malloc(nb + 1);
    uint64_t *used = malloc((nb + 1) * sizeof *used);
    if (!h || !colour || !used || all_targets(off, idx, n, block, nb, &toff, &tgt) != PST_OK)
        goto fail;
    h->block = block;
    h->nblocks = nb;
    h->ncolours = colour_blocks(toff, tgt, nb, colour, used);
    if (h->ncolours <= HALF_COLOURS) {
        h->colour_start = calloc((size_t)h->ncolours + 2, sizeof *h->colour_start);
        h->order = malloc((nb + 1) * sizeof *h->order);
        if (!h->colour_start || !h->order)
            goto fail;
        for (size_t b = 0; b < nb; ++b)
            h->colour_start[colour[b] + 1]++;
        for (int c = 0; c < h->ncolours; ++c)
            h->colour_start[c + 1] += h->colour_start[c];
        memcpy(used, h->colour_start, (size_t)h->ncolours * sizeof *used); /* write cursors */
        for (size_t b = 0; b < nb; ++b)
            h->order[used[colour[b]]++] = (uint32_t)b;
    }
    free(toff);
    free(tgt);
    free(colour);
    free(used);
    return h;

fail:
    pst_half_schedule_free(h);
    free(toff);
    free(tgt);
    free(colour);
    free(used);
    return NULL;
}

void pst_op_apply_half(const pst_op *op, const double *u, double *y)
{
    const struct pst_half_schedule *h = op->half;
    const int64_t *off = pst_nlist_offsets(op->nl);
    const uint32_t *idx = pst_nlist_indices(op->nl);
    const size_t n = op->n;
#pragma omp parallel
    {
#pragma omp for schedule(static)
        for (size_t i = 0; i < n; ++i)
            y[i] = 0.0;
        /* the barrier at the end of each loop orders the colours */
        for (int c = 0; c < h->ncolours; ++c) {
#pragma omp for schedule(dynamic, 1)
            for (size_t k = h->colour_start[c]; k < h->colour_start[c + 1]; ++k) {
                size_t i0 = (size_t)h->order[k] * h->block;
                size_t i1 = i0 + h->block < n ? i0 + h->block : n;
                op->scheme->half_rows(op, off, idx, i0, i1, u, y);
            }
        }
    }
}

static int check_half(const pst_op *op, const pst_nlist *half, char *err)
{
    PST_CHECK(!op || !half, PST_EINVAL, err, "pst_op_use_half_list needs an operator and a list");
    PST_CHECK(!op->scheme->half_rows, PST_EINVAL, err,
              "scheme '%s' has no half-list apply (pst_scheme_supports PST_SUPPORTS_HALF_LIST)",
              op->scheme->name);
    PST_CHECK(!op->rows, PST_EINVAL, err,
              "the operator was built without rows (laplacian = 0): it has no apply");
    PST_CHECK(op->half, PST_EINVAL, err, "the operator already uses a half list");
    PST_CHECK(pst_op_has_store(op), PST_EINVAL, err,
              "the operator has stored weights: the stored apply is faster than any list");
    PST_CHECK(!pst_nlist_is_half(half) || pst_nlist_rows(half) != op->n ||
                  pst_nlist_support(half) != pst_nlist_support(op->nl) ||
                  2 * pst_nlist_pairs(half) != pst_nlist_pairs(op->nl),
              PST_EINVAL, err,
              "the list is not the half (pst_nlist_halve) of the list the operator was built on");
    PST_CHECK(op->n > (size_t)UINT32_MAX, PST_EINVAL, err,
              "a half list of more than 2^32 - 1 rows has no block schedule");
    return PST_OK;
}

int pst_op_use_half_list(pst_op *op, const pst_nlist *half, char *err)
{
    PST_TRY(check_half(op, half, err));
    double *diag = pst_alloc((op->n + 1) * sizeof *diag);
    PST_CHECK_ALLOC(diag, err, "cannot allocate the diagonal of %zu rows", op->n);
    /* the diagonal needs whole rows: taken now, while the whole list is still there */
    if (pst_op_diagonal(op, diag) != PST_OK) {
        pst_free(diag);
        pst_set_err(err, "out of memory for the operator's diagonal");
        return PST_ENOMEM;
    }
    struct pst_half_schedule *h = NULL;
    for (size_t block = HALF_BLOCK;; block *= 2) { /* ends: one block needs one colour */
        h = schedule_of(half, block);
        if (!h || h->ncolours <= HALF_COLOURS)
            break;
        pst_half_schedule_free(h);
    }
    if (!h) {
        pst_free(diag);
        pst_set_err(err, "out of memory for the half list's block schedule");
        return PST_ENOMEM;
    }
    op->half = h;
    op->half_diag = diag;
    op->nl = half;
    op->poff = NULL; /* nothing may read the whole list any more */
    op->pidx = NULL;
    return PST_OK;
}

int pst_op_half_colours(const pst_op *op) { return op->half ? op->half->ncolours : 0; }
