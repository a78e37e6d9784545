/* Benchmarks of every registered scheme (pst_scheme_count / pst_scheme_name; options at their
 * defaults, i.e. each scheme's default kernel, gradient G1 for the LV family) on 10^6-particle
 * jittered lattices in 2D (1000^2) and 3D (100^3), K = 0.5, h = 1.2 s0, neighbour support the
 * default kernel's (2h cubic, 3h quintic), Morton-sorted, with 1 and 2 OpenMP threads:
 *   op_precompute_<scheme>_<dim>d   pst_op_create (per-particle data, one threaded pass)
 *   op_apply_<scheme>_<dim>d        pst_op_apply (matrix-free: pair weights recomputed)
 *   op_stored_<scheme>_<dim>d       pst_op_apply_stored (weights stored once, untimed)
 *   op_half_<scheme>_<dim>d         pst_op_apply on a half list (pst_op_use_half_list; the
 *                                   operator, the half list and the switch untimed), for the
 *                                   schemes that have one
 *   csr_{1sum,4sums}_lv_<dim>d      the assembled lv matrix times a vector, one or four partial
 *                                   sums per row (is the stored apply memory- or latency-bound?)
 * plus a STREAM-like triad a = b + s c (3 x 80 MB and 3 x 400 MB arrays) and a read-only
 * dot product (2 x 400 MB) as the bandwidth references of the stored apply. The run's context
 * records the machine, the flags and in-process triad and FP64 peak probes (peak.h); the stored
 * applies report triad_fraction, the matrix-free applies peak_fraction (flop model below).
 * bench/README.md explains the counters and the byte and flop models. */
#include "bench_common.h"
#include "bench_shim.h"
#include "markers.h"
#include "peak.h"
#include "stream.h"
#include "pstencil.h"

#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define NSUPP 2 /* neighbour-list supports: 2h (cubic) and 3h (quintic) */
static const double supports[NSUPP] = {2.0, 3.0};

/* Fixed iteration counts: each benchmark a few iterations (override needs a code change; the
 * counts keep a full run at about two minutes on a 2-core machine). */
#define ITERS_PRECOMPUTE 3
#define ITERS_APPLY 5
#define ITERS_STORED 20
#define ITERS_TRIAD 20
/* The quintic schemes (support 3h: ~40 neighbours in 2D, ~190 in 3D; their precomputes solve a
 * 5x5 / 9x9 or larger system per particle) run fewer iterations so that a full run stays near
 * ten minutes. */
#define ITERS_PRECOMPUTE_WIDE 1
#define ITERS_APPLY_WIDE_2D 3
#define ITERS_APPLY_WIDE_3D 1
#define ITERS_STORED_WIDE 5
#define MAX_SCHEMES 16

/* ---- clouds and lists, built once per process ------------------------------------------- */

typedef struct {
    pst_cloud *cloud;
    pst_nlist *nl;
    pst_nlist_stats st;
    double *u, *y;
} setup;

static setup setups[4][NSUPP];

static int supp_index(double support) { return support > 2.5 ? 1 : 0; }

static setup *get_setup(int dim, int si)
{
    setup *s = &setups[dim][si];
    if (s->nl)
        return s;
    char err[PST_ERRLEN] = "";
    s->cloud = bench_million("bench_operators", dim);
    if (!s->cloud)
        return NULL;
    pst_cloud_morton_sort(s->cloud, supports[si] * BENCH_H_RATIO, NULL);
    if (pst_nlist_build(&s->nl, s->cloud, supports[si], err) != PST_OK) {
        fprintf(stderr, "bench_operators: neighbour list: %s\n", err);
        return NULL;
    }
    pst_nlist_get_stats(s->nl, &s->st);
    size_t n = pst_cloud_size(s->cloud);
    s->u = malloc(n * sizeof *s->u);
    s->y = malloc(n * sizeof *s->y);
    if (!s->u || !s->y)
        return NULL;
    for (size_t i = 0; i < n; ++i) { /* a smooth field; the values do not affect the timing */
        double x = pst_cloud_coord_const(s->cloud, 0)[i];
        s->u[i] = 1.0 + 1e-3 * x * x;
        s->y[i] = 0.0;
    }
    return s;
}

/* ---- one cached operator: the last one built (keeps memory to one operator) -------------- */

static struct {
    pst_op *op;
    int scheme, dim;
} cached = {NULL, -1, 0};

static void release_op(void)
{
    pst_op_destroy(cached.op);
    cached.op = NULL;
    cached.scheme = -1;
}

/* The registered scheme of index `scheme` and the list support of its default kernel. */
static const char *scheme_name(int scheme) { return pst_scheme_name(scheme); }

static int scheme_supp(int scheme)
{
    return supp_index(pst_kernel_support((pst_kernel)pst_scheme_default_kernel(scheme_name(scheme))));
}

static int create_op(pst_op **op, const setup *s, int scheme, char *err)
{
    pst_op_opts o;
    pst_op_defaults(&o);
    o.scheme = scheme_name(scheme);
    o.gradient = PST_GRAD_G1;
    return pst_op_create(op, s->cloud, s->nl, &o, err);
}

/* The operator of (scheme, dim), built if it is not the cached one. */
static pst_op *get_op(const setup *s, int scheme, int dim, char *err)
{
    if (cached.op && cached.scheme == scheme && cached.dim == dim)
        return cached.op;
    release_op();
    if (create_op(&cached.op, s, scheme, err) != PST_OK)
        return NULL;
    cached.scheme = scheme;
    cached.dim = dim;
    return cached.op;
}

static void common_counters(pstb_state *st, const setup *s)
{
    pstb_counter(st, "particles/s", (double)pst_cloud_size(s->cloud), 1);
    pstb_counter(st, "neighbours/particle", s->st.mean, 0);
}

/* ---- the three benchmarks ---------------------------------------------------------------- */

enum { MODE_PRECOMPUTE, MODE_APPLY, MODE_STORED, MODE_HALF };

/* Bytes moved by one stored apply (the model of bench/README.md): per pair 8 (weight) + 4
 * (index); per row 8 (offset) + 8 (u_I) + 8 (y_I written); u_J gathers counted once per
 * particle (8), i.e. perfect cache reuse of u under Morton order. */
static double stored_bytes(const setup *s, double pattern_pairs)
{
    double n = (double)pst_cloud_size(s->cloud);
    return 12.0 * pattern_pairs + 32.0 * n;
}

/* Entries of the operator's stored pattern (off-diagonal): the neighbour list for every scheme
 * but the mixed ones, whose rows span the neighbours of neighbours. */
static double pattern_pairs(const pst_op *op) { return (double)pst_op_pattern_pairs(op); }

/* Flops per list pair of the matrix-free apply (pst_op_apply), counted once from each scheme's
 * per-pair function (adds, muls, divisions and sqrt 1 each; compares and selects not counted;
 * the kernel's shape from sph_kernels.h at its default kernel). bench/README.md, "Flop models
 * of the matrix-free applies", gives the function and line each is counted from. The mixed
 * schemes' apply makes two sweeps over the list (gradient, then divergence): both counted per
 * list pair. Unknown schemes get no peak_fraction. */
static const struct {
    const char *scheme;
    double flops[2]; /* 2D, 3D */
} flop_models[] = {
    {"brookshaw", {52, 60}}, {"cb", {52, 60}},      {"schwaiger", {52, 60}},
    {"lv", {52, 60}},        {"cspm", {82, 104}},   {"icspm", {82, 104}},
    {"csph2g", {82, 104}},   {"mixed0", {103, 142}}, {"mixed1", {101, 140}},
    {"mixed2", {135, 230}},  {"lsmps", {40, 52}},   {"lpmps", {39, 51}},
    {"qsfdi", {50, 69}},
};

static double apply_flops_per_pair(int scheme, int dim)
{
    for (size_t m = 0; m < sizeof flop_models / sizeof *flop_models; ++m)
        if (strcmp(flop_models[m].scheme, scheme_name(scheme)) == 0)
            return flop_models[m].flops[dim == 3];
    return 0;
}

/* The half-list apply: a second operator of the scheme switched to a half list of the setup's
 * list (both untimed), then the same applies as MODE_APPLY; pairs/s counts the whole list's
 * pairs, so it compares with op_apply's directly. */
static void run_half(pstb_state *st, const setup *s, int scheme)
{
    char err[PST_ERRLEN] = "";
    pst_op *op = NULL;
    pst_nlist *half = NULL;
    if (create_op(&op, s, scheme, err) != PST_OK || pst_nlist_halve(&half, s->nl, err) != PST_OK ||
        pst_op_use_half_list(op, half, err) != PST_OK) {
        pstb_skip(st, err[0] ? err : "cannot build the half-list operator");
    } else {
        while (pstb_keep_running(st))
            pst_op_apply(op, s->u, s->y);
        common_counters(st, s);
        pstb_counter(st, "pairs/s", (double)s->st.pairs, 1);
        pstb_counter(st, "colours", pst_op_half_colours(op), 0);
    }
    pst_op_destroy(op);
    pst_nlist_destroy(half);
}

/* The probes of the run's context, at 1 thread ([0]) and at all threads ([1]). */
static pstb_probes probes;

static int probe_index(int threads) { return threads > 1 ? 1 : 0; }

static void run(pstb_state *st, int scheme, int dim, int mode)
{
    int saved = omp_get_max_threads();
    omp_set_num_threads((int)pstb_arg(st));
    char err[PST_ERRLEN] = "";
    const char *name = scheme_name(scheme);
    if (mode == MODE_STORED && dim == 3 && strncmp(name, "mixed", 5) == 0) {
        /* 3D quintic list ~187 neighbours; the two-ring pattern ~1240 per row at 10^6
         * particles (~1500 in the bulk): 5.0 GB of index + 9.9 GB of stored weights, most of a
         * 24 GB machine, and pst_op_store would take ~5 min (pattern) + ~40 min (emission,
         * |N|^2 pair evaluations per row) at 2 threads. The precompute and the matrix-free
         * apply never build the pattern. */
        pstb_skip(st, "mixed 3D stored: the neighbours-of-neighbours pattern of 10^6 particles "
                      "needs 5.0 GB (index) + 9.9 GB (weights) and ~45 min to store");
        omp_set_num_threads(saved);
        return;
    }
    setup *s = get_setup(dim, scheme_supp(scheme));
    if (!s) {
        pstb_skip(st, "cannot build the cloud or its neighbour list");
        omp_set_num_threads(saved);
        return;
    }
    if (mode == MODE_PRECOMPUTE) {
        int status = PST_OK;
        release_op();
        while (status == PST_OK && pstb_keep_running(st)) {
            pstb_pause(st);
            release_op();
            pstb_resume(st);
            status = create_op(&cached.op, s, scheme, err);
        }
        if (status != PST_OK || !cached.op) {
            cached.op = NULL;
            pstb_skip(st, err[0] ? err : "pst_op_create failed");
        } else {
            cached.scheme = scheme; /* the last one built serves the apply benchmarks */
            cached.dim = dim;
            size_t counts[PST_ROW_NSTATUS];
            pst_op_status_counts(cached.op, counts);
            common_counters(st, s);
            /* rows that are not "ok" (lattice-boundary rows: one-sided support) */
            pstb_counter(st, "rows_fallback", (double)counts[PST_ROW_FALLBACK], 0);
            pstb_counter(st, "rows_ill_cond", (double)counts[PST_ROW_ILL_CONDITIONED], 0);
            pstb_counter(st, "rows_rank_def", (double)counts[PST_ROW_RANK_DEFICIENT], 0);
            pstb_counter(st, "rows_too_few", (double)counts[PST_ROW_TOO_FEW], 0);
        }
        omp_set_num_threads(saved);
        return;
    }
    if (mode == MODE_HALF) {
        run_half(st, s, scheme);
        omp_set_num_threads(saved);
        return;
    }
    pst_op *op = get_op(s, scheme, dim, err);
    if (!op) {
        pstb_skip(st, err[0] ? err : "pst_op_create failed");
        omp_set_num_threads(saved);
        return;
    }
    double pairs = (double)s->st.pairs;
    char region[96]; /* the likwid region: the benchmark's name without the thread count */
    snprintf(region, sizeof region, "%s_%s_%dd", mode == MODE_APPLY ? "op_apply" : "op_stored",
             name, dim);
    if (mode == MODE_APPLY) {
        PSTB_REGION_START(region);
        while (pstb_keep_running(st))
            pst_op_apply(op, s->u, s->y);
        PSTB_REGION_STOP(region);
        common_counters(st, s);
        pstb_counter(st, "pairs/s", pairs, 1);
        /* achieved flop rate (model above) over the FP64 probe at this thread count */
        double peak = probes.peak[probe_index((int)pstb_arg(st))].gflops;
        double fpp = apply_flops_per_pair(scheme, dim);
        if (fpp > 0)
            pstb_counter(st, "flops/particle", pairs / (double)pst_cloud_size(s->cloud) * fpp, 0);
        if (peak > 0 && fpp > 0)
            pstb_counter(st, "peak_fraction", pairs * fpp / (peak * 1e9), 1);
    } else {
        if (pst_op_store(op) != PST_OK) {
            pstb_skip(st, "pst_op_store: out of memory");
            omp_set_num_threads(saved);
            return;
        }
        pst_op_apply_stored(op, s->u, s->y); /* warm: first touch of y done, caches primed */
        PSTB_REGION_START(region);
        while (pstb_keep_running(st))
            pst_op_apply_stored(op, s->u, s->y);
        PSTB_REGION_STOP(region);
        double pp = pattern_pairs(op), bytes = stored_bytes(s, pp);
        common_counters(st, s);
        pstb_counter(st, "pairs/s", pp, 1); /* the stored pattern's entries */
        pstb_counter(st, "pattern/particle", pp / (double)pst_cloud_size(s->cloud), 0);
        pstb_counter(st, "bytes/apply", bytes, 0);
        pstb_counter(st, "bytes/s", bytes, 1);
        /* modelled bytes/s over the in-process triad at this thread count */
        double triad = probes.triad_gbs[probe_index((int)pstb_arg(st))];
        if (triad > 0)
            pstb_counter(st, "triad_fraction", bytes / (triad * 1e9), 1);
    }
    omp_set_num_threads(saved);
}

/* One body per (scheme index, dim, mode): the shim's bodies take no user data. */
#define OP_BENCH(SI, D)                                                                       \
    static void pre_##SI##_##D(pstb_state *st) { run(st, SI, D, MODE_PRECOMPUTE); }          \
    static void app_##SI##_##D(pstb_state *st) { run(st, SI, D, MODE_APPLY); }               \
    static void sto_##SI##_##D(pstb_state *st) { run(st, SI, D, MODE_STORED); }              \
    static void hal_##SI##_##D(pstb_state *st) { run(st, SI, D, MODE_HALF); }
#define OP_BENCH2(SI) OP_BENCH(SI, 2) OP_BENCH(SI, 3)
OP_BENCH2(0) OP_BENCH2(1) OP_BENCH2(2) OP_BENCH2(3) OP_BENCH2(4) OP_BENCH2(5) OP_BENCH2(6)
OP_BENCH2(7) OP_BENCH2(8) OP_BENCH2(9) OP_BENCH2(10) OP_BENCH2(11) OP_BENCH2(12) OP_BENCH2(13)
OP_BENCH2(14) OP_BENCH2(15)
#define FNS(SI)                                                                                \
    {{pre_##SI##_2, app_##SI##_2, sto_##SI##_2, hal_##SI##_2},                                 \
     {pre_##SI##_3, app_##SI##_3, sto_##SI##_3, hal_##SI##_3}}
static const pstb_fn op_fns[MAX_SCHEMES][2][4] = {
    FNS(0), FNS(1), FNS(2),  FNS(3),  FNS(4),  FNS(5),  FNS(6),  FNS(7),
    FNS(8), FNS(9), FNS(10), FNS(11), FNS(12), FNS(13), FNS(14), FNS(15),
};
#undef FNS

/* The index of the lv scheme (the CSR probes use its operator). */
static int lv_index(void)
{
    for (int k = 0; k < pst_scheme_count(); ++k)
        if (strcmp(pst_scheme_name(k), "lv") == 0)
            return k;
    return -1;
}

/* ---- the assembled matrix with 1 and 4 partial sums per row -------------------------------- */

/* y = A x over the explicit CSR matrix of the cached operator (pst_op_assemble: the list's
 * pairs plus the diagonal, 12 bytes per entry). With one partial sum per row this is the same
 * dependency chain as pst_op_apply_stored (one add per entry in sequence); with four the chain
 * is broken. The difference tells whether the stored apply is bound by memory or by the add
 * latency. Bytes per product: 12 per entry + 24 per row (row offset, y, x counted once). */
static void csr_spmv(pstb_state *st, int dim, int accumulators)
{
    int saved = omp_get_max_threads();
    omp_set_num_threads((int)pstb_arg(st));
    char err[PST_ERRLEN] = "";
    int lv = lv_index();
    setup *s = lv >= 0 ? get_setup(dim, scheme_supp(lv)) : NULL;
    pst_op *op = s ? get_op(s, lv, dim, err) : NULL;
    pst_csr a;
    if (!op || pst_op_assemble(op, &a) != PST_OK) {
        pstb_skip(st, err[0] ? err : "cannot assemble the lv matrix");
        omp_set_num_threads(saved);
        return;
    }
    const int64_t *rp = a.rowptr;
    const uint32_t *col = a.col;
    const double *val = a.val, *x = s->u;
    double *y = s->y;
    size_t n = a.n;
    while (pstb_keep_running(st)) {
        if (accumulators == 1) {
#pragma omp parallel for schedule(static)
            for (size_t i = 0; i < n; ++i) {
                double acc = 0;
                for (int64_t k = rp[i]; k < rp[i + 1]; ++k)
                    acc += val[k] * x[col[k]];
                y[i] = acc;
            }
        } else {
#pragma omp parallel for schedule(static)
            for (size_t i = 0; i < n; ++i) {
                double a0 = 0, a1 = 0, a2 = 0, a3 = 0;
                int64_t k = rp[i], end = rp[i + 1];
                for (; k + 4 <= end; k += 4) {
                    a0 += val[k] * x[col[k]];
                    a1 += val[k + 1] * x[col[k + 1]];
                    a2 += val[k + 2] * x[col[k + 2]];
                    a3 += val[k + 3] * x[col[k + 3]];
                }
                for (; k < end; ++k)
                    a0 += val[k] * x[col[k]];
                y[i] = (a0 + a1) + (a2 + a3);
            }
        }
    }
    double nnz = (double)rp[n], bytes = 12.0 * nnz + 24.0 * (double)n;
    pstb_counter(st, "particles/s", (double)n, 1);
    pstb_counter(st, "entries/s", nnz, 1);
    pstb_counter(st, "bytes/apply", bytes, 0);
    pstb_counter(st, "bytes/s", bytes, 1);
    pst_csr_free(&a);
    omp_set_num_threads(saved);
}

static void csr1_2(pstb_state *st) { csr_spmv(st, 2, 1); }
static void csr4_2(pstb_state *st) { csr_spmv(st, 2, 4); }
static void csr1_3(pstb_state *st) { csr_spmv(st, 3, 1); }
static void csr4_3(pstb_state *st) { csr_spmv(st, 3, 4); }

/* ---- STREAM-like triad ------------------------------------------------------------------- */

static void triad(pstb_state *st, size_t n)
{
    int saved = omp_get_max_threads();
    omp_set_num_threads((int)pstb_arg(st));
    release_op(); /* the triad runs first, but keep its memory to its own arrays anyway */
    double *a = malloc(n * sizeof *a), *b = malloc(n * sizeof *b), *c = malloc(n * sizeof *c);
    if (!a || !b || !c) {
        pstb_skip(st, "out of memory");
    } else {
        pstb_triad_fill(a, b, c, n);
        while (pstb_keep_running(st))
            pstb_triad_pass(a, b, c, n);
        double check = 0;
        for (size_t i = 0; i < n; i += 4096)
            check += a[i];
        if (check != 7.0 * (double)((n + 4095) / 4096))
            pstb_skip(st, "triad: wrong result");
        double bytes = 3.0 * (double)n * sizeof(double); /* 2 reads + 1 write, no write-allocate */
        pstb_counter(st, "bytes/iteration", bytes, 0);
        pstb_counter(st, "bytes/s", bytes, 1);
    }
    free(a);
    free(b);
    free(c);
    omp_set_num_threads(saved);
}

static void triad_80mb(pstb_state *st) { triad(st, 10000000); }  /* 3 x 80 MB  */
static void triad_400mb(pstb_state *st) { triad(st, 50000000); } /* 3 x 400 MB */

/* A read-only probe, s = sum b[i] c[i] over 2 x 400 MB: the stored apply is read-mostly (its
 * only write stream is y, 8 of ~700 bytes per row in 3D), the triad writes a third of its
 * bytes (plus the write-allocate reads its byte count leaves out). */
static void read_dot(pstb_state *st)
{
    int saved = omp_get_max_threads();
    omp_set_num_threads((int)pstb_arg(st));
    release_op();
    size_t n = 50000000; /* a multiple of 8 */
    double *b = malloc(n * sizeof *b), *c = malloc(n * sizeof *c);
    if (!b || !c) {
        pstb_skip(st, "out of memory");
    } else {
#pragma omp parallel for schedule(static)
        for (size_t i = 0; i < n; ++i) {
            b[i] = 1.0;
            c[i] = 0.5;
        }
        double sum = 0;
        while (pstb_keep_running(st)) {
            /* eight partial sums: one sum would be bound by the add latency, not memory */
            double s0 = 0, s1 = 0, s2 = 0, s3 = 0, s4 = 0, s5 = 0, s6 = 0, s7 = 0;
#pragma omp parallel for schedule(static) reduction(+ : s0, s1, s2, s3, s4, s5, s6, s7)
            for (size_t i = 0; i < n; i += 8) {
                s0 += b[i] * c[i];
                s1 += b[i + 1] * c[i + 1];
                s2 += b[i + 2] * c[i + 2];
                s3 += b[i + 3] * c[i + 3];
                s4 += b[i + 4] * c[i + 4];
                s5 += b[i + 5] * c[i + 5];
                s6 += b[i + 6] * c[i + 6];
                s7 += b[i + 7] * c[i + 7];
            }
            sum = ((s0 + s1) + (s2 + s3)) + ((s4 + s5) + (s6 + s7));
        }
        if (sum != 0.5 * (double)n)
            pstb_skip(st, "read probe: wrong result");
        double bytes = 2.0 * (double)n * sizeof(double);
        pstb_counter(st, "bytes/iteration", bytes, 0);
        pstb_counter(st, "bytes/s", bytes, 1);
    }
    free(b);
    free(c);
    omp_set_num_threads(saved);
}

void pstb_register_all(void)
{
    static const int64_t threads[2] = {1, 2};
    PSTB_MARKERS_INIT();
    pstb_probes_run(&probes);
    pstb_probes_record(&probes, pstb_context);
    pstb_register_iters("triad_3x80MB", triad_80mb, threads, 2, ITERS_TRIAD);
    pstb_register_iters("triad_3x400MB", triad_400mb, threads, 2, ITERS_TRIAD);
    pstb_register_iters("read_dot_2x400MB", read_dot, threads, 2, ITERS_TRIAD);
    /* per (dim, scheme): precompute (which leaves its operator cached), matrix-free apply,
     * stored apply, so every operator is built by the timed precompute only; then the
     * half-list apply (its own operator) */
    static const char *const mode_names[4] = {"op_precompute_", "op_apply_", "op_stored_",
                                              "op_half_"};
    int ns = pst_scheme_count(), lv = lv_index();
    if (ns > MAX_SCHEMES) {
        fprintf(stderr, "bench_operators: %d schemes, only the first %d benchmarked\n", ns,
                MAX_SCHEMES);
        ns = MAX_SCHEMES;
    }
    for (int dim = 2; dim <= 3; ++dim) {
        for (int k = 0; k < ns; ++k) {
            int wide = scheme_supp(k) > 0;
            int apply = wide ? (dim == 2 ? ITERS_APPLY_WIDE_2D : ITERS_APPLY_WIDE_3D) : ITERS_APPLY;
            int iters[4] = {wide ? ITERS_PRECOMPUTE_WIDE : ITERS_PRECOMPUTE, apply,
                            wide ? ITERS_STORED_WIDE : ITERS_STORED, apply};
            int modes = pst_scheme_supports(pst_scheme_name(k), PST_SUPPORTS_HALF_LIST) ? 4 : 3;
            for (int m = 0; m < modes; ++m) {
                char name[96];
                snprintf(name, sizeof name, "%s%s_%dd", mode_names[m], pst_scheme_name(k), dim);
                pstb_register_iters(name, op_fns[k][dim - 2][m], threads, 2, iters[m]);
            }
            if (k == lv) { /* while its operator is cached */
                pstb_register_iters(dim == 2 ? "csr_1sum_lv_2d" : "csr_1sum_lv_3d",
                                    dim == 2 ? csr1_2 : csr1_3, threads, 2, ITERS_STORED);
                pstb_register_iters(dim == 2 ? "csr_4sums_lv_2d" : "csr_4sums_lv_3d",
                                    dim == 2 ? csr4_2 : csr4_3, threads, 2, ITERS_STORED);
            }
        }
    }
}
