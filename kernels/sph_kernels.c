/* SPH smoothing kernels: names, support radii and the checked public W, dW/dr, d2W/dr2.
 * The maths lives in sph_kernels.h so that hot loops can inline it; formulas, constants and
 * sources are in docs/kernels.md. */
#include "internal.h"
#include "sph_kernels.h"

#include <math.h>
#include <string.h>

static const char *const kernel_names[4] = {"cubic", "quintic", "wendland_c2", "wendland_c4"};

const char *pst_kernel_name(pst_kernel k)
{
    /* Unsigned compare also rejects negative values cast into the enum. */
    if ((unsigned)k > (unsigned)PST_KERNEL_WENDLAND_C4)
        return "unknown";
    return kernel_names[k];
}

pst_kernel pst_kernel_from_name(const char *name)
{
    if (!name)
        return PST_KERNEL_UNKNOWN;
    for (int k = 0; k < 4; ++k)
        if (strcmp(name, kernel_names[k]) == 0)
            return (pst_kernel)k;
    return PST_KERNEL_UNKNOWN;
}

/* NaN for an unknown kernel, like the evaluation functions, so a bad value cannot silently
 * become a plausible support radius. */
double pst_kernel_support(pst_kernel k)
{
    if ((unsigned)k > (unsigned)PST_KERNEL_WENDLAND_C4)
        return NAN;
    return pst_sph_support[k];
}

/* Invalid arguments (unknown kernel, dim not 1..3, h <= 0 or not finite, r < 0, NaN) give
 * NaN rather than an error code: callers validate clouds and options once, up front, and
 * a NaN then poisons any result that a missed check would otherwise corrupt quietly. */
double pst_kernel_w(pst_kernel k, int dim, double r, double h)
{
    if (!pst_sph_valid(k, dim, r, h))
        return NAN;
    return pst_sph_w(k, dim, r, h);
}

double pst_kernel_dw(pst_kernel k, int dim, double r, double h)
{
    if (!pst_sph_valid(k, dim, r, h))
        return NAN;
    return pst_sph_dw(k, dim, r, h);
}

double pst_kernel_d2w(pst_kernel k, int dim, double r, double h)
{
    if (!pst_sph_valid(k, dim, r, h))
        return NAN;
    return pst_sph_d2w(k, dim, r, h);
}
