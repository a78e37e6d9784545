/* The FP64 peak this binary can reach with these flags (not the datasheet peak): independent
 * multiply-add chains on every OpenMP thread, in GFLOP/s (2 flops per multiply-add), plus the
 * machine record (src/machine.h) and the triad bandwidth (stream.h) the benchmarks print
 * beside their own numbers. */
#ifndef PSTENCIL_BENCH_PEAK_H
#define PSTENCIL_BENCH_PEAK_H

#include "machine.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    double gflops;   /* best of the repetitions, all threads together */
    const char *isa; /* the kernel used: "avx512f", "avx2+fma" or "default" (this build's flags) */
    int threads;
} pstb_peak;

/* Run the multiply-add kernel on `threads` OpenMP threads (<= 0: omp_get_max_threads()),
 * best of `reps` timed runs of about 20 ms each. The widest kernel the CPU supports is used:
 * a target("avx512f") or target("avx2,fma") multiversion of the kernel, else the default
 * flags' (SSE2 on x86-64 without -march: a multiply and an add, not fused). */
pstb_peak pstb_peak_probe(int threads, int reps);

/* The machine record and the probes, at 1 thread and at omp_get_max_threads(). */
typedef struct {
    pst_machine machine;
    int threads;                  /* omp_get_max_threads() at the probe */
    double triad_gbs[2];          /* [0] 1 thread, [1] `threads` threads; 3 x 80 MB triad */
    pstb_peak peak[2];            /* [0] 1 thread, [1] `threads` threads */
} pstb_probes;

void pstb_probes_run(pstb_probes *p);
/* The record as key/value strings through add(key, value): cpu, cores, caches, flags (the
 * pairs of pst_machine_pairs) and triad_gbs_1t, triad_gbs_<T>t, fp64_gflops_1t,
 * fp64_gflops_<T>t, fp64_kernel. */
void pstb_probes_record(const pstb_probes *p, void (*add)(const char *key, const char *value));
/* One line: "<machine line>; triad X / Y GB/s, FP64 peak X / Y GFLOP/s (1 / T threads, isa)". */
int pstb_probes_line(const pstb_probes *p, char *buf, size_t len);

#ifdef __cplusplus
}
#endif

#endif
