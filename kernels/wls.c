/* The weighted-least-squares engine of the quadric fits (spec qsfdi.md §2.5-2.6): the moment
 * pass, the moment matrix, the fallback levels, the precompute, the matrix-free apply and
 * emission, gradient, Hessian and interpolation. A scheme supplies only its factorisation of the
 * moment matrix (kernels/lsmps.c: LDL^T; kernels/lpmps.c: the Schur complement); qsfdi and the
 * mixed schemes use the vectorised moment sums (pst_wls_msums).
 *
 * Row I fits a full quadratic in the scaled offsets x^ = (x_j - x_I) / h_I (r_s = h, pinned
 * choice 3) by weighted least squares with the quintic weight w_j = f(|x^_j|) (QSFDI eq. 9; the
 * normalising constant cancels, so f is used without it):
 *     type B (variant 0): basis p^ = (1, x, y, xx, yy, xy)          6 / 10 (3D) unknowns, the
 *                         centre particle included with w(0) = f(0) = 66 in the constant moment;
 *     type A (variant 1): basis p  = (x, y, xx, yy, xy), data u_j - u_I   5 / 9 unknowns
 * (3D: 1, x, y, z, xx, yy, zz, xy, xz, yz). With M = sum_j w_j p_j p_j^T (+ w(0) e_0 e_0^T for
 * type B) the Laplacian weights are a_Ij = w_j lambda_I . p_j with lambda_I = M^-1 h^, h^ = 2/h_I^2
 * on the squares and 0 elsewhere; Neumann rows use h^ = n_I / h_I on the linear entries, the
 * fit's own n . grad u. Per particle only lambda (nb doubles) is kept: the matrix-free apply
 * recomputes x^, w and p from the positions. The precompute runs in blocks of particles, each
 * block as three threaded passes timed separately: moments (the distinct weighted monomial sums
 * of degree 0 (B) / 2 (A) to 4, one neighbour pass: the neighbours gathered into arrays, then
 * one vectorised reduction loop per degree), inversion (the scheme's factorisation) and weights
 * (the solve for lambda, or the fallback chain). Fallback chain: quadric fit (status ok or
 * ill-conditioned) -> the linear-exact fit on (x, y, |x|^2) (1 included for type B) -> a radial
 * row a_Ij = w_j |x^_j|^2 2D / (h^2 sum w |x^|^4) (exact for |x|^2) -> an empty row (no weighted
 * neighbour). Never NaN. */
#include "cells.h"
#include "check.h"
#include "isa.h"
#include "kernel_common.h"
#include "small_matrix.h"
#include "sph_kernels.h"
#include "wls.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>
#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#endif

/* ---- square roots of a block ---------------------------------------------------------------- */

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

/* Particles per block of the precompute: bounds the memory of the moments and factors kept
 * between passes (3D type B: 32768 x 235 doubles, 62 MB) and the number of parallel regions;
 * rows are dealt in dynamic chunks of 128 (each row is still computed by one thread, so the
 * results do not depend on the thread count). */
#define WLS_BLOCK 32768
/* Largest basis (3D type B) and number of monomials of degree 0..4 in 2D / 3D. */
#define WLS_NBMAX 10
#define WLS_NMOM(D) ((D) == 2 ? 15 : 35)

/* Fit levels of a row (the fallback chain in the file comment). */
enum { LVL_QUADRIC = 0, LVL_REDUCED = 1, LVL_RADIAL = 2, LVL_EMPTY = 3 };

/* Monomials of degree 0..4, ordered so that the first 6 (2D) / 10 (3D) are the type-B basis:
 * monomial k > 0 is monomial par[k] times coordinate var[k] (tables generated by a script). */
static const signed char wls_par[2][35] = {
    {-1, 0, 0, 1, 2, 2, 3, 5, 4, 4, 6, 7, 8, 9, 9},
    {-1, 0, 0, 0, 1, 2, 3, 2, 3, 3, 4, 7, 8, 5, 9, 6, 5, 9,
     6, 6, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 16, 17, 18, 19, 19}};
static const signed char wls_var[2][35] = {
    {-1, 0, 1, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1},
    {-1, 0, 1, 2, 0, 1, 2, 0, 0, 1, 0, 0, 0, 0, 0, 0, 1, 1, 1, 2, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
     1, 1, 1, 1, 2}};
/* The monomial index of the product of type-B basis entries a and b: M[a][b] = mom[sum]. */
static const signed char wls_sum2[6][6] = {
    {0, 1, 2, 3, 4, 5},    {1, 3, 5, 6, 8, 7},     {2, 5, 4, 7, 9, 8},
    {3, 6, 7, 10, 12, 11}, {4, 8, 9, 12, 14, 13}, {5, 7, 8, 11, 13, 12}};
static const signed char wls_sum3[10][10] = {
    {0, 1, 2, 3, 4, 5, 6, 7, 8, 9},
    {1, 4, 7, 8, 10, 13, 15, 11, 12, 14},
    {2, 7, 5, 9, 11, 16, 18, 13, 14, 17},
    {3, 8, 9, 6, 12, 17, 19, 14, 15, 18},
    {4, 10, 11, 12, 20, 23, 25, 21, 22, 24},
    {5, 13, 16, 17, 23, 30, 32, 26, 27, 31},
    {6, 15, 18, 19, 25, 32, 34, 28, 29, 33},
    {7, 11, 13, 14, 21, 26, 28, 23, 24, 27},
    {8, 12, 14, 15, 22, 27, 29, 24, 25, 28},
    {9, 14, 17, 18, 24, 31, 33, 27, 28, 32}};

typedef struct {
    int dim, typeB, nb;    /* nb = basis size: D + D(D+1)/2, plus 1 for type B */
    pst_kernel kernel;
    wls_factor_fn factor;
    wls_solve_fn solve;
    double *lam;           /* nb per particle: a_Ij = w_j lam_I . p_j            */
    uint8_t *level;        /* LVL_* per particle                                 */
} wls_data;

/* Everything the pair functions read, gathered once per call (the rows are those of the
 * neighbour list, c.off / c.idx: the engine keeps the default pattern). */
typedef struct {
    pst_kctx c;
    const wls_data *d;
} wls_ctx;

static wls_ctx make_ctx(const pst_op *op) { return (wls_ctx){.c = pst_kctx_of(op), .d = op->data}; }

/* The hot functions (PST_KHOT) take the dimension D, the type flag B and the kernel K as
 * arguments; the instantiations below call them with constants, so the pair loops carry no
 * branches on them. */
/* Scaled offset x^ = (x_j - x_c) * ih of a pair and its weight f(|x^|) (0 outside the support
 * and for degenerate pairs). */
PST_KHOT double pair_weight(const wls_ctx *k, int D, pst_kernel K, const double *xc, size_t j,
                           double ih, double xh[3])
{
    double q2 = 0;
    for (int a = 0; a < D; ++a) {
        xh[a] = (k->c.x[a][j] - xc[a]) * ih;
        q2 += xh[a] * xh[a];
    }
    double q = sqrt(q2);
    double f = pst_sph_shape(K, D, q, 0);
    return q < pst_sph_support[K] && q > k->c.pair_eps ? f : 0.0;
}

/* The moment passes gather a row's neighbours, a chunk at a time, into stack arrays (structure
 * of arrays), then form the sums as separate reduction loops over them that the compiler
 * vectorises. The order of a vectorised sum is fixed by the code, the same for every row and
 * thread: results do not depend on the thread count. A 3D row (~190 neighbours) is one chunk. */
#define WLS_CHUNK 256

/* Scaled offsets r[a][c] of the neighbours idx[0..n) of xc and their weights w (pair_weight's
 * values). Separate loops, so that only the sqrt stays scalar (GCC does not vectorise sqrt
 * while it may set errno, the default -fmath-errno) and the kernel loop has no select: GCC
 * would sink the kernel into a branch of it. Bound by the scalar sqrt and the gather: ~2 ns
 * per neighbour, about a quarter of the moment pass. */
PST_KHOT void gather(const wls_ctx *k, int D, pst_kernel K, const double *xc, double ih,
                    const uint32_t *idx, int n, double (*r)[WLS_CHUNK], double *w)
{
    double q[WLS_CHUNK];
    for (int c = 0; c < n; ++c)
        for (int a = 0; a < D; ++a)
            r[a][c] = (k->c.x[a][idx[c]] - xc[a]) * ih;
    for (int c = 0; c < n; ++c)
        w[c] = r[0][c] * r[0][c] + r[1][c] * r[1][c] + (D == 3 ? r[2][c] * r[2][c] : 0.0);
    pst_sqrt_block(n, w, q);
#pragma omp simd
    for (int c = 0; c < n; ++c)
        w[c] = pst_sph_shape(K, D, q[c], 0);
    const double supp = pst_sph_support[K], eps = k->c.pair_eps;
#pragma omp simd
    for (int c = 0; c < n; ++c)
        w[c] = (q[c] < supp) & (q[c] > eps) ? w[c] : 0.0;
}

/* s[.] += sum_c w_c m(r_c) over the monomials m of one degree (1 to 4) in graded
 * lexicographic order (2D: x y | xx xy yy | xxx xxy xyy yyy | xxxx xxxy xxyy xyyy yyyy; 3D
 * likewise with z; z is not read in 2D). One vectorised reduction loop per degree, at most 15
 * accumulators so that they stay in registers. Compute-bound: a multiply and an add per sum
 * and neighbour (ISO C mode: no FMA contraction) plus the shared products; qsfdi's 56 sums
 * in 3D take ~8 ns per neighbour with SSE2 (2 lanes), ~4.3 with -march=native (4 lanes). */
PST_KHOT void wls_msum1(int D, int n, const double *x, const double *y, const double *z,
                      const double *w, double *s)
{
    double a0 = 0, a1 = 0, a2 = 0;
#pragma omp simd reduction(+ : a0, a1, a2)
    for (int c = 0; c < n; ++c) {
        a0 += w[c] * x[c];
        a1 += w[c] * y[c];
        a2 += D == 3 ? w[c] * z[c] : 0.0;
    }
    s[0] += a0;
    s[1] += a1;
    if (D == 3)
        s[2] += a2;
}

PST_KHOT void wls_msum2(int D, int n, const double *x, const double *y, const double *z,
                      const double *w, double *s)
{
    if (D == 2) {
        double a0 = 0, a1 = 0, a2 = 0;
#pragma omp simd reduction(+ : a0, a1, a2)
        for (int c = 0; c < n; ++c) {
            double wx = w[c] * x[c], wy = w[c] * y[c];
            a0 += wx * x[c];
            a1 += wx * y[c];
            a2 += wy * y[c];
        }
        const double acc[3] = {a0, a1, a2};
        for (int e = 0; e < 3; ++e)
            s[e] += acc[e];
        return;
    }
    double a0 = 0, a1 = 0, a2 = 0, a3 = 0, a4 = 0, a5 = 0;
#pragma omp simd reduction(+ : a0, a1, a2, a3, a4, a5)
    for (int c = 0; c < n; ++c) {
        double wx = w[c] * x[c], wy = w[c] * y[c], wz = w[c] * z[c];
        a0 += wx * x[c];
        a1 += wx * y[c];
        a2 += wx * z[c];
        a3 += wy * y[c];
        a4 += wy * z[c];
        a5 += wz * z[c];
    }
    const double acc[6] = {a0, a1, a2, a3, a4, a5};
    for (int e = 0; e < 6; ++e)
        s[e] += acc[e];
}

PST_KHOT void wls_msum3(int D, int n, const double *x, const double *y, const double *z,
                      const double *w, double *s)
{
    if (D == 2) {
        double a0 = 0, a1 = 0, a2 = 0, a3 = 0;
#pragma omp simd reduction(+ : a0, a1, a2, a3)
        for (int c = 0; c < n; ++c) {
            double wxx = w[c] * x[c] * x[c], wxy = w[c] * x[c] * y[c], wyy = w[c] * y[c] * y[c];
            a0 += wxx * x[c];
            a1 += wxx * y[c];
            a2 += wxy * y[c];
            a3 += wyy * y[c];
        }
        const double acc[4] = {a0, a1, a2, a3};
        for (int e = 0; e < 4; ++e)
            s[e] += acc[e];
        return;
    }
    double a0 = 0, a1 = 0, a2 = 0, a3 = 0, a4 = 0, a5 = 0, a6 = 0, a7 = 0, a8 = 0, a9 = 0;
#pragma omp simd reduction(+ : a0, a1, a2, a3, a4, a5, a6, a7, a8, a9)
    for (int c = 0; c < n; ++c) {
        double wx = w[c] * x[c], wy = w[c] * y[c], wz = w[c] * z[c];
        double wxx = wx * x[c], wxy = wx * y[c], wxz = wx * z[c], wyy = wy * y[c],
               wyz = wy * z[c], wzz = wz * z[c];
        a0 += wxx * x[c];
        a1 += wxx * y[c];
        a2 += wxx * z[c];
        a3 += wxy * y[c];
        a4 += wxy * z[c];
        a5 += wxz * z[c];
        a6 += wyy * y[c];
        a7 += wyy * z[c];
        a8 += wyz * z[c];
        a9 += wzz * z[c];
    }
    const double acc[10] = {a0, a1, a2, a3, a4, a5, a6, a7, a8, a9};
    for (int e = 0; e < 10; ++e)
        s[e] += acc[e];
}

PST_KHOT void wls_msum4(int D, int n, const double *x, const double *y, const double *z,
                      const double *w, double *s)
{
    if (D == 2) {
        double a0 = 0, a1 = 0, a2 = 0, a3 = 0, a4 = 0;
#pragma omp simd reduction(+ : a0, a1, a2, a3, a4)
        for (int c = 0; c < n; ++c) {
            double xx = x[c] * x[c], xy = x[c] * y[c], yy = y[c] * y[c];
            double wxx = w[c] * xx, wxy = w[c] * xy, wyy = w[c] * yy;
            a0 += wxx * xx;
            a1 += wxx * xy;
            a2 += wxx * yy;
            a3 += wxy * yy;
            a4 += wyy * yy;
        }
        const double acc[5] = {a0, a1, a2, a3, a4};
        for (int e = 0; e < 5; ++e)
            s[e] += acc[e];
        return;
    }
    double a0 = 0, a1 = 0, a2 = 0, a3 = 0, a4 = 0, a5 = 0, a6 = 0, a7 = 0, a8 = 0, a9 = 0,
           a10 = 0, a11 = 0, a12 = 0, a13 = 0, a14 = 0;
#pragma omp simd reduction(+ : a0, a1, a2, a3, a4, a5, a6, a7, a8, a9, a10, a11, a12, a13, a14)
    for (int c = 0; c < n; ++c) {
        double xx = x[c] * x[c], xy = x[c] * y[c], xz = x[c] * z[c], yy = y[c] * y[c],
               yz = y[c] * z[c], zz = z[c] * z[c];
        double wxx = w[c] * xx, wxy = w[c] * xy, wxz = w[c] * xz, wyy = w[c] * yy,
               wyz = w[c] * yz, wzz = w[c] * zz;
        a0 += wxx * xx;
        a1 += wxx * xy;
        a2 += wxx * xz;
        a3 += wxx * yy;
        a4 += wxx * yz;
        a5 += wxx * zz;
        a6 += wxy * yy;
        a7 += wxy * yz;
        a8 += wxy * zz;
        a9 += wxz * zz;
        a10 += wyy * yy;
        a11 += wyy * yz;
        a12 += wyy * zz;
        a13 += wyz * zz;
        a14 += wzz * zz;
    }
    const double acc[15] = {a0, a1, a2, a3, a4, a5, a6, a7, a8, a9, a10, a11, a12, a13, a14};
    for (int e = 0; e < 15; ++e)
        s[e] += acc[e];
}

/* The same sums for qsfdi.c (wls.h). */
void pst_wls_msums(int dim, int deg, int n, const double *r, int stride, const double *w,
                   double *s)
{
    const double *x = r, *y = r + stride, *z = dim == 3 ? r + 2 * stride : NULL;
    if (dim == 2) {
        switch (deg) {
        case 1: wls_msum1(2, n, x, y, z, w, s); break;
        case 2: wls_msum2(2, n, x, y, z, w, s); break;
        case 3: wls_msum3(2, n, x, y, z, w, s); break;
        default: wls_msum4(2, n, x, y, z, w, s); break;
        }
    } else {
        switch (deg) {
        case 1: wls_msum1(3, n, x, y, z, w, s); break;
        case 2: wls_msum2(3, n, x, y, z, w, s); break;
        case 3: wls_msum3(3, n, x, y, z, w, s); break;
        default: wls_msum4(3, n, x, y, z, w, s); break;
        }
    }
}

/* The basis at x^: (1,) x, y[, z], squares, cross products (xy[, xz, yz]). */
PST_KHOT void basis(int D, int B, const double *xh, double *p)
{
    int o = B;
    if (B)
        p[0] = 1.0;
    for (int a = 0; a < D; ++a) {
        p[o + a] = xh[a];
        p[o + D + a] = xh[a] * xh[a];
    }
    p[o + 2 * D] = xh[0] * xh[1];
    if (D == 3) {
        p[o + 7] = xh[0] * xh[2];
        p[o + 8] = xh[1] * xh[2];
    }
}

PST_KHOT void centre_of(const wls_ctx *k, int D, size_t i, double xc[3])
{
    for (int a = 0; a < D; ++a)
        xc[a] = k->c.x[a][i];
}

/* w lam . p(x, y, z): the weight of a pair with scaled offset (x, y, z) (z unused in 2D) and
 * kernel weight w in the row of coefficients lam; the sum in basis order. Scalars, not the
 * basis array, so that GCC vectorises the loops over a chunk that call it. */
PST_KHOT double basis_weight_xyz(int D, int B, double w, double x, double y, double z,
                                 const double *lam)
{
    const double *l = lam + B;
    double s = B ? 0.0 + lam[0] * 1.0 : 0.0;
    s += l[0] * x;
    s += l[1] * y;
    if (D == 2) {
        s += l[2] * (x * x);
        s += l[3] * (y * y);
        s += l[4] * (x * y);
        return w * s;
    }
    s += l[2] * z;
    s += l[3] * (x * x);
    s += l[4] * (y * y);
    s += l[5] * (z * z);
    s += l[6] * (x * y);
    s += l[7] * (x * z);
    s += l[8] * (y * z);
    return w * s;
}

PST_KHOT double basis_weight(int D, int B, double w, const double xh[3], const double *lam)
{
    return basis_weight_xyz(D, B, w, xh[0], xh[1], D == 3 ? xh[2] : 0.0, lam);
}

/* a_Ij of row i for neighbour j: shared by apply and emit_row (bit-identical weights). */
PST_KHOT double row_weight(const wls_ctx *k, int D, int B, pst_kernel K, const double *xc,
                          double ih, const double *lam, size_t j)
{
    double xh[3];
    double w = pair_weight(k, D, K, xc, j, ih, xh);
    return basis_weight(D, B, w, xh, lam);
}

/* a_Ji: row j's weight for its neighbour i, from row j's own centre, h and coefficients. */
PST_KHOT double reverse_weight(const wls_ctx *k, int D, int B, pst_kernel K, size_t j, size_t i)
{
    const int nb = D + D * (D + 1) / 2 + B;
    double xc[3];
    centre_of(k, D, j, xc);
    return row_weight(k, D, B, K, xc, 1.0 / pst_h(&k->c, j), k->d->lam + (size_t)nb * j, i);
}

/* Row i of a half list (operator.h, half_rows). With one h for the cloud the pair's offset and
 * kernel weight serve both directions (x^_JI = -x^_IJ exactly): one sqrt for two weights, each
 * bit for bit apply's; with per-particle h each direction is computed as apply does. */
PST_KHOT void half_row_t(const wls_ctx *k, const int64_t *off, const uint32_t *idx, size_t i,
                         const double *u, double *y, int D, int B, pst_kernel K)
{
    const int nb = D + D * (D + 1) / 2 + B;
    const uint8_t *kind = k->c.kind;
    double xc[3], ih = 1.0 / pst_h(&k->c, i);
    const double *lam = k->d->lam + (size_t)nb * i, *lam0 = k->d->lam;
    centre_of(k, D, i, xc);
    if (k->c.h) {
        PST_HALF_LOOP(off, idx, kind, i, u, y, j, (void)0,
                      row_weight(k, D, B, K, xc, ih, lam, j), reverse_weight(k, D, B, K, j, i));
    } else {
        double xh[3] = {0, 0, 0}, m[3] = {0, 0, 0}, w;
        PST_HALF_LOOP(off, idx, kind, i, u, y, j, w = pair_weight(k, D, K, xc, j, ih, xh),
                      basis_weight(D, B, w, xh, lam),
                      basis_weight(D, B, w, pst_negated(D, xh, m), lam0 + (size_t)nb * j));
    }
}

/* The weights a_Ij of row i for its neighbours idx[0..n) into t: the chunk's gather, then
 * w_c lam . p(r_c) in one loop over the chunk that the compiler vectorises (basis_weight's
 * arithmetic, so the half-list rows, which take a pair at a time, agree bit for bit). */
PST_KHOT void chunk_weights(const wls_ctx *k, int D, int B, pst_kernel K, const double *xc,
                            double ih, const double *lam, const uint32_t *idx, int n, double *t)
{
    double r[3][WLS_CHUNK];
    gather(k, D, K, xc, ih, idx, n, r, t);
#pragma omp simd
    for (int c = 0; c < n; ++c)
        t[c] = basis_weight_xyz(D, B, t[c], r[0][c], r[1][c], D == 3 ? r[2][c] : 0.0, lam);
}

/* Row i into y (apply) or its weights into w (emission), a chunk of neighbours at a time: the
 * weights of a chunk (chunk_weights), then their dot product with u_J - u_I (pst_dot_du). Per
 * neighbour: the gather of x_J and u_J, one sqrt (pst_sqrt_block) and ~60 flops (3D), all in
 * vector lanes. Measured (3D, 2 threads): see bench/README.md, "matrix-free apply". */
PST_KHOT void row_t(const wls_ctx *k, size_t i, const double *u, double *y, double *w, int D,
                   int B, pst_kernel K)
{
    const int nb = D + D * (D + 1) / 2 + B;
    double xc[3], ih = 1.0 / pst_h(&k->c, i), acc[PST_DOT_LANES] = {0}, t[WLS_CHUNK];
    const double *lam = k->d->lam + (size_t)nb * i, ui = u ? u[i] : 0.0;
    const int64_t e0 = k->c.off[i], e1 = k->c.off[i + 1];
    centre_of(k, D, i, xc);
    for (int64_t c0 = e0; c0 < e1; c0 += WLS_CHUNK) {
        int n = (int)(e1 - c0 < WLS_CHUNK ? e1 - c0 : WLS_CHUNK);
        chunk_weights(k, D, B, K, xc, ih, lam, k->c.idx + c0, n, w ? w + (c0 - e0) : t);
        if (!w)
            pst_dot_du(n, t, k->c.idx + c0, u, ui, acc);
    }
    if (!w)
        y[i] = pst_dot_sum(acc);
}

/* The degree-2 sums of graded lexicographic order (xx xy yy / xx xy xz yy yz zz) in the
 * basis order (xx yy xy / xx yy zz xy xz yz). */
static const unsigned char wls_gl2b[2][6] = {{0, 2, 1}, {0, 3, 5, 1, 2, 4}};

/* s[0] += sum_c w_c (type B's constant moment and data entry). */
PST_KHOT void wls_msum0(int n, const double *w, double *s)
{
    double a = 0;
#pragma omp simd reduction(+ : a)
    for (int c = 0; c < n; ++c)
        a += w[c];
    s[0] += a;
}

/* s[0..nb) += sum_c w_c p(r_c), p the basis ((1,) x, y[, z], squares, crosses). */
PST_KHOT void wls_basis_sums(int D, int B, int n, const double *x, const double *y,
                            const double *z, const double *w, double *s)
{
    double g[6] = {0};
    if (B)
        wls_msum0(n, w, s);
    wls_msum1(D, n, x, y, z, w, s + B);
    wls_msum2(D, n, x, y, z, w, g);
    for (int e = 0; e < D * (D + 1) / 2; ++e)
        s[B + D + e] += g[wls_gl2b[D - 2][e]];
}

/* The weighted monomial sums of row i (degree 0..4 for B, 2..4 for A: mom[k - first]) and,
 * with u, the data vector b = sum_j w_j p_j (u_j - u_I). Per neighbour: the gather, one sqrt
 * and ~19 flops of kernel (gather()), then 2 flops per moment plus the shared products (15 /
 * 35 moments for B, 12 / 31 for A) in the vectorised loops of wls_msum*: compute-bound.
 * Measured (3D, 1 thread, type B / A): 8.8 / 8.1 ns per neighbour with default flags, 6.0 /
 * 5.5 native (was ~26 ns). */
PST_KHOT void moments_row(const wls_ctx *k, int D, int B, pst_kernel K, size_t i,
                         const double *u, double *mom, double *b)
{
    const int nm = WLS_NMOM(D), first = B ? 0 : D + 1, nb = D + D * (D + 1) / 2 + B;
    const int o2 = D + 1, o3 = o2 + D * (D + 1) / 2, o4 = o3 + (D == 2 ? 4 : 10);
    double acc[35] = {0}, xc[3], ih = 1.0 / pst_h(&k->c, i);
    if (b)
        for (int e = 0; e < nb; ++e)
            b[e] = 0;
    centre_of(k, D, i, xc);
    for (int64_t c0 = k->c.off[i]; c0 < k->c.off[i + 1]; c0 += WLS_CHUNK) {
        int n = (int)(k->c.off[i + 1] - c0 < WLS_CHUNK ? k->c.off[i + 1] - c0 : WLS_CHUNK);
        double r[3][WLS_CHUNK], w[WLS_CHUNK];
        gather(k, D, K, xc, ih, k->c.idx + c0, n, r, w);
        if (B) { /* degree 0 and 1: the same sums as the basis' first entries */
            wls_msum0(n, w, acc);
            wls_msum1(D, n, r[0], r[1], r[2], w, acc + 1);
        }
        double g[6] = {0};
        wls_msum2(D, n, r[0], r[1], r[2], w, g);
        for (int e = 0; e < o3 - o2; ++e)
            acc[o2 + e] += g[wls_gl2b[D - 2][e]];
        wls_msum3(D, n, r[0], r[1], r[2], w, acc + o3);
        wls_msum4(D, n, r[0], r[1], r[2], w, acc + o4);
        if (b) {
            double wu[WLS_CHUNK];
            for (int c = 0; c < n; ++c)
                wu[c] = w[c] * (u[k->c.idx[c0 + c]] - u[i]);
            wls_basis_sums(D, B, n, r[0], r[1], r[2], wu, b);
        }
    }
    if (B) /* the centre particle: p^(0) = e_0, weight f(0) */
        acc[0] += pst_sph_shape(K, D, 0.0, 0);
    for (int m = first; m < nm; ++m)
        mom[m - first] = acc[m];
}

/* M (nb x nb) of a row from its moments. */
static void build_matrix(int D, int B, const double *mom, double *M)
{
    const int nb = D + D * (D + 1) / 2 + B, first = B ? 0 : D + 1;
    for (int a = 0; a < nb; ++a)
        for (int c = 0; c < nb; ++c) {
            int s = D == 2 ? wls_sum2[a + 1 - B][c + 1 - B] : wls_sum3[a + 1 - B][c + 1 - B];
            M[a * nb + c] = mom[s - first];
        }
}

/* ---- the fallback levels ------------------------------------------------------------------ */

/* The reduced (linear-exact) fit on (1,) x, y[, z], rho = |x^|^2: Mr = R^T M R with R mapping
 * rho onto the squares. Factorises Mr into fr ((D+1+B)^2) and returns 1 when usable. */
static int reduced_factor(int D, int B, const double *M, double *fr, double rank_tol)
{
    const int nb = D + D * (D + 1) / 2 + B, nl = B + D, nr = nl + 1;
    for (int a = 0; a < nl; ++a) {
        double s = 0;
        for (int c = 0; c < nl; ++c)
            fr[a * nr + c] = M[a * nb + c];
        for (int t = nl; t < nl + D; ++t)
            s += M[a * nb + t];
        fr[a * nr + nl] = fr[nl * nr + a] = s;
    }
    double s = 0;
    for (int t = nl; t < nl + D; ++t)
        for (int c = nl; c < nl + D; ++c)
            s += M[t * nb + c];
    fr[nl * nr + nl] = s;
    return pst_ldlt_factor(nr, fr) > rank_tol;
}

/* Solve the reduced system for the right-hand side R^T b (b in the full basis) and expand the
 * solution back: linear entries as they are, every square the rho coefficient, crosses 0. */
static void reduced_solve(int D, int B, const double *fr, double *b)
{
    const int nb = D + D * (D + 1) / 2 + B, nl = B + D, nr = nl + 1;
    double r[WLS_NBMAX];
    for (int a = 0; a < nl; ++a)
        r[a] = b[a];
    r[nl] = 0;
    for (int t = nl; t < nl + D; ++t)
        r[nl] += b[t];
    pst_ldlt_solve(nr, fr, r);
    for (int a = 0; a < nb; ++a)
        b[a] = a < nl ? r[a] : a < nl + D ? r[nl] : 0.0;
}

/* The radial level: b in the full basis becomes D b_lin / S2 on the linear entries and
 * (sum of b on the squares) / S4 on every square, S2 = sum w |x^|^2 and S4 = sum w |x^|^4 read
 * from M. Returns 0 (b zeroed) when the row has no weighted neighbour. */
static int radial_solve(int D, int B, const double *M, double *b)
{
    const int nb = D + D * (D + 1) / 2 + B, nl = B + D;
    double S2 = 0, S4 = 0, bs = 0;
    for (int a = B; a < nl; ++a)
        S2 += M[a * nb + a];
    for (int t = nl; t < nl + D; ++t) {
        bs += b[t];
        for (int c = nl; c < nl + D; ++c)
            S4 += M[t * nb + c];
    }
    int ok = S2 > 0 && S4 > 0;
    for (int a = 0; a < nb; ++a)
        b[a] = !ok ? 0.0 : a >= B && a < nl ? D * b[a] / S2 : a >= nl && a < nl + D ? bs / S4 : 0;
    return ok;
}

/* Solve M c = b at the row's level (b in, c out): the coefficients of the fit in scaled
 * coordinates. fac holds the scheme's factor for LVL_QUADRIC; fr is scratch. */
static void solve_level(const wls_data *d, int level, const double *M, const double *fac,
                        double *fr, double rank_tol, double *b)
{
    int D = d->dim, B = d->typeB;
    if (level == LVL_QUADRIC)
        d->solve(D, d->nb, M, fac, b);
    else if (level == LVL_REDUCED && reduced_factor(D, B, M, fr, rank_tol))
        reduced_solve(D, B, fr, b);
    else
        radial_solve(D, B, M, b);
}

/* ---- precompute --------------------------------------------------------------------------- */

static inline uint8_t cond_status(const pst_op *op, double cond)
{
    if (!(cond * op->opts.rank_tol < 1.0))
        return PST_ROW_RANK_DEFICIENT;
    return cond > op->opts.cond_max ? PST_ROW_ILL_CONDITIONED : PST_ROW_OK;
}

/* spec choice 6: a quadratic fit needs 5 (2D) / 9 (3D) neighbours j != I */
int pst_wls_min_neighbours(int dim) { return dim == 2 ? 5 : 9; }

/* Rows per call of a dispatched moment function (isa.h), dealt dynamically to the threads. */
#define WLS_ROWS 128
typedef void (*moments_fn)(const wls_ctx *, size_t, size_t, double *);
#define WLS_MOMENTS(D, B, K)                                                                   \
    PST_ISA_DISPATCH static void mrows_##D##_##B##_##K(const wls_ctx *k, size_t i0, size_t i1,  \
                                                       size_t b0, double *mom)                 \
    {                                                                                          \
        const int nm = WLS_NMOM(D) - (B ? 0 : D + 1);                                          \
        for (size_t i = i0; i < i1; ++i)                                                       \
            moments_row(k, D, B, (pst_kernel)K, i, NULL, mom + (size_t)nm * (i - b0), NULL);   \
    }                                                                                          \
    static void moments_##D##_##B##_##K(const wls_ctx *k, size_t b0, size_t b1, double *mom)    \
    {                                                                                          \
        _Pragma("omp parallel for schedule(dynamic, 1)")                                        \
        for (size_t c = b0; c < b1; c += WLS_ROWS)                                             \
            mrows_##D##_##B##_##K(k, c, c + WLS_ROWS < b1 ? c + WLS_ROWS : b1, b0, mom);       \
    }
#define WLS_MOMENTS_K(D, B)                                                                    \
    WLS_MOMENTS(D, B, 0) WLS_MOMENTS(D, B, 1) WLS_MOMENTS(D, B, 2) WLS_MOMENTS(D, B, 3)
WLS_MOMENTS_K(2, 0)
WLS_MOMENTS_K(2, 1)
WLS_MOMENTS_K(3, 0)
WLS_MOMENTS_K(3, 1)
static const moments_fn moments_table[2][2][4] = {
    {{moments_2_0_0, moments_2_0_1, moments_2_0_2, moments_2_0_3},
     {moments_2_1_0, moments_2_1_1, moments_2_1_2, moments_2_1_3}},
    {{moments_3_0_0, moments_3_0_1, moments_3_0_2, moments_3_0_3},
     {moments_3_1_0, moments_3_1_1, moments_3_1_2, moments_3_1_3}}};

void pst_wls_free(void *p)
{
    wls_data *d = p;
    if (!d)
        return;
    pst_free(d->lam);
    pst_free(d->level);
    free(d);
}

/* The right-hand side of row i: the Laplacian h^ (2/h^2 on the squares) or, on a Neumann row,
 * n_I / h on the linear entries. */
static void row_rhs(const wls_ctx *k, size_t i, double *r)
{
    const wls_data *d = k->d;
    int D = d->dim, B = d->typeB;
    double ih = 1.0 / pst_h(&k->c, i);
    for (int a = 0; a < d->nb; ++a)
        r[a] = 0;
    for (int a = 0; a < D; ++a) {
        if (k->c.kind[i] == PST_NEUMANN)
            r[B + a] = k->c.normal[a][i] * ih;
        else
            r[B + D + a] = 2.0 * ih * ih;
    }
}

int pst_wls_precompute(pst_op *op, int typeB, wls_factor_fn factor, wls_solve_fn solve,
                       char *err)
{
    double t0 = omp_get_wtime();
    size_t n = op->n;
    int D = op->dim;
    wls_data *d = calloc(1, sizeof *d);
    if (!d)
        return PST_ENOMEM;
    op->data = d;
    d->dim = D;
    d->typeB = typeB;
    d->nb = D + D * (D + 1) / 2 + typeB;
    d->kernel = op->kernel;
    d->factor = factor;
    d->solve = solve;
    int nb = d->nb, nm = WLS_NMOM(D) - (typeB ? 0 : D + 1);
    size_t blk = n < WLS_BLOCK ? n : WLS_BLOCK;
    d->lam = pst_alloc(n * (size_t)nb * sizeof *d->lam);
    d->level = pst_alloc(n);
    double *mom = pst_alloc(blk * (size_t)nm * sizeof *mom);
    double *Mb = pst_alloc(blk * (size_t)(nb * nb) * sizeof *Mb);
    double *fac = pst_alloc(blk * (size_t)(nb * nb) * sizeof *fac);
    if (!d->lam || !d->level || !mom || !Mb || !fac) {
        pst_free(mom);
        pst_free(Mb);
        pst_free(fac);
        pst_set_err(err, "%s: cannot allocate the per-particle data of %zu particles",
                    op->scheme->name, n);
        return PST_ENOMEM;
    }
    wls_ctx k = make_ctx(op);
    moments_fn moments = moments_table[D - 2][typeB][op->kernel];
    int minn = pst_wls_min_neighbours(D);
    double rank_tol = op->opts.rank_tol;
    /* the pair geometry and weights are fused into the moment pass (recomputing them is
     * cheaper than storing them): this phase is the setup only */
    op->phase[PST_PHASE_GEOMETRY] = omp_get_wtime() - t0;
    for (size_t b0 = 0; b0 < n; b0 += blk) {
        size_t b1 = b0 + blk < n ? b0 + blk : n;
        double t = omp_get_wtime();
        moments(&k, b0, b1, mom);
        op->phase[PST_PHASE_MOMENTS] += omp_get_wtime() - t;

        /* Bound by the factorisations: ~nb^3/6 flops per particle, no neighbour access. */
        t = omp_get_wtime();
#pragma omp parallel for schedule(dynamic, 128)
        for (size_t i = b0; i < b1; ++i) {
            double *M = Mb + (size_t)(nb * nb) * (i - b0);
            build_matrix(D, typeB, mom + (size_t)nm * (i - b0), M);
            if (k.c.off[i + 1] - k.c.off[i] < minn) {
                op->status[i] = PST_ROW_TOO_FEW;
                continue;
            }
            op->status[i] = cond_status(op, factor(D, nb, M, fac + (size_t)(nb * nb) * (i - b0)));
        }
        op->phase[PST_PHASE_INVERSION] += omp_get_wtime() - t;

        /* Bound by the triangular solves: ~nb^2 flops per particle. */
        t = omp_get_wtime();
#pragma omp parallel for schedule(dynamic, 128)
        for (size_t i = b0; i < b1; ++i) {
            const double *M = Mb + (size_t)(nb * nb) * (i - b0);
            double *lam = d->lam + (size_t)nb * i, fr[(WLS_NBMAX - 3) * (WLS_NBMAX - 3)];
            row_rhs(&k, i, lam);
            uint8_t lvl = LVL_QUADRIC;
            if (op->status[i] >= PST_ROW_RANK_DEFICIENT) {
                lvl = reduced_factor(D, typeB, M, fr, rank_tol) ? LVL_REDUCED : LVL_RADIAL;
                if (lvl == LVL_REDUCED)
                    reduced_solve(D, typeB, fr, lam);
                else if (!radial_solve(D, typeB, M, lam))
                    lvl = LVL_EMPTY;
            } else {
                solve(D, nb, M, fac + (size_t)(nb * nb) * (i - b0), lam);
            }
            d->level[i] = lvl;
        }
        op->phase[PST_PHASE_WEIGHTS] += omp_get_wtime() - t;
    }
    pst_free(mom);
    pst_free(Mb);
    pst_free(fac);
    return PST_OK;
}

/* The reduced fit is linear-exact and so has no diagonal on a flat neighbourhood that misses
 * I: the row drops to the radial row, which is non-negative and exact for |x|^2. The moments
 * are recomputed (a flat row is rare; keeping them would cost nm doubles per particle). */
void pst_wls_degrade(pst_op *op, size_t i)
{
    wls_ctx k = make_ctx(op);
    wls_data *d = op->data;
    int D = d->dim, B = d->typeB;
    double mom[35], M[WLS_NBMAX * WLS_NBMAX], *lam = d->lam + (size_t)d->nb * i;
    moments_row(&k, D, B, d->kernel, i, NULL, mom, NULL);
    build_matrix(D, B, mom, M);
    row_rhs(&k, i, lam);
    d->level[i] = radial_solve(D, B, M, lam) ? LVL_RADIAL : LVL_EMPTY;
}

/* ---- apply and emission ------------------------------------------------------------------- */

/* Row i: of the whole list (apply, emission) or, with off != NULL, of the half list (off,
 * idx). */
typedef void (*row_fn)(const wls_ctx *, size_t, const double *, double *, double *,
                       const int64_t *off, const uint32_t *idx);
#define WLS_ROW(D, B, K)                                                                       \
    PST_ISA_DISPATCH static void row_##D##_##B##_##K(const wls_ctx *k, size_t i, const double *u, double *y,     \
                                    double *w, const int64_t *off, const uint32_t *idx)        \
    {                                                                                          \
        if (off)                                                                               \
            half_row_t(k, off, idx, i, u, y, D, B, (pst_kernel)K);                             \
        else                                                                                   \
            row_t(k, i, u, y, w, D, B, (pst_kernel)K);                                         \
    }
#define WLS_ROW_K(D, B) WLS_ROW(D, B, 0) WLS_ROW(D, B, 1) WLS_ROW(D, B, 2) WLS_ROW(D, B, 3)
WLS_ROW_K(2, 0)
WLS_ROW_K(2, 1)
WLS_ROW_K(3, 0)
WLS_ROW_K(3, 1)
static const row_fn row_table[2][2][4] = {
    {{row_2_0_0, row_2_0_1, row_2_0_2, row_2_0_3}, {row_2_1_0, row_2_1_1, row_2_1_2, row_2_1_3}},
    {{row_3_0_0, row_3_0_1, row_3_0_2, row_3_0_3},
     {row_3_1_0, row_3_1_1, row_3_1_2, row_3_1_3}}};

static row_fn row_for(const wls_ctx *k)
{
    return row_table[k->c.dim - 2][k->d->typeB][k->d->kernel];
}

void pst_wls_apply(const pst_op *op, const double *u, double *y)
{
    wls_ctx k = make_ctx(op);
    row_fn row = row_for(&k);
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < op->n; ++i)
        if (k.c.kind[i] != PST_DIRICHLET)
            row(&k, i, u, y, NULL, NULL, NULL);
}

void pst_wls_half_rows(const pst_op *op, const int64_t *off, const uint32_t *idx, size_t i0,
                       size_t i1, const double *u, double *y)
{
    wls_ctx k = make_ctx(op);
    row_fn row = row_for(&k);
    for (size_t i = i0; i < i1; ++i)
        row(&k, i, u, y, NULL, off, idx);
}

void pst_wls_emit_row(const pst_op *op, size_t i, double *w)
{
    wls_ctx k = make_ctx(op);
    row_for(&k)(&k, i, NULL, NULL, w, NULL, NULL);
}

/* ---- the fit at the particles: gradient and Hessian --------------------------------------- */

/* The fit coefficients c of row i for data u (scaled coordinates), at the row's level. */
static void fit_row(const pst_op *op, const wls_ctx *k, size_t i, const double *u, double *c)
{
    const wls_data *d = k->d;
    int D = d->dim, B = d->typeB, nb = d->nb;
    double mom[35], M[WLS_NBMAX * WLS_NBMAX], fac[WLS_NBMAX * WLS_NBMAX],
        fr[(WLS_NBMAX - 3) * (WLS_NBMAX - 3)];
    moments_row(k, D, B, d->kernel, i, u, mom, c);
    build_matrix(D, B, mom, M);
    int lvl = d->level[i];
    if (lvl == LVL_QUADRIC && !(d->factor(D, nb, M, fac) * op->opts.rank_tol < 1.0))
        lvl = LVL_REDUCED; /* cannot happen for a row classified as quadric; keeps c finite */
    solve_level(d, lvl, M, fac, fr, op->opts.rank_tol, c);
}

void pst_wls_gradient(const pst_op *op, const double *u, double *const grad[3])
{
    wls_ctx k = make_ctx(op);
    int D = k.c.dim, B = k.d->typeB;
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < op->n; ++i) {
        double c[WLS_NBMAX], ih = 1.0 / pst_h(&k.c, i);
        fit_row(op, &k, i, u, c);
        for (int a = 0; a < D; ++a)
            grad[a][i] = c[B + a] * ih;
    }
}

void pst_wls_hessian(const pst_op *op, const double *u, double *const hess[6])
{
    wls_ctx k = make_ctx(op);
    int D = k.c.dim, B = k.d->typeB, nh = D * (D + 1) / 2;
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < op->n; ++i) {
        double c[WLS_NBMAX], ih = 1.0 / pst_h(&k.c, i);
        fit_row(op, &k, i, u, c);
        /* the squares' coefficients are u_aa / 2, the crosses' u_ab (the layout of hess) */
        for (int e = 0; e < nh; ++e)
            hess[e][i] = (e < D ? 2.0 : 1.0) * c[B + D + e] * ih * ih;
    }
}

/* ---- interpolation at points -------------------------------------------------------------- */

/* A local cell grid answers the point queries (the operator's list has rows for particles
 * only): edge = support * h_max, so a point's neighbours lie in the 3^D cells around it. */
static size_t cell_rank(const pst_cells *g, const long *cc)
{
    return g->rank[((size_t)cc[2] * g->dims[1] + (size_t)cc[1]) * g->dims[0] + (size_t)cc[0]];
}

/* Nearest particle to X: rings of cells around X's cell until the best distance is below the
 * ring's lower bound (r cells). */
static size_t nearest(const wls_ctx *k, const pst_cells *g, const double *X)
{
    int D = k->c.dim;
    long c0[3] = {0, 0, 0}, maxr = 0;
    for (int a = 0; a < D; ++a) {
        c0[a] = pst_cell_coord(X[a], g->lo[a], g->inv, g->dims[a]);
        long ext = (long)g->dims[a] - 1 - c0[a] > c0[a] ? (long)g->dims[a] - 1 - c0[a] : c0[a];
        maxr = ext > maxr ? ext : maxr;
    }
    double best = INFINITY;
    size_t who = 0;
    for (long r = 0; r <= maxr; ++r) {
        long lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0}, cc[3] = {0, 0, 0};
        for (int a = 0; a < D; ++a) {
            lo[a] = c0[a] - r < 0 ? 0 : c0[a] - r;
            hi[a] = c0[a] + r > (long)g->dims[a] - 1 ? (long)g->dims[a] - 1 : c0[a] + r;
        }
        for (cc[2] = lo[2]; cc[2] <= hi[2]; ++cc[2])
            for (cc[1] = lo[1]; cc[1] <= hi[1]; ++cc[1])
                for (cc[0] = lo[0]; cc[0] <= hi[0]; ++cc[0]) {
                    long cheb = 0;
                    for (int a = 0; a < D; ++a) {
                        long dd = labs(cc[a] - c0[a]);
                        cheb = dd > cheb ? dd : cheb;
                    }
                    if (cheb != r)
                        continue;
                    size_t rk = cell_rank(g, cc);
                    for (uint32_t p = g->start[rk]; p < g->start[rk + 1]; ++p) {
                        size_t j = g->order[p];
                        double d2 = 0;
                        for (int a = 0; a < D; ++a)
                            d2 += (k->c.x[a][j] - X[a]) * (k->c.x[a][j] - X[a]);
                        if (d2 < best || (d2 == best && j < who)) {
                            best = d2;
                            who = j;
                        }
                    }
                }
        if (best <= (double)r * g->size * ((double)r * g->size))
            break;
    }
    return who;
}

/* Type B at a point X: fit u_j - u_K (K the nearest particle) on p^(x_j - X) over the particles
 * with |x_j - X| < support * h (no centre particle). Returns 1 and the value / Laplacian when
 * the fit is usable. */
static int fit_point_B(const pst_op *op, const wls_ctx *k, const pst_cells *g, const double *X,
                       double h, const double *u, size_t K, double *value, double *lap)
{
    const wls_data *d = k->d;
    int D = d->dim, nb = d->nb, nm = WLS_NMOM(D);
    const signed char *par = wls_par[D - 2], *var = wls_var[D - 2];
    double acc[35] = {0}, b[WLS_NBMAX] = {0}, ih = 1.0 / h;
    long lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0}, cc[3];
    double R = pst_sph_support[d->kernel] * h;
    for (int a = 0; a < D; ++a) {
        lo[a] = pst_cell_coord(X[a] - R, g->lo[a], g->inv, g->dims[a]);
        hi[a] = pst_cell_coord(X[a] + R, g->lo[a], g->inv, g->dims[a]);
    }
    int count = 0;
    for (cc[2] = lo[2]; cc[2] <= hi[2]; ++cc[2])
        for (cc[1] = lo[1]; cc[1] <= hi[1]; ++cc[1])
            for (cc[0] = lo[0]; cc[0] <= hi[0]; ++cc[0]) {
                size_t rk = cell_rank(g, cc);
                for (uint32_t p = g->start[rk]; p < g->start[rk + 1]; ++p) {
                    size_t j = g->order[p];
                    double xh[3], wm[35];
                    wm[0] = pair_weight(k, D, d->kernel, X, j, ih, xh);
                    if (wm[0] == 0.0 && xh[0] * xh[0] + xh[1] * xh[1] +
                                                (D == 3 ? xh[2] * xh[2] : 0.0) > 1e-16)
                        continue; /* outside the support */
                    if (wm[0] == 0.0) /* a particle at X: the centre, weight f(0) */
                        wm[0] = pst_sph_shape(d->kernel, D, 0.0, 0);
                    ++count;
                    for (int m = 1; m < nm; ++m)
                        wm[m] = wm[par[m]] * xh[var[m]];
                    for (int m = 0; m < nm; ++m)
                        acc[m] += wm[m];
                    for (int q = 0; q < nb; ++q)
                        b[q] += wm[q] * (u[j] - u[K]);
                }
            }
    if (count < pst_wls_min_neighbours(D))
        return 0;
    double M[WLS_NBMAX * WLS_NBMAX], fac[WLS_NBMAX * WLS_NBMAX];
    build_matrix(D, 1, acc, M);
    if (!(d->factor(D, nb, M, fac) * op->opts.rank_tol < 1.0))
        return 0;
    d->solve(D, nb, M, fac, b);
    double l = 0;
    for (int a = 0; a < D; ++a)
        l += 2.0 * b[1 + D + a] * ih * ih;
    *value = u[K] + b[0];
    *lap = l;
    return 1;
}

/* Type A and lpmps at a point X: the Taylor polynomial of the nearest particle K's quadric fit,
 * u_K + g_K . (X - x_K) + (X - x_K)^T H_K (X - x_K) / 2, and Laplacian tr H_K. */
static int fit_point_A(const pst_op *op, const wls_ctx *k, const double *X, const double *u,
                       size_t K, double *value, double *lap)
{
    const wls_data *d = k->d;
    int D = d->dim;
    if (d->level[K] != LVL_QUADRIC)
        return 0;
    double c[WLS_NBMAX], ih = 1.0 / pst_h(&k->c, K), xh[3] = {0, 0, 0};
    fit_row(op, k, K, u, c);
    /* in K's scaled coordinates the fit is sum c_e p_e(x^), whose Laplacian is 2 sum c_squares */
    for (int a = 0; a < D; ++a)
        xh[a] = (X[a] - k->c.x[a][K]) * ih;
    double p[WLS_NBMAX], v = 0, l = 0;
    basis(D, 0, xh, p);
    for (int e = 0; e < d->nb; ++e)
        v += c[e] * p[e];
    for (int a = 0; a < D; ++a)
        l += 2.0 * c[D + a] * ih * ih;
    *value = u[K] + v;
    *lap = l;
    return 1;
}

int pst_wls_interpolate(const pst_op *op, const double *const pts[3], size_t m,
                        const double *u, double *value, double *lap, size_t *fallbacks,
                        char *err)
{
    wls_ctx k = make_ctx(op);
    double h = pst_cloud_h_max(op->cloud);
    pst_cells g;
    *fallbacks = 0;
    PST_CHECK(op->n == 0, PST_EINVAL, err,
              "%s: cannot interpolate on an empty cloud", op->scheme->name);
    int st = pst_cells_build(&g, op->cloud, pst_sph_support[k.d->kernel] * h, err);
    if (st != PST_OK)
        return st;
    size_t fb = 0;
#pragma omp parallel for schedule(dynamic, 64) reduction(+ : fb)
    for (size_t p = 0; p < m; ++p) {
        double X[3] = {0, 0, 0}, v, l;
        for (int a = 0; a < k.c.dim; ++a)
            X[a] = pts[a][p];
        size_t K = nearest(&k, &g, X);
        int ok = k.d->typeB ? fit_point_B(op, &k, &g, X, h, u, K, &v, &l)
                            : fit_point_A(op, &k, X, u, K, &v, &l);
        if (!ok) {
            v = u[K];
            l = 0.0;
            ++fb;
        }
        if (value)
            value[p] = v;
        if (lap)
            lap[p] = l;
    }
    pst_cells_free(&g);
    *fallbacks = fb;
    return PST_OK;
}
