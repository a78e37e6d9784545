/* pstencil: Operators: the schemes, their rows, apply, assembly, audit, derivatives. Part of the public API; include <pstencil.h>. */
#ifndef PSTENCIL_PUBLIC_OPERATOR_H
#define PSTENCIL_PUBLIC_OPERATOR_H

#include "pstencil/cloud.h"
#include "pstencil/kernel.h"
#include "pstencil/neighbours.h"

#ifdef __cplusplus
extern "C" {
#endif

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

/* Pair mobility of the LV family (brookshaw, cb, schwaiger, lv), the factor (m_I + m_J) of
 * w_IJ = s_I V_J (m_I + m_J) T_IJ (LV eqs. 27, 29, 90), per component for a diagonal tensor:
 *   PST_MEAN_ARITHMETIC: m_I + m_J = 2 x the arithmetic mean (LV eq. 29, the paper's choice);
 *   PST_MEAN_HARMONIC:   4 m_I m_J / (m_I + m_J) = 2 x the harmonic mean, the transmissibility
 *                        average of TPFA. An implementer extension, not from the paper;
 *                        for discontinuous, high-contrast mobility. Defined as 0 when
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

typedef struct {
    const char *scheme;   /* "brookshaw", "cb", "schwaiger", "lv", ... (pst_scheme_name)      */
    pst_kernel kernel;    /* or PST_KERNEL_DEFAULT (-1) for the scheme's default               */
    pst_gradient gradient; /* for the LV family (default G1)                                  */
    int variant;          /* scheme-specific variant: lsmps 0 = type B (default), 1 = type A;
                             0 for every other scheme                                         */
    double cond_max;      /* a moment matrix with condition estimate above this is flagged
                             ill-conditioned (default 1e10)                                   */
    double rank_tol;      /* ... and below 1/cond of rank_tol it is rank-deficient and the
                             row falls back (default 1e-13)                                    */
    double min_pair_distance; /* pairs closer than this fraction of the smoothing length (h~_IJ
                             for the LV family, h_I otherwise) are degenerate and contribute
                             nothing (default 1e-8; in (0, 0.5))                              */
    pst_on_degenerate on_degenerate; /* what a rank-deficient or too-few-neighbours
                             row does (default PST_DEGENERATE_FALL_BACK)                      */
    pst_mobility_mean mobility_mean; /* how a pair (I, J) averages the mobility
                             (default PST_MEAN_ARITHMETIC, the paper's)                        */
    int laplacian;        /* 1 (default): precompute the rows of L. 0: the operator serves
                             pst_op_gradient, _hessian and _interpolate only; schemes whose
                             derivative estimates do not read the rows (PST_SUPPORTS_
                             DERIVATIVES_ONLY) then skip the precompute, and every call that
                             needs the rows (apply, store, diagonal, scale, assemble, audit)
                             returns PST_EINVAL                                               */
    int keep;             /* PST_KEEP_* bits: what the precompute keeps beyond the rows, so
                             that later derivative calls reuse it (docs/operators.md, "Kept
                             derivatives"); 0 (default): nothing. Needs the rows (laplacian
                             = 1), a scheme with PST_SUPPORTS_KEEP and, for
                             PST_KEEP_HESSIAN, a Hessian, else PST_EINVAL                  */
    /* The boundary description of the rows, instead of the cloud's own (a solve's boundary
     * groups): kinds[i] is particle i's pst_kind and normals[d][i] its outward normal, in
     * cloud order. NULL (the default) takes the cloud's kinds, and normals[0] == NULL the
     * cloud's normals. The cloud is never modified; the arrays must outlive the operator and
     * must not change. Checked: every kind known, every Neumann particle's normal finite. */
    const uint8_t *kinds;
    const double *normals[3];
    /* A progress hook (pstencil/core.h; fn NULL, the default: none). pst_op_create reports
     * the rows of its precompute through it (total = n, counted as blocks of rows finish),
     * and the operator keeps it for pst_op_gradient, pst_op_hessian (total = n) and
     * pst_op_interpolate (total = the points), until pst_op_set_progress changes it. The
     * applies never report: one apply is short, and a solve reports its iterations through
     * pst_solve_opts.monitor. user must outlive every call that reports to it. */
    pst_progress progress;
} pst_op_opts;

/* What pst_op_opts.keep asks the precompute to keep: the weights of the derivative estimates
 * at every particle, which the precompute's inversions already give, so that pst_op_gradient
 * (pst_op_hessian) is one pass over the neighbours that forms the data moments and dots them
 * with the kept weights, instead of redoing the moments and inversions of every particle
 * (qsfdi and the CSPM family: PST_SUPPORTS_KEEP). pst_scheme_keep_bytes gives the memory; the
 * results are the computed ones, bit for bit. */
enum {
    PST_KEEP_GRADIENT = 1, /* what pst_op_gradient needs */
    PST_KEEP_HESSIAN = 2   /* what pst_op_hessian needs  */
};

/* Defaults: scheme "qsfdi" (as in scenes), its default kernel, G1, variant 0, cond_max 1e10,
 * rank_tol 1e-13, min_pair_distance 1e-8, on_degenerate PST_DEGENERATE_FALL_BACK,
 * mobility_mean PST_MEAN_ARITHMETIC, laplacian 1, keep 0, no progress hook.
 * Degenerate rows are never regularised: they drop down the scheme's fallback chain. */
void pst_op_defaults(pst_op_opts *o);

/* The registered schemes: count, names (index < count) and a one-line description. */
int pst_scheme_count(void);
const char *pst_scheme_name(int index);
const char *pst_scheme_description(int index);
/* The kernel a scheme uses by default, or PST_KERNEL_UNKNOWN for an unknown scheme name. */
pst_kernel pst_scheme_default_kernel(const char *name);
/* The fallback chain of a scheme's degenerate rows, in the order it is tried, as one line
 * ("quadric fit: too few neighbours or singular -> linear-exact row -> ..."); NULL for an
 * unknown name. docs/operators.md, "Row status and fallbacks". */
const char *pst_scheme_fallback(const char *name);
/* The highest polynomial degree whose Laplacian a scheme's interior rows reproduce to rounding:
 * on any cloud (lattice = 0: jittered particles, rows cut by the cloud's edge included) or on
 * the rows of a regular lattice with full support (lattice = 1). -1 for an unknown name.
 * tests/test_contract.c holds every scheme to it; docs/schemes/README.md, "exact for". */
int pst_scheme_degree(const char *name, int lattice);
/* The number of values pst_op_opts.variant takes for a scheme (0 .. n-1; 1: only the default
 * 0), 0 for an unknown name. */
int pst_scheme_variants(const char *name);

/* Bytes per particle of a scheme's precomputed data in dimension dim (2 or 3), the largest
 * over its variants, without the stored weights (8 per pattern entry) or the row status
 * (1): what a memory plan counts. 0 for an unknown name or dimension. */
int pst_scheme_data_bytes(const char *name, int dim);

/* Bytes per particle that an operator keeps for its lane rows, the positions and values
 * packed for the precompute, the matrix-free apply and qsfdi's derivatives (32 for qsfdi,
 * lpmps, lsmps, the CSPM and the LV families; docs/operators.md, "Matrix-free rows in lanes"),
 * beside its data (pst_scheme_data_bytes), on a half list too (pst_op_use_half_list: its lane
 * rows read them). 0 for the other schemes and an unknown name. */
int pst_scheme_apply_bytes(const char *name);

/* 1 when a scheme's own assembled matrix serves AMG better than the Brookshaw proxy (lsmps;
 * measured in docs/solving.md, "The AMG matrix per scheme"): the matrix pst_solve_opts
 * amg_source PST_AMG_AUTO takes. 0 for the other schemes and an unknown name. */
int pst_scheme_amg_own(const char *name);

/* The automatic radius (in h) of a scheme's Brookshaw AMG proxy, what pst_solve_opts
 * amg_radius = -1 takes (where the mobility does not vary tenfold): 1.3 for qsfdi (the same
 * iterations as 1.6 h at 60 % of the entries, a faster set-up and cycle), 1.6 for the others
 * (docs/solving.md, "The AMG matrix's stencil"). 0 for an unknown name. */
double pst_scheme_amg_radius(const char *name);

/* What a scheme can do, for planning before an operator exists (0 for an unknown name). */
enum {
    PST_SUPPORTS_GRADIENT = 0,     /* pst_op_gradient                                          */
    PST_SUPPORTS_HESSIAN,          /* pst_op_hessian                                           */
    PST_SUPPORTS_INTERPOLATE,      /* pst_op_interpolate                                       */
    PST_SUPPORTS_MOBILITY,         /* a per-particle mobility: div(M grad u)                   */
    PST_SUPPORTS_SYMMETRIC,        /* CG through a symmetric scaling (with G1, no Neumann rows) */
    PST_SUPPORTS_DERIVATIVES_ONLY, /* derivatives without the rows (opts.laplacian = 0)        */
    PST_SUPPORTS_HALF_LIST,        /* the matrix-free apply on a half list (pst_op_use_half_list) */
    PST_SUPPORTS_KEEP              /* pst_op_opts.keep (qsfdi, lsmps, lpmps, the CSPM family)  */
};
int pst_scheme_supports(const char *name, int what);

/* How many rings of neighbours a row of the scheme reads, 1 to 3 (0 for an unknown name): 1
 * when a row reads its particle and its neighbours only; 2 for the CSPM family (the neighbours'
 * volumes come from their own neighbours) and mixed1 / mixed2 (the neighbours' gradients); 3
 * for mixed0 (the volumes inside those gradients). A rank's part (pst_part_create) of that many
 * hops gives its owned rows exactly. */
int pst_scheme_halo(const char *name);

/* Bytes per particle that pst_op_opts.keep = `keep` (PST_KEEP_* bits) adds to an operator of
 * the scheme in dimension dim; 0 for schemes without PST_SUPPORTS_KEEP (and for the Hessian
 * of a scheme without one). */
int pst_scheme_keep_bytes(const char *name, int dim, int keep);

/* Build an operator: validate the inputs, precompute the per-particle data (one threaded
 * pass), classify every row. The cloud and the list must outlive the operator and must not
 * change between its calls, except as pst_op_refresh allows (pst_op_use_half_list replaces
 * the list). The list must be whole (not a half list) and its support must cover the
 * kernel's (pst_kernel_support), else PST_EINVAL.
 * No output of an operator is ever NaN: degenerate rows fall back and are counted. */
int pst_op_create(pst_op **out, const pst_cloud *c, const pst_nlist *nl, const pst_op_opts *o,
                  char *err);
void pst_op_destroy(pst_op *op);

/* Compute op again after its particles moved: the positions (h, volumes, mobility) of its
 * cloud changed in place and its list was brought up to date (pst_nlist_update). The scheme,
 * kernel and options stay; the precompute runs again on the same handle, which keeps its row
 * status, packed positions and the scheme's per-particle data (filled again in place, no
 * allocation); stored weights are stored again in their precision, in their array while the
 * new pattern fits it (else one an eighth larger); the rows are those pst_op_create would give
 * now, bit for bit. Handles built on op (pst_krylov) are brought up to date by
 * pst_krylov_refresh. PST_EINVAL (an operator on a half list: create it again; a cloud or list
 * of another size), the errors of pst_op_create's precompute; on failure op keeps no rows and
 * every apply refuses it (destroy it). */
int pst_op_refresh(pst_op *op, char *err);

/* Replace op's progress hook (pst_op_opts.progress) by *progress, or remove it (NULL). Not
 * while another thread calls op. */
void pst_op_set_progress(pst_op *op, const pst_progress *progress);

/* Matrix-free apply: y = L u, pair geometry recomputed from the positions and the per-particle
 * data. u and y have one value per particle (cloud order) and must not alias. The apply is
 * parallel inside; two applies (gradients, Hessians) of one operator must not run at the same
 * time (qsfdi, lpmps, lsmps, the CSPM and the LV families write u into the operator's packed
 * positions and values, 32 bytes per particle). PST_EINVAL for an operator built without rows
 * (opts.laplacian = 0). */
int pst_op_apply(const pst_op *op, const double *u, double *y);

/* The low-memory layout of the largest clouds (docs/operators.md, "The half-list apply"):
 * from now on op's matrix-free apply reads `half`, the half (pst_nlist_halve) of the list op
 * was built on, so the caller may destroy that whole list once this returns; `half` must
 * outlive op. The list then costs 4 bytes per pair instead of 8. Each stored pair is visited
 * once per apply: its two weights (those of pst_op_apply) are scattered to both rows, in an
 * order fixed by a colouring of fixed-size blocks of rows, so the result is the same for every
 * thread count and agrees with the whole-list apply to rounding. The diagonal is taken here,
 * from the whole rows. Afterwards pst_op_apply, pst_op_diagonal, pst_op_scale, the status,
 * option and timer queries work, and an AMG proxy (pst_krylov_create) is built from `half`;
 * pst_op_store, pst_op_assemble, the audits, pst_op_gradient, pst_op_hessian and
 * pst_op_interpolate return PST_EINVAL. Schemes: pst_scheme_supports(name,
 * PST_SUPPORTS_HALF_LIST) (the LV family, qsfdi, lpmps, lsmps). PST_EINVAL (no such apply, no
 * rows, stored weights, a list that is not op's half), PST_ENOMEM (message in err). */
int pst_op_use_half_list(pst_op *op, const pst_nlist *half, char *err);
/* Colours of op's half-list schedule (the applies' sequential steps); 0 before
 * pst_op_use_half_list. */
int pst_op_half_colours(const pst_op *op);

/* 1 when the operator has its rows (see pst_op_opts.laplacian); its scheme's name; its kernel. */
int pst_op_has_rows(const pst_op *op);
const char *pst_op_scheme(const pst_op *op);
pst_kernel pst_op_kernel(const pst_op *op);
/* The options an operator was built with, as resolved (the kernel is the one in use, never
 * -1; scheme points at the registry's name): what to report beside its results. */
void pst_op_options(const pst_op *op, pst_op_opts *o);
/* Entries of the operator's sparsity pattern without the diagonal: the neighbour list's
 * pairs, or more for schemes with a wider stencil (the mixed schemes' neighbours of
 * neighbours, counted on demand until pst_op_store builds the pattern; -1 when the count
 * cannot allocate its n + 1 offsets). pst_op_store keeps 8 bytes per entry (4 in float). */
int64_t pst_op_pattern_pairs(const pst_op *op);

/* Compute and keep the stencil weights w_IJ (CSR in the pattern's layout: 8 bytes per entry;
 * a wider pattern than the list, the mixed schemes', is built here and kept with them, 4 bytes
 * more per entry). PST_ENOMEM when they do not fit (nothing is kept then). The same as
 * pst_op_store_with(op, NULL, NULL): PST_EINVAL without rows, on a half list, or when the
 * weights are already stored in float. */
int pst_op_store(pst_op *op);

/* The precision of stored weights; PST_STORE_NONE (-1) when none are stored. */
typedef enum {
    PST_STORE_NONE = -1,
    PST_STORE_DOUBLE = 0, /* 8 bytes per entry: the stored apply agrees with pst_op_apply to
                             rounding (the default)                                         */
    PST_STORE_FLOAT = 1   /* 4 bytes per entry: each weight rounded to float (2^-24 relative),
                             the apply still sums in double; 8 instead of 12 bytes streamed per
                             pair. Effect on the error and on solves: docs/operators.md,
                             "Stored weights in float"                                      */
} pst_store_precision;

typedef struct {
    pst_store_precision precision; /* default PST_STORE_DOUBLE */
} pst_op_store_opts;

/* Defaults: PST_STORE_DOUBLE. */
void pst_op_store_defaults(pst_op_store_opts *o);

/* pst_op_store with options (o NULL: the defaults); one store per operator. Storing again in
 * the precision already stored is PST_OK and does nothing. Refused: PST_EINVAL for a NULL
 * operator, an unknown precision, an operator without rows (opts.laplacian = 0), one on a half
 * list, or weights already stored in the other precision (pst_op_drop_store them first);
 * PST_ENUMERIC for a float store with a row whose largest |w_IJ| lies outside [2^-102,
 * FLT_MAX], where float would not keep it to 2^-24 (a cloud of extreme coordinates: the
 * message names the first such row); PST_ENOMEM.
 * Nothing is kept on failure.
 * Whatever the store, pst_op_diagonal, pst_op_assemble and the audits use the double weights
 * (emitted per row when only floats are stored), so a float-stored operator's Jacobi and AMG
 * preconditioners are those of the double rows. */
int pst_op_store_with(pst_op *op, const pst_op_store_opts *o, char *err);

/* The precision of op's stored weights, or PST_STORE_NONE when none are stored. */
pst_store_precision pst_op_store_precision(const pst_op *op);

/* Free op's stored weights (either precision) and the pattern built for them: the operator
 * goes on matrix-free (pst_op_apply_stored refuses it until the next store), and may be
 * stored again in either precision. Nothing stored, or op NULL: nothing happens. */
void pst_op_drop_store(pst_op *op);

/* Apply from the stored weights of either precision (same rows as pst_op_apply, to rounding
 * of the stored weights), deterministic for every thread count. PST_EINVAL when nothing is
 * stored. The solves' stored path (pst_solve_opts.stored = 1, pst_op_linop) is this call, so
 * it takes a float store as it is. */
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

/* Monotonicity audit of an operator (LV §4.5): the discrete K = -L. */
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
 * grad has dim arrays of n values. PST_EINVAL for schemes without C (brookshaw). Like
 * pst_op_apply, not at the same time as another apply, gradient or Hessian of the same
 * operator: they write u into its packed rows. */
int pst_op_gradient(const pst_op *op, const double *u, double *const grad[3]);

/* Second derivatives of u at the particles from the scheme's fit: hess[0..2] = u_xx, u_yy, u_xy
 * in 2D; u_xx, u_yy, u_zz, u_xy, u_xz, u_yz in 3D (n values each). PST_EINVAL for schemes
 * without a quadratic fit. Not at the same time as another apply, gradient or Hessian of the
 * same operator (pst_op_gradient). */
int pst_op_hessian(const pst_op *op, const double *u, double *const hess[6]);

/* Interpolate u, and its Laplacian, at m points that need not be particles (QSFDI eqs. 32-35
 * and the schemes' own fits): pts[d][k] is coordinate d of point k; value and lap (either may
 * be NULL) receive m values each. The smoothing length at a point is the largest h of the
 * cloud. Points with too few neighbours get the nearest particle's value and a Laplacian of 0,
 * and are counted in *fallbacks (may be NULL). In a periodic box the search and the offsets
 * wrap through its faces. PST_EINVAL for schemes without interpolation; PST_EINPUT for a point
 * with a coordinate that is not finite, or outside the box along a periodic axis. */
int pst_op_interpolate(const pst_op *op, const double *const pts[3], size_t m, const double *u,
                       double *value, double *lap, size_t *fallbacks, char *err);

#ifdef __cplusplus
}
#endif

#endif /* PSTENCIL_PUBLIC_OPERATOR_H */
