/* Tests of the smoothing kernels (kernels/sph_kernels.c, docs/kernels.md) through the public
 * API only: normalisation by exact quadrature, derivatives against finite differences,
 * continuity at the piece breakpoints, exact zeros at and beyond the support, hand-computed
 * values, names and NaN on invalid arguments. */
#include "check.h"
#include "pstencil.h"

#include <math.h>
#include <stdio.h>

#define PI 3.14159265358979323846
#define NKERNELS 4

/* Gauss-Legendre rule with GL_N points on [-1, 1], computed by Newton on P_n; exact for
 * polynomials of degree <= 2*GL_N - 1 = 19, more than the degree-10 integrands here
 * (Wendland C4 in 3D: degree 8 times r^2), so the quadrature itself is exact to rounding. */
#define GL_N 10
static double gl_x[GL_N], gl_w[GL_N];

static void gl_init(void)
{
    for (int i = 0; i < GL_N; ++i) {
        double x = cos(PI * (i + 0.75) / (GL_N + 0.5)), dp = 0.0;
        for (int it = 0; it < 100; ++it) {
            double p0 = 1.0, p1 = x;
            for (int n = 2; n <= GL_N; ++n) {
                double p2 = ((2.0 * n - 1.0) * x * p1 - (n - 1.0) * p0) / n;
                p0 = p1;
                p1 = p2;
            }
            dp = GL_N * (x * p1 - p0) / (x * x - 1.0);
            double dx = p1 / dp;
            x -= dx;
            if (fabs(dx) < 1e-16)
                break;
        }
        gl_x[i] = x;
        gl_w[i] = 2.0 / ((1.0 - x * x) * dp * dp);
    }
}

/* Integral of W over R^dim as a radial integral (1D: 2 int W dr, 2D: 2 pi int W r dr, 3D:
 * 4 pi int W r^2 dr), Gauss-Legendre on each polynomial piece [j h, (j+1) h], j < support. */
static double kernel_integral(pst_kernel k, int dim, double h)
{
    const double meas = dim == 1 ? 2.0 : dim == 2 ? 2.0 * PI : 4.0 * PI;
    const int pieces = (int)pst_kernel_support(k);
    double sum = 0.0;
    for (int j = 0; j < pieces; ++j) {
        const double a = j * h, b = (j + 1) * h, mid = 0.5 * (a + b), half = 0.5 * (b - a);
        for (int i = 0; i < GL_N; ++i) {
            const double r = mid + half * gl_x[i];
            sum += half * gl_w[i] * pst_kernel_w(k, dim, r, h) * pow(r, dim - 1);
        }
    }
    return meas * sum;
}

/* Normalisation constant C_D = sigma / h^dim, written out independently of the library. */
static double norm_const(pst_kernel k, int dim, double h)
{
    static const double sigma[NKERNELS][3] = {
        {2.0 / 3.0, 10.0 / (7.0 * PI), 1.0 / PI},
        {1.0 / 120.0, 7.0 / (478.0 * PI), 1.0 / (120.0 * PI)},
        {5.0 / 8.0, 7.0 / (4.0 * PI), 21.0 / (16.0 * PI)},
        {3.0 / 4.0, 9.0 / (4.0 * PI), 495.0 / (256.0 * PI)},
    };
    return sigma[k][dim - 1] / pow(h, dim);
}

static void test_names(void)
{
    static const char *names[NKERNELS] = {"cubic", "quintic", "wendland_c2", "wendland_c4"};
    static const double support[NKERNELS] = {2.0, 3.0, 2.0, 2.0};
    for (int k = 0; k < NKERNELS; ++k) {
        CHECK_INT(pst_kernel_from_name(pst_kernel_name((pst_kernel)k)), k);
        CHECK_INT(pst_kernel_from_name(names[k]), k);
        CHECK(pst_kernel_support((pst_kernel)k) == support[k]);
    }
    CHECK_INT(pst_kernel_from_name("gaussian"), -1);
    CHECK_INT(pst_kernel_from_name(""), -1);
    CHECK_INT(pst_kernel_from_name("cubic "), -1);
    CHECK_INT(pst_kernel_from_name(NULL), -1);
    CHECK(pst_kernel_name((pst_kernel)7) != NULL);
    CHECK(isnan(pst_kernel_support((pst_kernel)7)));
}

/* Integral of W is 1 for every kernel, dimension and several h (an odd h catches a missing
 * power of h). Claimed accuracy 1e-12, tighter than the 1e-6 requirement: the rule is exact. */
static void test_normalisation(void)
{
    static const double hs[] = {1.0, 0.37, 2.5};
    for (int k = 0; k < NKERNELS; ++k)
        for (int dim = 1; dim <= 3; ++dim)
            for (size_t ih = 0; ih < sizeof hs / sizeof hs[0]; ++ih)
                CHECK_NEAR(kernel_integral((pst_kernel)k, dim, hs[ih]), 1.0, 1e-12);
}

/* dW/dr and d2W/dr2 against central differences of W and dW with step d = 2e-5 h at 400
 * radii spread over (0, support h), skipping 1e-3 h around the breakpoints q = 1, 2 (the
 * cubic's d2W has a kink there). Truncation ~ d^2 |f'''|/6 and rounding ~ 1e-16/d keep the
 * error near 1e-9 (measured max 1.5e-9), so the stated tolerance is 1e-7 of max|dW| (resp.
 * max|d2W|) over the support; a bound relative to each point's value would fail where dW or
 * d2W crosses 0. Also checks the sign convention: dW/dr <= 0 everywhere (monotone kernels). */
static void test_derivatives(void)
{
    const double h = 0.7, d = 2e-5 * h, tol = 1e-7;
    enum { N = 400 };
    for (int k = 0; k < NKERNELS; ++k) {
        const double sup = pst_kernel_support((pst_kernel)k);
        for (int dim = 1; dim <= 3; ++dim) {
            double err1 = 0.0, err2 = 0.0, max1 = 0.0, max2 = 0.0, dwmax = -INFINITY;
            int used = 0;
            for (int i = 0; i < N; ++i) {
                const double q = sup * (i + 0.5) / N;
                if (fabs(q - nearbyint(q)) < 1e-3)
                    continue;
                const double r = q * h;
                const double dw = pst_kernel_dw((pst_kernel)k, dim, r, h);
                const double d2w = pst_kernel_d2w((pst_kernel)k, dim, r, h);
                const double fd1 = (pst_kernel_w((pst_kernel)k, dim, r + d, h)
                                    - pst_kernel_w((pst_kernel)k, dim, r - d, h)) / (2.0 * d);
                const double fd2 = (pst_kernel_dw((pst_kernel)k, dim, r + d, h)
                                    - pst_kernel_dw((pst_kernel)k, dim, r - d, h)) / (2.0 * d);
                err1 = fmax(err1, fabs(fd1 - dw));
                err2 = fmax(err2, fabs(fd2 - d2w));
                max1 = fmax(max1, fabs(dw));
                max2 = fmax(max2, fabs(d2w));
                dwmax = fmax(dwmax, dw);
                ++used;
            }
            CHECK(used > N - 10);
            CHECK_NEAR(err1 / max1, 0.0, tol);
            CHECK_NEAR(err2 / max2, 0.0, tol);
            CHECK(dwmax <= 0.0);
        }
    }
}

/* W, dW and d2W are continuous at every breakpoint, the support edge included (all four
 * kernels are at least C2): the jump across q0 +- 1e-9 must be below 1e-6 of the function's
 * scale at 0 (W(0), and |d2W(0)| for both derivatives since dW(0) = 0). */
static void test_continuity(void)
{
    const double h = 1.3, eps = 1e-9 * h;
    for (int k = 0; k < NKERNELS; ++k) {
        const pst_kernel kk = (pst_kernel)k;
        const int sup = (int)pst_kernel_support(kk);
        const int first = (k == PST_KERNEL_CUBIC || k == PST_KERNEL_QUINTIC) ? 1 : sup;
        for (int dim = 1; dim <= 3; ++dim) {
            const double sw = pst_kernel_w(kk, dim, 0.0, h);
            const double sd = fabs(pst_kernel_d2w(kk, dim, 0.0, h)) * h;
            const double sd2 = fabs(pst_kernel_d2w(kk, dim, 0.0, h));
            for (int q0 = first; q0 <= sup; ++q0) {
                const double a = q0 * h - eps, b = q0 * h + eps;
                CHECK_NEAR(pst_kernel_w(kk, dim, a, h), pst_kernel_w(kk, dim, b, h), 1e-6 * sw);
                CHECK_NEAR(pst_kernel_dw(kk, dim, a, h), pst_kernel_dw(kk, dim, b, h), 1e-6 * sd);
                CHECK_NEAR(pst_kernel_d2w(kk, dim, a, h), pst_kernel_d2w(kk, dim, b, h),
                           1e-6 * sd2);
            }
        }
    }
}

/* Exactly 0 at r = support*h (as a caller computes it) and beyond, including r = inf, for h
 * whose product with 3 is inexact; and W(0) = C_D * f(0), dW(0) = 0 exactly. */
static void test_support_and_origin(void)
{
    static const double hs[] = {1.0, 0.1, 0.37, 1.7};
    for (int k = 0; k < NKERNELS; ++k) {
        const pst_kernel kk = (pst_kernel)k;
        const double sup = pst_kernel_support(kk);
        for (int dim = 1; dim <= 3; ++dim) {
            for (size_t ih = 0; ih < sizeof hs / sizeof hs[0]; ++ih) {
                const double h = hs[ih], edge = sup * h;
                const double rs[] = {edge, nextafter(edge, INFINITY), 1.5 * edge, 100.0 * h,
                                     INFINITY};
                for (size_t ir = 0; ir < sizeof rs / sizeof rs[0]; ++ir) {
                    CHECK(pst_kernel_w(kk, dim, rs[ir], h) == 0.0);
                    CHECK(pst_kernel_dw(kk, dim, rs[ir], h) == 0.0);
                    CHECK(pst_kernel_d2w(kk, dim, rs[ir], h) == 0.0);
                }
                /* Just inside the support W is still positive: the cut is not early. */
                CHECK(pst_kernel_w(kk, dim, nextafter(edge, 0.0) * (1.0 - 1e-6), h) > 0.0);
                CHECK(pst_kernel_dw(kk, dim, 0.0, h) == 0.0);
            }
            /* W(0): quintic 66 C_D (QSFDI section 3); cubic and Wendland f(0) = 1. */
            const double h = 0.9, c = norm_const(kk, dim, h);
            const double w0 = k == PST_KERNEL_QUINTIC ? 66.0 * c : c;
            CHECK_NEAR(pst_kernel_w(kk, dim, 0.0, h), w0, 1e-14 * w0);
        }
    }
}

/* One or more values per kernel computed by hand from the piece formulas, at h = 0.8. */
static void test_hand_values(void)
{
    const double h = 0.8, h2 = h * h, h3 = h2 * h, h4 = h3 * h;
    const double rel = 1e-14;
    double e;
    /* cubic 2D, q = 1: 10/(7 pi h^2) * 0.25 */
    e = 10.0 / (7.0 * PI * h2) * 0.25;
    CHECK_NEAR(pst_kernel_w(PST_KERNEL_CUBIC, 2, 1.0 * h, h), e, rel * e);
    /* cubic 1D, q = 0.5: 2/(3h) * (1 - 0.375 + 0.09375): the corrected 2/3, not 3/2 */
    e = 2.0 / (3.0 * h) * 0.71875;
    CHECK_NEAR(pst_kernel_w(PST_KERNEL_CUBIC, 1, 0.5 * h, h), e, rel * e);
    /* cubic 3D, q = 1.5: dW/dr = 1/(pi h^4) * (-0.75 * 0.5^2) */
    e = -0.1875 / (PI * h4);
    CHECK_NEAR(pst_kernel_dw(PST_KERNEL_CUBIC, 3, 1.5 * h, h), e, rel * fabs(e));
    /* cubic 2D, q = 0: d2W/dr2 = 10/(7 pi h^4) * (-3) */
    e = -30.0 / (7.0 * PI * h4);
    CHECK_NEAR(pst_kernel_d2w(PST_KERNEL_CUBIC, 2, 0.0, h), e, rel * fabs(e));
    /* quintic 3D, q = 1.5: (1.5^5 - 6 * 0.5^5) / (120 pi h^3) = 7.40625 / (120 pi h^3) */
    e = 7.40625 / (120.0 * PI * h3);
    CHECK_NEAR(pst_kernel_w(PST_KERNEL_QUINTIC, 3, 1.5 * h, h), e, rel * e);
    /* quintic 2D, q = 0.5: (2.5^5 - 6 * 1.5^5 + 15 * 0.5^5) = 52.5625, times 7/(478 pi h^2) */
    e = 52.5625 * 7.0 / (478.0 * PI * h2);
    CHECK_NEAR(pst_kernel_w(PST_KERNEL_QUINTIC, 2, 0.5 * h, h), e, rel * e);
    /* quintic 1D, q = 2.5: dW/dr = -5 * 0.5^4 / (120 h^2) */
    e = -5.0 * 0.0625 / (120.0 * h2);
    CHECK_NEAR(pst_kernel_dw(PST_KERNEL_QUINTIC, 1, 2.5 * h, h), e, rel * fabs(e));
    /* Wendland C2 2D, q = 1: 7/(4 pi h^2) * 0.5^4 * 3 */
    e = 7.0 / (4.0 * PI * h2) * 0.1875;
    CHECK_NEAR(pst_kernel_w(PST_KERNEL_WENDLAND_C2, 2, 1.0 * h, h), e, rel * e);
    /* Wendland C2 1D, q = 1: 5/(8h) * 0.5^3 * 2.5 */
    e = 5.0 / (8.0 * h) * 0.3125;
    CHECK_NEAR(pst_kernel_w(PST_KERNEL_WENDLAND_C2, 1, 1.0 * h, h), e, rel * e);
    /* Wendland C2 3D, q = 1: dW/dr = 21/(16 pi h^4) * (-5 * 1 * 0.5^3) */
    e = 21.0 / (16.0 * PI * h4) * -0.625;
    CHECK_NEAR(pst_kernel_dw(PST_KERNEL_WENDLAND_C2, 3, 1.0 * h, h), e, rel * fabs(e));
    /* Wendland C4 3D, q = 1: 495/(256 pi h^3) * 0.5^6 * (35/12 + 3 + 1) = ... * 83/768 */
    e = 495.0 / (256.0 * PI * h3) * (83.0 / 768.0);
    CHECK_NEAR(pst_kernel_w(PST_KERNEL_WENDLAND_C4, 3, 1.0 * h, h), e, rel * e);
    /* Wendland C4 1D, q = 1: 3/(4h) * 0.5^5 * (2 + 2.5 + 1) */
    e = 3.0 / (4.0 * h) * (5.5 / 32.0);
    CHECK_NEAR(pst_kernel_w(PST_KERNEL_WENDLAND_C4, 1, 1.0 * h, h), e, rel * e);
    /* Wendland C4 2D, q = 0: d2W/dr2 = 9/(4 pi h^4) * (-14/3) */
    e = 9.0 / (4.0 * PI * h4) * (-14.0 / 3.0);
    CHECK_NEAR(pst_kernel_d2w(PST_KERNEL_WENDLAND_C4, 2, 0.0, h), e, rel * fabs(e));
}

/* Invalid arguments give NaN from all three evaluation functions. */
static void test_invalid(void)
{
    const struct {
        int k, dim;
        double r, h;
    } bad[] = {
        {0, 2, 0.5, 0.0},   {1, 2, 0.5, -1.0}, {2, 3, 0.5, NAN},   {3, 1, 0.5, INFINITY},
        {0, 2, -1e-300, 1}, {1, 3, NAN, 1.0},  {0, 0, 0.5, 1.0},   {1, 4, 0.5, 1.0},
        {4, 2, 0.5, 1.0},   {-1, 2, 0.5, 1.0}, {0, -1, 0.5, -1.0},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        const pst_kernel k = (pst_kernel)bad[i].k;
        CHECK(isnan(pst_kernel_w(k, bad[i].dim, bad[i].r, bad[i].h)));
        CHECK(isnan(pst_kernel_dw(k, bad[i].dim, bad[i].r, bad[i].h)));
        CHECK(isnan(pst_kernel_d2w(k, bad[i].dim, bad[i].r, bad[i].h)));
    }
}

int main(void)
{
    gl_init();
    test_names();
    test_normalisation();
    test_derivatives();
    test_continuity();
    test_support_and_origin();
    test_hand_values();
    test_invalid();
    return check_summary("test_kernels");
}
