/* pstencil: past one process — a rank's part of the cloud, and the operator inside PETSc.
 * Part of the public API; include <pstencil.h>. docs/distributed.md tells the whole story. */
#ifndef PSTENCIL_PUBLIC_DIST_H
#define PSTENCIL_PUBLIC_DIST_H

#include "pstencil/solve.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------------------------------------------ */
/* A rank's part of a cloud                                                                   */
/* ------------------------------------------------------------------------------------------ */

/* Rank r of R owns the contiguous range [n r / R, n (r + 1) / R) of the cloud's order (Morton
 * sort the cloud first, pst_cloud_morton_sort, so that a range is a compact region) and sees
 * the ghosts: the other particles within `hops` links of an owned particle in the neighbour
 * list (choice 1 of pst_nlist_build with the same support), one ring for a scheme whose rows
 * read their particle and its neighbours, as many as pst_scheme_halo says for the others. The
 * part's local cloud holds owned and ghosts in the cloud's order, every per-particle array
 * copied (positions, V, h, kinds, normals, mobility, ids, the periodic box; not the fields);
 * its ghosts are Dirichlet particles, so an operator on it computes only the owned rows, and
 * those are the whole cloud's rows bit for bit (the same neighbours in the same order, and
 * each neighbour's own list whole where the scheme reads it). No PETSc or MPI is needed: a
 * part is plain data. */
typedef struct pst_part pst_part;

#define PST_PART_MAX_RANKS 65536
#define PST_PART_MAX_HOPS 3

/* The part of rank `rank` of `ranks` (1..PST_PART_MAX_RANKS) of cloud c for neighbour lists of
 * `support` (in units of h, as pst_nlist_build), with `hops` rings of ghosts
 * (1..PST_PART_MAX_HOPS; pst_scheme_halo of the scheme to be built on it). The owned particles
 * take their kinds and normals from `kind` and `normal` (whole-cloud arrays, as
 * pst_op_opts.kinds and .normals: a solve's boundary groups) or, NULL, the cloud's. The ghosts
 * are found from local data: the particles within hops * support * h_max of the owned bounding
 * box (through the faces of a periodic box), kept when they are within `hops` links of an
 * owned particle in their list. PST_EINVAL (bad ranks, rank, support or hops), PST_ENOMEM, or
 * a neighbour-list failure (reason in err). */
int pst_part_create(pst_part **out, const pst_cloud *c, const uint8_t *kind,
                    const double *const normal[3], int ranks, int rank, double support,
                    int hops, char *err);
void pst_part_destroy(pst_part *p);

/* The local cloud (owned and ghosts, in the cloud's order): build the neighbour list and the
 * operator of the rank on it. It belongs to the part. */
const pst_cloud *pst_part_cloud(const pst_part *p);

typedef struct {
    int ranks, rank;
    int hops;       /* the rings of ghosts                                               */
    size_t n;       /* particles of the whole cloud                                      */
    size_t lo, hi;  /* the owned range of the whole cloud's order                        */
    size_t own0;    /* local index of the first owned particle: owned are own0 .. own0 + hi - lo */
    size_t nlocal;  /* owned + ghosts                                                    */
    size_t nghost;
} pst_part_info;
void pst_part_layout(const pst_part *p, pst_part_info *info);

/* Local index k -> index in the whole cloud (nlocal values, ascending). */
const size_t *pst_part_global(const pst_part *p);

/* A whole-cloud array (n values) into the local order (nlocal values). */
void pst_part_take(const pst_part *p, const double *whole, double *local);

/* The owned values of every rank's local array (nlocal values each) into `whole` (n values,
 * the cloud's order) on every rank: MPI_Allgatherv over MPI_COMM_WORLD, which must have the
 * part's number of ranks; every rank calls it together. PST_EINVAL (MPI not running, another
 * number of ranks, more than 2^31 - 1 particles), PST_ENOMEM. */
int pst_part_gather(const pst_part *p, const double *local, double *whole, char *err);

/* ------------------------------------------------------------------------------------------ */
/* The operator inside PETSc                                                                  */
/* ------------------------------------------------------------------------------------------ */

/* 1 when the library was built with PETSc (an optional dependency: Debian's petsc-dev), else
 * 0; then the calls below return PST_EINVAL with the reason. */
int pst_petsc_available(void);

/* PETSc's version ("3.18.5"), or "" without PETSc. */
const char *pst_petsc_version(void);

/* Start PETSc for the calls below, after the program started MPI or letting PETSc start it;
 * argc / argv (NULL allowed) reach PETSc's options database as its command line would.
 * Idempotent. PST_EINVAL without PETSc or when PETSc fails to start. */
int pst_petsc_start(int *argc, char ***argv, char *err);

/* Finalise PETSc if pst_petsc_start started it (before the program's MPI_Finalize). */
void pst_petsc_stop(void);

/* The rank of this process and the number of ranks of MPI_COMM_WORLD (0 and 1 when MPI is not
 * running). */
void pst_mpi_rank(int *rank, int *ranks);

typedef struct {
    const char *options;  /* PETSc options of this solve, "-ksp_type bcgs -pc_type jacobi": they
                             override the defaults below and stay with this solve only; NULL
                             or "" for none                                                  */
    double rtol;          /* ||b - L u|| <= rtol ||b|| on the unpreconditioned residual       */
    int max_iter;
    int restart;          /* GMRES(restart)                                                   */
    pst_amg_source amg_source; /* the preconditioner's matrix, as pst_solve_opts.amg_source:
                             the Brookshaw proxy, the scheme's own stencil, or AUTO (own for
                             lsmps, else the proxy; the proxy where own has a row without a
                             positive diagonal)                                              */
    double amg_radius;    /* the proxy's radius in h, as pst_solve_opts.amg_radius (-1: auto) */
    int fix_mean;         /* 1: a problem without Dirichlet rows, solved as pst_solve_opts
                             fix_mean does: (L + c 1 V^T) u = b, u with zero V-weighted mean,
                             lambda = c V^T u in the result's mean_shift (docs/solving.md)     */
    int history;          /* 1: the relative residual per iteration in the result (the first
                             PST_PETSC_HISTORY)                                               */
    void (*monitor)(int iteration, double rel_residual, void *ctx); /* NULL: none              */
    void *monitor_ctx;
} pst_petsc_opts;

#define PST_PETSC_HISTORY 65536

/* rtol 1e-8, max_iter 1000, restart 30, amg_source AUTO, amg_radius -1, no fixed mean, no
 * history, no monitor, no options. */
void pst_petsc_defaults(pst_petsc_opts *o);

/* Solve L u = b with PETSc's KSP. The system is S L u = S b with S = -1 on interior rows and +1
 * on Neumann and Dirichlet rows (every diagonal positive, as BoomerAMG needs; the residual
 * norms are L's): S L is a matrix-free MatShell (MatMult through pst_op_apply, MatGetDiagonal
 * through pst_op_diagonal) with identity Dirichlet rows, and the preconditioner is built from
 * S times the low-order matrix of o->amg_source (the Brookshaw proxy or op's own stencil,
 * assembled) as an AIJ matrix. Defaults: GMRES(restart) with right
 * preconditioning and BoomerAMG (-pc_type hypre) where PETSc has hypre, else GAMG, whose
 * smoothers relax on that matrix (-pc_use_amat false); o->options change any of it, the
 * options of the objects a PC makes in its set-up included (-mg_levels_..., -sub_...). With p
 * NULL, op is the whole cloud's operator on one process and b, u hold its n values; with a
 * part, op is built on pst_part_cloud(p) (a part of at least pst_scheme_halo(scheme) hops),
 * every rank of MPI_COMM_WORLD calls this together (p's ranks must be its size), b and u hold
 * the local cloud's nlocal values and only the owned ones are read and written (the ghosts'
 * values of u are exchanged inside every MatMult). b as pst_solve describes it: the value on
 * Dirichlet rows. r (NULL allowed) as pst_solve fills it, rel_residual recomputed as
 * ||b - L u|| / ||b|| over all ranks. PST_OK, PST_ENUMERIC (not converged; PETSc's reason in
 * r->message and err), PST_EINVAL (bad arguments, a part of fewer hops than the scheme's
 * halo, no PETSc, PETSc not started, a PETSc error: its message in err), PST_EINPUT (a
 * non-finite owned value of b or u), PST_ENOMEM; with fix_mean, PST_EINVAL when some row is a
 * Dirichlet row. */
int pst_petsc_solve(const pst_op *op, const pst_part *p, const double *b, double *u,
                    const pst_petsc_opts *o, pst_solve_result *r, char *err);

#ifdef __cplusplus
}
#endif

#endif
