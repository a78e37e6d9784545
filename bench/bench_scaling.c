/* Multicore scaling of the engine's phases (bench/README.md, "bench_scaling"; bench/scaling.sh
 * runs it at 1, 2, 4, 8, 16 threads, as many as the machine has).
 *
 * The manufactured Poisson problem of bench_solve (bench_poisson_cloud: jittered lattice on the
 * unit box, K = 0.3, h = 1.2 s0, Dirichlet layer), Morton-sorted once. Per repetition and per
 * thread count, alternating the thread counts so that each is measured beside the others:
 *   triad         a STREAM triad over 3 x 80 MB (the bandwidth the stored apply is bound by)
 *   neighbours    pst_nlist_build at the scheme's default support
 *   precompute    pst_op_create
 *   stored apply  pst_op_apply_stored, the mean of 10 (weights stored once, untimed)
 *   matrix-free   pst_op_apply, the mean of 3
 *   solve set-up  pst_krylov_create: GMRES(50) with AMG (hypre: serial in Debian's build)
 *   solve         pst_krylov_solve to rtol 1e-8 from u = 0, matrix-free
 * The table gives the median time per thread count, the speed-up t(1) / t(p) and the parallel
 * efficiency t(1) / (p t(p)). The solve's iterations are the same at every thread count
 * (reductions in a fixed order), so its rows compare equal work.
 *
 * usage: bench_scaling [--dim 2|3] [--n N] [--scheme S] [--threads 1,2,..] [--reps R]
 * Defaults: 3, 1000000, qsfdi, 1,2 (bench/scaling.sh passes 1..16 up to the core count), 3. */
#include "bench_common.h"
#include "peak.h"
#include "pstencil.h"
#include "stream.h"
#include "support.h"

#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAXT 8
#define MAXREPS 15
#define TRIAD_N 10000000 /* 3 x 80 MB: beyond most caches, not a 300 MiB L3 (bench/README.md) */

enum { TRIAD, NEIGHBOURS, PRECOMPUTE, STORED, FREE, SETUP, SOLVE, NPHASE };
static const char *const phase_names[NPHASE] = {
    "triad (reference)", "neighbour list", "precompute",          "stored apply",
    "matrix-free apply", "solve set-up (AMG)", "solve (GMRES iterations)"};

typedef struct {
    int dim, threads[MAXT], nthreads, reps;
    size_t n;
    const char *scheme;
} args;

static int parse(int argc, char **argv, args *a)
{
    *a = (args){.dim = 3, .threads = {1, 2}, .nthreads = 2, .reps = 3, .n = 1000000,
                .scheme = "qsfdi"};
    for (int i = 1; i < argc; i += 2) {
        const char *v = i + 1 < argc ? argv[i + 1] : "";
        if (strcmp(argv[i], "--dim") == 0)
            a->dim = atoi(v);
        else if (strcmp(argv[i], "--n") == 0)
            a->n = (size_t)atof(v);
        else if (strcmp(argv[i], "--scheme") == 0)
            a->scheme = v;
        else if (strcmp(argv[i], "--reps") == 0)
            a->reps = atoi(v);
        else if (strcmp(argv[i], "--threads") == 0) {
            a->nthreads = 0;
            for (const char *p = v; *p && a->nthreads < MAXT;
                 p = strchr(p, ',') ? strchr(p, ',') + 1 : "")
                a->threads[a->nthreads++] = atoi(p);
        } else {
            fprintf(stderr, "bench_scaling: unknown option %s\n", argv[i]);
            return -1;
        }
    }
    for (int t = 0; t < a->nthreads; ++t)
        if (a->threads[t] < 1 || a->threads[t] > 1024) {
            fprintf(stderr, "bench_scaling: thread counts 1..1024\n");
            return -1;
        }
    if ((a->dim != 2 && a->dim != 3) || a->reps < 1 || a->reps > MAXREPS || a->nthreads < 1 ||
        a->n < 1000 || a->n > 100000000) {
        fprintf(stderr, "bench_scaling: --dim 2|3, --reps 1..%d, --n 1000..1e8\n", MAXREPS);
        return -1;
    }
    if (pst_scheme_default_kernel(a->scheme) == PST_KERNEL_UNKNOWN) {
        fprintf(stderr, "bench_scaling: unknown scheme '%s'\n", a->scheme);
        return -1;
    }
    return 0;
}

/* What one repetition at one thread count needs: the cloud, its list, the stored operator. */
typedef struct {
    pst_cloud *c;
    pst_nlist *nl;
    pst_op *op;
    double support, *u, *y, *b, *ta, *tb, *tc;
    size_t np;
} problem;

static int fail(const char *what, const char *err)
{
    fprintf(stderr, "bench_scaling: %s: %s\n", what, err);
    return -1;
}

/* Every phase once at the current thread count; t[phase] in seconds, *iters the solve's. */
static int one_rep(problem *p, const args *a, double t[NPHASE], int *iters)
{
    char err[PST_ERRLEN] = "";
    double t0 = omp_get_wtime();
    pstb_triad_pass(p->ta, p->tb, p->tc, TRIAD_N);
    t[TRIAD] = omp_get_wtime() - t0;

    pst_nlist *nl = NULL;
    t0 = omp_get_wtime();
    if (pst_nlist_build(&nl, p->c, p->support, err) != PST_OK)
        return fail("neighbour list", err);
    t[NEIGHBOURS] = omp_get_wtime() - t0;
    pst_nlist_destroy(nl);

    pst_op_opts oo;
    pst_op_defaults(&oo);
    oo.scheme = a->scheme;
    pst_op *op = NULL;
    t0 = omp_get_wtime();
    if (pst_op_create(&op, p->c, p->nl, &oo, err) != PST_OK)
        return fail("precompute", err);
    t[PRECOMPUTE] = omp_get_wtime() - t0;
    pst_op_destroy(op);

    t0 = omp_get_wtime();
    for (int r = 0; r < 10; ++r)
        pst_op_apply_stored(p->op, p->u, p->y);
    t[STORED] = (omp_get_wtime() - t0) / 10;
    t0 = omp_get_wtime();
    for (int r = 0; r < 3; ++r)
        pst_op_apply(p->op, p->u, p->y);
    t[FREE] = (omp_get_wtime() - t0) / 3;

    pst_solve_opts so;
    pst_solve_defaults(&so);
    so.solver = PST_SOLVER_GMRES;
    so.precond = pst_have_amg() ? PST_PREC_AMG : PST_PREC_JACOBI;
    so.rtol = 1e-8;
    pst_krylov *ks = NULL;
    pst_solve_result r = {0};
    memset(p->y, 0, p->np * sizeof *p->y);
    t0 = omp_get_wtime();
    int st = pst_krylov_create(&ks, p->op, &so, err);
    t[SETUP] = omp_get_wtime() - t0;
    t0 = omp_get_wtime();
    if (st == PST_OK)
        st = pst_krylov_solve(ks, p->b, p->y, &r, err);
    t[SOLVE] = omp_get_wtime() - t0;
    pst_krylov_destroy(ks);
    *iters = r.iterations;
    return st == PST_OK ? 0 : fail("solve", err);
}

static int setup(problem *p, const args *a)
{
    char err[PST_ERRLEN] = "";
    *p = (problem){0};
    p->c = bench_poisson_cloud("bench_scaling", a->dim, a->n, BENCH_H_RATIO);
    if (!p->c)
        return -1;
    p->support = pst_kernel_support(pst_scheme_default_kernel(a->scheme));
    p->np = pst_cloud_size(p->c);
    pst_cloud_morton_sort(p->c, p->support * BENCH_H_RATIO / bench_side(a->n, a->dim), NULL);
    pst_op_opts oo;
    pst_op_defaults(&oo);
    oo.scheme = a->scheme;
    if (pst_nlist_build(&p->nl, p->c, p->support, err) != PST_OK ||
        pst_op_create(&p->op, p->c, p->nl, &oo, err) != PST_OK)
        return fail(a->scheme, err);
    if (pst_op_store(p->op) != PST_OK)
        return fail(a->scheme, "cannot store the weights");
    p->u = malloc(p->np * sizeof *p->u);
    p->y = malloc(p->np * sizeof *p->y);
    p->b = malloc(p->np * sizeof *p->b);
    double *ue = malloc(p->np * sizeof *ue);
    p->ta = malloc(TRIAD_N * sizeof *p->ta);
    p->tb = malloc(TRIAD_N * sizeof *p->tb);
    p->tc = malloc(TRIAD_N * sizeof *p->tc);
    if (!p->u || !p->y || !p->b || !ue || !p->ta || !p->tb || !p->tc) {
        free(ue);
        return fail("set-up", "out of memory");
    }
    bench_poisson_rhs(p->c, p->b, ue);
    memcpy(p->u, ue, p->np * sizeof *ue);
    free(ue);
    pstb_triad_fill(p->ta, p->tb, p->tc, TRIAD_N);
    return 0;
}

static void teardown(problem *p)
{
    pst_op_destroy(p->op);
    pst_nlist_destroy(p->nl);
    pst_cloud_destroy(p->c);
    free(p->u);
    free(p->y);
    free(p->b);
    free(p->ta);
    free(p->tb);
    free(p->tc);
}

static void print_table(const args *a, const problem *p, double t[MAXT][NPHASE][MAXREPS],
                        const int *iters)
{
    int cores = omp_get_num_procs();
    printf("\n## scaling: %dD %zu particles, %s, %.0f neighbours per particle, %d cores; "
           "medians of %d alternated repetitions; solve %d iterations\n\n",
           a->dim, p->np, a->scheme,
           (double)pst_op_pattern_pairs(p->op) / (double)p->np, cores, a->reps, iters[0]);
    printf("| phase |");
    for (int k = 0; k < a->nthreads; ++k)
        printf(" %d thr s |", a->threads[k]);
    for (int k = 1; k < a->nthreads; ++k)
        printf(" speed-up / efficiency %d |", a->threads[k]);
    printf("\n|---|");
    for (int k = 0; k < 2 * a->nthreads - 1; ++k)
        printf("---|");
    printf("\n");
    for (int ph = 0; ph < NPHASE; ++ph) {
        double m[MAXT];
        printf("| %s |", phase_names[ph]);
        for (int k = 0; k < a->nthreads; ++k) {
            m[k] = bench_median(t[k][ph], a->reps);
            printf(" %.4g |", m[k]);
        }
        for (int k = 1; k < a->nthreads; ++k) {
            double s = m[0] / m[k] * a->threads[0];
            printf(" %.2f / %.0f %% |", s, 100.0 * s / a->threads[k]);
        }
        printf("\n");
    }
    for (int k = 0; k < a->nthreads; ++k)
        if (a->threads[k] > cores)
            printf("\n%d threads exceed the %d cores: that column is oversubscribed.\n",
                   a->threads[k], cores);
    for (int k = 1; k < a->nthreads; ++k)
        if (iters[k] != iters[0])
            printf("\nthe solve took %d iterations at %d threads, %d at %d\n", iters[k],
                   a->threads[k], iters[0], a->threads[0]);
}

int main(int argc, char **argv)
{
    args a;
    if (parse(argc, argv, &a) != 0)
        return 1;
    test_mpi_init();
    pstb_probes pr;
    pstb_probes_run(&pr);
    char line[2048];
    pstb_probes_line(&pr, line, sizeof line);
    printf("# machine: %s\n", line);
    problem p;
    if (setup(&p, &a) != 0) {
        teardown(&p);
        return 1;
    }
    static double t[MAXT][NPHASE][MAXREPS];
    int iters[MAXT] = {0}, saved = omp_get_max_threads(), st = 0;
    for (int r = 0; r < a.reps && st == 0; ++r)
        for (int k = 0; k < a.nthreads && st == 0; ++k) {
            double tk[NPHASE] = {0};
            omp_set_num_threads(a.threads[k]);
            st = one_rep(&p, &a, tk, &iters[k]);
            for (int ph = 0; ph < NPHASE; ++ph)
                t[k][ph][r] = tk[ph];
            fprintf(stderr, "bench_scaling: repetition %d, %d threads done\n", r + 1,
                    a.threads[k]);
        }
    omp_set_num_threads(saved);
    if (st == 0)
        print_table(&a, &p, t, iters);
    teardown(&p);
    return st == 0 ? 0 : 1;
}
