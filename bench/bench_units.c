/* The rates of the vector units a matrix-free row is made of (bench/README.md, "Which bound"):
 * nanoseconds per vector multiplication, addition, square root and division on one thread, in
 * the widest instruction set the CPU has. Each measurement runs UNITS_CHAINS independent chains
 * x = op(x) in the lanes of 12 vectors, enough to cover the latency of every unit on current
 * cores, so the time is the unit's throughput; best of 5 runs. A matrix-free row's cost per
 * pair set beside these (multiplications per pair x the multiplication's rate, and so on)
 * says which unit it could be bound by and how far it is from that bound. */
#include <omp.h>
#include <math.h>
#include <stdio.h>

#define UNITS_ITERS 400000L /* steps per chain per timed run */
#define UNITS_REPS 5

/* One chain step of each unit; every value stays near 1 or 2 (no overflow, no subnormals). */
#define STEP_MUL(x) ((x) * 0.999999999999)
#define STEP_ADD(x) ((x) + 1e-12)
#define STEP_SQRT(x) sqrt((x) + 2.0) /* the addition runs on other pipes than the sqrt */
#define STEP_DIV(x) (3.0 / ((x) + 1.0))

/* NAME(iters): NACC chains of STEP, vectorised across the chains; returns their sum so that
 * the compiler keeps the work. */
#define UNITS_KERNEL(NAME, NACC, STEP)                                                       \
    static double NAME(long iters)                                                           \
    {                                                                                        \
        double x[NACC];                                                                      \
        for (int k = 0; k < NACC; ++k)                                                       \
            x[k] = 1.0 + 1e-3 * k;                                                           \
        for (long i = 0; i < iters; ++i) {                                                   \
            _Pragma("omp simd") for (int k = 0; k < NACC; ++k) x[k] = STEP(x[k]);            \
        }                                                                                    \
        double s = 0;                                                                        \
        for (int k = 0; k < NACC; ++k)                                                       \
            s += x[k];                                                                       \
        return s;                                                                            \
    }

/* The four units at one vector width: WIDTH doubles per vector, 12 vectors of chains. */
#define UNITS_SET(SUFFIX, WIDTH, ATTR)                                                       \
    ATTR UNITS_KERNEL(mul_##SUFFIX, 12 * (WIDTH), STEP_MUL)                                  \
    ATTR UNITS_KERNEL(add_##SUFFIX, 12 * (WIDTH), STEP_ADD)                                  \
    ATTR UNITS_KERNEL(sqrt_##SUFFIX, 12 * (WIDTH), STEP_SQRT)                                \
    ATTR UNITS_KERNEL(div_##SUFFIX, 12 * (WIDTH), STEP_DIV)

UNITS_SET(default, 2, )
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#define UNITS_X86 1
UNITS_SET(avx2, 4, __attribute__((target("avx2,fma"))))
UNITS_SET(avx512, 8, __attribute__((target("avx512f"))))
#endif

typedef double (*unit_fn)(long);

typedef struct {
    const char *isa;
    int width;
    unit_fn fn[4];
} unit_set;

static unit_set pick(void)
{
#ifdef UNITS_X86
    __builtin_cpu_init();
    if (__builtin_cpu_supports("avx512f"))
        return (unit_set){"avx512f", 8, {mul_avx512, add_avx512, sqrt_avx512, div_avx512}};
    if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma"))
        return (unit_set){"avx2", 4, {mul_avx2, add_avx2, sqrt_avx2, div_avx2}};
#endif
    return (unit_set){"default", 2, {mul_default, add_default, sqrt_default, div_default}};
}

int main(void)
{
    static const char *name[4] = {"multiplication", "addition", "square root (+ an addition)",
                                  "division (+ an addition)"};
    unit_set u = pick();
    double sink = 0;
    printf("| unit (%s, %d doubles per vector, 1 thread) | ns per vector | ns per double |\n"
           "|---|---|---|\n",
           u.isa, u.width);
    for (int f = 0; f < 4; ++f) {
        double best = INFINITY;
        for (int r = 0; r < UNITS_REPS; ++r) {
            double t0 = omp_get_wtime();
            sink += u.fn[f](UNITS_ITERS);
            double t = omp_get_wtime() - t0;
            best = t < best ? t : best;
        }
        double per_vector = best / (12.0 * UNITS_ITERS) * 1e9;
        printf("| %s | %.3f | %.3f |\n", name[f], per_vector, per_vector / u.width);
    }
    volatile double keep = sink; /* the chains' results stay live */
    (void)keep;
    return 0;
}
