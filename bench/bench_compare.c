/* QSFDI against the LP-MPS-style inversions, phase by phase (QSFDI paper §1, Table 1, Figs 2
 * and 14; docs/qsfdi-vs-lpmps.md). For each dimension and h/s0 it builds one jittered
 * cloud (K = 0.4, Morton-sorted, quintic support 3h), then for qsfdi, lpmps and lsmps (type B
 * and A) the operator, REPS times, and keeps the median of every phase (geometry, moments,
 * inversion, weights, precompute) and of the matrix-free apply. It prints a table, the ratios
 * the paper claims (LP-MPS / QSFDI time for the direct Laplacian, the inversion-cost share) and,
 * with --json FILE, the same as JSON. Both record the machine and the compiler flags
 * (src/machine.h: a "# machine:" line under the title, "machine" and "compiler_flags" in JSON).
 *
 * usage: bench_compare [--n N] [--dims 2,3] [--ratios 0.75,0.9,1.2] [--reps R] [--json FILE]
 *   --n    particles per cloud (default 1000000; the lattice side is rounded)
 */
#include "bench_common.h"
#include "machine.h"
#include "pstencil.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    const char *scheme;
    int variant;
    const char *label;
} entry;

static const entry entries[] = {
    {"qsfdi", 0, "qsfdi"},
    {"lpmps", 0, "lpmps"},
    {"lsmps", 0, "lsmps-B"},
    {"lsmps", 1, "lsmps-A"},
};
#define NENTRIES (sizeof entries / sizeof *entries)
#define NCOLS (PST_NPHASES) /* geometry, moments, inversion, weights, precompute, apply */

static int parse_list(const char *s, double *out, int max)
{
    int k = 0;
    char buf[256];
    snprintf(buf, sizeof buf, "%s", s);
    for (char *t = strtok(buf, ","); t && k < max; t = strtok(NULL, ","))
        out[k++] = atof(t);
    return k;
}

/* One jittered lattice on the unit box with about n particles, Morton-sorted, and its list. */
static int make_cloud(int dim, size_t n, double ratio, pst_cloud **c, pst_nlist **nl)
{
    pst_lattice_opts o = bench_box(dim, bench_side(n, dim), 1.0, 0.4, ratio);
    if (!(*c = bench_lattice("bench_compare", &o)))
        return -1;
    char err[PST_ERRLEN];
    if (pst_cloud_morton_sort(*c, 3.0 * ratio, NULL) != PST_OK ||
        pst_nlist_build(nl, *c, 3.0, err) != PST_OK) {
        fprintf(stderr, "bench_compare: %s\n", err);
        return -1;
    }
    return 0;
}

/* s as a JSON string (quotes and backslashes escaped, control characters dropped). */
static void json_string(FILE *f, const char *s)
{
    fputc('"', f);
    for (; *s; ++s)
        if (*s == '"' || *s == '\\')
            fprintf(f, "\\%c", *s);
        else if ((unsigned char)*s >= 0x20)
            fputc(*s, f);
    fputc('"', f);
}

int main(int argc, char **argv)
{
    size_t n = 1000000;
    double dims[3] = {2, 3}, ratios[8] = {0.75, 0.9, 1.2};
    int ndims = 2, nratios = 3, reps = 3;
    const char *json = NULL;
    for (int i = 1; i < argc; i += 2) {
        if (i + 1 == argc) {
            fprintf(stderr, "bench_compare: %s needs a value\n", argv[i]);
            return 1;
        }
        if (strcmp(argv[i], "--n") == 0)
            n = (size_t)atol(argv[i + 1]);
        else if (strcmp(argv[i], "--dims") == 0)
            ndims = parse_list(argv[i + 1], dims, 3);
        else if (strcmp(argv[i], "--ratios") == 0)
            nratios = parse_list(argv[i + 1], ratios, 8);
        else if (strcmp(argv[i], "--reps") == 0)
            reps = atoi(argv[i + 1]);
        else if (strcmp(argv[i], "--json") == 0)
            json = argv[i + 1];
        else {
            fprintf(stderr, "bench_compare: unknown option %s\n", argv[i]);
            return 1;
        }
    }
    if (reps < 1 || reps > 50 || n < 100) {
        fprintf(stderr, "bench_compare: bad --reps or --n\n");
        return 1;
    }
    FILE *js = json ? fopen(json, "w") : NULL;
    if (json && !js) {
        fprintf(stderr, "bench_compare: cannot write %s\n", json);
        return 1;
    }
    pst_machine mach;
    pst_machine_probe(&mach);
    if (js) {
        /* the machine record as {"cpu": "...", "cores": "2", ...} (string values) and the flags */
        const char *keys[PST_MACHINE_NPAIRS];
        char values[PST_MACHINE_NPAIRS][PST_MACHINE_VLEN];
        int np = pst_machine_pairs(&mach, keys, values, PST_MACHINE_NPAIRS);
        fprintf(js, "{\"pstencil\": \"%s\", \"threads\": %d, \"reps\": %d,\n \"machine\": {",
                pst_version(), pst_threads(), reps);
        for (int i = 0; i < np; ++i) {
            fprintf(js, "%s\"%s\": ", i ? ", " : "", keys[i]);
            json_string(js, values[i]);
        }
        fprintf(js, "},\n \"compiler_flags\": ");
        json_string(js, mach.compile_flags);
        fprintf(js, ",\n \"runs\": [\n");
    }
    char mline[1024];
    pst_machine_line(&mach, mline, sizeof mline);
    printf("pstencil %s, %d threads, median of %d; seconds per phase\n# machine: %s\n",
           pst_version(), pst_threads(), reps, mline);
    int first = 1;
    for (int di = 0; di < ndims; ++di)
        for (int ri = 0; ri < nratios; ++ri) {
            int dim = (int)dims[di];
            pst_cloud *c = NULL;
            pst_nlist *nl = NULL;
            if (make_cloud(dim, n, ratios[ri], &c, &nl) != 0)
                return 1;
            pst_nlist_stats ns;
            pst_nlist_get_stats(nl, &ns);
            printf("\n%dD, %zu particles, h = %.2f s0, %.1f neighbours\n", dim, pst_cloud_size(c),
                   ratios[ri], ns.mean);
            printf("%-8s %9s %9s %9s %9s %10s %9s  %s\n", "scheme", "geometry", "moments",
                   "inversion", "weights", "precompute", "apply", "rows not ok");
            double med[NENTRIES][NCOLS];
            double *u = malloc(pst_cloud_size(c) * sizeof *u),
                   *y = malloc(pst_cloud_size(c) * sizeof *y);
            for (size_t i = 0; i < pst_cloud_size(c); ++i)
                u[i] = sin(0.1 * pst_cloud_coord_const(c, 0)[i]) +
                       cos(0.07 * pst_cloud_coord_const(c, 1)[i]);
            for (size_t e = 0; e < NENTRIES; ++e) {
                double t[NCOLS][50];
                size_t notok = 0;
                for (int r = 0; r < reps; ++r) {
                    pst_op_opts o;
                    pst_op_defaults(&o);
                    o.scheme = entries[e].scheme;
                    o.variant = entries[e].variant;
                    pst_op *op = NULL;
                    char err[PST_ERRLEN];
                    if (pst_op_create(&op, c, nl, &o, err) != PST_OK) {
                        fprintf(stderr, "bench_compare: %s: %s\n", entries[e].label, err);
                        return 1;
                    }
                    pst_op_apply(op, u, y);
                    double ph[PST_NPHASES];
                    pst_op_phase_times(op, ph);
                    for (int k = 0; k < NCOLS; ++k)
                        t[k][r] = ph[k];
                    size_t counts[PST_ROW_NSTATUS];
                    pst_op_status_counts(op, counts);
                    notok = pst_cloud_size(c) - counts[PST_ROW_OK];
                    pst_op_destroy(op);
                }
                for (int k = 0; k < NCOLS; ++k)
                    med[e][k] = bench_median(t[k], reps);
                printf("%-8s %9.4f %9.4f %9.4f %9.4f %10.4f %9.4f  %zu\n", entries[e].label,
                       med[e][0], med[e][1], med[e][2], med[e][3], med[e][4], med[e][5], notok);
                if (js) {
                    fprintf(js,
                            "%s  {\"dim\": %d, \"particles\": %zu, \"h_ratio\": %g, "
                            "\"neighbours\": %.2f, \"scheme\": \"%s\"",
                            first ? "" : ",\n", dim, pst_cloud_size(c), ratios[ri], ns.mean,
                            entries[e].label);
                    for (int k = 0; k < NCOLS; ++k)
                        fprintf(js, ", \"%s\": %.6g", pst_phase_name(k), med[e][k]);
                    fprintf(js, ", \"rows_not_ok\": %zu}", notok);
                    first = 0;
                }
            }
            /* the paper's ratios: LP-MPS / QSFDI for the direct Laplacian (precompute + one
             * apply), and QSFDI's inversion time as a share of LP-MPS's */
            double q = med[0][PST_PHASE_PRECOMPUTE] + med[0][PST_PHASE_APPLY];
            double l = med[1][PST_PHASE_PRECOMPUTE] + med[1][PST_PHASE_APPLY];
            double b = med[2][PST_PHASE_PRECOMPUTE] + med[2][PST_PHASE_APPLY];
            printf("ratio LP-MPS/QSFDI (precompute + apply) %.2f (paper: ~1.25); "
                   "LSMPS-B/QSFDI %.2f; inversion QSFDI/LP-MPS %.1f %% (paper 2D: 45.7 %%)\n",
                   l / q, b / q,
                   med[1][PST_PHASE_INVERSION] > 0
                       ? 100 * med[0][PST_PHASE_INVERSION] / med[1][PST_PHASE_INVERSION]
                       : 0.0);
            free(u);
            free(y);
            pst_nlist_destroy(nl);
            pst_cloud_destroy(c);
        }
    if (js) {
        fprintf(js, "\n]}\n");
        fclose(js);
    }
    return 0;
}
