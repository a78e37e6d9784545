/* Inline core of the SPH smoothing kernels (docs/kernels.md). Hot loops include this header
 * so that W, dW/dr and d2W/dr2 inline into them; the public pst_kernel_* functions in
 * sph_kernels.c are thin checked wrappers around the same maths. Not installed.
 *
 * Every kernel is written branch-free in truncated powers t_i = max(c_i - q, 0), q = r/h, and
 * the result is then selected against r < support*h: that is the product the neighbour search
 * forms, so W, dW and d2W are exactly 0 at and beyond the support whatever the rounding of
 * r/h, and q = 0 gives t_i = c_i exactly, so dW(0) is exactly 0. */
#ifndef PSTENCIL_SPH_KERNELS_H
#define PSTENCIL_SPH_KERNELS_H

#include "pstencil.h"

#include <math.h>

/* pi to double precision; M_PI is POSIX, not C17. */
#define PST_SPH_PI 3.14159265358979323846

/* Dimensionless normalisation sigma[k][dim-1]: W = sigma / h^dim * f(q). Each value is the
 * inverse of the radial integral of f (verified symbolically and by tests/test_kernels.c).
 * The 1D cubic value is 2/3; LV print 3/2, a typo. */
static const double pst_sph_sigma[4][3] = {
    {2.0 / 3.0, 10.0 / (7.0 * PST_SPH_PI), 1.0 / PST_SPH_PI},                 /* cubic   */
    {1.0 / 120.0, 7.0 / (478.0 * PST_SPH_PI), 1.0 / (120.0 * PST_SPH_PI)},    /* quintic */
    {5.0 / 8.0, 7.0 / (4.0 * PST_SPH_PI), 21.0 / (16.0 * PST_SPH_PI)},        /* W. C2   */
    {3.0 / 4.0, 9.0 / (4.0 * PST_SPH_PI), 495.0 / (256.0 * PST_SPH_PI)},      /* W. C4   */
};

/* Support radius in units of h, indexed by pst_kernel. */
static const double pst_sph_support[4] = {2.0, 3.0, 2.0, 2.0};

/* The arguments every kernel function accepts: a known kernel, dim 1..3, finite h > 0 and
 * r >= 0 (r = +inf is allowed and gives 0). NaN fails every comparison, so it is rejected. */
static inline int pst_sph_valid(pst_kernel k, int dim, double r, double h)
{
    return (unsigned)k <= (unsigned)PST_KERNEL_WENDLAND_C4 && dim >= 1 && dim <= 3 && h > 0.0
           && h < INFINITY && r >= 0.0;
}

/* 2 max(x, 0) = x + |x|, exact for finite x: arithmetic, not a compare-select, which GCC turns
 * into a branch around the powers (it may not speculate FP multiplies under -ftrapping-math),
 * and that keeps kernel loops from vectorising. NaN never reaches here. The shapes take their
 * truncated powers doubled, T = 2 t, and every product of them starts with its constant scaled
 * by 2^-k (k: the power of T that follows): each rounding is then the rounding of the plain
 * t-product times a power of 2, and the shape is the t-formula's value bit for bit
 * (tests/test_kernel_bits.c), without the multiplication by 1/2 of max(x, 0) = (x + |x|) / 2:
 * 2-3 multiplications fewer per cubic or quintic evaluation (the quintic is about a third of
 * the lpmps matrix-free apply, bench/README.md). No power underflows: c - q is 0 or at least
 * 2^-53 for 0 <= q <= c. */
static inline double pst_sph_pos2(double x)
{
    return x + fabs(x);
}

/* 1/h^n for n = 0..5 without pow(). */
static inline double pst_sph_ipow(double ih, int n)
{
    double p = 1.0;
    for (int i = 0; i < n; ++i)
        p *= ih;
    return p;
}

/* Dimensionless shape f(q) (deriv 0), df/dq (1) or d2f/dq2 (2) at q >= 0, without the cut
 * at the support (pst_sph_eval applies it). `deriv` is a literal at every call site, so after
 * inlining only one branch survives. */
static inline double pst_sph_shape(pst_kernel k, int dim, double q, int deriv)
{
    switch (k) {
    case PST_KERNEL_CUBIC: {
        /* What = (t2^3 - 4 t1^3)/4 equals 1 - 1.5q^2 + 0.75q^3 on [0,1], (2-q)^3/4 on [1,2];
         * in T = 2t (pst_sph_pos2): t^3 = 2^-3 T^3, t^2 = 2^-2 T^2, t = 2^-1 T. */
        const double T2 = pst_sph_pos2(2.0 - q), T1 = pst_sph_pos2(1.0 - q);
        if (deriv == 0)
            return 0.03125 * T2 * T2 * T2 - 0.125 * T1 * T1 * T1;
        if (deriv == 1)
            return 0.75 * T1 * T1 - 0.1875 * T2 * T2;
        return 0.75 * T2 - 3.0 * T1;
    }
    case PST_KERNEL_QUINTIC: {
        /* QSFDI eq. 9: t3^5 - 6 t2^5 + 15 t1^5; in T = 2t and S = T^2 = 4 t^2 (pst_sph_pos2):
         * t^5 = 2^-5 S S T, s s = 2^-4 S S, s t = 2^-3 S T. */
        const double T3 = pst_sph_pos2(3.0 - q), T2 = pst_sph_pos2(2.0 - q),
                     T1 = pst_sph_pos2(1.0 - q);
        const double S3 = T3 * T3, S2 = T2 * T2, S1 = T1 * T1;
        if (deriv == 0)
            return 0.03125 * S3 * S3 * T3 - 0.1875 * S2 * S2 * T2 + 0.46875 * S1 * S1 * T1;
        if (deriv == 1)
            return 1.875 * S2 * S2 - 0.3125 * S3 * S3 - 4.6875 * S1 * S1;
        return 2.5 * S3 * T3 - 15.0 * S2 * T2 + 37.5 * S1 * T1;
    }
    case PST_KERNEL_WENDLAND_C2:
    case PST_KERNEL_WENDLAND_C4: {
        /* t = 1 - q/2 (Dehnen & Aly with H = 2h); derivatives are the sympy-factored forms;
         * in T = 2t and T2 = T^2 (pst_sph_pos2): t = 2^-1 T, t2 = 2^-2 T2. */
        const double T = pst_sph_pos2(1.0 - 0.5 * q), T2 = T * T;
        if (k == PST_KERNEL_WENDLAND_C2) {
            if (dim == 1) {
                if (deriv == 0)
                    return 0.125 * T2 * T * (1.5 * q + 1.0);
                if (deriv == 1)
                    return -0.75 * q * T2;
                return 0.5 * T * (4.5 * q - 3.0);
            }
            if (deriv == 0)
                return 0.0625 * T2 * T2 * (2.0 * q + 1.0);
            if (deriv == 1)
                return -0.625 * q * T2 * T;
            return 0.25 * T2 * (10.0 * q - 5.0);
        }
        if (dim == 1) {
            if (deriv == 0)
                return 0.03125 * T2 * T2 * T * ((2.0 * q + 2.5) * q + 1.0);
            if (deriv == 1)
                return -0.21875 * q * T2 * T2 * (2.0 * q + 1.0);
            return 0.21875 * T2 * T * ((12.0 * q - 3.0) * q - 2.0);
        }
        if (deriv == 0)
            return 0.015625 * T2 * T2 * T2 * ((35.0 / 12.0 * q + 3.0) * q + 1.0);
        if (deriv == 1)
            return -(7.0 / 3.0) * 0.03125 * q * T2 * T2 * T * (5.0 * q + 2.0);
        return (7.0 / 6.0) * 0.0625 * T2 * T2 * ((35.0 * q - 8.0) * q - 4.0);
    }
    default: /* PST_KERNEL_DEFAULT and _UNKNOWN name no kernel: excluded by the preconditions */
        break;
    }
    return NAN; /* unreachable under the preconditions */
}

/* h^-(dim+deriv) * sigma * f^(deriv)(r/h), cut to exactly 0 for r >= support*h (a select, not
 * a branch; it also turns r = inf, where Wendland's q*t is inf*0, into 0). The chain rule
 * d/dr = (1/h) d/dq gives the extra 1/h per derivative. Preconditions:
 * pst_sph_valid(k, dim, r, h) and deriv in 0..2; callers check once, outside hot loops.
 * pst_sph_uncut is the value before the cut: a vectorised loop takes it and applies the cut
 * (r < support*h ? v : 0) in a loop of its own, the same numbers; in one loop GCC keeps the
 * select as a branch around the powers (it may not speculate FP multiplies) and the generic
 * x86-64 clone, which has no masked stores, does not vectorise it. */
static inline double pst_sph_uncut(pst_kernel k, int dim, double r, double h, int deriv)
{
    const double ih = 1.0 / h;
    return pst_sph_sigma[k][dim - 1] * pst_sph_ipow(ih, dim + deriv)
           * pst_sph_shape(k, dim, r * ih, deriv);
}

static inline double pst_sph_eval(pst_kernel k, int dim, double r, double h, int deriv)
{
    const double v = pst_sph_uncut(k, dim, r, h, deriv);
    return r < pst_sph_support[k] * h ? v : 0.0;
}

static inline double pst_sph_w(pst_kernel k, int dim, double r, double h)
{
    return pst_sph_eval(k, dim, r, h, 0);
}

static inline double pst_sph_dw(pst_kernel k, int dim, double r, double h)
{
    return pst_sph_eval(k, dim, r, h, 1);
}

/* X(D, K, name) for each kernel K, name its short name: the rows that the kernels instantiate
 * per dimension and kernel; PST_KERNEL_TABLE(E), the table [D - 2][K] of E(D, name). */
#define PST_FOR_KERNELS(X, D)                                                                  \
    X(D, PST_KERNEL_CUBIC, cubic) X(D, PST_KERNEL_QUINTIC, quintic)                            \
    X(D, PST_KERNEL_WENDLAND_C2, wc2) X(D, PST_KERNEL_WENDLAND_C4, wc4)
#define PST_KERNEL_TABLE(E)                                                                    \
    {{E(2, cubic), E(2, quintic), E(2, wc2), E(2, wc4)},                                       \
     {E(3, cubic), E(3, quintic), E(3, wc2), E(3, wc4)}}

static inline double pst_sph_d2w(pst_kernel k, int dim, double r, double h)
{
    return pst_sph_eval(k, dim, r, h, 2);
}

#endif
