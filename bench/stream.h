/* A STREAM-style triad a[i] = b[i] + s c[i], the bandwidth reference the benchmarks print beside
 * their own rates. Bytes are counted as STREAM does: 24 per element (two reads, one write, no
 * write-allocate). */
#ifndef PSTENCIL_BENCH_STREAM_H
#define PSTENCIL_BENCH_STREAM_H

#include <stddef.h>

/* Fill the three arrays with the same static schedule as the timed loop (first touch places
 * the pages next to the threads that stream them). */
void pstb_triad_fill(double *a, double *b, double *c, size_t n);
/* One triad pass with s = 3; after pstb_triad_fill every a[i] is 7. */
void pstb_triad_pass(double *a, const double *b, const double *c, size_t n);
/* Best-of-`reps` triad bandwidth over n-element arrays with the current OpenMP thread count,
 * in GB/s (10^9 bytes); 0 when the arrays cannot be allocated or the result is wrong. */
double pstb_triad_gbs(size_t n, int reps);

#endif
