/* Fixtures shared by the tests: clouds, neighbour lists and operators that exit(1) with the
 * library's message when they cannot be built, fields sampled at the particles, the "full
 * support" predicate, the measurements behind the apply-path and thread-independence tests,
 * scratch folders and files for the writers' tests, and a random stream for test data.
 *
 * Nothing here asserts: check.h's counters are private to each test program, so the helpers
 * return what they measured and the test's own CHECKs judge it (and report its line). */
#ifndef PSTENCIL_TEST_SUPPORT_H
#define PSTENCIL_TEST_SUPPORT_H

#include "pstencil.h"

#include <stddef.h>
#include <stdint.h>

/* A lattice on [lo,hi]^dim with spacing s0, h = h_ratio s0, jitter K (fraction of s0), the
 * given seed and boundary layer (pst_lattice_opts). Exits on failure. */
pst_cloud *test_lattice(int dim, double lo, double hi, double s0, double h_ratio, double K,
                        uint64_t seed, int boundary_layer);
/* The same lattice rotated by `angle` (radians, about the box centre; pst_lattice_opts). */
pst_cloud *test_lattice_rotated(int dim, double lo, double hi, double s0, double h_ratio,
                                double K, uint64_t seed, int boundary_layer, double angle);

/* The lattice of any options. Exits on failure. */
pst_cloud *test_lattice_of(const pst_lattice_opts *o);

/* A copy of the 2D cloud c without the particles closer than r to (0.5, 0.5): a hole whose edge
 * particles keep their kinds (an internal free surface). Exits on failure. */
pst_cloud *test_cut_hole(const pst_cloud *c, double r);

/* The neighbour list of radius support * h. Exits on failure. */
pst_nlist *test_nlist(const pst_cloud *c, double support);

/* An operator of `scheme` with the kernel-gradient variant `gradient` (PST_GRAD_G1 is the
 * default) and scheme variant `variant` (0 the default), every other option at its default.
 * Exits on failure. */
pst_op *test_op(const pst_cloud *c, const pst_nlist *nl, const char *scheme, int gradient,
                int variant);

/* The operator of any options. Exits on failure. */
pst_op *test_op_of(const pst_cloud *c, const pst_nlist *nl, const pst_op_opts *o);

/* Position of particle i, zero-padded to three components. */
void test_position(const pst_cloud *c, size_t i, double x[3]);

/* fn at every particle (x zero-padded to three components); the caller frees the array. */
double *test_field(const pst_cloud *c, double (*fn)(const double *x));

/* Full support: every coordinate of particle i at least `margin` inside [lo, hi]. */
int test_inside(const pst_cloud *c, size_t i, double lo, double hi, double margin);

/* How many of the ncomp arrays a[k], b[k] of n doubles differ in any bit. */
size_t test_arrays_differ(double *const a[], double *const b[], int ncomp, size_t n);

/* How many of the gradient arrays (and, with hessian, Hessian arrays) of op, an operator on a
 * cloud of n particles in dimension dim, for the field u differ in any bit between 1 and 2
 * threads (the thread count is restored); (size_t)-1 when a call fails. */
size_t test_derivatives_thread_differ(const pst_op *op, const double *u, int dim, size_t n,
                                      int hessian);

/* Every stride-th particle (0, stride, 2 stride, ..) that is Dirichlet becomes Neumann. */
void test_make_neumann(pst_cloud *c, size_t stride);

/* The cloud of the lane rows' tests: a jittered lattice on [0, 1]^dim (2D s0 = 1/37, h = 1.3 s0;
 * 3D s0 = 1/12, h = 1.2 s0), test_make_neumann's stride 5; with per_particle_h, h varied by up
 * to 15 % from particle to particle (inside lists built for 1.2 times the kernel's support). */
pst_cloud *test_lane_cloud(int dim, int per_particle_h);

/* Mobility with ncomp components (0: none), component k = 1 + k/2 with a 1e3 jump at every
 * particle i with (i * 2654435761) mod 5 == 0: heterogeneous by six orders of magnitude. */
void test_rough_mobility(pst_cloud *c, int ncomp);

/* The degenerate layout: 11 particles on the x axis 0.1 apart (2D) or a 5 x 5 grid of spacing
 * 0.1 in the plane z = 0 (3D), as the first particles of c; returns their number (11 or 25).
 * The caller places the particles after them. */
size_t test_flat_layout(pst_cloud *c);

/* Entry (i, j) of an assembled matrix, 0 when absent. */
double test_csr_entry(const pst_csr *a, size_t i, size_t j);

/* Operators built from the same input with 1 and with 2 OpenMP threads (which stays set),
 * each applied to u (y1 from the 1-thread operator, y2 from the 2-thread one) and, when
 * derivs >= 1, asked for the gradient, when derivs >= 2 also for the Hessian. */
typedef struct {
    pst_op *op1, *op2;   /* the caller destroys both */
    int same_apply;      /* y1 and y2 bit for bit */
    int same_status;     /* row status bit for bit */
    int same_grad[3];    /* gradient component a bit for bit (a < dim; 1 when not asked) */
    int same_hess[6];    /* Hessian entry k bit for bit (k < dim (dim + 1) / 2; 1 if not asked) */
} test_threads;

test_threads test_one_vs_two_threads(const pst_cloud *c, const pst_nlist *nl,
                                     const char *scheme, int gradient, int variant,
                                     const double *u, double *y1, double *y2, int derivs);

/* The apply paths of op against each other: pst_op_apply_stored before pst_op_store (PST_EINVAL
 * expected), pst_op_store, pst_op_apply_stored into y_stored, pst_op_assemble's matvec and
 * pst_op_diagonal, against y_free = pst_op_apply(op, u). Differences are relative to
 * sum_j |a_ij u_j| of the row (1 where that is 0). */
typedef struct {
    int unstored;          /* return of pst_op_apply_stored before pst_op_store */
    int store;             /* return of pst_op_store */
    int stored;            /* return of pst_op_apply_stored after it */
    int assemble;          /* return of pst_op_assemble */
    int diagonal;          /* return of pst_op_diagonal */
    double worst;          /* max relative |y_free - y_stored| */
    double worst_csr;      /* max relative |A u - y_free| */
    double worst_diag;     /* max |a_ii - diagonal_i| */
    int finite;            /* y_free and y_stored finite everywhere */
    int finite_values;     /* every assembled entry finite */
    int sorted;            /* columns strictly increasing in every row */
    int64_t offdiag;       /* entries of A minus its rows: the off-diagonal pattern size */
} test_paths;

/* Least-squares slope of log e against log s over m points (a convergence order). */
double test_slope(const double *s, const double *e, int m);

test_paths test_compare_paths(pst_op *op, const double *u, const double *y_free,
                              double *y_stored);

/* A fresh scratch folder "/tmp/PREFIX_XXXXXX" written into dir; 0, or -1 after a message. */
int test_scratch_dir(char *dir, size_t size, const char *prefix);
/* Remove the files of a scratch folder, then the folder (it holds no subfolders). */
void test_remove_dir(const char *dir);
/* "dir/name" in a static buffer (overwritten by the next call). */
const char *test_path_in(const char *dir, const char *name);
/* The temporary files (".tmp." in the name) an atomic writer left in dir. */
int test_count_temporaries(const char *dir);
/* Write text to path; 0, or -1 when the file cannot be written. */
int test_write_text(const char *path, const char *text);
/* 1 when the file at path holds exactly text. */
int test_file_holds(const char *path, const char *text);
/* write(job)'s return while files may grow to at most `bytes` (RLIMIT_FSIZE; SIGXFSZ ignored,
 * so an oversized write fails instead of killing the test); INT_MIN when the limit cannot be
 * set. The limit is restored afterwards. */
int test_under_file_limit(long bytes, int (*write)(const void *job), const void *job);

/* Test data from one splitmix64 stream per program: test_rng_seed starts it, test_rnd64 gives
 * its next word, test_rnd a double in [0, 1), test_rndi an int in [0, n). */
void test_rng_seed(uint64_t seed);
uint64_t test_rnd64(void);
double test_rnd(void);
int test_rndi(int n);

/* Initialise MPI (MPI_THREAD_SERIALIZED) and finalise it at exit: the library leaves MPI to
 * the program, and the AMG preconditioner (hypre) needs it. For the main() of every test that
 * runs an AMG solve. Exits on failure. */
void test_mpi_init(void);

#endif
