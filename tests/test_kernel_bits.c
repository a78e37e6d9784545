/* The kernel shapes (kernels/sph_kernels.h), evaluated in doubled truncated powers
 * T = 2 max(c - q, 0) with constants scaled by powers of 2, against the plain formulas in
 * t = max(c - q, 0) of docs/kernels.md written out here: the same bits for every q tried
 * (dense on [0, support + 0.5], the breakpoints and their neighbours, values of q that the
 * neighbour rows form), for the value and both derivatives, every kernel, 1D and 3D (2D has
 * the 3D formulas). */
#include "check.h"
#include "sph_kernels.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static double plain_pos(double x)
{
    return x > 0.0 ? x : 0.0;
}

/* The t-formulas of docs/kernels.md, each product written from its constant. */
static double plain_shape(pst_kernel k, int dim, double q, int deriv)
{
    if (k == PST_KERNEL_WENDLAND_C2 || k == PST_KERNEL_WENDLAND_C4) {
        const double t = plain_pos(1.0 - 0.5 * q), t2 = t * t;
        if (k == PST_KERNEL_WENDLAND_C2 && dim == 1)
            return deriv == 0   ? t2 * t * (1.5 * q + 1.0)
                   : deriv == 1 ? -3.0 * q * t2
                                : t * (4.5 * q - 3.0);
        if (k == PST_KERNEL_WENDLAND_C2)
            return deriv == 0   ? t2 * t2 * (2.0 * q + 1.0)
                   : deriv == 1 ? -5.0 * q * t2 * t
                                : t2 * (10.0 * q - 5.0);
        if (dim == 1)
            return deriv == 0   ? t2 * t2 * t * ((2.0 * q + 2.5) * q + 1.0)
                   : deriv == 1 ? -3.5 * q * t2 * t2 * (2.0 * q + 1.0)
                                : 1.75 * t2 * t * ((12.0 * q - 3.0) * q - 2.0);
        return deriv == 0   ? t2 * t2 * t2 * ((35.0 / 12.0 * q + 3.0) * q + 1.0)
               : deriv == 1 ? -(7.0 / 3.0) * q * t2 * t2 * t * (5.0 * q + 2.0)
                            : (7.0 / 6.0) * t2 * t2 * ((35.0 * q - 8.0) * q - 4.0);
    }
    if (k == PST_KERNEL_CUBIC) {
        const double t2 = plain_pos(2.0 - q), t1 = plain_pos(1.0 - q);
        if (deriv == 0)
            return 0.25 * t2 * t2 * t2 - t1 * t1 * t1;
        if (deriv == 1)
            return 3.0 * t1 * t1 - 0.75 * t2 * t2;
        return 1.5 * t2 - 6.0 * t1;
    }
    const double t3 = plain_pos(3.0 - q), t2 = plain_pos(2.0 - q), t1 = plain_pos(1.0 - q);
    const double s3 = t3 * t3, s2 = t2 * t2, s1 = t1 * t1;
    if (deriv == 0)
        return s3 * s3 * t3 - 6.0 * s2 * s2 * t2 + 15.0 * s1 * s1 * t1;
    if (deriv == 1)
        return 30.0 * s2 * s2 - 5.0 * s3 * s3 - 75.0 * s1 * s1;
    return 20.0 * s3 * t3 - 120.0 * s2 * t2 + 300.0 * s1 * t1;
}

static int same_bits(double a, double b)
{
    return memcmp(&a, &b, sizeof a) == 0;
}

/* Compares the two at q in 1D and 3D; returns 1 on a difference (and says where). */
static int differs(pst_kernel k, double q)
{
    for (int dim = 1; dim <= 3; dim += 2)
        for (int deriv = 0; deriv <= 2; ++deriv) {
            double a = pst_sph_shape(k, dim, q, deriv), b = plain_shape(k, dim, q, deriv);
            if (!same_bits(a, b)) {
                printf("  kernel %d dim %d deriv %d q = %.17g: %.17g against %.17g\n", (int)k,
                       dim, deriv, q, a, b);
                return 1;
            }
        }
    return 0;
}

int main(void)
{
    const pst_kernel ks[4] = {PST_KERNEL_CUBIC, PST_KERNEL_QUINTIC, PST_KERNEL_WENDLAND_C2,
                              PST_KERNEL_WENDLAND_C4};
    for (int m = 0; m < 4; ++m) {
        const double supp = pst_sph_support[ks[m]];
        long bad = 0, tried = 0;
        /* dense, and the irrational offsets a jittered cloud gives */
        for (long i = 0; i <= 400000; ++i, tried += 2) {
            double q = (supp + 0.5) * (double)i / 400000.0;
            bad += differs(ks[m], q);
            bad += differs(ks[m], sqrt(q * q + 1e-3 * (double)(i % 7)));
        }
        /* the breakpoints, a few ulps either side */
        for (double c = 1.0; c <= supp; c += 1.0) {
            double q = c;
            for (int s = 0; s < 8; ++s, q = nextafter(q, 0.0), ++tried)
                bad += differs(ks[m], q);
            q = c;
            for (int s = 0; s < 8; ++s, q = nextafter(q, 10.0), ++tried)
                bad += differs(ks[m], q);
        }
        /* tiny q (the nearest neighbours of a degenerate pair) and the origin */
        for (double q = 1e-300; q < 1e-3; q *= 1e3, ++tried)
            bad += differs(ks[m], q);
        bad += differs(ks[m], 0.0);
        printf("kernel %d: %ld of %ld values differ\n", (int)ks[m], bad, tried);
        CHECK(bad == 0);
    }
    return check_summary("test_kernel_bits");
}
