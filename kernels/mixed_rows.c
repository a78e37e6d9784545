/* The mixed schemes' rows (kernels/mixed.c): the matrix-free apply as two one-ring sweeps over
 * the neighbour list (the gradient G = M D u, then its divergence), the composed weights of a
 * stored row in the neighbours-of-neighbours pattern, and the LS gradient, each instantiated
 * per dimension and scheme. */
#include "mixed.h"

#include <string.h>

/* (D u)_i into g. */
PST_KHOT void grad_row(const mx_ctx *k, int D, int S, size_t i, const double *u, double g[3])
{
    const int64_t *off = k->c.off;
    const uint32_t *idx = k->c.idx;
    double ui = u[i];
    for (int a = 0; a < D; ++a)
        g[a] = 0;
    for (int64_t e = off[i]; e < off[i + 1]; ++e) {
        size_t j = idx[e];
        double phi[3], du = u[j] - ui;
        deriv_weights(k, D, S, i, j, phi);
        for (int a = 0; a < D; ++a)
            g[a] += phi[a] * du;
    }
}

/* Sweep 1: G[a][i] = M^a_i (D_a u)_i for every particle (Dirichlet ones too: interior rows
 * use their one-sided gradients). Compute-bound like sweep 2: one sqrt, the kernel and D*m
 * multiply-adds per pair. */
PST_KHOT void sweep_gradient(const mx_ctx *k, int D, int S, size_t n, const double *u,
                           double *const G[3])
{
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; ++i) {
        double g[3];
        grad_row(k, D, S, i, u, g);
        for (int a = 0; a < D; ++a)
            G[a][i] = pst_mob(&k->c, a, i) * g[a];
    }
}

/* The rows of sweep 2 that take no divergence: a Neumann row, the flux n . g of the particle's
 * g = M D u, and a no-fit particle's Brookshaw row. Returns 1 with the row's value in *y for
 * those, 0 otherwise. */
PST_KHOT int flux_or_nofit_row(const mx_ctx *k, int D, size_t i, const double *u,
                               const double g[3], double *y)
{
    const int64_t *off = k->c.off;
    const uint32_t *idx = k->c.idx;
    *y = 0;
    if (k->c.kind[i] == PST_NEUMANN) {
        for (int a = 0; a < D; ++a)
            *y += k->c.normal[a][i] * g[a];
        return 1;
    }
    if (k->d->mode[i] == MX_NOFIT) {
        for (int64_t e = off[i]; e < off[i + 1]; ++e)
            *y += brookshaw_weight(k, D, i, idx[e]) * (u[idx[e]] - u[i]);
        return 1;
    }
    return 0;
}

/* Sweep 2, row i of L from G (not Dirichlet). */
PST_KHOT double divergence_row(const mx_ctx *k, int D, int S, size_t i, const double *u,
                             double *const G[3])
{
    const int64_t *off = k->c.off;
    const uint32_t *idx = k->c.idx;
    double y, gi[3] = {0, 0, 0};
    for (int a = 0; a < D; ++a)
        gi[a] = G[a][i];
    if (flux_or_nofit_row(k, D, i, u, gi, &y))
        return y;
    for (int64_t e = off[i]; e < off[i + 1]; ++e) {
        size_t j = idx[e];
        double phi[3];
        deriv_weights(k, D, S, i, j, phi);
        for (int a = 0; a < D; ++a)
            y += phi[a] * (G[a][j] - G[a][i]);
    }
    return y;
}

/* Row i without the sweep-1 buffer (used only when it cannot be allocated): every neighbour's
 * gradient is recomputed, |N|^2 pair evaluations per row. */
PST_KHOT double divergence_row_direct(const mx_ctx *k, int D, int S, size_t i, const double *u)
{
    const int64_t *off = k->c.off;
    const uint32_t *idx = k->c.idx;
    double gi[3], y = 0;
    grad_row(k, D, S, i, u, gi);
    for (int a = 0; a < D; ++a)
        gi[a] *= pst_mob(&k->c, a, i);
    if (flux_or_nofit_row(k, D, i, u, gi, &y))
        return y;
    for (int64_t e = off[i]; e < off[i + 1]; ++e) {
        size_t j = idx[e];
        double phi[3], gj[3];
        deriv_weights(k, D, S, i, j, phi);
        grad_row(k, D, S, j, u, gj);
        for (int a = 0; a < D; ++a)
            y += phi[a] * (pst_mob(&k->c, a, j) * gj[a] - gi[a]);
    }
    return y;
}

/* Position of column j in pattern row [lo, hi) (sorted; j is always present). */
static inline int64_t pattern_pos(const uint32_t *pidx, int64_t lo, int64_t hi, uint32_t j)
{
    while (hi - lo > 1) {
        int64_t mid = lo + (hi - lo) / 2;
        if (pidx[mid] <= j)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

/* The weights of row i in the pattern's order: the composition of the two sweeps with the
 * diagonal dropped (rows sum to zero, so it is minus the sum of the others). |N|^2 pair
 * evaluations and binary searches per row. */
PST_KHOT void emit_t(const mx_ctx *k, int D, int S, const int64_t *poff, const uint32_t *pidx,
                   size_t i, double *w)
{
    const int64_t *off = k->c.off;
    const uint32_t *idx = k->c.idx;
    int64_t lo = poff[i], hi = poff[i + 1];
    memset(w, 0, (size_t)(hi - lo) * sizeof *w);
    if (k->c.kind[i] == PST_NEUMANN || k->d->mode[i] == MX_NOFIT) {
        for (int64_t e = off[i]; e < off[i + 1]; ++e) {
            size_t j = idx[e];
            double v = 0, phi[3];
            if (k->c.kind[i] == PST_NEUMANN) {
                deriv_weights(k, D, S, i, j, phi);
                for (int a = 0; a < D; ++a)
                    v += k->c.normal[a][i] * pst_mob(&k->c, a, i) * phi[a];
            } else {
                v = brookshaw_weight(k, D, i, j);
            }
            w[pattern_pos(pidx, lo, hi, (uint32_t)j) - lo] += v;
        }
        return;
    }
    double S_i[3] = {0, 0, 0};
    for (int64_t e = off[i]; e < off[i + 1]; ++e) {
        size_t j = idx[e];
        double phi[3], mphi[3], cj = 0;
        deriv_weights(k, D, S, i, j, phi);
        for (int a = 0; a < D; ++a) {
            S_i[a] += phi[a];
            mphi[a] = phi[a] * pst_mob(&k->c, a, j);
        }
        for (int64_t f = off[j]; f < off[j + 1]; ++f) {
            size_t l = idx[f];
            double psi[3], c = 0;
            deriv_weights(k, D, S, j, l, psi);
            for (int a = 0; a < D; ++a)
                c += mphi[a] * psi[a];
            cj += c;
            if (l != i)
                w[pattern_pos(pidx, lo, hi, (uint32_t)l) - lo] += c;
        }
        w[pattern_pos(pidx, lo, hi, (uint32_t)j) - lo] -= cj; /* the -u_j of (D u)_j */
    }
    for (int a = 0; a < D; ++a)
        S_i[a] *= pst_mob(&k->c, a, i);
    for (int64_t e = off[i]; e < off[i + 1]; ++e) { /* the -(D u)_i term */
        size_t j = idx[e];
        double phi[3], c = 0;
        deriv_weights(k, D, S, i, j, phi);
        for (int a = 0; a < D; ++a)
            c += S_i[a] * phi[a];
        w[pattern_pos(pidx, lo, hi, (uint32_t)j) - lo] -= c;
    }
}

/* ---- instantiation per (D, S) ------------------------------------------------------------ */

typedef struct {
    void (*sweep)(const mx_ctx *, size_t, const double *, double *const[3]);
    double (*row)(const mx_ctx *, size_t, const double *, double *const[3]);
    double (*row_direct)(const mx_ctx *, size_t, const double *);
    void (*grad)(const mx_ctx *, size_t, const double *, double[3]);
    void (*emit)(const mx_ctx *, const int64_t *, const uint32_t *, size_t, double *);
} mx_fns;

#define MX_INST(D, S)                                                                          \
    static void sweep_##D##_##S(const mx_ctx *k, size_t n, const double *u, double *const G[3]) \
    {                                                                                          \
        sweep_gradient(k, D, S, n, u, G);                                                      \
    }                                                                                          \
    static double row_##D##_##S(const mx_ctx *k, size_t i, const double *u, double *const G[3]) \
    {                                                                                          \
        return divergence_row(k, D, S, i, u, G);                                               \
    }                                                                                          \
    static double direct_##D##_##S(const mx_ctx *k, size_t i, const double *u)                 \
    {                                                                                          \
        return divergence_row_direct(k, D, S, i, u);                                           \
    }                                                                                          \
    static void grad_##D##_##S(const mx_ctx *k, size_t i, const double *u, double g[3])        \
    {                                                                                          \
        grad_row(k, D, S, i, u, g);                                                            \
    }                                                                                          \
    static void emit_##D##_##S(const mx_ctx *k, const int64_t *po, const uint32_t *pi,         \
                               size_t i, double *w)                                            \
    {                                                                                          \
        emit_t(k, D, S, po, pi, i, w);                                                         \
    }
MX_INST(2, 0)
MX_INST(2, 1)
MX_INST(2, 2)
MX_INST(3, 0)
MX_INST(3, 1)
MX_INST(3, 2)
#define MX_FNS(D, S)                                                                           \
    {sweep_##D##_##S, row_##D##_##S, direct_##D##_##S, grad_##D##_##S, emit_##D##_##S}
static const mx_fns fns_table[2][3] = {{MX_FNS(2, 0), MX_FNS(2, 1), MX_FNS(2, 2)},
                                       {MX_FNS(3, 0), MX_FNS(3, 1), MX_FNS(3, 2)}};

static const mx_fns *fns_for(const mx_ctx *k) { return &fns_table[k->c.dim - 2][k->d->which]; }

/* Matrix-free apply: sweep 1 (G = M D u) into a buffer of D*n doubles, then sweep 2 (the
 * divergence). The buffer is this apply's one allocation: sweep 2 reads G of every neighbour,
 * so all of G must exist before any row, and it depends on u while the operator stays
 * read-only. If it cannot be allocated, each row recomputes its neighbours' gradients (|N|
 * times the work, the same result to rounding), so an apply never fails. */
void pst_mx_apply(const pst_op *op, const double *u, double *y)
{
    mx_ctx k = make_ctx(op);
    const mx_fns *f = fns_for(&k);
    size_t n = op->n;
    double *buf = pst_alloc((size_t)k.c.dim * (n ? n : 1) * sizeof *buf);
    if (!buf) {
#pragma omp parallel for schedule(dynamic, 256)
        for (size_t i = 0; i < n; ++i)
            if (k.c.kind[i] != PST_DIRICHLET)
                y[i] = f->row_direct(&k, i, u);
        return;
    }
    double *const G[3] = {buf, buf + n, k.c.dim == 3 ? buf + 2 * n : buf};
    f->sweep(&k, n, u, G);
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; ++i)
        if (k.c.kind[i] != PST_DIRICHLET)
            y[i] = f->row(&k, i, u, G);
    pst_free(buf);
}

void pst_mx_emit_row(const pst_op *op, size_t i, double *w)
{
    mx_ctx k = make_ctx(op);
    fns_for(&k)->emit(&k, op->poff, op->pidx, i, w);
}

/* The LS gradient (D u)_I (the fallback gradient on rows without a fit). */
void pst_mx_gradient(const pst_op *op, const double *u, double *const grad[3])
{
    mx_ctx k = make_ctx(op);
    const mx_fns *f = fns_for(&k);
#pragma omp parallel for schedule(static)
    for (size_t b = 0; b < pst_chunks(op->n, PST_CHUNK); ++b)
        PST_CHUNK_ROWS(op->tally, b, op->n, PST_CHUNK, i) {
            double g[3];
            f->grad(&k, i, u, g);
            for (int a = 0; a < k.c.dim; ++a)
                grad[a][i] = g[a];
        }
}
