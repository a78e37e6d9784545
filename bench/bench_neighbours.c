/* Benchmarks of the Morton sort and the neighbour-list build on 10^6-particle jittered lattices
 * (K = 0.5, h = 1.2 s0, quintic support 3h), with 1 and 2 OpenMP threads (the argument). The
 * run's context records the machine, the flags and the triad / FP64 peak probes (peak.h). */
#include "bench_common.h"
#include "bench_shim.h"
#include "peak.h"
#include "pstencil.h"

#include <omp.h>
#include <stdlib.h>
#include <string.h>

#define SUPPORT 3.0 /* quintic spline: R = 3h, ~195 neighbours in 3D, ~40 in 2D */

/* The Morton-sorted clouds of the neighbour benchmarks, built once. */
static pst_cloud *sorted[4];
static pst_cloud *sorted_cloud(int dim)
{
    if (!sorted[dim]) {
        sorted[dim] = bench_million("bench_neighbours", dim);
        if (sorted[dim])
            pst_cloud_morton_sort(sorted[dim], SUPPORT * BENCH_H_RATIO, NULL);
    }
    return sorted[dim];
}

static void morton_sort(pstb_state *s)
{
    int saved = omp_get_max_threads();
    omp_set_num_threads((int)pstb_arg(s));
    pst_cloud *c = bench_million("bench_neighbours", 3);
    size_t n = c ? pst_cloud_size(c) : 0;
    double *x0 = malloc(3 * n * sizeof *x0);
    if (!c || !x0) {
        pstb_skip(s, "out of memory");
    } else {
        for (int d = 0; d < 3; ++d)
            memcpy(x0 + (size_t)d * n, pst_cloud_coord(c, d), n * sizeof *x0);
        while (pstb_keep_running(s)) {
            pstb_pause(s); /* back to lattice order */
            for (int d = 0; d < 3; ++d)
                memcpy(pst_cloud_coord(c, d), x0 + (size_t)d * n, n * sizeof *x0);
            for (size_t i = 0; i < n; ++i)
                pst_cloud_ids(c)[i] = (int64_t)i;
            pstb_resume(s);
            pst_cloud_morton_sort(c, SUPPORT * BENCH_H_RATIO, NULL);
        }
        pstb_counter(s, "particles/s", (double)n, 1);
    }
    free(x0);
    pst_cloud_destroy(c);
    omp_set_num_threads(saved);
}

static void nlist_build(pstb_state *s, int dim)
{
    int saved = omp_get_max_threads();
    omp_set_num_threads((int)pstb_arg(s));
    pst_cloud *c = sorted_cloud(dim);
    pst_nlist_stats st = {0};
    char err[PST_ERRLEN] = "";
    int status = c ? PST_OK : PST_ENOMEM;
    while (status == PST_OK && pstb_keep_running(s)) {
        pst_nlist *nl;
        status = pst_nlist_build(&nl, c, SUPPORT, err);
        pstb_pause(s);
        if (status == PST_OK)
            pst_nlist_get_stats(nl, &st);
        pst_nlist_destroy(nl);
        pstb_resume(s);
    }
    if (status != PST_OK) {
        pstb_skip(s, err[0] ? err : "cannot build the cloud");
    } else {
        double n = (double)pst_cloud_size(c);
        pstb_counter(s, "particles/s", n, 1);
        pstb_counter(s, "neighbours/particle", st.mean, 0);
        pstb_counter(s, "bytes/pair", (double)st.bytes / (double)st.pairs, 0);
        pstb_counter(s, "bytes/particle", (double)st.bytes / n, 0);
    }
    omp_set_num_threads(saved);
}

static void nlist_2d(pstb_state *s) { nlist_build(s, 2); }
static void nlist_3d(pstb_state *s) { nlist_build(s, 3); }

void pstb_register_all(void)
{
    static const int64_t threads[2] = {1, 2};
    /* the machine record and the triad / FP64 probes, in the run's context (bench/README.md) */
    static pstb_probes probes;
    pstb_probes_run(&probes);
    pstb_probes_record(&probes, pstb_context);
    pstb_register("morton_sort_3d_1e6", morton_sort, threads, 2);
    pstb_register("nlist_build_2d_1e6", nlist_2d, threads, 2);
    pstb_register("nlist_build_3d_1e6", nlist_3d, threads, 2);
}
