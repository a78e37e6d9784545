/* The weighted monomial sums of the WLS moment passes (kernels/wls.c) over a chunk of
 * neighbours gathered into arrays (structure of arrays): one vectorised reduction loop per
 * degree. Inline, so that the dispatched workers (isa.h) inline them into each clone. Internal. */
#ifndef PSTENCIL_WLS_SUMS_H
#define PSTENCIL_WLS_SUMS_H

#include "kernel_common.h"

/* s[0] += sum_c w_c (type B's constant moment and data entry). */
PST_KHOT void wls_msum0(int n, const double *w, double *s)
{
    double a = 0;
#pragma omp simd reduction(+ : a)
    for (int c = 0; c < n; ++c)
        a += w[c];
    s[0] += a;
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


#endif
