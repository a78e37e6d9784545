/* Time to solution of a manufactured Poisson problem (docs/solving.md): a jittered lattice on
 * the unit square or cube (K = 0.3, Dirichlet boundary layer), u = sin(6x + 8y) (2D) or
 * sin(2x + 3y + 4z) (3D), b = the exact Laplacian inside and u on the boundary, solved to a
 * relative residual of 1e-8. Prints the phases (cloud, neighbours, precompute, store, solve),
 * iterations, the eq. 15 error and the peak memory, one line per run.
 *
 * usage: bench_solve [--dim 2|3] [--n N] [--scheme S] [--precond jacobi|amg] [--stored 0|1]
 *                    [--h-ratio F]
 */
#include "pstencil.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

static double exact(int dim, const double *x)
{
    return dim == 2 ? sin(6 * x[0] + 8 * x[1]) : sin(2 * x[0] + 3 * x[1] + 4 * x[2]);
}

static double laplacian(int dim, const double *x)
{
    return dim == 2 ? -100 * sin(6 * x[0] + 8 * x[1]) : -29 * sin(2 * x[0] + 3 * x[1] + 4 * x[2]);
}

int main(int argc, char **argv)
{
    int dim = 2, stored = 1, precond = PST_PREC_AMG;
    size_t n = 1000000;
    double ratio = 1.2;
    const char *scheme = "qsfdi";
    for (int i = 1; i + 1 < argc; i += 2) {
        if (strcmp(argv[i], "--dim") == 0)
            dim = atoi(argv[i + 1]);
        else if (strcmp(argv[i], "--n") == 0)
            n = (size_t)atol(argv[i + 1]);
        else if (strcmp(argv[i], "--scheme") == 0)
            scheme = argv[i + 1];
        else if (strcmp(argv[i], "--precond") == 0)
            precond = strcmp(argv[i + 1], "amg") == 0 ? PST_PREC_AMG : PST_PREC_JACOBI;
        else if (strcmp(argv[i], "--stored") == 0)
            stored = atoi(argv[i + 1]);
        else if (strcmp(argv[i], "--h-ratio") == 0)
            ratio = atof(argv[i + 1]);
        else {
            fprintf(stderr, "bench_solve: unknown option %s\n", argv[i]);
            return 1;
        }
    }
    if (dim != 2 && dim != 3) {
        fprintf(stderr, "bench_solve: --dim 2 or 3\n");
        return 1;
    }
    char err[PST_ERRLEN];
    double t0 = omp_get_wtime();
    pst_lattice_opts o;
    pst_lattice_defaults(&o);
    o.dim = dim;
    int side = (int)lround(pow((double)n, 1.0 / dim)) - 1;
    for (int d = 0; d < 3; ++d) {
        o.lo[d] = 0;
        o.hi[d] = 1;
    }
    o.s0 = 1.0 / side;
    o.jitter = 0.3;
    o.boundary_layer = 1;
    o.h_ratio = ratio;
    pst_cloud *c = NULL;
    if (pst_cloud_lattice(&c, &o, err) != PST_OK) {
        fprintf(stderr, "bench_solve: %s\n", err);
        return 1;
    }
    double support = pst_kernel_support(pst_scheme_default_kernel(scheme));
    pst_cloud_morton_sort(c, support * ratio * o.s0);
    double t1 = omp_get_wtime();
    pst_nlist *nl = NULL;
    if (pst_nlist_build(&nl, c, support, err) != PST_OK) {
        fprintf(stderr, "bench_solve: %s\n", err);
        return 1;
    }
    double t2 = omp_get_wtime();
    pst_op_opts oo;
    pst_op_defaults(&oo);
    oo.scheme = scheme;
    pst_op *op = NULL;
    if (pst_op_create(&op, c, nl, &oo, err) != PST_OK) {
        fprintf(stderr, "bench_solve: %s\n", err);
        return 1;
    }
    double t3 = omp_get_wtime();
    if (stored && pst_op_store(op) != PST_OK) {
        fprintf(stderr, "bench_solve: cannot store the weights\n");
        return 1;
    }
    double t4 = omp_get_wtime();
    size_t np = pst_cloud_size(c);
    double *b = malloc(np * sizeof *b), *u = calloc(np, sizeof *u), *ue = malloc(np * sizeof *ue);
    const uint8_t *kind = pst_cloud_kinds_const(c);
    for (size_t i = 0; i < np; ++i) {
        double x[3] = {0, 0, 0};
        for (int d = 0; d < dim; ++d)
            x[d] = pst_cloud_coord_const(c, d)[i];
        ue[i] = exact(dim, x);
        b[i] = kind[i] == PST_DIRICHLET ? ue[i] : laplacian(dim, x);
    }
    pst_solve_opts so;
    pst_solve_defaults(&so);
    so.rtol = 1e-8;
    so.stored = stored;
    so.precond = precond;
    pst_solve_result r;
    int st = pst_solve(op, b, u, &so, &r, err);
    double t5 = omp_get_wtime();
    double num = 0, den = 0;
    for (size_t i = 0; i < np; ++i)
        if (kind[i] != PST_DIRICHLET) {
            num += (u[i] - ue[i]) * (u[i] - ue[i]);
            den += ue[i] * ue[i];
        }
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    printf("%dD %zu particles (%.1f neighbours) %s %s %s: cloud %.2f s, neighbours %.2f s, "
           "precompute %.2f s, store %.2f s, solve %.2f s (%d it, %s, rel. residual %.1e), "
           "eq. 15 error %.2e, peak memory %.2f GB\n",
           dim, np, (double)pst_nlist_pairs(nl) / (double)np, scheme,
           precond == PST_PREC_AMG ? "AMG" : "Jacobi", stored ? "stored" : "matrix-free",
           t1 - t0, t2 - t1, t3 - t2, t4 - t3, t5 - t4, r.iterations,
           st == PST_OK ? "converged" : "NOT converged", r.rel_residual, sqrt(num / den),
           (double)ru.ru_maxrss / (1 << 20));
    pst_solve_result_free(&r);
    free(b);
    free(u);
    free(ue);
    pst_op_destroy(op);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
    return st == PST_OK ? 0 : 3;
}
