/* The counter behind a progress hook (pst_progress, pstencil/core.h): rows done, added once per
 * chunk by the thread that finished it, and the hook called under a try-lock so that it is
 * never entered twice at once and never sees the count go back. Internal. */
#ifndef PSTENCIL_TALLY_H
#define PSTENCIL_TALLY_H

#include "internal.h"

#include <stdatomic.h>

typedef struct {
    pst_progress hook;
    uint64_t total;
    _Atomic uint64_t done;
    atomic_flag busy; /* held while the hook runs */
    uint64_t shown;   /* the last count the hook saw (read and written under busy) */
} pst_tally;

/* A tally of `total` units for hook p; NULL when p is NULL or has no fn, so that the chunks
 * of a call without a hook cost one test of a pointer. t is the caller's storage. */
pst_tally *pst_tally_start(pst_tally *t, const pst_progress *p, uint64_t total);

/* Count `units` finished and report them unless the hook is busy (pst_tally_add's slow path). */
void pst_tally_report(pst_tally *t, uint64_t units);

/* Count `units` finished: the one branch per chunk that a call without a hook pays. */
static inline void pst_tally_add(pst_tally *t, uint64_t units)
{
    if (t)
        pst_tally_report(t, units);
}

/* The end of a successful call, from the calling thread outside any parallel region: the
 * hook sees done == total. */
void pst_tally_finish(pst_tally *t);

/* Rows per chunk of a row loop that counts its rows (PST_CHUNK_ROWS): a count per chunk is
 * cheap beside the chunk's pairs, and a million rows still give ~2000 counts. */
#define PST_CHUNK 512

/* The number of chunks of `chunk` rows that cover n rows. */
static inline size_t pst_chunks(size_t n, size_t chunk) { return (n + chunk - 1) / chunk; }

/* The rows i of chunk b of [0, n), then the chunk counted in tally t (NULL: none): the body of
 * an OpenMP loop over b < pst_chunks(n, chunk). The count is made once, when the rows run out,
 * so a `continue` in the body is safe (a `break` would lose the chunk's count). */
#define PST_CHUNK_ROWS(t, b, n, chunk, i)                                                     \
    for (size_t i = (b) * (chunk), pst_end_ = i + (chunk) < (n) ? i + (chunk) : (n);           \
         i < pst_end_ || (pst_tally_add((t), pst_end_ - (b) * (chunk)), 0); ++i)

#endif
