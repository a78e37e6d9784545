/* The benchmark programs' shared set-up; see bench_common.h. */
#include "bench_common.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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

static int by_value(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

double bench_median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, by_value);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

pst_cloud *bench_poisson_cloud(const char *who, int dim, size_t n, double h_ratio)
{
    pst_lattice_opts o = bench_box(dim, 1, 1.0 / bench_side(n, dim), 0.3, h_ratio);
    o.boundary_layer = 1;
    return bench_lattice(who, &o);
}

static double exact(int dim, const double *x)
{
    return dim == 2 ? sin(6 * x[0] + 8 * x[1]) : sin(2 * x[0] + 3 * x[1] + 4 * x[2]);
}

static double laplacian(int dim, const double *x)
{
    return dim == 2 ? -100 * sin(6 * x[0] + 8 * x[1]) : -29 * sin(2 * x[0] + 3 * x[1] + 4 * x[2]);
}

void bench_poisson_rhs(const pst_cloud *c, double *b, double *ue)
{
    int dim = pst_cloud_dim(c);
    const uint8_t *kind = pst_cloud_kinds_const(c);
    for (size_t i = 0; i < pst_cloud_size(c); ++i) {
        double x[3] = {0, 0, 0};
        for (int d = 0; d < dim; ++d)
            x[d] = pst_cloud_coord_const(c, d)[i];
        ue[i] = exact(dim, x);
        b[i] = kind[i] == PST_DIRICHLET ? ue[i] : laplacian(dim, x);
    }
}

void bench_peak_reset(void)
{
    FILE *f = fopen("/proc/self/clear_refs", "w");
    if (f) {
        fputs("5", f);
        fclose(f);
    }
}

double bench_memory(const char *key)
{
    FILE *f = fopen("/proc/self/status", "r");
    char line[256];
    double kb = 0;
    size_t len = strlen(key);
    while (f && fgets(line, sizeof line, f))
        if (strncmp(line, key, len) == 0 && line[len] == ':')
            kb = atof(line + len + 1);
    if (f)
        fclose(f);
    return kb * 1024;
}
