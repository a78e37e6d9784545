/* The operator object and the scheme table every discretisation plugs into. Internal. */
#ifndef PSTENCIL_OPERATOR_H
#define PSTENCIL_OPERATOR_H

#include "cloud_layout.h"
#include "internal.h"
#include "nlist_layout.h"
#include "tally.h"

#include <stdlib.h>

/* One scheme: a kernel file in kernels/ fills this table and operator.c registers it.
 *
 * A scheme owns the interior and Neumann rows; operator.c owns the Dirichlet rows (identity),
 * the stored weights, the stored apply, the diagonal, assembly, audit and status counts, all
 * derived from `emit_row`. `apply` and `emit_row` must produce the same weights bit for bit
 * (share one inline function for w_IJ), so the two apply paths agree to rounding. */
typedef struct pst_scheme {
    const char *name;
    const char *description;
    /* the fallback chain of a degenerate row, in order (pst_scheme_fallback) */
    const char *fallback;
    pst_kernel default_kernel;
    /* The contract tests/test_contract.c checks for every scheme: the interior rows reproduce
     * the Laplacian of every polynomial of degree <= `degree` to rounding on any cloud (a
     * jittered lattice, the rows cut by its edges included), and of degree <= `degree_lattice`
     * on the rows of a regular lattice with full support (pst_scheme_degree). */
    int degree, degree_lattice;
    /* opts.variant takes the values 0 .. variants - 1 (pst_scheme_variants); 0 is read as 1 */
    int variants;
    /* 1 when the rows average the mobility pairwise, (M_I + M_J), and honour
     * opts.mobility_mean (the LV family); 0: PST_MEAN_HARMONIC is refused */
    int pair_mobility;
    /* 1 when the rows accept a per-particle mobility (div(M grad u)); 0: refused */
    int mobility;
    /* 1 when gradient, hessian and interpolate do not read the precomputed rows, so an
     * operator for derivatives only (opts.laplacian = 0) can skip the precompute */
    int derivatives_standalone;
    /* bytes per particle of the precomputed data (op->data) in 2D and 3D, the largest over
     * the variants: the planner's memory estimate (pst_scheme_data_bytes) */
    int data_bytes[2];
    /* bytes per particle that opts.keep adds in 2D and 3D, for PST_KEEP_GRADIENT and
     * PST_KEEP_HESSIAN; all 0: the scheme keeps nothing (opts.keep is refused) */
    int keep_bytes[2][2];
    /* minimum neighbours (j != i) of a row in dimension dim (choice 6, docs/choices.md) */
    int (*min_neighbours)(int dim);
    /* Precompute the per-particle data into op->data (op->status is zeroed, fill it); one
     * threaded pass over particles. Returns PST_OK or an error with a message in err. On a
     * refresh op->data is the previous precompute's (the same n, dimension and options, so
     * the same sizes): the scheme takes it and its arrays (pst_op_data, PST_DATA_ARRAY) and
     * writes every entry again. */
    int (*precompute)(pst_op *op, char *err);
    /* The rows' sparsity pattern when it is wider than the neighbour list (the mixed schemes'
     * neighbours of neighbours), into fresh arrays: *poff (n + 1 offsets) and, unless pidx is
     * NULL (count only), *pidx, sorted by column in a row, without the diagonal. NULL: the
     * pattern is the neighbour list. Never called by precompute or the applies: it is such a
     * scheme's largest array, built only for the paths that read the pattern (operator.c). */
    int (*wide_pattern)(const pst_op *op, int64_t **poff, uint32_t **pidx, char *err);
    /* y_I = sum_J w_IJ (u_J - u_I) for every non-Dirichlet row I (threaded). */
    void (*apply)(const pst_op *op, const double *u, double *y);
    /* 1 when the precompute, apply (and derivatives) read op->xyzu, the positions and u packed
     * per particle (kernels/lanes.h): pst_op_create packs the positions, pst_op_apply,
     * pst_op_gradient and pst_op_hessian u before the call; kept on a half list, whose lane
     * rows read it too */
    int lanes;
    /* The apply on a half list (hoff, hidx: row I holds its neighbours J > I), rows I in
     * [i0, i1): for each pair, y_I += w_IJ (u_J - u_I) unless I is a Dirichlet row and
     * y_J += w_JI (u_I - u_J) unless J is, with the weights of apply (operator_half.c schedules
     * the blocks so that no two threads write one y). NULL: no half-list apply. */
    void (*half_rows)(const pst_op *op, const int64_t *hoff, const uint32_t *hidx, size_t i0,
                      size_t i1, const double *u, double *y);
    /* The weights w_IJ of non-Dirichlet row i, in the order of the row's pattern. */
    void (*emit_row)(const pst_op *op, size_t i, double *w);
    /* s_I of the scheme (NULL: 1 everywhere). */
    double (*scale)(const pst_op *op, size_t i);
    /* Gradient of u at the particles, or NULL when the scheme has none. */
    void (*gradient)(const pst_op *op, const double *u, double *const grad[3]);
    /* Second derivatives (pst_op_hessian's layout), or NULL. */
    void (*hessian)(const pst_op *op, const double *u, double *const hess[6]);
    /* Value and Laplacian at arbitrary points (pst_op_interpolate), or NULL. */
    int (*interpolate)(const pst_op *op, const double *const pts[3], size_t m, const double *u,
                       double *value, double *lap, size_t *fallbacks, char *err);
    /* Switch interior row i to the scheme's last-resort row, writing row i's data only: called
     * by pst_op_check_flat_rows for rows whose neighbours are flat. NULL when the scheme's rows
     * do not need it (non-negative rows; rows coupled through the neighbours' fits; a scheme
     * whose own fallback already guards its diagonal) and then no row is checked. */
    void (*degrade)(pst_op *op, size_t i);
    /* Lemma 3 diagnostics of row i into the two counters, or NULL (not applicable). */
    void (*lemma3)(const pst_op *op, size_t i, int *sign_mixed, int *xi_large);
    /* 1 when the scheme's own assembled matrix is its better AMG matrix (measured,
     * docs/solving.md): amg_source AUTO takes it; 0: the Brookshaw proxy (pst_scheme_amg_own) */
    int amg_own;
    /* How far a row reaches, in neighbour hops: 1 when it reads its particle and its
     * neighbours only; 2 when it reads its neighbours' own results, computed from their
     * neighbours (the CSPM family's volumes, the mixed schemes' nested gradients); 3 when those
     * read their neighbours' results in turn (mixed0's volumes inside the gradients). 0 means
     * 1. A rank's part (pst_part) takes this many rings of ghosts (pst_scheme_halo). */
    int halo;
    /* The automatic radius (in h) of its Brookshaw AMG proxy where it differs from the
     * library's 1.6 h (measured, docs/solving.md); 0: 1.6 h (pst_scheme_amg_radius) */
    double amg_radius;
    void (*free_data)(void *data);
} pst_scheme;

struct pst_op {
    const pst_scheme *scheme;
    const pst_cloud *cloud;
    const pst_nlist *nl;
    /* the boundary description the rows use: the cloud's, or opts.kinds / opts.normals */
    const uint8_t *kind;
    const double *normal[3];
    pst_op_opts opts;
    pst_kernel kernel;
    int dim;
    size_t n;
    void *data;            /* the scheme's per-particle data                         */
    uint8_t *status;       /* pst_row_status per particle                            */
    size_t counts[PST_ROW_NSTATUS];
    double *w;             /* stored weights (pattern layout) or NULL                */
    float *w32;            /* ... stored as float (pst_op_store_with), or NULL; at most one
                              of w and w32 is set                                        */
    void *spare_w;         /* a refresh's parked weight array (pst_op_park_store) and its   */
    size_t spare_bytes;    /* size: the next store takes it when the pattern fits in it,
                              else frees it                                             */
    size_t w_bytes;        /* the size of the array of w or w32                           */
    /* The sparsity pattern of the rows (without the diagonal), sorted by column in a row: the
     * neighbour list, or for a scheme with a wide_pattern NULL until pst_op_store builds it
     * into own_poff / own_pidx (the read-only paths build theirs per call, operator.c). */
    const int64_t *poff;
    const uint32_t *pidx;
    int64_t *own_poff;
    uint32_t *own_pidx;
    double phase[PST_NPHASES]; /* seconds per phase (pst_op_phase_times); apply is mutable */
    /* (x, y, z, u) per particle (z = 0 in 2D): the positions packed by pst_op_create for the
     * precompute and the flat-row check of the schemes with lanes or a degrade hook; kept by a
     * lane scheme (scheme->lanes), into which every apply, gradient and Hessian writes its u
     * (like the timer, scratch of the call), until the operator moves to a half list; freed
     * after the create otherwise */
    double *xyzu;
    int rows;              /* 1 when the Laplacian rows were precomputed (opts.laplacian)     */
    /* After pst_op_use_half_list: the schedule of the half-list apply and the diagonal, taken
     * from the whole rows before the switch (NULL before). */
    struct pst_half_schedule *half;
    double *half_diag;
    /* The progress counter of the call in progress (pst_op_create's precompute, a
     * derivative or an interpolation), NULL without a hook: a scheme's row loops count their
     * rows into it once per chunk or block (pst_tally_add, PST_CHUNK_ROWS). */
    pst_tally *tally;
};

/* Set the apply timer (PST_PHASE_APPLY) to the time since t0 (omp_get_wtime). */
void pst_op_record_apply(const pst_op *op, double t0);

/* A refresh's release of the store: the weight array parked for the store that follows
 * (op->spare_w), the wide pattern freed. */
void pst_op_park_store(pst_op *op);

/* 1 when op holds stored weights of either precision (operator_store.c). */
int pst_op_has_store(const pst_op *op);

/* The half-list apply (operator_half.c): y = L u through scheme->half_rows. */
void pst_op_apply_half(const pst_op *op, const double *u, double *y);

/* Free op's half-list schedule. */
void pst_half_schedule_free(struct pst_half_schedule *h);

/* Flag interior rows whose live neighbours are flat (on one line in 2D, one plane in 3D):
 * rank-deficient and degraded (scheme->degrade) when the condition of their centred second
 * moment reaches 1/rank_tol, ill-conditioned above cond_max (operator_flat.c; its sums in
 * operator_flat_sums.c, compiled once per ISA level). */
void pst_op_check_flat_rows(pst_op *op);

/* 1 for the schemes CG can solve through their symmetric scaling (brookshaw, cb). */
int pst_scheme_symmetrisable(const pst_scheme *s);
/* The registered scheme of that name, or NULL (registry.c). */
const pst_scheme *pst_scheme_find(const char *name);
/* The names of the registered schemes, ", "-separated into names (size bytes), for a message. */
const char *pst_scheme_names(char *names, size_t size);

/* The registered schemes (one file each under kernels/), one declaration per line. */
extern const pst_scheme pst_scheme_brookshaw;
extern const pst_scheme pst_scheme_cb;
extern const pst_scheme pst_scheme_schwaiger;
extern const pst_scheme pst_scheme_lv;
extern const pst_scheme pst_scheme_cspm;
extern const pst_scheme pst_scheme_icspm;
extern const pst_scheme pst_scheme_csph2g;
extern const pst_scheme pst_scheme_mixed0;
extern const pst_scheme pst_scheme_mixed1;
extern const pst_scheme pst_scheme_mixed2;
extern const pst_scheme pst_scheme_qsfdi;
extern const pst_scheme pst_scheme_lsmps;
extern const pst_scheme pst_scheme_lpmps;

/* The scheme's data struct of `bytes`: the previous precompute's on a refresh, else a new
 * zeroed one stored in op->data; NULL when out of memory. */
static inline void *pst_op_data(pst_op *op, size_t bytes)
{
    if (!op->data)
        op->data = calloc(1, bytes);
    return op->data;
}

/* A per-particle array of the scheme's data: kept from the previous precompute (a refresh
 * allocates nothing and touches no new page: the first touch was up to 12 % of a precompute
 * in a VM, src/core/alloc.c), else allocated; the pointer, NULL when out of memory. */
#define PST_DATA_ARRAY(p, bytes) ((p) ? (p) : ((p) = pst_alloc(bytes)))

#endif
