/* pstencil: Particle clouds and their generators. Part of the public API; include <pstencil.h>. */
#ifndef PSTENCIL_PUBLIC_CLOUD_H
#define PSTENCIL_PUBLIC_CLOUD_H

#include "pstencil/core.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------------------------------------------ */
/* Particle clouds                                                                            */
/* ------------------------------------------------------------------------------------------ */

/* Field names (pst_cloud_add_field) are C identifiers shorter than PST_MAX_NAME bytes (with
 * the terminating 0) that are not one of the CSV format's own column names (x, y, z, V, h,
 * kind, nx, ny, nz, m, mx, my, mz, id). The two checks, each 1 when it holds: */
#define PST_MAX_NAME 64
/* The most fields the cloud readers take from one file (CSV columns after the required ones,
 * VTU PointData arrays that are fields): more is refused as bad input (docs/io.md). */
#define PST_MAX_FIELDS 4096
int pst_is_identifier(const char *name);
int pst_is_reserved_column(const char *name);

/* Role of a particle in a boundary-value problem. */
typedef enum { PST_INTERIOR = 0, PST_DIRICHLET = 1, PST_NEUMANN = 2 } pst_kind;

typedef struct pst_cloud pst_cloud;

/* Create a cloud of `n` particles in `dim` (2 or 3) dimensions. Positions and normals start at
 * 0, V at 1, h uniform at 1, every particle interior, mobility absent (meaning m = 1), ids
 * 0..n-1. Returns PST_EINVAL for a bad dim or more than 2^32 - 1 particles, PST_ENOMEM when
 * allocation fails (the reason in err). */
int pst_cloud_create(pst_cloud **out, int dim, size_t n, char *err);

/* The caller's own particle arrays, for pst_cloud_borrow: one array of n values per axis and
 * per quantity (structure of arrays). NULL means "not given": the cloud then owns that array
 * at its pst_cloud_create default. */
typedef struct {
    double *x[3];       /* positions x[d], d < dim: required                                  */
    double *V;          /* volumes: required                                                   */
    double *h;          /* per-particle smoothing length, or NULL for the uniform h below      */
    double h_uniform;   /* the smoothing length of every particle when h is NULL (> 0)         */
    uint8_t *kind;      /* pst_kind values, or NULL (every particle interior)                  */
    double *normal[3];  /* outward normals, all dim axes or none (NULL: zero normals)          */
    int mob_ncomp;      /* 0 (no mobility, m = 1), 1 (scalar) or dim (diagonal tensor)        */
    double *mob[3];     /* mob[k], k < mob_ncomp: required when mob_ncomp > 0                  */
} pst_cloud_arrays;

/* A cloud of `n` particles in `dim` (2 or 3) dimensions that reads the caller's arrays `a` in
 * place, without copying them (docs/embedding.md, "The host code's own data"). The arrays
 * must hold n values each and outlive the cloud; the caller may change their values in place
 * between steps (then pst_nlist_update or pst_nlist_set_csr, and pst_op_refresh, as for any
 * moved cloud). Only structure-of-arrays data is borrowed: interleaved (x y z x y z ...)
 * positions must be copied into per-axis arrays, since every kernel reads x[d][i]. Arrays not
 * given, the ids (0..n-1) and the fields (pst_cloud_add_field) belong to the cloud.
 * The library never writes into a borrowed array except through the calls that say they
 * write: pst_cloud_wrap folds the borrowed positions, pst_cloud_mobility_from_grid and the
 * pointer accessors (pst_cloud_coord, ...) return them for the caller to write. A borrowed
 * cloud is never reordered: pst_cloud_permute and pst_cloud_morton_sort refuse it
 * (PST_EINVAL), so every per-particle result is in the caller's order. Setters that replace an
 * array (pst_cloud_set_h_uniform, pst_cloud_set_mobility) let go of a borrowed one without
 * freeing it; pst_cloud_destroy frees only the cloud's own arrays. Nothing is validated beyond
 * the arguments: call pst_cloud_validate as for any cloud. PST_EINVAL (a bad dim, more than
 * 2^32 - 1 particles, a required array NULL, normals on some axes only, a bad mob_ncomp or
 * uniform h), PST_ENOMEM (the reason in err). */
int pst_cloud_borrow(pst_cloud **out, int dim, size_t n, const pst_cloud_arrays *a, char *err);

/* 1 when c reads some of the caller's arrays (pst_cloud_borrow), else 0. */
int pst_cloud_is_borrowed(const pst_cloud *c);

/* Free a cloud and everything it owns (never the arrays it borrows). NULL is allowed. */
void pst_cloud_destroy(pst_cloud *c);

/* Dimension (2 or 3) and number of particles. */
int pst_cloud_dim(const pst_cloud *c);
size_t pst_cloud_size(const pst_cloud *c);

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
const double *pst_cloud_normal_const(const pst_cloud *c, int axis);
const int64_t *pst_cloud_ids_const(const pst_cloud *c);

/* Smoothing length: one value for every particle, or one per particle. */
int pst_cloud_set_h_uniform(pst_cloud *c, double h, char *err);   /* frees any per-particle array
                                                          (a borrowed one is only let go)   */
double *pst_cloud_h_per_particle(pst_cloud *c);        /* allocates (filled with the uniform
                                                          value) on first call; NULL on OOM */
int pst_cloud_h_is_uniform(const pst_cloud *c);
double pst_cloud_h_uniform(const pst_cloud *c);        /* the uniform value (0 if per particle) */
const double *pst_cloud_h_array(const pst_cloud *c);   /* per-particle array or NULL        */
double pst_cloud_h_max(const pst_cloud *c);            /* largest h over the cloud          */

/* Mobility: absent (m = 1 everywhere), a scalar per particle (ncomp = 1), or a diagonal
 * tensor per particle (ncomp = dim). Setting a layout allocates it filled with 1 (replacing,
 * never freeing, a borrowed mobility). */
int pst_cloud_set_mobility(pst_cloud *c, int ncomp, char *err);   /* ncomp in {0, 1, dim}               */
int pst_cloud_mobility_ncomp(const pst_cloud *c);
double *pst_cloud_mobility(pst_cloud *c, int comp);    /* comp < ncomp; NULL otherwise       */

/* Named scalar fields. Adding a field allocates it filled with 0; names are unique and are
 * C identifiers (letters, digits, '_', not starting with a digit) that do not collide with
 * the reserved CSV column names. */
int pst_cloud_add_field(pst_cloud *c, const char *name, double **data, char *err);
size_t pst_cloud_nfields(const pst_cloud *c);
const char *pst_cloud_field_name(const pst_cloud *c, size_t k);
double *pst_cloud_field(pst_cloud *c, size_t k);
double *pst_cloud_field_by_name(pst_cloud *c, const char *name);   /* NULL when absent */

/* Axis-aligned bounding box of the positions (lo[d], hi[d] for d < dim). An empty cloud
 * gives lo = hi = 0. */
void pst_cloud_bbox(const pst_cloud *c, double lo[3], double hi[3]);

/* Check a cloud: finite positions whose extent along every axis is finite too, V > 0, h > 0,
 * known kinds, finite normals (non-zero on Neumann particles), mobility > 0, no two particles
 * at the same coordinates. On failure the cloud's error names the first
 * offending particle; returns PST_EINPUT. */
int pst_cloud_validate(pst_cloud *c, char *err);

/* Reorder every field (positions, V, h, kind, normals, mobility, ids, fields) by one
 * permutation: new particle i is old particle perm[i]. `perm` must be a permutation of 0..n-1
 * (checked: PST_EINVAL otherwise). A borrowed cloud (pst_cloud_borrow) is refused with
 * PST_EINVAL and left as it is. */
int pst_cloud_permute(pst_cloud *c, const uint32_t *perm, char *err);

/* Scatter a per-particle array given in the cloud's current order back to input order:
 * out[ids[i]] = in[i]. `in` and `out` must not alias. */
void pst_cloud_to_input_order(const pst_cloud *c, const double *in, double *out);

/* inv[r] = the particle whose id is r (the inverse of the ids, to write rows in input order).
 * PST_EINVAL (message in err) when the ids are not a permutation of 0..n-1. Free with free(). */
int pst_cloud_input_inverse(const pst_cloud *c, size_t **inv, char *err);

/* --- Periodic boxes (docs/periodic.md) ---------------------------------------------------- */

/* Make axis d (d < dim) periodic where periodic[d] != 0, with period hi[d] - lo[d]: positions
 * along a periodic axis must lie in [lo[d], hi[d]) (pst_cloud_validate checks it,
 * pst_cloud_wrap folds moved particles back), and every neighbour list, operator and solve on
 * the cloud then takes the minimum image of each pair offset along it. lo and hi are read
 * only on the periodic axes; all periodic[d] 0 makes the cloud non-periodic again. The lists
 * built on the cloud also need each period longer than twice their largest neighbour radius
 * (checked when they are built). PST_EINVAL (reason in err) for a box that is not finite with
 * lo < hi on a periodic axis. */
int pst_cloud_set_periodic(pst_cloud *c, const int periodic[3], const double lo[3],
                           const double hi[3], char *err);

/* Which axes are periodic (periodic[d] 0 or 1 for d < 3; 0 above dim) and their box (lo[d],
 * hi[d]; 0 on the other axes). Any pointer may be NULL. Returns the number of periodic axes. */
int pst_cloud_periodic(const pst_cloud *c, int periodic[3], double lo[3], double hi[3]);

/* Fold every position along a periodic axis into [lo, hi) (x - P floor((x - lo) / P), with a
 * result that rounds onto hi taken as lo, the same point of the torus): what a particle code
 * calls after moving its particles. Positions that are not finite are left for
 * pst_cloud_validate to report. On a borrowed cloud (pst_cloud_borrow) this writes the
 * caller's position arrays in place. */
void pst_cloud_wrap(pst_cloud *c);

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
    int periodic[3];         /* periodic axes: the lattice leaves out the hi end along them
                                (n_d points, lo + i s0 for i < n_d), jittered positions are
                                folded into [lo, hi), no boundary layer on their faces, and the
                                cloud gets the box (pst_cloud_set_periodic). Needs angle 0.      */
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

#ifdef __cplusplus
}
#endif

#endif /* PSTENCIL_PUBLIC_CLOUD_H */
