/* The stored apply against a STREAM triad measured beside it, and the float weight store
 * (pst_op_store_with PST_STORE_FLOAT) against the double one (bench/README.md, "bench_stored").
 *
 * Part "speed": per dimension and scheme, the 10^6-particle lattice of bench_operators
 * (bench_million: spacing 1, h = 1.2, jitter 0.5, all interior, Morton-sorted, the scheme's
 * default kernel's support), one operator stored in double and one in float. Per thread count
 * the repetitions alternate triad, double apply, float apply, so each triad is taken next to
 * the applies it is compared with; the medians are printed, and for the double apply also the
 * ratio of the best apply to the best triad (on a shared machine the slow repetitions are the
 * other programs'; the best of each is what the two loops can do). The triad's three arrays hold as
 * many bytes together as the double apply streams by the byte model: 12 bytes per pattern
 * entry (8 weight + 4 index) + 32 per row (offset, u_I, y_I, the u_J gathers once); the float
 * apply's model is 8 + 32.
 *
 * Part "accuracy": the manufactured Poisson problem of bench_solve (bench_poisson_cloud: unit
 * box, K = 0.3, h = 1.2 s0, Dirichlet layer; u = sin(6x + 8y) or sin(2x + 3y + 4z)). Per size
 * and scheme: the Laplacian of u from both stores over the interior rows, relative L2 against
 * each other and against the exact Laplacian; then GMRES with AMG (Jacobi without hypre) on
 * each store to rtol 1e-10 from u = 0: iterations, final relative residual, the error against
 * u (interior rows) and the distance between the two solutions.
 *
 * usage: bench_stored [--part speed|accuracy|all] [--dims 2,3] [--schemes a,b,..]
 *                     [--threads 1,2] [--reps R] [--sizes 2:N,3:N,..]
 * Defaults: all; 2,3; qsfdi,lpmps,lsmps,lv; 1,2; 11; 2:100000,2:1000000,3:125000,3:1000000.
 */
#include "bench_common.h"
#include "pstencil.h"
#include "stream.h"
#include "support.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAXL 8
#define MAXREPS 101

typedef struct {
    int dims[MAXL], ndims, threads[MAXL], nthreads, reps, nsizes, size_dim[MAXL];
    const char *schemes[MAXL];
    int nschemes;
    size_t sizes[MAXL];
    int speed, accuracy;
} args;

static char scheme_buf[256];

static int parse(int argc, char **argv, args *a)
{
    static const char *const defaults[] = {"qsfdi", "lpmps", "lsmps", "lv"};
    *a = (args){.dims = {2, 3}, .ndims = 2, .threads = {1, 2}, .nthreads = 2, .reps = 11,
                .nschemes = 4, .nsizes = 4, .size_dim = {2, 2, 3, 3},
                .sizes = {100000, 1000000, 125000, 1000000}, .speed = 1, .accuracy = 1};
    for (int k = 0; k < 4; ++k)
        a->schemes[k] = defaults[k];
    for (int i = 1; i < argc; i += 2) {
        if (i + 1 == argc) {
            fprintf(stderr, "bench_stored: %s needs a value\n", argv[i]);
            return -1;
        }
        const char *v = argv[i + 1];
        if (strcmp(argv[i], "--part") == 0) {
            if (strcmp(v, "speed") != 0 && strcmp(v, "accuracy") != 0 && strcmp(v, "all") != 0) {
                fprintf(stderr, "bench_stored: --part speed|accuracy|all, not %s\n", v);
                return -1;
            }
            a->speed = strcmp(v, "accuracy") != 0;
            a->accuracy = strcmp(v, "speed") != 0;
        } else if (strcmp(argv[i], "--dims") == 0 || strcmp(argv[i], "--threads") == 0) {
            int *out = argv[i][2] == 'd' ? a->dims : a->threads, k = 0;
            for (const char *p = v; *p && k < MAXL; p = strchr(p, ',') ? strchr(p, ',') + 1 : "")
                out[k++] = atoi(p);
            *(argv[i][2] == 'd' ? &a->ndims : &a->nthreads) = k;
        } else if (strcmp(argv[i], "--schemes") == 0) {
            snprintf(scheme_buf, sizeof scheme_buf, "%s", v);
            a->nschemes = 0;
            for (char *t = strtok(scheme_buf, ","); t && a->nschemes < MAXL; t = strtok(NULL, ","))
                a->schemes[a->nschemes++] = t;
        } else if (strcmp(argv[i], "--reps") == 0) {
            a->reps = atoi(v);
        } else if (strcmp(argv[i], "--sizes") == 0) {
            a->nsizes = 0;
            for (const char *p = v; *p && a->nsizes < MAXL;
                 p = strchr(p, ',') ? strchr(p, ',') + 1 : "") {
                a->size_dim[a->nsizes] = atoi(p);
                a->sizes[a->nsizes++] = (size_t)atof(strchr(p, ':') ? strchr(p, ':') + 1 : "0");
            }
        } else {
            fprintf(stderr, "bench_stored: unknown option %s\n", argv[i]);
            return -1;
        }
    }
    if (a->reps < 1 || a->reps > MAXREPS) {
        fprintf(stderr, "bench_stored: --reps 1..%d\n", MAXREPS);
        return -1;
    }
    return 0;
}

/* A list of c at the scheme's default support and the scheme's operator stored in `prec`. */
static pst_op *stored_op(const pst_cloud *c, const pst_nlist *nl, const char *scheme, int prec)
{
    char err[PST_ERRLEN] = "";
    pst_op_opts o;
    pst_op_defaults(&o);
    o.scheme = scheme;
    pst_op_store_opts so = {.precision = prec};
    pst_op *op = NULL;
    if (pst_op_create(&op, c, nl, &o, err) != PST_OK ||
        pst_op_store_with(op, &so, err) != PST_OK) {
        fprintf(stderr, "bench_stored: %s: %s\n", scheme, err);
        pst_op_destroy(op);
        return NULL;
    }
    return op;
}

static double scheme_support(const char *scheme)
{
    return pst_kernel_support((pst_kernel)pst_scheme_default_kernel(scheme));
}

/* One row of the speed table per thread count: medians of the alternated repetitions. */
static void speed_rows(const args *a, int dim, const char *scheme, pst_op *const op[2],
                       const double *u, double *y, size_t n)
{
    double pairs = (double)pst_op_pattern_pairs(op[0]), nd = (double)n;
    double bytes[2] = {12.0 * pairs + 32.0 * nd, 8.0 * pairs + 32.0 * nd};
    size_t nt = (size_t)(bytes[0] / 24.0);
    double *ta = malloc(nt * sizeof *ta), *tb = malloc(nt * sizeof *tb),
           *tc = malloc(nt * sizeof *tc);
    if (!ta || !tb || !tc) {
        fprintf(stderr, "bench_stored: no memory for the triad\n");
        goto done;
    }
    int saved = omp_get_max_threads();
    for (int ti = 0; ti < a->nthreads; ++ti) {
        omp_set_num_threads(a->threads[ti]);
        pstb_triad_fill(ta, tb, tc, nt);
        double t[3][MAXREPS], ratio[2][MAXREPS];
        for (int r = -1; r < a->reps; ++r) { /* r = -1: warm-up (first touch of y, caches) */
            for (int v = 0; v < 3; ++v) {
                double t0 = omp_get_wtime();
                if (v == 0)
                    pstb_triad_pass(ta, tb, tc, nt);
                else
                    pst_op_apply_stored(op[v - 1], u, y);
                if (r >= 0)
                    t[v][r] = omp_get_wtime() - t0;
            }
            if (r >= 0)
                for (int p = 0; p < 2; ++p) /* modelled apply rate over this repetition's triad */
                    ratio[p][r] = bytes[p] / t[p + 1][r] / (24.0 * (double)nt / t[0][r]);
        }
        double m[3], mr[2], best[3];
        for (int v = 0; v < 3; ++v) {
            best[v] = t[v][0];
            for (int r = 1; r < a->reps; ++r)
                best[v] = t[v][r] < best[v] ? t[v][r] : best[v];
            m[v] = bench_median(t[v], a->reps); /* sorts t[v] */
        }
        for (int p = 0; p < 2; ++p)
            mr[p] = bench_median(ratio[p], a->reps);
        double triad = 24.0 * (double)nt / m[0] * 1e-9;
        printf("| %dD | %s | %d | %.1f | %.1f | %.2f | %.1f | **%.2f** | %.2f | %.2f | %.1f | "
               "%.2f | %.2f |\n",
               dim, scheme, a->threads[ti], pairs / nd, triad, m[1] * 1e3,
               bytes[0] / m[1] * 1e-9, mr[0], bytes[0] / best[1] / (24.0 * (double)nt / best[0]),
               m[2] * 1e3, bytes[1] / m[2] * 1e-9, mr[1], m[1] / m[2]);
        fflush(stdout);
    }
    omp_set_num_threads(saved);
done:
    free(ta);
    free(tb);
    free(tc);
}

static void speed(const args *a)
{
    printf("\n## stored apply beside a triad (10^6 particles, medians of %d alternated "
           "repetitions)\n\n",
           a->reps);
    printf("| dim | scheme | threads | pairs/row | triad GB/s | double ms | double GB/s | "
           "double / triad | double / triad, best of each | float ms | float GB/s | "
           "float / triad | double / float time |\n"
           "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (int di = 0; di < a->ndims; ++di) {
        int dim = a->dims[di];
        for (int si = 0; si < a->nschemes; ++si) {
            const char *scheme = a->schemes[si];
            double support = scheme_support(scheme);
            pst_cloud *c = bench_million("bench_stored", dim);
            pst_nlist *nl = NULL;
            char err[PST_ERRLEN] = "";
            if (!c || pst_cloud_morton_sort(c, support * BENCH_H_RATIO, NULL) != PST_OK ||
                pst_nlist_build(&nl, c, support, err) != PST_OK) {
                fprintf(stderr, "bench_stored: %dD %s: %s\n", dim, scheme, err);
                pst_cloud_destroy(c);
                continue;
            }
            size_t n = pst_cloud_size(c);
            double *u = malloc(n * sizeof *u), *y = calloc(n, sizeof *y);
            const double *x = pst_cloud_coord_const(c, 0);
            for (size_t i = 0; i < n && u; ++i)
                u[i] = 1.0 + 1e-3 * x[i] * x[i];
            pst_op *op[2] = {stored_op(c, nl, scheme, PST_STORE_DOUBLE),
                             stored_op(c, nl, scheme, PST_STORE_FLOAT)};
            if (op[0] && op[1] && u && y)
                speed_rows(a, dim, scheme, op, u, y, n);
            pst_op_destroy(op[0]);
            pst_op_destroy(op[1]);
            free(u);
            free(y);
            pst_nlist_destroy(nl);
            pst_cloud_destroy(c);
        }
    }
}

/* ||a - b|| / ||b|| over the non-Dirichlet rows. */
static double rel_l2(const double *a, const double *b, const uint8_t *kind, size_t n)
{
    double num = 0, den = 0;
    for (size_t i = 0; i < n; ++i)
        if (kind[i] != PST_DIRICHLET) {
            num += (a[i] - b[i]) * (a[i] - b[i]);
            den += b[i] * b[i];
        }
    return den > 0 ? sqrt(num / den) : sqrt(num);
}

/* GMRES (+ AMG where built) on op's stored path from u = 0; u receives the solution. */
static pst_solve_result solve_stored(const pst_op *op, const double *b, double *u, size_t n)
{
    pst_solve_opts so;
    pst_solve_defaults(&so);
    so.solver = PST_SOLVER_GMRES;
    so.precond = pst_have_amg() ? PST_PREC_AMG : PST_PREC_JACOBI;
    so.stored = 1;
    so.rtol = 1e-10;
    memset(u, 0, n * sizeof *u);
    pst_solve_result r = {0};
    char err[PST_ERRLEN] = "";
    if (pst_solve(op, b, u, &so, &r, err) != PST_OK)
        fprintf(stderr, "bench_stored: solve: %s\n", err[0] ? err : r.message);
    return r;
}

static void accuracy_rows(int dim, size_t np, const char *scheme)
{
    pst_cloud *c = bench_poisson_cloud("bench_stored", dim, np, BENCH_H_RATIO);
    pst_nlist *nl = NULL;
    char err[PST_ERRLEN] = "";
    double support = scheme_support(scheme), s0 = 1.0 / bench_side(np, dim);
    if (!c || pst_cloud_morton_sort(c, support * BENCH_H_RATIO * s0, NULL) != PST_OK ||
        pst_nlist_build(&nl, c, support, err) != PST_OK) {
        fprintf(stderr, "bench_stored: %dD %s: %s\n", dim, scheme, err);
        pst_cloud_destroy(c);
        return;
    }
    size_t n = pst_cloud_size(c);
    const uint8_t *kind = pst_cloud_kinds_const(c);
    pst_op *op[2] = {stored_op(c, nl, scheme, PST_STORE_DOUBLE),
                     stored_op(c, nl, scheme, PST_STORE_FLOAT)};
    double *b = malloc(n * sizeof *b), *ue = malloc(n * sizeof *ue);
    double *l[2] = {malloc(n * sizeof(double)), malloc(n * sizeof(double))};
    double *u[2] = {malloc(n * sizeof(double)), malloc(n * sizeof(double))};
    if (op[0] && op[1] && b && ue && l[0] && l[1] && u[0] && u[1]) {
        bench_poisson_rhs(c, b, ue);
        pst_solve_result r[2];
        for (int p = 0; p < 2; ++p) {
            pst_op_apply_stored(op[p], ue, l[p]);
            r[p] = solve_stored(op[p], b, u[p], n);
        }
        printf("| %dD | %zu | %s | %.2e | %.2e | %.2e | %d / %d | %.1e / %.1e | %.3e / %.3e | "
               "%.1e |\n",
               dim, n, scheme, rel_l2(l[1], l[0], kind, n), rel_l2(l[0], b, kind, n),
               rel_l2(l[1], b, kind, n), r[0].iterations, r[1].iterations, r[0].rel_residual,
               r[1].rel_residual, rel_l2(u[0], ue, kind, n), rel_l2(u[1], ue, kind, n),
               rel_l2(u[1], u[0], kind, n));
        fflush(stdout);
        pst_solve_result_free(&r[0]);
        pst_solve_result_free(&r[1]);
    }
    for (int p = 0; p < 2; ++p) {
        pst_op_destroy(op[p]);
        free(l[p]);
        free(u[p]);
    }
    free(b);
    free(ue);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
}

static void accuracy(const args *a)
{
    printf("\n## float against double weights: the Laplacian of u and a Poisson solve (GMRES + "
           "%s, rtol 1e-10)\n\n",
           pst_have_amg() ? "AMG" : "Jacobi");
    printf("| dim | particles | scheme | Lu: float vs double | Lu double vs exact | Lu float vs "
           "exact | iterations double / float | residual double / float | error double / "
           "float | solutions float vs double |\n|---|---|---|---|---|---|---|---|---|---|\n");
    for (int k = 0; k < a->nsizes; ++k)
        for (int si = 0; si < a->nschemes; ++si)
            accuracy_rows(a->size_dim[k], a->sizes[k], a->schemes[si]);
}

int main(int argc, char **argv)
{
    args a;
    if (parse(argc, argv, &a) != 0)
        return 1;
    test_mpi_init();
    if (a.speed)
        speed(&a);
    if (a.accuracy)
        accuracy(&a);
    return 0;
}
