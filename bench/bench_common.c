/* The benchmark programs' shared set-up; see bench_common.h. */
#include "bench_common.h"

#include <math.h>
#include <stdio.h>

pst_lattice_opts bench_box(int dim, double hi, double s0, double jitter, double h_ratio)
{
    pst_lattice_opts o;
    pst_lattice_defaults(&o);
    o.dim = dim;
    for (int d = 0; d < 3; ++d) {
        o.lo[d] = 0;
        o.hi[d] = hi;
    }
    o.s0 = s0;
    o.jitter = jitter;
    o.h_ratio = h_ratio;
    return o;
}

pst_cloud *bench_lattice(const char *who, const pst_lattice_opts *o)
{
    pst_cloud *c = NULL;
    char err[PST_ERRLEN];
    if (pst_cloud_lattice(&c, o, err) != PST_OK) {
        fprintf(stderr, "%s: %s\n", who, err);
        return NULL;
    }
    return c;
}

pst_cloud *bench_million(const char *who, int dim)
{
    pst_lattice_opts o = bench_box(dim, dim == 2 ? 999 : 99, 1.0, BENCH_JITTER, BENCH_H_RATIO);
    o.seed = 2024;
    return bench_lattice(who, &o);
}

int bench_side(size_t n, int dim) { return (int)lround(pow((double)n, 1.0 / dim)) - 1; }
