#include "stream.h"

#include <omp.h>
#include <stdlib.h>

void pstb_triad_fill(double *a, double *b, double *c, size_t n)
{
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; ++i) {
        a[i] = 0.0;
        b[i] = 1.0;
        c[i] = 2.0;
    }
}

void pstb_triad_pass(double *a, const double *b, const double *c, size_t n)
{
    const double s = 3.0;
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; ++i)
        a[i] = b[i] + s * c[i];
}

double pstb_triad_gbs(size_t n, int reps)
{
    double *a = malloc(n * sizeof *a), *b = malloc(n * sizeof *b), *c = malloc(n * sizeof *c);
    double best = 0;
    if (a && b && c) {
        pstb_triad_fill(a, b, c, n);
        pstb_triad_pass(a, b, c, n); /* warm-up: page faults and frequency ramp */
        for (int r = 0; r < reps; ++r) {
            double t = omp_get_wtime();
            pstb_triad_pass(a, b, c, n);
            t = omp_get_wtime() - t;
            double gbs = 24.0 * (double)n / t * 1e-9;
            best = gbs > best ? gbs : best;
        }
        for (size_t i = 0; i < n; i += 4096)
            if (a[i] != 7.0)
                best = 0;
    }
    free(a);
    free(b);
    free(c);
    return best;
}
