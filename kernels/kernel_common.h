/* The scaffolding every kernel file shares: the context its pair functions read, filled once per
 * call from the operator, the h and mobility lookups and the pair helpers (offset, the
 * min_pair_distance rule). A scheme's own context holds this one as its member `c` and adds
 * only what is its own (its per-particle data, its variant flags). Internal. */
#ifndef PSTENCIL_KERNEL_COMMON_H
#define PSTENCIL_KERNEL_COMMON_H

#include "operator.h"

/* The hot functions of a kernel file take the dimension (and the scheme's flags) as arguments;
 * their instantiations call them with constants, so the pair loops carry no branches on them. */
#define PST_KHOT static inline __attribute__((always_inline))

typedef struct {
    int dim, ncomp;      /* ncomp: the cloud's mobility components (0: none)             */
    pst_kernel kernel;
    const double *x[3], *V, *h, *mob[3];
    double h_uniform;    /* h when the cloud has no per-particle h                       */
    /* the boundary description of the operator (op->kind, op->normal): the cloud's, or the
     * override of opts.kinds / opts.normals */
    const uint8_t *kind;
    const double *normal[3];
    const int64_t *off; /* the neighbour list (op->nl) */
    const uint32_t *idx;
    double pair_eps;    /* opts.min_pair_distance: closer pairs (in units of h) are degenerate */
    const double *xyzu; /* op->xyzu: the packed rows of a lane apply (kernels/lanes.h), or NULL */
    pst_image im;       /* the cloud's periodic box: every offset is its minimum image       */
} pst_kctx;

static inline pst_kctx pst_kctx_of(const pst_op *op)
{
    const pst_cloud *c = op->cloud;
    pst_kctx k = {.dim = c->dim, .ncomp = c->mob_ncomp, .kernel = op->kernel, .V = c->V,
                  .h = c->h, .h_uniform = c->h_uniform, .kind = op->kind,
                  .off = pst_nlist_offsets(op->nl), .idx = pst_nlist_indices(op->nl),
                  .pair_eps = op->opts.min_pair_distance, .xyzu = op->xyzu,
                  .im = pst_cloud_image(c)};
    for (int a = 0; a < 3; ++a) {
        k.x[a] = c->x[a];
        k.mob[a] = c->mob[a];
        k.normal[a] = op->normal[a];
    }
    return k;
}

/* h of particle i. */
static inline double pst_h(const pst_kctx *k, size_t i) { return k->h ? k->h[i] : k->h_uniform; }

/* Mobility component comp of particle i: 1 without mobility, the scalar for one component. */
static inline double pst_mob(const pst_kctx *k, int comp, size_t i)
{
    return k->ncomp ? k->mob[k->ncomp == 1 ? 0 : comp][i] : 1.0;
}

/* x_j - x_i along axis a, for x_j and x_i given: the minimum image in a periodic box
 * (docs/periodic.md), the plain difference bit for bit on an axis that is not periodic. Every
 * pair offset of every kernel comes from here or from pst_pair_offset. The test of im.any is
 * the same for every pair: the compiler takes it out of the loops (-O3 unswitching), so a
 * cloud without a box runs the gathers it ran before. */
PST_KHOT double pst_offset(const pst_kctx *k, int a, double xj, double xi)
{
    return k->im.any ? pst_min_image(xj - xi, k->im.P[a], k->im.hP[a]) : xj - xi;
}

/* The offset x = r_j - r_i of a pair (D components); returns |x|^2. */
PST_KHOT double pst_pair_offset(const pst_kctx *k, int D, size_t i, size_t j, double x[3])
{
    double d2 = 0;
    for (int a = 0; a < D; ++a) {
        x[a] = pst_offset(k, a, k->x[a][j], k->x[a][i]);
        d2 += x[a] * x[a];
    }
    return d2;
}

/* The min_pair_distance rule: a pair at distance d is live when d > eps h (h the pair's
 * smoothing length; 1 for distances already scaled by h). */
PST_KHOT int pst_pair_live(const pst_kctx *k, double d, double h) { return d > k->pair_eps * h; }

#endif
