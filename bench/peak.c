/* The FP64 multiply-add probe of peak.h. Each thread runs NACC independent chains
 * acc[k] = acc[k] * a + b; NACC covers latency x throughput (4-cycle FMA, two ports: 8 vectors
 * in flight), so the chains keep the FMA units busy if the compiler keeps them in registers.
 * a < 1 and b small keep every value near b / (1 - a): no overflow, no subnormals. */
#include "peak.h"
#include "stream.h"

#include <omp.h>
#include <stdio.h>

#define PEAK_ITERS 200000L /* multiply-add steps per chain per timed run */

/* MADD(x, a, b) = x * a + b: a multiply and an add in the default kernel (ISO C17 mode:
 * GCC's -std=c17 implies -ffp-contract=off, so nothing is fused), one fused multiply-add
 * (__builtin_fma) in the FMA multiversions. */
#define PEAK_KERNEL(NAME, NACC, MADD)                                                         \
    static double NAME(long iters, double a, double b)                                       \
    {                                                                                         \
        double acc[NACC];                                                                     \
        for (int k = 0; k < NACC; ++k)                                                        \
            acc[k] = 1.0 + 1e-3 * k;                                                          \
        for (long i = 0; i < iters; ++i) {                                                    \
            _Pragma("omp simd") for (int k = 0; k < NACC; ++k) acc[k] = MADD(acc[k], a, b);    \
        }                                                                                     \
        double s = 0;                                                                         \
        for (int k = 0; k < NACC; ++k)                                                        \
            s += acc[k];                                                                      \
        return s;                                                                             \
    }

/* default flags: 16 doubles (8 SSE2 vectors) */
#define MADD_PLAIN(x, a, b) ((x) * (a) + (b))
PEAK_KERNEL(kernel_default, 16, MADD_PLAIN)
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#define PEAK_X86 1
/* AVX2 + FMA: 48 doubles = 12 ymm vectors */
#define MADD_FMA(x, a, b) __builtin_fma(x, a, b)
__attribute__((target("avx2,fma"))) PEAK_KERNEL(kernel_avx2, 48, MADD_FMA)
/* AVX-512: 96 doubles = 12 zmm vectors */
__attribute__((target("avx512f"))) PEAK_KERNEL(kernel_avx512, 96, MADD_FMA)
#endif

typedef double (*kernel_fn)(long, double, double);

static kernel_fn pick(const char **isa, int *nacc)
{
#ifdef PEAK_X86
    __builtin_cpu_init();
    if (__builtin_cpu_supports("avx512f")) {
        *isa = "avx512f";
        *nacc = 96;
        return kernel_avx512;
    }
    if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) {
        *isa = "avx2+fma";
        *nacc = 48;
        return kernel_avx2;
    }
#endif
    *isa = "default";
    *nacc = 16;
    return kernel_default;
}

static volatile double pstb_peak_sink; /* keeps the results alive */

pstb_peak pstb_peak_probe(int threads, int reps)
{
    pstb_peak r = {0, NULL, threads > 0 ? threads : omp_get_max_threads()};
    int nacc;
    kernel_fn k = pick(&r.isa, &nacc);
    const double a = 0.999999, b = 1e-6;
    for (int rep = -1; rep < reps; ++rep) { /* rep -1: warm-up (frequency ramp, thread start) */
        double t = 0, sink = 0;
#pragma omp parallel num_threads(r.threads) reduction(+ : sink)
        {
#pragma omp barrier
#pragma omp master
            t = omp_get_wtime();
            sink += k(PEAK_ITERS, a, b);
#pragma omp barrier
#pragma omp master
            t = omp_get_wtime() - t;
        }
        pstb_peak_sink = sink;
        double gf = 2.0 * (double)nacc * (double)PEAK_ITERS * r.threads / t * 1e-9;
        if (rep >= 0 && gf > r.gflops)
            r.gflops = gf;
    }
    return r;
}

void pstb_probes_run(pstb_probes *p)
{
    pst_machine_probe(&p->machine);
    p->threads = omp_get_max_threads();
    int saved = p->threads;
    omp_set_num_threads(1);
    p->triad_gbs[0] = pstb_triad_gbs(10000000, 10);
    omp_set_num_threads(saved);
    p->triad_gbs[1] = pstb_triad_gbs(10000000, 10);
    p->peak[0] = pstb_peak_probe(1, 5);
    p->peak[1] = pstb_peak_probe(saved, 5);
}

void pstb_probes_record(const pstb_probes *p, void (*add)(const char *key, const char *value))
{
    const char *keys[PST_MACHINE_NPAIRS];
    char values[PST_MACHINE_NPAIRS][PST_MACHINE_VLEN];
    int n = pst_machine_pairs(&p->machine, keys, values, PST_MACHINE_NPAIRS);
    for (int i = 0; i < n; ++i)
        add(keys[i], values[i]);
    char key[32], value[64];
    int t[2] = {1, p->threads};
    for (int i = 0; i < 2; ++i) {
        snprintf(key, sizeof key, "triad_gbs_%dt", t[i]);
        snprintf(value, sizeof value, "%.2f", p->triad_gbs[i]);
        add(key, value);
        snprintf(key, sizeof key, "fp64_gflops_%dt", t[i]);
        snprintf(value, sizeof value, "%.2f", p->peak[i].gflops);
        add(key, value);
    }
    add("fp64_kernel", p->peak[1].isa);
}

int pstb_probes_line(const pstb_probes *p, char *buf, size_t len)
{
    char m[1024];
    pst_machine_line(&p->machine, m, sizeof m);
    return snprintf(buf, len,
                    "%s; triad %.1f / %.1f GB/s, FP64 peak %.1f / %.1f GFLOP/s (1 / %d threads, "
                    "%s kernel)",
                    m, p->triad_gbs[0], p->triad_gbs[1], p->peak[0].gflops, p->peak[1].gflops,
                    p->threads, p->peak[1].isa);
}
