/* Time to solution of a manufactured Poisson problem (docs/solving.md): a jittered lattice on
 * the unit square or cube (K = 0.3, Dirichlet boundary layer), u = sin(6x + 8y) (2D) or
 * sin(2x + 3y + 4z) (3D), b = the exact Laplacian inside and u on the boundary, solved to a
 * relative residual of 1e-8. Prints one markdown table row per run: the phases (neighbours,
 * precompute, store, solve), iterations, the eq. 15 error, the operator apply's rate beside a
 * STREAM triad measured in the same process, and the peak memory. bench/solve_table.sh runs
 * the grid of docs/solving.md.
 *
 * usage: bench_solve [--dim 2|3] [--n N] [--scheme S] [--precond jacobi|amg] [--stored 0|1]
 *                    [--h-ratio F] [--max-iter N] [--restart M] [--amg-radius F]
 *                    [--amg-aggressive L] [--amg-strong T] [--amg-source brookshaw|own|auto]
 *                    [--amg-coarsen hmis|pmis|falgout]
 *                    [--amg-interp ext_i|classical] [--amg-pmax P] [--header]
 *
 * "setup s" is the preconditioner's set-up (pst_krylov_create), "solve s" the iterations
 * (pst_krylov_solve); "AMG nnz/row" the entries per row of the matrix handed to hypre;
 * "setup peak" and "setup kept" the set-up's resident memory above what was there before it,
 * at its peak and after it (Linux /proc/self/status; the freed heap trimmed and the peak reset
 * first).
 *
 * --header prints "# machine: <cpu, topology, caches>; flags: <compiler flags>; triad ...,
 * FP64 peak ..." (src/machine.h, peak.h: probes run in this process) and the table header.
 */
#include "bench_common.h"
#include "pstencil.h"
#include "peak.h"
#include "stream.h"
#include "support.h"

#include <malloc.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

/* The operator's apply rate: the mean of `reps` applies of the path the solver uses. The stored
 * path's byte model is bench/README.md's: 12 bytes per pair (weight + index) and 32 per row. */
static double apply_seconds(const pst_op *op, size_t np, int stored, int reps)
{
    double *u = malloc(np * sizeof *u), *y = malloc(np * sizeof *y);
    for (size_t i = 0; i < np; ++i)
        u[i] = (double)(i % 7);
    double t = omp_get_wtime();
    for (int r = 0; r < reps; ++r) {
        if (stored)
            pst_op_apply_stored(op, u, y);
        else
            pst_op_apply(op, u, y);
    }
    t = (omp_get_wtime() - t) / reps;
    free(u);
    free(y);
    return t;
}

static void print_header(void)
{
    pstb_probes p;
    pstb_probes_run(&p);
    char line[2048];
    pstb_probes_line(&p, line, sizeof line);
    printf("# machine: %s\n", line);
    printf("| dim | particles | nbrs | scheme | precond | operator | neighbours s | precompute s "
           "| store s | setup s | solve s | iterations | rel. residual | eq. 15 error | apply ms "
           "| apply rate | AMG nnz/row | setup peak B/row | setup kept B/row | triad GB/s "
           "| peak GB |\n"
           "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
}

/* The names of the AMG options' values, in their enums' order. */
static const char *const sources[] = {"brookshaw", "own", "auto", NULL};
static const char *const coarsenings[] = {"hmis", "pmis", "falgout", NULL};
static const char *const interps[] = {"ext_i", "classical", NULL};

/* The index of `name` in the NULL-terminated `names`; an unknown name ends the program. */
static int name_index(const char *name, const char *const *names)
{
    for (int k = 0; names[k]; ++k)
        if (strcmp(name, names[k]) == 0)
            return k;
    fprintf(stderr, "bench_solve: unknown AMG option value %s\n", name);
    exit(1);
}

int main(int argc, char **argv)
{
    test_mpi_init();
    int dim = 2, stored = 1, precond = PST_PREC_AMG, max_iter = 0;
    size_t n = 1000000;
    double ratio = 1.2;
    pst_solve_opts so;
    pst_solve_defaults(&so);
    const char *scheme = "qsfdi";
    if (argc == 2 && strcmp(argv[1], "--header") == 0) {
        print_header();
        return 0;
    }
    for (int i = 1; i < argc; i += 2) {
        if (i + 1 == argc) {
            fprintf(stderr, "bench_solve: %s needs a value\n", argv[i]);
            return 1;
        }
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
        else if (strcmp(argv[i], "--max-iter") == 0)
            max_iter = atoi(argv[i + 1]);
        else if (strcmp(argv[i], "--restart") == 0)
            so.restart = atoi(argv[i + 1]);
        else if (strcmp(argv[i], "--amg-radius") == 0)
            so.amg_radius = atof(argv[i + 1]);
        else if (strcmp(argv[i], "--amg-aggressive") == 0)
            so.amg_aggressive = atoi(argv[i + 1]);
        else if (strcmp(argv[i], "--amg-strong") == 0)
            so.amg_strong = atof(argv[i + 1]);
        else if (strcmp(argv[i], "--amg-source") == 0)
            so.amg_source = name_index(argv[i + 1], sources);
        else if (strcmp(argv[i], "--amg-coarsen") == 0)
            so.amg_coarsen = name_index(argv[i + 1], coarsenings);
        else if (strcmp(argv[i], "--amg-interp") == 0)
            so.amg_interp = name_index(argv[i + 1], interps);
        else if (strcmp(argv[i], "--amg-pmax") == 0)
            so.amg_pmax = atoi(argv[i + 1]);
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
    /* 3 x 80 MB: beyond most caches (not a 300 MiB L3), small beside the solve's memory. */
    double triad = pstb_triad_gbs(10000000, 10);
    pst_cloud *c = bench_poisson_cloud("bench_solve", dim, n, ratio);
    if (!c)
        return 1;
    double support = pst_kernel_support(pst_scheme_default_kernel(scheme));
    pst_cloud_morton_sort(c, support * ratio * (1.0 / bench_side(n, dim)), NULL);
    bench_peak_reset();
    double t1 = omp_get_wtime(), rss1 = bench_memory("VmRSS");
    pst_nlist *nl = NULL;
    if (pst_nlist_build(&nl, c, support, err) != PST_OK) {
        fprintf(stderr, "bench_solve: %s\n", err);
        return 1;
    }
    double t2 = omp_get_wtime(), nl_peak = bench_memory("VmHWM") - rss1;
    bench_peak_reset();
    double rss2 = bench_memory("VmRSS");
    pst_op_opts oo;
    pst_op_defaults(&oo);
    oo.scheme = scheme;
    pst_op *op = NULL;
    if (pst_op_create(&op, c, nl, &oo, err) != PST_OK) {
        fprintf(stderr, "bench_solve: %s\n", err);
        return 1;
    }
    double t3 = omp_get_wtime(), op_peak = bench_memory("VmHWM") - rss2;
    if (stored && pst_op_store(op) != PST_OK) {
        fprintf(stderr, "bench_solve: cannot store the weights\n");
        return 1;
    }
    double t4 = omp_get_wtime();
    size_t np = pst_cloud_size(c);
    double *b = malloc(np * sizeof *b), *u = calloc(np, sizeof *u), *ue = malloc(np * sizeof *ue);
    const uint8_t *kind = pst_cloud_kinds_const(c);
    bench_poisson_rhs(c, b, ue);
    so.rtol = 1e-8;
    so.stored = stored;
    so.precond = precond;
    if (max_iter > 0)
        so.max_iter = max_iter;
    pst_solve_result r = {0};
    pst_krylov *ks = NULL;
    /* Freed heap pages (the cloud's set-up, the precompute's scratch) are handed back first:
     * reused, they would hide the set-up's peak below 10^6 rows. */
    malloc_trim(0);
    bench_peak_reset();
    double rss0 = bench_memory("VmRSS");
    int st = pst_krylov_create(&ks, op, &so, err);
    /* the set-up's own peak and what it keeps (the preconditioner and the Krylov vectors) */
    double setup_peak = bench_memory("VmHWM") - rss0, setup_kept = bench_memory("VmRSS") - rss0;
    double t45 = omp_get_wtime();
    if (st == PST_OK)
        st = pst_krylov_solve(ks, b, u, &r, err);
    else
        fprintf(stderr, "bench_solve: %s\n", err);
    pst_krylov_stats ksst;
    pst_krylov_get_stats(ks, &ksst);
    pst_krylov_destroy(ks);
    double t5 = omp_get_wtime();
    double num = 0, den = 0;
    for (size_t i = 0; i < np; ++i)
        if (kind[i] != PST_DIRICHLET) {
            num += (u[i] - ue[i]) * (u[i] - ue[i]);
            den += ue[i] * ue[i];
        }
    double ta = apply_seconds(op, np, stored, 10);
    double pairs = (double)pst_nlist_pairs(nl);
    char rate[64];
    if (stored) {
        double gbs = (12.0 * pairs + 32.0 * (double)np) / ta * 1e-9;
        snprintf(rate, sizeof rate, "%.1f GB/s (%.0f %%)", gbs, 100 * gbs / triad);
    } else {
        snprintf(rate, sizeof rate, "%.0f M pairs/s", pairs / ta * 1e-6);
    }
    fprintf(stderr, "bench_solve: peak B/row above the start of the phase: neighbours %.0f, "
            "precompute %.0f, solver set-up %.0f\n", nl_peak / (double)np, op_peak / (double)np,
            setup_peak / (double)np);
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    char pc[160] = "Jacobi";
    if (precond == PST_PREC_AMG)
        snprintf(pc, sizeof pc, "AMG %s r %g agg %d thr %g %s %s pmax %d",
                 so.amg_source == PST_AMG_OWN ||
                         (so.amg_source == PST_AMG_AUTO && pst_scheme_amg_own(scheme))
                     ? "own"
                     : "proxy",
                 so.amg_radius, so.amg_aggressive,
                 so.amg_strong > 0 ? so.amg_strong : dim == 3 ? 0.5 : 0.25,
                 coarsenings[so.amg_coarsen], interps[so.amg_interp], so.amg_pmax);
    printf("| %dD | %zu | %.1f | %s | %s | %s | %.2f | %.2f | %.2f | %.2f | %.2f | %d%s | %.1e "
           "| %.2e | %.1f | %s | %.1f | %.0f | %.0f | %.1f | %.2f |\n",
           dim, np, pairs / (double)np, scheme, pc,
           stored ? "stored" : "matrix-free", t2 - t1, t3 - t2, t4 - t3, t45 - t4, t5 - t45,
           r.iterations, st == PST_OK ? "" : " (not converged)", r.rel_residual,
           sqrt(num / den), ta * 1e3, rate, (double)ksst.amg_entries / (double)np,
           setup_peak / (double)np, setup_kept / (double)np, triad,
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
