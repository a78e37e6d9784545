/* Fixtures shared by the tests; see support.h. */
#define _POSIX_C_SOURCE 200809L /* mkdtemp, opendir, setrlimit */

#include "support.h"

#include <dirent.h>
#include <limits.h>
#include <math.h>
#include <mpi.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <signal.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

pst_cloud *test_lattice(int dim, double lo, double hi, double s0, double h_ratio, double K,
                        uint64_t seed, int boundary_layer)
{
    return test_lattice_rotated(dim, lo, hi, s0, h_ratio, K, seed, boundary_layer, 0.0);
}

pst_cloud *test_lattice_rotated(int dim, double lo, double hi, double s0, double h_ratio,
                                double K, uint64_t seed, int boundary_layer, double angle)
{
    pst_lattice_opts o;
    pst_lattice_defaults(&o);
    o.dim = dim;
    for (int d = 0; d < 3; ++d) {
        o.lo[d] = lo;
        o.hi[d] = hi;
    }
    o.s0 = s0;
    o.h_ratio = h_ratio;
    o.jitter = K;
    o.seed = seed;
    o.boundary_layer = boundary_layer;
    o.angle = angle;
    return test_lattice_of(&o);
}

pst_cloud *test_cut_hole(const pst_cloud *full, double r)
{
    size_t nf = pst_cloud_size(full), n = 0;
    const double *x = pst_cloud_coord_const(full, 0), *y = pst_cloud_coord_const(full, 1);
    for (size_t i = 0; i < nf; ++i)
        n += (x[i] - 0.5) * (x[i] - 0.5) + (y[i] - 0.5) * (y[i] - 0.5) >= r * r;
    pst_cloud *c = NULL;
    if (pst_cloud_create(&c, 2, n, NULL) != PST_OK) {
        fprintf(stderr, "test_cut_hole: cannot create the cloud\n");
        exit(1);
    }
    size_t k = 0;
    for (size_t i = 0; i < nf; ++i) {
        if ((x[i] - 0.5) * (x[i] - 0.5) + (y[i] - 0.5) * (y[i] - 0.5) < r * r)
            continue;
        pst_cloud_coord(c, 0)[k] = x[i];
        pst_cloud_coord(c, 1)[k] = y[i];
        pst_cloud_volume(c)[k] = pst_cloud_volume_const(full)[i];
        pst_cloud_kinds(c)[k] = pst_cloud_kinds_const(full)[i];
        ++k;
    }
    pst_cloud_set_h_uniform(c, pst_cloud_h_uniform(full), NULL);
    return c;
}

pst_cloud *test_lattice_of(const pst_lattice_opts *o)
{
    pst_cloud *c = NULL;
    char err[PST_ERRLEN];
    if (pst_cloud_lattice(&c, o, err) != PST_OK) {
        fprintf(stderr, "lattice: %s\n", err);
        exit(1);
    }
    return c;
}

pst_nlist *test_nlist(const pst_cloud *c, double support)
{
    pst_nlist *nl = NULL;
    char err[PST_ERRLEN];
    if (pst_nlist_build(&nl, c, support, err) != PST_OK) {
        fprintf(stderr, "nlist: %s\n", err);
        exit(1);
    }
    return nl;
}

pst_op *test_op(const pst_cloud *c, const pst_nlist *nl, const char *scheme, int gradient,
                int variant)
{
    pst_op_opts o;
    pst_op_defaults(&o);
    o.scheme = scheme;
    o.gradient = gradient;
    o.variant = variant;
    return test_op_of(c, nl, &o);
}

pst_op *test_op_of(const pst_cloud *c, const pst_nlist *nl, const pst_op_opts *o)
{
    pst_op *op = NULL;
    char err[PST_ERRLEN];
    if (pst_op_create(&op, c, nl, o, err) != PST_OK) {
        fprintf(stderr, "op %s (gradient %d, variant %d): %s\n", o->scheme, o->gradient,
                o->variant, err);
        exit(1);
    }
    return op;
}

void test_position(const pst_cloud *c, size_t i, double x[3])
{
    x[0] = x[1] = x[2] = 0;
    for (int d = 0; d < pst_cloud_dim(c); ++d)
        x[d] = pst_cloud_coord_const(c, d)[i];
}

double *test_field(const pst_cloud *c, double (*fn)(const double *x))
{
    size_t n = pst_cloud_size(c);
    double *u = malloc(n * sizeof *u);
    for (size_t i = 0; i < n; ++i) {
        double x[3];
        test_position(c, i, x);
        u[i] = fn(x);
    }
    return u;
}

int test_inside(const pst_cloud *c, size_t i, double lo, double hi, double margin)
{
    for (int d = 0; d < pst_cloud_dim(c); ++d) {
        double x = pst_cloud_coord_const(c, d)[i];
        if (x < lo + margin || x > hi - margin)
            return 0;
    }
    return 1;
}

void test_make_neumann(pst_cloud *c, size_t stride)
{
    uint8_t *kind = pst_cloud_kinds(c);
    for (size_t i = 0; i < pst_cloud_size(c); i += stride)
        if (kind[i] == PST_DIRICHLET)
            kind[i] = PST_NEUMANN;
}

pst_cloud *test_lane_cloud(int dim, int per_particle_h)
{
    pst_cloud *c = dim == 2 ? test_lattice(2, 0, 1, 1.0 / 37, 1.3, 0.4, 11, 1)
                            : test_lattice(3, 0, 1, 1.0 / 12, 1.2, 0.4, 11, 1);
    test_make_neumann(c, 5);
    if (per_particle_h) {
        double *h = pst_cloud_h_per_particle(c);
        if (!h) {
            fprintf(stderr, "test_lane_cloud: out of memory\n");
            exit(1);
        }
        for (size_t i = 0; i < pst_cloud_size(c); ++i)
            h[i] *= 1.0 + 0.15 * sin(7.0 * (double)i);
    }
    return c;
}

void test_rough_mobility(pst_cloud *c, int ncomp)
{
    size_t n = pst_cloud_size(c);
    pst_cloud_set_mobility(c, ncomp, NULL);
    for (int k = 0; k < ncomp; ++k) {
        double *m = pst_cloud_mobility(c, k);
        for (size_t i = 0; i < n; ++i)
            m[i] = 1.0 + 0.5 * k + 1e3 * ((i * 2654435761u) % 5 == 0);
    }
}

size_t test_arrays_differ(double *const a[], double *const b[], int ncomp, size_t n)
{
    size_t d = 0;
    for (int k = 0; k < ncomp; ++k)
        d += memcmp(a[k], b[k], n * sizeof(double)) != 0;
    return d;
}

size_t test_derivatives_thread_differ(const pst_op *op, const double *u, int dim, size_t n,
                                      int hessian)
{
    const int nh = dim * (dim + 1) / 2, saved = omp_get_max_threads();
    double *g[2][3], *h[2][6];
    int ok = 1;
    for (int t = 0; t < 2; ++t) {
        for (int k = 0; k < 3; ++k)
            g[t][k] = malloc(n * sizeof(double));
        for (int k = 0; k < 6; ++k)
            h[t][k] = malloc(n * sizeof(double));
        omp_set_num_threads(t + 1);
        ok = ok && pst_op_gradient(op, u, g[t]) == PST_OK;
        ok = ok && (!hessian || pst_op_hessian(op, u, h[t]) == PST_OK);
    }
    omp_set_num_threads(saved);
    size_t d = ok ? test_arrays_differ(g[0], g[1], dim, n) +
                        (hessian ? test_arrays_differ(h[0], h[1], nh, n) : 0)
                  : (size_t)-1;
    for (int t = 0; t < 2; ++t) {
        for (int k = 0; k < 3; ++k)
            free(g[t][k]);
        for (int k = 0; k < 6; ++k)
            free(h[t][k]);
    }
    return d;
}

size_t test_flat_layout(pst_cloud *c)
{
    int dim = pst_cloud_dim(c);
    size_t m = dim == 2 ? 11 : 25;
    for (size_t i = 0; i < m; ++i) {
        pst_cloud_coord(c, 0)[i] = 0.1 * (double)(dim == 2 ? i : i % 5);
        pst_cloud_coord(c, 1)[i] = dim == 2 ? 0.0 : 0.1 * (double)(i / 5);
        if (dim == 3)
            pst_cloud_coord(c, 2)[i] = 0.0;
    }
    return m;
}

double test_csr_entry(const pst_csr *a, size_t i, size_t j)
{
    for (int64_t k = a->rowptr[i]; k < a->rowptr[i + 1]; ++k)
        if (a->col[k] == j)
            return a->val[k];
    return 0.0;
}

/* Apply, and the derivatives asked for, into y and the 9 arrays d (gradient 0-2, Hessian 3-8). */
static void evaluate(const pst_op *op, const double *u, double *y, double **d, int derivs)
{
    pst_op_apply(op, u, y);
    if (derivs >= 1)
        pst_op_gradient(op, u, d);
    if (derivs >= 2)
        pst_op_hessian(op, u, d + 3);
}

test_threads test_one_vs_two_threads(const pst_cloud *c, const pst_nlist *nl,
                                     const char *scheme, int gradient, int variant,
                                     const double *u, double *y1, double *y2, int derivs)
{
    size_t n = pst_cloud_size(c);
    int dim = pst_cloud_dim(c);
    double *d1[9], *d2[9];
    for (int k = 0; k < 9; ++k) {
        d1[k] = malloc(n * sizeof **d1);
        d2[k] = malloc(n * sizeof **d2);
    }
    test_threads t;
    omp_set_num_threads(1);
    t.op1 = test_op(c, nl, scheme, gradient, variant);
    evaluate(t.op1, u, y1, d1, derivs);
    omp_set_num_threads(2);
    t.op2 = test_op(c, nl, scheme, gradient, variant);
    evaluate(t.op2, u, y2, d2, derivs);
    t.same_apply = memcmp(y1, y2, n * sizeof *y1) == 0;
    t.same_status = memcmp(pst_op_status(t.op1), pst_op_status(t.op2), n) == 0;
    for (int a = 0; a < 3; ++a)
        t.same_grad[a] = derivs < 1 || a >= dim || memcmp(d1[a], d2[a], n * sizeof **d1) == 0;
    for (int k = 0; k < 6; ++k)
        t.same_hess[k] = derivs < 2 || k >= dim * (dim + 1) / 2 ||
                         memcmp(d1[3 + k], d2[3 + k], n * sizeof **d1) == 0;
    for (int k = 0; k < 9; ++k) {
        free(d1[k]);
        free(d2[k]);
    }
    return t;
}

test_paths test_compare_paths(pst_op *op, const double *u, const double *y_free,
                              double *y_stored)
{
    test_paths p = {0};
    p.unstored = pst_op_apply_stored(op, u, y_stored);
    p.store = pst_op_store(op);
    p.stored = pst_op_apply_stored(op, u, y_stored);
    pst_csr a;
    p.assemble = pst_op_assemble(op, &a);
    p.diagonal = PST_EINVAL;
    p.worst = p.worst_csr = p.worst_diag = INFINITY;
    if (p.assemble != PST_OK)
        return p;
    size_t n = a.n;
    double *dg = malloc(n * sizeof *dg);
    p.diagonal = pst_op_diagonal(op, dg);
    if (p.diagonal != PST_OK || p.stored != PST_OK) {
        pst_csr_free(&a);
        free(dg);
        return p;
    }
    p.worst = p.worst_csr = p.worst_diag = 0;
    p.finite = p.finite_values = p.sorted = 1;
    for (size_t i = 0; i < n; ++i) {
        double sum = 0, mag = 0;
        for (int64_t e = a.rowptr[i]; e < a.rowptr[i + 1]; ++e) {
            sum += a.val[e] * u[a.col[e]];
            mag += fabs(a.val[e] * u[a.col[e]]);
            if (a.col[e] == i)
                p.worst_diag = fmax(p.worst_diag, fabs(a.val[e] - dg[i]));
            if (e > a.rowptr[i])
                p.sorted = p.sorted && a.col[e] > a.col[e - 1];
            p.finite_values = p.finite_values && isfinite(a.val[e]);
        }
        p.finite = p.finite && isfinite(y_free[i]) && isfinite(y_stored[i]);
        p.worst = fmax(p.worst, fabs(y_free[i] - y_stored[i]) / (mag > 0 ? mag : 1));
        p.worst_csr = fmax(p.worst_csr, fabs(sum - y_free[i]) / (mag > 0 ? mag : 1));
    }
    p.offdiag = a.rowptr[n] - (int64_t)n;
    pst_csr_free(&a);
    free(dg);
    return p;
}

double test_slope(const double *s, const double *e, int m)
{
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (int k = 0; k < m; ++k) {
        double x = log(s[k]), y = log(e[k]);
        sx += x;
        sy += y;
        sxx += x * x;
        sxy += x * y;
    }
    return (m * sxy - sx * sy) / (m * sxx - sx * sx);
}

int test_scratch_dir(char *dir, size_t size, const char *prefix)
{
    snprintf(dir, size, "/tmp/%s_XXXXXX", prefix);
    if (!mkdtemp(dir)) {
        perror("mkdtemp");
        return -1;
    }
    return 0;
}

void test_remove_dir(const char *dir)
{
    DIR *d = opendir(dir);
    char p[1024];
    for (struct dirent *e; d && (e = readdir(d));) {
        if (e->d_name[0] == '.')
            continue;
        snprintf(p, sizeof p, "%s/%s", dir, e->d_name);
        unlink(p);
    }
    if (d)
        closedir(d);
    rmdir(dir);
}

/* MPI_Finalize for atexit, once the test's handles are gone. */
static void finalize_mpi(void)
{
    MPI_Finalize();
}

void test_mpi_init(void)
{
    int provided = 0;
    if (MPI_Init_thread(NULL, NULL, MPI_THREAD_SERIALIZED, &provided) != MPI_SUCCESS ||
        atexit(finalize_mpi) != 0) {
        fprintf(stderr, "test_mpi_init: cannot initialise MPI\n");
        exit(1);
    }
}

const char *test_path_in(const char *dir, const char *name)
{
    static char buf[1024];
    snprintf(buf, sizeof buf, "%s/%s", dir, name);
    return buf;
}

int test_count_temporaries(const char *dir)
{
    int k = 0;
    DIR *d = opendir(dir);
    for (struct dirent *e; d && (e = readdir(d));)
        k += strstr(e->d_name, ".tmp.") != NULL;
    if (d)
        closedir(d);
    return k;
}

int test_write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    if (!f)
        return -1;
    int bad = fputs(text, f) < 0;
    return fclose(f) != 0 || bad ? -1 : 0;
}

int test_file_holds(const char *path, const char *text)
{
    size_t len = strlen(text);
    char *buf = malloc(len + 2);
    FILE *f = fopen(path, "r");
    size_t got = f && buf ? fread(buf, 1, len + 1, f) : 0;
    if (f)
        fclose(f);
    int same = buf && got == len && memcmp(buf, text, len) == 0;
    free(buf);
    return same;
}

int test_under_file_limit(long bytes, int (*write)(const void *job), const void *job)
{
    struct rlimit saved, small;
    if (getrlimit(RLIMIT_FSIZE, &saved) != 0)
        return INT_MIN;
    small = saved;
    small.rlim_cur = (rlim_t)bytes;
    void (*prev)(int) = signal(SIGXFSZ, SIG_IGN); /* a failed write, not a killed test */
    int st = setrlimit(RLIMIT_FSIZE, &small) == 0 ? write(job) : INT_MIN;
    setrlimit(RLIMIT_FSIZE, &saved);
    signal(SIGXFSZ, prev);
    return st;
}

/* The one splitmix64 stream of a test program. */
static uint64_t rng_state;

void test_rng_seed(uint64_t seed) { rng_state = seed; }

uint64_t test_rnd64(void)
{
    uint64_t z = (rng_state += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

double test_rnd(void) { return (double)(test_rnd64() >> 11) * 0x1p-53; }

int test_rndi(int n) { return (int)(test_rnd64() % (uint64_t)n); }
