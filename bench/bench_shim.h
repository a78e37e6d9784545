/* A C-callable face of Google Benchmark: C benchmark bodies register themselves and drive the
 * timing loop through these calls; shim.cc implements them in C++. */
#ifndef PSTENCIL_BENCH_SHIM_H
#define PSTENCIL_BENCH_SHIM_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct pstb_state pstb_state;

/* A benchmark body: set up (untimed), then `while (pstb_keep_running(s)) { ... }`. */
typedef void (*pstb_fn)(pstb_state *s);

/* Register `fn` under `name` once per argument in args[0..nargs) (read with pstb_arg); timed
 * in wall-clock time (OpenMP bodies), reported in milliseconds. */
void pstb_register(const char *name, pstb_fn fn, const int64_t *args, int nargs);
/* As pstb_register, with a fixed number of timed iterations (iterations <= 0: Google Benchmark
 * picks the count from --benchmark_min_time). A fixed count also runs the body only once, so
 * its untimed setup is paid once per argument. */
void pstb_register_iters(const char *name, pstb_fn fn, const int64_t *args, int nargs,
                         int64_t iterations);

int pstb_keep_running(pstb_state *s);
int64_t pstb_arg(const pstb_state *s);
void pstb_pause(pstb_state *s);
void pstb_resume(pstb_state *s);
void pstb_skip(pstb_state *s, const char *message);

/* A counter: a plain value, or (rate != 0) value per second per iteration. */
void pstb_counter(pstb_state *s, const char *name, double value, int rate);

/* A key/value pair of the run's context (Google Benchmark's AddCustomContext: printed in the
 * console header, the "context" object of --benchmark_format=json). Call it from
 * pstb_register_all, before the benchmarks run; a key given twice is an error. */
void pstb_context(const char *key, const char *value);

/* Defined by the C side: registers every benchmark. */
void pstb_register_all(void);

#ifdef __cplusplus
}
#endif

#endif
