/* pst_sqrt_block (wls.h): the square roots of a block of values in vector instructions. */
#include "wls.h"

#include <math.h>
#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#endif

/* GCC does not vectorise sqrt while it may set errno (the default -fmath-errno; the optimize
 * attribute does not lift it), and the scalar sqrt with its errno check costs ~2.8 ns here, as
 * much as the rest of a pair's weight. These take the vector instruction directly: sqrt is
 * correctly rounded in every width, so the values are those of sqrt() bit for bit. Measured
 * per value (this EPYC, one thread): scalar 2.8 ns, SSE2 1.4, AVX 0.6, AVX-512 0.3. */
#if defined(__x86_64__) && defined(__GNUC__)
__attribute__((target("avx512f"))) static void sqrt_avx512(int n, const double *a, double *b)
{
    int c = 0;
    for (; c + 8 <= n; c += 8)
        _mm512_storeu_pd(b + c, _mm512_sqrt_pd(_mm512_loadu_pd(a + c)));
    if (c < n) {
        __mmask8 m = (__mmask8)((1u << (n - c)) - 1);
        _mm512_mask_storeu_pd(b + c, m, _mm512_sqrt_pd(_mm512_maskz_loadu_pd(m, a + c)));
    }
}

__attribute__((target("avx"))) static void sqrt_avx(int n, const double *a, double *b)
{
    int c = 0;
    for (; c + 4 <= n; c += 4)
        _mm256_storeu_pd(b + c, _mm256_sqrt_pd(_mm256_loadu_pd(a + c)));
    for (; c < n; ++c)
        _mm_store_sd(b + c, _mm_sqrt_pd(_mm_load_sd(a + c)));
}

static void sqrt_sse2(int n, const double *a, double *b)
{
    int c = 0;
    for (; c + 2 <= n; c += 2)
        _mm_storeu_pd(b + c, _mm_sqrt_pd(_mm_loadu_pd(a + c)));
    if (c < n)
        _mm_store_sd(b + c, _mm_sqrt_pd(_mm_load_sd(a + c)));
}

void pst_sqrt_block(int n, const double *a, double *b)
{
#if !defined(PSTENCIL_NO_ISA_DISPATCH) && !defined(__clang__)
    /* the levels of PST_ISA_DISPATCH's resolver (pst_isa()) */
    if (__builtin_cpu_supports("x86-64-v4"))
        sqrt_avx512(n, a, b);
    else if (__builtin_cpu_supports("x86-64-v3"))
        sqrt_avx(n, a, b);
    else
        sqrt_sse2(n, a, b);
#elif defined(__AVX512F__)
    sqrt_avx512(n, a, b);
#elif defined(__AVX__)
    sqrt_avx(n, a, b);
#else
    sqrt_sse2(n, a, b);
#endif
}
#else
void pst_sqrt_block(int n, const double *a, double *b)
{
    for (int c = 0; c < n; ++c)
        b[c] = sqrt(a[c]);
}
#endif
