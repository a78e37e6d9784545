/*
 * pstencil — meshless discretisations of the Laplacian and of div(M grad u) on disordered
 * particle clouds in 2D and 3D.
 *
 * Conventions of the whole API:
 *   - opaque handles with create/destroy pairs;
 *   - every fallible call returns an int: PST_OK (0) or a negative PST_E* code;
 *     pst_strerror() names the code, and the handle (or the `err` buffer the call was given)
 *     holds a detail message of the last failure;
 *   - the library never prints, never calls exit(), keeps no global mutable state;
 *   - threads are OpenMP threads: results are identical for every thread count.
 */
#ifndef PSTENCIL_H
#define PSTENCIL_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define PSTENCIL_VERSION_MAJOR 0
#define PSTENCIL_VERSION_MINOR 1
#define PSTENCIL_VERSION_PATCH 0

/* ------------------------------------------------------------------------------------------ */
/* Status codes                                                                               */
/* ------------------------------------------------------------------------------------------ */

enum {
    PST_OK = 0,
    PST_EINVAL = -1,   /* a bad argument from the caller (wrong dimension, negative size, ...) */
    PST_EINPUT = -2,   /* bad input data: malformed file, NaN, duplicate particles, ...        */
    PST_ENOMEM = -3,   /* an allocation failed, or an estimate exceeds the allowed memory       */
    PST_EIO = -4,      /* a file could not be opened, written or renamed                       */
    PST_ENUMERIC = -5  /* a numerical failure (singular system, no convergence)                 */
};

/* A static, human-readable name of a status code ("ok", "invalid argument", ...). */
const char *pst_strerror(int status);

/* The library version as "MAJOR.MINOR.PATCH". */
const char *pst_version(void);

/* Size of the error-detail buffers that functions without a handle fill. */
#define PST_ERRLEN 512

/* ------------------------------------------------------------------------------------------ */
/* Particle clouds                                                                            */
/* ------------------------------------------------------------------------------------------ */

/* Role of a particle in a boundary-value problem. */
typedef enum { PST_INTERIOR = 0, PST_DIRICHLET = 1, PST_NEUMANN = 2 } pst_kind;

typedef struct pst_cloud pst_cloud;

/* Create a cloud of `n` particles in `dim` (2 or 3) dimensions. Positions and normals start at
 * 0, V at 1, h uniform at 1, every particle interior, mobility absent (meaning m = 1), ids
 * 0..n-1. Returns PST_EINVAL for a bad dim, PST_ENOMEM when allocation fails. */
int pst_cloud_create(pst_cloud **out, int dim, size_t n);

/* Free a cloud and everything it owns. NULL is allowed. */
void pst_cloud_destroy(pst_cloud *c);

/* Dimension (2 or 3) and number of particles. */
int pst_cloud_dim(const pst_cloud *c);
size_t pst_cloud_size(const pst_cloud *c);

/* Detail message of the last failure of a call on this cloud ("" when none). */
const char *pst_cloud_error(const pst_cloud *c);

/* The structure-of-arrays fields. Pointers stay valid until the cloud is destroyed or its
 * smoothing-length or mobility layout is changed by the setters below. Writing through them
 * is how callers fill a cloud. */
double *pst_cloud_coord(pst_cloud *c, int axis);       /* axis < dim; NULL otherwise       */
double *pst_cloud_volume(pst_cloud *c);
double *pst_cloud_normal(pst_cloud *c, int axis);      /* outward unit normal (boundaries) */
uint8_t *pst_cloud_kinds(pst_cloud *c);                /* pst_kind values                  */
int64_t *pst_cloud_ids(pst_cloud *c);                  /* original (input) index           */
const double *pst_cloud_coord_const(const pst_cloud *c, int axis);
const double *pst_cloud_volume_const(const pst_cloud *c);
const uint8_t *pst_cloud_kinds_const(const pst_cloud *c);
const int64_t *pst_cloud_ids_const(const pst_cloud *c);

/* Smoothing length: one value for every particle, or one per particle. */
int pst_cloud_set_h_uniform(pst_cloud *c, double h);   /* frees any per-particle array     */
double *pst_cloud_h_per_particle(pst_cloud *c);        /* allocates (filled with the uniform
                                                          value) on first call; NULL on OOM */
int pst_cloud_h_is_uniform(const pst_cloud *c);
double pst_cloud_h_uniform(const pst_cloud *c);        /* the uniform value (0 if per particle) */
const double *pst_cloud_h_array(const pst_cloud *c);   /* per-particle array or NULL        */
double pst_cloud_h_max(const pst_cloud *c);            /* largest h over the cloud          */

/* Mobility: absent (m = 1 everywhere), a scalar per particle (ncomp = 1), or a diagonal
 * tensor per particle (ncomp = dim). Setting a layout allocates it filled with 1. */
int pst_cloud_set_mobility(pst_cloud *c, int ncomp);   /* ncomp in {0, 1, dim}               */
int pst_cloud_mobility_ncomp(const pst_cloud *c);
double *pst_cloud_mobility(pst_cloud *c, int comp);    /* comp < ncomp; NULL otherwise       */

/* Named scalar fields. Adding a field allocates it filled with 0; names are unique and are
 * C identifiers (letters, digits, '_', not starting with a digit) that do not collide with
 * the reserved CSV column names. */
int pst_cloud_add_field(pst_cloud *c, const char *name, double **data);
size_t pst_cloud_nfields(const pst_cloud *c);
const char *pst_cloud_field_name(const pst_cloud *c, size_t k);
double *pst_cloud_field(pst_cloud *c, size_t k);
double *pst_cloud_field_by_name(pst_cloud *c, const char *name);   /* NULL when absent */

/* Axis-aligned bounding box of the positions (lo[d], hi[d] for d < dim). An empty cloud
 * gives lo = hi = 0. */
void pst_cloud_bbox(const pst_cloud *c, double lo[3], double hi[3]);

/* Check a cloud: finite positions, V > 0, h > 0, known kinds, finite normals, mobility > 0,
 * no two particles at the same coordinates. On failure the cloud's error names the first
 * offending particle; returns PST_EINPUT. */
int pst_cloud_validate(pst_cloud *c);

/* Reorder every field (positions, V, h, kind, normals, mobility, ids, fields) by one
 * permutation: new particle i is old particle perm[i]. `perm` must be a permutation of 0..n-1
 * (checked: PST_EINVAL otherwise). */
int pst_cloud_permute(pst_cloud *c, const uint32_t *perm);

/* Scatter a per-particle array given in the cloud's current order back to input order:
 * out[ids[i]] = in[i]. `in` and `out` must not alias. */
void pst_cloud_to_input_order(const pst_cloud *c, const double *in, double *out);

/* --- Generators ---------------------------------------------------------------------------- */

/* Lattice generator options. The lattice is x_i = lo + i*s0 for i = 0..n_d along each axis,
 * n_d = round((hi - lo)/s0) (both ends included; the box must be a whole number of spacings,
 * to 1e-9 relative). */
typedef struct {
    int dim;                 /* 2 or 3                                                          */
    double lo[3], hi[3];     /* the box                                                         */
    double s0;               /* lattice spacing                                                 */
    double jitter;           /* K: each coordinate moves by K*delta*s0, delta uniform in [-1,1] */
    uint64_t seed;           /* counter-based RNG seed: same cloud for every thread count       */
    int boundary_layer;      /* 1: the outer layer stays unjittered and is marked Dirichlet     */
    double h_ratio;          /* h = h_ratio * s0 (uniform)                                      */
    double angle;            /* rotation of the lattice about the box centre, radians (2D: in
                                the x-y plane; 3D: about the z axis). 0 for none.               */
} pst_lattice_opts;

/* Fill `o` with defaults: 2D unit box, s0 = 0.1, no jitter, seed 1, no boundary layer,
 * h_ratio 1.2, no rotation. */
void pst_lattice_defaults(pst_lattice_opts *o);

/* Generate a jittered (optionally rotated) node lattice. V = s0^dim. On a rotated lattice the
 * box is rotated with it (the particles are the rotated lattice points). `err` (PST_ERRLEN
 * bytes, may be NULL) receives the reason of a failure. */
int pst_cloud_lattice(pst_cloud **out, const pst_lattice_opts *o, char *err);

/* Generate the Lukyanov–Vuik cell-centred layout: one interior particle at the centre of each
 * of the cells of spacing s0 that tile the box, plus one Dirichlet particle at the centre of
 * every cell face that lies on the box boundary (none on edges or corners), with its outward
 * normal. Interior particles are jittered by K*delta*s0; face particles never move
 * (o->boundary_layer is ignored). V = s0^dim for every particle (docs/clouds.md). */
int pst_cloud_cell_centred(pst_cloud **out, const pst_lattice_opts *o, char *err);

/* The counter-based RNG behind the generators: a uniform double in [-1, 1] from (seed, index,
 * stream). Exposed so that tests and users can reproduce a jitter. */
double pst_rng_symmetric(uint64_t seed, uint64_t index, uint64_t stream);

/* --- CSV ----------------------------------------------------------------------------------- */

/* Read a cloud from CSV. The header names the columns: x,y[,z],V,h,kind,nx,ny[,nz], then
 * optionally m (scalar mobility) or mx,my[,mz] (diagonal), then any named fields. kind is
 * "interior", "dirichlet", "neumann" (or 0, 1, 2). Errors (PST_EINPUT / PST_EIO) name the file,
 * line and column in `err`: NaN/Inf, wrong column count, unknown kind, V or h <= 0, duplicate
 * particles. The cloud is Morton-unsorted: particle i is data line i. */
int pst_cloud_read_csv(pst_cloud **out, const char *path, char *err);

/* Write a cloud to CSV in input order (by ids), with full round-trip precision (%.17g). The
 * file is written to a temporary name in the same directory and renamed, so a failed write
 * never leaves a half-written file. */
int pst_cloud_write_csv(const pst_cloud *c, const char *path, char *err);

/* --- VTU (ParaView) ------------------------------------------------------------------------ */

/* Write a cloud as a VTK XML UnstructuredGrid (.vtu), binary appended raw data, little-endian,
 * 64-bit byte-count headers: the particles as Points (z = 0 in 2D), one VTK_VERTEX cell each,
 * and the PointData arrays id, kind, V, h, normal (3 components), m or M (when the cloud has a
 * mobility; M is the diagonal, 3 components), status (when `row_status` is given) and every
 * named field (docs/io.md). Particles are written in input order (by ids), so a file does not
 * depend on the cloud's storage order or the thread count. `row_status` (may be NULL) holds n
 * bytes in cloud order, e.g. pst_op_status(). All or nothing, like the CSV writer: PST_EIO on a
 * failed write, PST_EINVAL when the ids are not a permutation or a field is named like one of
 * the arrays above ("normal", "M", "status"); `err` names the path. */
int pst_cloud_write_vtu(const pst_cloud *c, const char *path, const uint8_t *row_status,
                        char *err);

/* Read a cloud from a VTK XML UnstructuredGrid (.vtu) or PolyData (.vtp) file with one Piece
 * (docs/io.md, "Reading VTU"): DataArrays in format "appended" (encoding raw, UInt32 or UInt64
 * headers, either byte order), "binary" (inline base64, uncompressed) or "ascii", of any
 * Int8..Int64, UInt8..UInt64, Float32 or Float64 type (converted to double). Points give the
 * positions: the cloud is 2D when every z is exactly 0, else 3D. PointData: V and h (required),
 * kind (0, 1, 2; default interior), normal (3 components), m (scalar mobility) or M (3-component
 * diagonal; x, y only in 2D), id (a permutation of 0..n-1: row k of the file becomes particle
 * id[k]; without it particle k is row k), status (ignored); every other array is a named field
 * and must have 1 component and a valid field name. Cells are ignored. Compressed files are
 * refused. Errors: PST_EIO (cannot open or read), PST_EINPUT (malformed or truncated file,
 * non-finite value, V, h or mobility <= 0, unknown kind, bad ids, duplicate particles; `err`
 * names the file and "LINE:COLUMN" of the XML, or the array and the 0-based point, or the offset
 * into the appended data), PST_ENOMEM. On failure *out is NULL. */
int pst_cloud_read_vtu(pst_cloud **out, const char *path, char *err);

/* ------------------------------------------------------------------------------------------ */
/* Smoothing kernels                                                                          */
/* ------------------------------------------------------------------------------------------ */

typedef enum {
    PST_KERNEL_CUBIC = 0,       /* cubic B-spline, LV eq. 12, support 2h                     */
    PST_KERNEL_QUINTIC = 1,     /* quintic spline, QSFDI eq. 9, support 3h                   */
    PST_KERNEL_WENDLAND_C2 = 2, /* Wendland C2, support 2h                                   */
    PST_KERNEL_WENDLAND_C4 = 3  /* Wendland C4, support 2h                                   */
} pst_kernel;

/* Name ("cubic", "quintic", "wendland_c2", "wendland_c4") and lookup by name (-1 if unknown). */
const char *pst_kernel_name(pst_kernel k);
int pst_kernel_from_name(const char *name);

/* Support radius in units of h (2 or 3). */
double pst_kernel_support(pst_kernel k);

/* Kernel value W(r, h), dW/dr and d2W/dr2 in `dim` = 1, 2 or 3 dimensions, normalised so that
 * the integral of W over R^dim is 1. All three are 0 at and beyond the support radius. */
double pst_kernel_w(pst_kernel k, int dim, double r, double h);
double pst_kernel_dw(pst_kernel k, int dim, double r, double h);
double pst_kernel_d2w(pst_kernel k, int dim, double r, double h);

/* ------------------------------------------------------------------------------------------ */
/* Morton order and neighbour lists                                                           */
/* ------------------------------------------------------------------------------------------ */

/* Sort the cloud along a Morton (Z-order) curve of cells of size `cell` (> 0): 64-bit keys,
 * 21 bits per axis in 3D and 32 in 2D (coarser cells are used when the box needs more), a
 * parallel LSD radix sort, and one permutation applied to every field. The ids keep the input
 * order (pst_cloud_to_input_order). */
int pst_cloud_morton_sort(pst_cloud *c, double cell);

/* Morton key of integer cell coordinates (3D: 21 bits per axis; 2D: 32 bits per axis, iz
 * ignored). */
uint64_t pst_morton_key(int dim, uint32_t ix, uint32_t iy, uint32_t iz);

typedef struct pst_nlist pst_nlist;

/* Build the CSR neighbour list of spec choice 1: j is a neighbour of i iff j != i and
 * |x_j - x_i| < support * (h_i + h_j)/2 (strict), with `support` the kernel's support radius
 * in units of h (pst_kernel_support). Rows are sorted by neighbour index. Works on any order
 * of the cloud; a Morton-sorted cloud is faster. */
int pst_nlist_build(pst_nlist **out, const pst_cloud *c, double support, char *err);

void pst_nlist_destroy(pst_nlist *nl);

/* Rows: the neighbours of particle i are index[offset[i] .. offset[i+1]). */
size_t pst_nlist_rows(const pst_nlist *nl);
const int64_t *pst_nlist_offsets(const pst_nlist *nl);   /* rows + 1 entries */
const uint32_t *pst_nlist_indices(const pst_nlist *nl);
int64_t pst_nlist_pairs(const pst_nlist *nl);            /* total entries (each pair twice) */

/* The support (radius in units of h) the list was built with. */
double pst_nlist_support(const pst_nlist *nl);

/* Statistics of a list. */
typedef struct {
    int64_t pairs;             /* stored entries                                  */
    int64_t min, max;          /* neighbours per particle                         */
    double mean;
    size_t isolated;           /* particles with no neighbour                     */
    size_t bytes;              /* memory held by the list                         */
} pst_nlist_stats;
void pst_nlist_get_stats(const pst_nlist *nl, pst_nlist_stats *s);

/* ------------------------------------------------------------------------------------------ */
/* Operators                                                                                  */
/* ------------------------------------------------------------------------------------------ */

/* An operator is a discretisation of +div(M grad u) on a cloud, in two-point form: row I is
 *     (L u)_I = sum_{J in N(I)} w_IJ (u_J - u_I)
 * for interior particles (the scheme), the same form with the flux weights of LV eq. 100 for
 * Neumann particles (n . M_I . corrected gradient, outward normal), and (L u)_I = u_I for
 * Dirichlet particles (their values are data). The matrix of L has the sparsity of the
 * neighbour list plus the diagonal -sum_J w_IJ (1 on Dirichlet rows). docs/operators.md. */
typedef struct pst_op pst_op;

/* Per-particle status of an operator row (one byte per particle). */
typedef enum {
    PST_ROW_OK = 0,
    PST_ROW_FALLBACK = 1,        /* a documented fallback was used (e.g. Gamma-bar = Gamma)   */
    PST_ROW_ILL_CONDITIONED = 2, /* a moment matrix is invertible but badly conditioned      */
    PST_ROW_RANK_DEFICIENT = 3,  /* a moment matrix is singular: the row fell back            */
    PST_ROW_TOO_FEW = 4          /* fewer neighbours than the scheme needs: the row fell back */
} pst_row_status;
#define PST_ROW_NSTATUS 5

/* A short name of a row status ("ok", "fallback", "ill-conditioned", "rank-deficient",
 * "too-few-neighbours"). */
const char *pst_row_status_name(int status);

/* Kernel-gradient variants of the Lukyanov-Vuik family (LV eqs. 15-18). */
typedef enum {
    PST_GRAD_G1 = 1, /* grad_I W_IJ                                   (15) */
    PST_GRAD_G2 = 2, /* full Shepard gradient, non-radial             (16) */
    PST_GRAD_G3 = 3, /* grad_I W_IJ / nu_I                            (17) */
    PST_GRAD_G4 = 4  /* grad_I W_IJ / nu_I (1 - W_IJ V_J / nu_I)       (18) */
} pst_gradient;

typedef struct {
    const char *scheme;   /* "brookshaw", "cb", "schwaiger", "lv", ... (pst_scheme_name)      */
    int kernel;           /* a pst_kernel, or -1 for the scheme's default                     */
    int gradient;         /* pst_gradient for the LV family (default G1)                      */
    int variant;          /* scheme-specific variant: lsmps 0 = type B (default), 1 = type A;
                             0 for every other scheme                                         */
    double cond_max;      /* a moment matrix with condition estimate above this is flagged
                             ill-conditioned (default 1e10)                                   */
    double rank_tol;      /* ... and below 1/cond of rank_tol it is rank-deficient and the
                             row falls back (default 1e-13)                                    */
    double min_pair_distance; /* pairs closer than this fraction of the smoothing length (h~_IJ
                             for the LV family, h_I otherwise) are degenerate and contribute
                             nothing (default 1e-8; in (0, 0.5))                              */
    int on_degenerate;    /* pst_on_degenerate: what a rank-deficient or too-few-neighbours
                             row does (default PST_DEGENERATE_FALL_BACK)                      */
    int mobility_mean;    /* pst_mobility_mean: how a pair (I, J) averages the mobility
                             (default PST_MEAN_ARITHMETIC, the paper's)                        */
    int laplacian;        /* 1 (default): precompute the rows of L. 0: the operator serves
                             pst_op_gradient, _hessian and _interpolate only; schemes whose
                             derivative estimates do not read the rows (PST_SUPPORTS_
                             DERIVATIVES_ONLY) then skip the precompute, and every call that
                             needs the rows (apply, store, diagonal, scale, assemble, audit)
                             returns PST_EINVAL                                               */
} pst_op_opts;

/* Pair mobility of the LV family (brookshaw, cb, schwaiger, lv), the factor (m_I + m_J) of
 * w_IJ = s_I V_J (m_I + m_J) T_IJ (LV eqs. 27, 29, 90), per component for a diagonal tensor:
 *   PST_MEAN_ARITHMETIC: m_I + m_J = 2 x the arithmetic mean (LV eq. 29, the paper's choice);
 *   PST_MEAN_HARMONIC:   4 m_I m_J / (m_I + m_J) = 2 x the harmonic mean, the transmissibility
 *                        average of TPFA. An implementer extension, not from the paper (spec
 *                        §3.6); for discontinuous, high-contrast mobility. Defined as 0 when
 *                        m_I + m_J <= 0 (never NaN). Equal to the arithmetic sum where m_I = m_J.
 * Only the LV family averages pairwise: harmonic with any other scheme is PST_EINVAL. Neumann
 * rows (LV eq. 100) use M_I alone and are the same for both. docs/operators.md. */
typedef enum {
    PST_MEAN_ARITHMETIC = 0,
    PST_MEAN_HARMONIC = 1
} pst_mobility_mean;

/* What pst_op_create does with rows that are rank-deficient or have too few neighbours. */
typedef enum {
    PST_DEGENERATE_FALL_BACK = 0, /* take the next level of the scheme's fallback chain
                                     (pst_scheme_fallback), flag and count the row          */
    PST_DEGENERATE_REFUSE = 1     /* refuse the operator: PST_ENUMERIC, the counts and the
                                     first such particle in the message                     */
} pst_on_degenerate;

/* Defaults: scheme "lv", the scheme's default kernel, G1, variant 0, cond_max 1e10,
 * rank_tol 1e-13, min_pair_distance 1e-8, on_degenerate PST_DEGENERATE_FALL_BACK,
 * mobility_mean PST_MEAN_ARITHMETIC, laplacian 1.
 * Degenerate rows are never regularised: they drop down the scheme's fallback chain. */
void pst_op_defaults(pst_op_opts *o);

/* The registered schemes: count, names (index < count) and a one-line description. */
int pst_scheme_count(void);
const char *pst_scheme_name(int index);
const char *pst_scheme_description(int index);
/* The kernel a scheme uses by default (a pst_kernel), or -1 for an unknown scheme name. */
int pst_scheme_default_kernel(const char *name);
/* The fallback chain of a scheme's degenerate rows, in the order it is tried, as one line
 * ("quadric fit: too few neighbours or singular -> linear-exact row -> ..."); NULL for an
 * unknown name. docs/operators.md, "Row status and fallbacks". */
const char *pst_scheme_fallback(const char *name);

/* What a scheme can do, for planning before an operator exists (0 for an unknown name). */
enum {
    PST_SUPPORTS_GRADIENT = 0,     /* pst_op_gradient                                          */
    PST_SUPPORTS_HESSIAN,          /* pst_op_hessian                                           */
    PST_SUPPORTS_INTERPOLATE,      /* pst_op_interpolate                                       */
    PST_SUPPORTS_MOBILITY,         /* a per-particle mobility: div(M grad u)                   */
    PST_SUPPORTS_SYMMETRIC,        /* CG through a symmetric scaling (with G1, no Neumann rows) */
    PST_SUPPORTS_DERIVATIVES_ONLY  /* derivatives without the rows (opts.laplacian = 0)        */
};
int pst_scheme_supports(const char *name, int what);

/* Build an operator: validate the inputs, precompute the per-particle data (one threaded
 * pass), classify every row. The cloud and the list must outlive the operator and must not
 * change. The list's support must cover the kernel's (pst_kernel_support), else PST_EINVAL.
 * No output of an operator is ever NaN: degenerate rows fall back and are counted. */
int pst_op_create(pst_op **out, const pst_cloud *c, const pst_nlist *nl, const pst_op_opts *o,
                  char *err);
void pst_op_destroy(pst_op *op);

/* Matrix-free apply: y = L u, pair geometry recomputed from the positions and the per-particle
 * data. u and y have one value per particle (cloud order) and must not alias. PST_EINVAL for
 * an operator built without rows (opts.laplacian = 0). */
int pst_op_apply(const pst_op *op, const double *u, double *y);

/* 1 when the operator has its rows (see pst_op_opts.laplacian); its scheme's name; its kernel
 * (a pst_kernel). */
int pst_op_has_rows(const pst_op *op);
const char *pst_op_scheme(const pst_op *op);
int pst_op_kernel(const pst_op *op);
/* The options an operator was built with, as resolved (the kernel is the one in use, never
 * -1; scheme points at the registry's name): what to report beside its results. */
void pst_op_options(const pst_op *op, pst_op_opts *o);
/* Entries of the operator's sparsity pattern without the diagonal: the neighbour list's
 * pairs, or more for schemes with a wider stencil (the mixed schemes' neighbours of
 * neighbours). pst_op_store keeps 8 bytes per entry. */
int64_t pst_op_pattern_pairs(const pst_op *op);

/* Compute and keep the stencil weights w_IJ (CSR, the list's layout: 8 bytes per pair). */
int pst_op_store(pst_op *op);
/* Apply from the stored weights (same rows as pst_op_apply, to rounding). PST_EINVAL when
 * pst_op_store has not been called. */
int pst_op_apply_stored(const pst_op *op, const double *u, double *y);

/* The diagonal of L: -sum_J w_IJ on scheme and Neumann rows, 1 on Dirichlet rows. */
int pst_op_diagonal(const pst_op *op, double *diag);   /* PST_ENOMEM possible */

/* Per-row status (n bytes, pst_row_status) and the count of each status. */
const uint8_t *pst_op_status(const pst_op *op);
void pst_op_status_counts(const pst_op *op, size_t counts[PST_ROW_NSTATUS]);

/* Per-phase wall-clock timers of an operator, in seconds. Schemes that run their precompute as
 * separate passes fill the first four; fused single-pass schemes (the LV family) fill only
 * PST_PHASE_PRECOMPUTE. PST_PHASE_APPLY is the time of the latest apply (either path). */
enum {
    PST_PHASE_GEOMETRY = 0,   /* neighbour geometry and kernel weights (incl. volume pre-passes) */
    PST_PHASE_MOMENTS = 1,    /* moment accumulation                                            */
    PST_PHASE_INVERSION = 2,  /* the per-particle inversions                                    */
    PST_PHASE_WEIGHTS = 3,    /* formation of stencil weights or coefficients (kappa)           */
    PST_PHASE_PRECOMPUTE = 4, /* the whole of pst_op_create                                     */
    PST_PHASE_APPLY = 5
};
#define PST_NPHASES 6
const char *pst_phase_name(int phase);
void pst_op_phase_times(const pst_op *op, double t[PST_NPHASES]);

/* The scheme's per-particle normalising factor s_I (1 where the scheme has none): tr C/n for
 * cb, tr(Gamma^-1)/n for schwaiger, tr(Gamma-bar^-1)/n for lv. n values. */
int pst_op_scale(const pst_op *op, double *s);

/* An explicit sparse matrix in CSR form with 64-bit row offsets. */
typedef struct {
    size_t n;          /* rows = columns                         */
    int64_t *rowptr;   /* n + 1                                  */
    uint32_t *col;     /* rowptr[n], sorted by column in a row   */
    double *val;       /* rowptr[n]                              */
} pst_csr;
void pst_csr_free(pst_csr *a);

/* The explicit matrix of L (with the diagonal), rows and columns in cloud order. */
int pst_op_assemble(const pst_op *op, pst_csr *a);

/* Write a matrix as MatrixMarket "coordinate real general", 1-based. With `ids` (the cloud's
 * ids, or NULL for the identity) row/column i is written as ids[i] + 1, i.e. in input order.
 * All-or-nothing file write (PST_EIO on failure). */
int pst_csr_write_mtx(const pst_csr *a, const int64_t *ids, const char *path, char *err);

/* Monotonicity audit of an operator (LV §4.4): the discrete K = -L. */
typedef struct {
    size_t rows;                 /* interior rows audited                                     */
    size_t rows_positive_offdiag;/* rows of K with a positive off-diagonal entry (w_IJ < 0)   */
    int64_t positive_offdiag;    /* such entries                                              */
    size_t rows_not_dominant;    /* rows of K that are not weakly diagonally dominant with a
                                    positive diagonal                                        */
    /* Lemma 3 diagnostics, for schemes with a bracket 1 - xi_I . x_IJ (schwaiger, lv);
     * -1 for the others */
    int64_t lemma3_sign_mixed;   /* rows whose brackets do not all share one sign (92)       */
    int64_t lemma3_xi_large;     /* rows with |xi_I| * max_J d_IJ >= 1 (sufficient check)     */
} pst_op_audit;
int pst_op_audit_rows(const pst_op *op, pst_op_audit *a);  /* PST_ENOMEM possible */

/* The same audit per row: flags[i] is an OR of the bits below for interior row i, 0 for the
 * other rows (n bytes, cloud order). PST_EINVAL without rows, PST_ENOMEM possible. */
enum {
    PST_AUDIT_POSITIVE_OFFDIAG = 1, /* K = -L has a positive off-diagonal entry (w_IJ < 0)  */
    PST_AUDIT_NOT_DOMINANT = 2,     /* not weakly diagonally dominant with K_II > 0         */
    PST_AUDIT_LEMMA3_MIXED = 4,     /* the brackets 1 - xi_I . x_IJ change sign (LV eq. 92) */
    PST_AUDIT_XI_LARGE = 8          /* |xi_I| max_J d_IJ >= 1 (the sufficient check fails)   */
};
int pst_op_audit_flags(const pst_op *op, uint8_t *flags);

/* Corrected gradient <grad u>_I = sum_J V_J (u_J - u_I) C_I grad W_IJ (LV eq. 54) with the
 * operator's kernel and gradient variant; exact for linear fields wherever C exists.
 * grad has dim arrays of n values. PST_EINVAL for schemes without C (brookshaw). */
int pst_op_gradient(const pst_op *op, const double *u, double *const grad[3]);

/* Second derivatives of u at the particles from the scheme's fit: hess[0..2] = u_xx, u_yy, u_xy
 * in 2D; u_xx, u_yy, u_zz, u_xy, u_xz, u_yz in 3D (n values each). PST_EINVAL for schemes
 * without a quadratic fit. */
int pst_op_hessian(const pst_op *op, const double *u, double *const hess[6]);

/* Interpolate u, and its Laplacian, at m points that need not be particles (QSFDI eqs. 32-35
 * and the schemes' own fits): pts[d][k] is coordinate d of point k; value and lap (either may
 * be NULL) receive m values each. The smoothing length at a point is the largest h of the
 * cloud. Points with too few neighbours get the nearest particle's value and a Laplacian of 0,
 * and are counted in *fallbacks (may be NULL). PST_EINVAL for schemes without interpolation. */
int pst_op_interpolate(const pst_op *op, const double *const pts[3], size_t m, const double *u,
                       double *value, double *lap, size_t *fallbacks, char *err);

/* ------------------------------------------------------------------------------------------ */
/* Solving                                                                                    */
/* ------------------------------------------------------------------------------------------ */

/* Solve L u = b for an operator L (docs/solving.md). Row by row the right-hand side b means:
 *   interior particles:  (L u)_I = b_I          (div(M grad u) = g, so b = g)
 *   Neumann particles:   flux row (LV eq. 100) = b_I   (n . M grad u = g_N)
 *   Dirichlet particles: u_I = b_I               (the value; moved to the right-hand side)
 * u holds the initial guess on entry (Dirichlet entries are ignored) and the solution on
 * return, also on failure (the last iterate, never NaN). */
typedef enum {
    PST_SOLVER_AUTO = 0,   /* CG when the operator is symmetrisable (brookshaw, cb with G1
                              and without Neumann rows), else GMRES                          */
    PST_SOLVER_CG = 1,     /* on diag(V/s) K, the symmetric scaling of spec lukyanov_vuik §4.5 */
    PST_SOLVER_GMRES = 2,  /* restarted GMRES(m), right preconditioning, CGS2 orthogonalisation */
    PST_SOLVER_BICGSTAB = 3
} pst_solver;

typedef enum {
    PST_PREC_NONE = 0,
    PST_PREC_JACOBI = 1,   /* 1 / diag(L) (pst_op_diagonal)                                   */
    PST_PREC_AMG = 2       /* hypre BoomerAMG on an assembled low-order M-matrix              */
} pst_precond;

typedef enum {
    PST_AMG_BROOKSHAW = 0, /* the Brookshaw operator on the same cloud (an M-matrix)          */
    PST_AMG_OWN = 1        /* the scheme's own assembled stencil                             */
} pst_amg_source;

typedef struct {
    int solver;            /* pst_solver (default AUTO)                                       */
    int precond;           /* pst_precond (default JACOBI)                                    */
    int amg_source;        /* pst_amg_source (default BROOKSHAW)                              */
    int restart;           /* GMRES restart length m (default 50)                             */
    int max_iter;          /* iteration limit (default 5000)                                  */
    double rtol;           /* stop when ||b - L u|| <= rtol ||b|| (2-norms, default 1e-10)      */
    int stored;            /* 1: apply the stored weights (pst_op_store), 0: matrix-free      */
    int history;           /* 1: keep the relative residual of every iteration                */
    /* Called after every iteration with the iteration count and the estimated relative
     * residual, from the calling thread outside any parallel region (progress bars); NULL
     * (the default) for none. */
    void (*monitor)(int iteration, double rel_residual, void *ctx);
    void *monitor_ctx;
} pst_solve_opts;

void pst_solve_defaults(pst_solve_opts *o);

typedef struct {
    int converged;         /* 1 when the tolerance was reached                                */
    int solver;            /* the pst_solver actually used                                    */
    int iterations;
    double rel_residual;   /* true residual ||b - L u|| / ||b|| at return                      */
    double *history;       /* relative residual per iteration (when asked); free with
                              pst_solve_result_free                                          */
    int nhistory;
    double seconds;
    char message[PST_ERRLEN]; /* why it stopped: converged, iteration limit, breakdown, ...   */
} pst_solve_result;
void pst_solve_result_free(pst_solve_result *r);

/* Returns PST_OK when converged, PST_ENUMERIC (with the reached residual in r->message) when
 * not converged or broken down, PST_EINVAL for a bad request (e.g. CG on a non-symmetrisable
 * operator, AMG without hypre), PST_ENOMEM. Results are identical for every thread count. */
int pst_solve(const pst_op *op, const double *b, double *u, const pst_solve_opts *o,
              pst_solve_result *r, char *err);

/* ------------------------------------------------------------------------------------------ */
/* Error norms                                                                                */
/* ------------------------------------------------------------------------------------------ */

/* The papers' error norms (docs/norms.md), e = approx - exact over the particles of a region:
 *   REL_L2              ||e||_2 / ||exact||_2                              QSFDI eqs. 14, 15
 *   QSFDI11             sqrt(sum V (e / exact)^2)      (as printed)         QSFDI eq. 11
 *   QSFDI11_NORMALISED  sqrt(sum V (e / exact)^2 / sum V)
 *   LV78                sqrt(sum V e^2 / sum V)        (absolute)           LV eq. 78
 *   LV95                sqrt(sum V (e / exact)^2 / sum V)                   LV eq. 95
 *   MAX_ABS             max |e|;   MAX_REL  max |e| / max |exact|
 * For vector values (ncomp > 1: gradients, Hessians) e and exact are Euclidean lengths per
 * particle. */
typedef enum {
    PST_NORM_REL_L2 = 0,
    PST_NORM_QSFDI11,
    PST_NORM_QSFDI11_NORMALISED,
    PST_NORM_LV78,
    PST_NORM_LV95,
    PST_NORM_MAX_ABS,
    PST_NORM_MAX_REL,
    PST_NNORMS
} pst_norm;

/* The norm's name ("rel_l2", "qsfdi11", ...; NULL when out of range) and its inverse (-1 for
 * an unknown name). */
const char *pst_norm_name(int norm);
int pst_norm_from_name(const char *name);

/* One norm of approx[a][i] - exact[a][i] (a < ncomp <= 6) over the particles with mask[i] != 0
 * (every particle when mask is NULL), in the cloud's order. Errors, with the reason in err:
 * PST_EINVAL (bad norm or ncomp, empty region), PST_ENUMERIC (a non-finite value; a
 * pointwise-relative norm where the exact value is 0; a relative norm whose exact values are all
 * 0). The result never is NaN. */
int pst_error_norm(const pst_cloud *c, int ncomp, const double *const *approx,
                   const double *const *exact, const uint8_t *mask, int norm, double *out,
                   char *err);
/* The same over n values at points that are not particles (unit volumes; no mask). */
int pst_error_norm_points(size_t n, int ncomp, const double *const *approx,
                          const double *const *exact, int norm, double *out, char *err);

/* ------------------------------------------------------------------------------------------ */
/* Permeability grids (SPE10)                                                                 */
/* ------------------------------------------------------------------------------------------ */

/* A Cartesian permeability grid of nx x ny x nz cells of size dx x dy x dz (any length unit;
 * the SPE10 reader uses metres). Component c (0 = Kx, 1 = Ky, 2 = Kz) of cell (i, j, l) is
 * k[c][i + nx*(j + ny*l)]. A grid filled by pst_spe10_read owns arrays from the library's
 * allocator: free it with pst_perm_grid_free. A grid filled by hand keeps the caller's arrays
 * (the caller frees them). docs/spe10.md. */
typedef struct {
    int nx, ny, nz;
    double dx, dy, dz;
    double *k[3];
} pst_perm_grid;

/* Read one layer of SPE10 model 2 permeability (millidarcy) into `g`: the sub-block
 * i in [i0, i0+ni), j in [j0, j0+nj) of the 60 x 220 layer (i along the 60-cell x direction,
 * j along the 220-cell y direction; 0, 0, 60, 60 is the 60x60 block of LV §5.3), as a grid of
 * ni x nj x 1 cells of 6.096 m x 3.048 m x 0.6096 m (20 x 10 x 2 ft) with Kx, Ky and Kz.
 * The format follows the file name:
 *   ".../permx.geos": the GEOS voxel files; permy.geos and permz.geos are read from the same
 *                     directory; `layer` is 84 or 85;
 *   ".../perm.txt":   the RTSPHEM Tarbert layer (Kx, Ky, Kz blocks); `layer` must be 0.
 * Every value of each file is parsed and checked, including those outside the sub-block.
 * Errors: PST_EINVAL (unknown file name, bad layer, sub-block outside the layer), PST_EIO
 * (missing file), PST_EINPUT (non-numeric, non-finite or non-positive value, too few or too
 * many values: "FILE:LINE: ..." in `err`), PST_ENOMEM. On failure `g` is left empty (all
 * zero), so pst_perm_grid_free is always safe. */
int pst_spe10_read(pst_perm_grid *g, const char *path, int layer, int i0, int j0, int ni,
                   int nj, char *err);

/* Free the arrays of a grid filled by pst_spe10_read and zero it. NULL is allowed. */
void pst_perm_grid_free(pst_perm_grid *g);

/* Set the cloud's mobility from the grid cell holding each particle. Along axis a the cell
 * index is floor((x_a - origin[a]) / (d_a * scale[a])), clamped to [0, n_a - 1]: particles
 * exactly on the grid's upper outer faces (e.g. the boundary particles of a cell-centred
 * layout) and any particle outside the grid take the nearest boundary cell, so check the
 * mapping if particles may lie outside. `scale` maps grid units to cloud units (the 60x60
 * SPE10 block onto the unit square: scale = {1/(60*dx), 1/(60*dy), 1}); `origin` is the grid
 * corner in cloud units. NULL origin means 0, NULL scale means 1. A 2D cloud reads layer
 * l = 0 and ignores origin[2], scale[2]. diagonal == 0 sets a scalar mobility (Kx);
 * otherwise the diagonal tensor (Kx, Ky[, Kz]) with dim components. Values are copied as
 * they are (no unit conversion). Errors: PST_EINVAL (bad grid, scale <= 0, missing
 * component), PST_EINPUT (a non-finite particle coordinate), PST_ENOMEM; the cloud is
 * unchanged on every failure. */
int pst_cloud_mobility_from_grid(pst_cloud *c, const pst_perm_grid *g, const double origin[3],
                                 const double scale[3], int diagonal, char *err);

/* ------------------------------------------------------------------------------------------ */
/* Threads                                                                                    */
/* ------------------------------------------------------------------------------------------ */

/* The number of OpenMP threads the library will use (omp_get_max_threads). */
int pst_threads(void);

#ifdef __cplusplus
}
#endif

#endif /* PSTENCIL_H */
