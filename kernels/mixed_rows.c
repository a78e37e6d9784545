/* The mixed schemes' rows (kernels/mixed.c): the matrix-free apply as two one-ring sweeps over
 * the neighbour list (the gradient G = M D u, then its divergence), the composed weights of a
 * stored row in the neighbours-of-neighbours pattern, and the LS gradient, each instantiated
 * per dimension and scheme and compiled per ISA level (isa.h). */
#include "isa.h"
#include "mixed.h"

#include <string.h>

/* The derivative weights phi^a_ij of row i (centre xi, smoothing length h) for its neighbours
 * idx[0..n) into phi[a][0..n): deriv_weights' numbers bit for bit. A fit row takes the chunk
 * in vector loops, mx_gather's offsets and weights, then the basis and Q p lane by lane in
 * deriv_weights' order; a no-fit row (rare) takes its pairs one by one. Per pair the gather, a
 * sqrt, the kernel's ~20 flops and the D m multiply-adds of Q p: compute-bound. */
PST_KHOT void phi_chunk(const mx_ctx *k, int D, int S, size_t i, const double xi[3], double h,
                        const uint32_t *idx, int n, double (*phi)[MX_CHUNK])
{
    if (k->d->mode[i] == MX_NOFIT) {
        for (int c = 0; c < n; ++c) {
            double one[3];
            deriv_weights(k, D, S, i, idx[c], one);
            for (int a = 0; a < D; ++a)
                phi[a][c] = one[a];
        }
        return;
    }
    const int m = basis_size(D, S);
    const double *Q = k->d->Q + (size_t)D * m * i;
    double r[3][MX_CHUNK], w[MX_CHUNK];
    mx_gather(k, D, xi, h, 0.0, idx, n, S == MX_ORDINARY ? k->d->Vn : NULL, r, w);
    /* no omp simd here: under it GCC 12 finds no vector type for the columns read into p and
     * leaves the loop scalar; without it the loop vectorises */
    for (int c = 0; c < n; ++c) {
        double p[10];
        basis_xyz(D, S, r[0][c], r[1][c], D == 3 ? r[2][c] : 0.0, p);
        for (int a = 0; a < D; ++a) {
            double s = 0;
            for (int q = 0; q < m; ++q)
                s += Q[a * m + q] * p[q];
            phi[a][c] = w[c] * s;
        }
    }
}

/* The centre and smoothing length of row i, for phi_chunk. */
PST_KHOT double row_centre(const mx_ctx *k, int D, size_t i, double xi[3])
{
    for (int a = 0; a < 3; ++a)
        xi[a] = a < D ? k->c.x[a][i] : 0.0;
    return pst_h(&k->c, i);
}

/* (D u)_i into g: the pairs in list order, each g[a] += phi^a du as deriv_weights' pair loop
 * summed them (the same bits). */
PST_KHOT void grad_row(const mx_ctx *k, int D, int S, size_t i, const double *u, double g[3])
{
    const int64_t e0 = k->c.off[i], e1 = k->c.off[i + 1];
    double xi[3], h = row_centre(k, D, i, xi), ui = u[i];
    for (int a = 0; a < D; ++a)
        g[a] = 0;
    for (int64_t c0 = e0; c0 < e1; c0 += MX_CHUNK) {
        const int n = (int)(e1 - c0 < MX_CHUNK ? e1 - c0 : MX_CHUNK);
        const uint32_t *idx = k->c.idx + c0;
        double phi[3][MX_CHUNK];
        phi_chunk(k, D, S, i, xi, h, idx, n, phi);
        for (int c = 0; c < n; ++c) {
            double du = u[idx[c]] - ui;
            for (int a = 0; a < D; ++a)
                g[a] += phi[a][c] * du;
        }
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

/* Sweep 2, row i of L from G (not Dirichlet): phi_chunk's weights, the pairs summed in list
 * order. */
PST_KHOT double divergence_row(const mx_ctx *k, int D, int S, size_t i, const double *u,
                               double *const G[3])
{
    const int64_t e0 = k->c.off[i], e1 = k->c.off[i + 1];
    double y, gi[3] = {0, 0, 0};
    for (int a = 0; a < D; ++a)
        gi[a] = G[a][i];
    if (flux_or_nofit_row(k, D, i, u, gi, &y))
        return y;
    double xi[3], h = row_centre(k, D, i, xi);
    for (int64_t c0 = e0; c0 < e1; c0 += MX_CHUNK) {
        const int n = (int)(e1 - c0 < MX_CHUNK ? e1 - c0 : MX_CHUNK);
        const uint32_t *idx = k->c.idx + c0;
        double phi[3][MX_CHUNK];
        phi_chunk(k, D, S, i, xi, h, idx, n, phi);
        for (int c = 0; c < n; ++c)
            for (int a = 0; a < D; ++a)
                y += phi[a][c] * (G[a][idx[c]] - gi[a]);
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
 * evaluations (each neighbour's row through phi_chunk) and binary searches per row. */
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
    double S_i[3] = {0, 0, 0}, xi[3], h = row_centre(k, D, i, xi);
    for (int64_t c0 = off[i]; c0 < off[i + 1]; c0 += MX_CHUNK) {
        const int n = (int)(off[i + 1] - c0 < MX_CHUNK ? off[i + 1] - c0 : MX_CHUNK);
        double phi[3][MX_CHUNK];
        phi_chunk(k, D, S, i, xi, h, idx + c0, n, phi);
        for (int c = 0; c < n; ++c) {
            size_t j = idx[c0 + c];
            double mphi[3], cj = 0, xj[3], hj = row_centre(k, D, j, xj);
            for (int a = 0; a < D; ++a) {
                S_i[a] += phi[a][c];
                mphi[a] = phi[a][c] * pst_mob(&k->c, a, j);
            }
            for (int64_t f0 = off[j]; f0 < off[j + 1]; f0 += MX_CHUNK) {
                const int nf = (int)(off[j + 1] - f0 < MX_CHUNK ? off[j + 1] - f0 : MX_CHUNK);
                double psi[3][MX_CHUNK];
                phi_chunk(k, D, S, j, xj, hj, idx + f0, nf, psi);
                for (int t = 0; t < nf; ++t) {
                    size_t l = idx[f0 + t];
                    double v = 0;
                    for (int a = 0; a < D; ++a)
                        v += mphi[a] * psi[a][t];
                    cj += v;
                    if (l != i)
                        w[pattern_pos(pidx, lo, hi, (uint32_t)l) - lo] += v;
                }
            }
            w[pattern_pos(pidx, lo, hi, (uint32_t)j) - lo] -= cj; /* the -u_j of (D u)_j */
        }
    }
    for (int a = 0; a < D; ++a)
        S_i[a] *= pst_mob(&k->c, a, i);
    for (int64_t c0 = off[i]; c0 < off[i + 1]; c0 += MX_CHUNK) { /* the -(D u)_i term */
        const int n = (int)(off[i + 1] - c0 < MX_CHUNK ? off[i + 1] - c0 : MX_CHUNK);
        double phi[3][MX_CHUNK];
        phi_chunk(k, D, S, i, xi, h, idx + c0, n, phi);
        for (int c = 0; c < n; ++c) {
            double v = 0;
            for (int a = 0; a < D; ++a)
                v += S_i[a] * phi[a][c];
            w[pattern_pos(pidx, lo, hi, (uint32_t)idx[c0 + c]) - lo] -= v;
        }
    }
}

/* ---- instantiation per (D, S) ------------------------------------------------------------ */

/* The rows per dimension and scheme, each compiled per ISA level (isa.h) and called from the
 * OpenMP regions below. */
typedef struct {
    double (*row)(const mx_ctx *, size_t, const double *, double *const[3]);
    double (*row_direct)(const mx_ctx *, size_t, const double *);
    void (*grad)(const mx_ctx *, size_t, const double *, double[3]);
    void (*emit)(const mx_ctx *, const int64_t *, const uint32_t *, size_t, double *);
} mx_fns;

#define MX_INST(D, S)                                                                          \
    PST_ISA_DISPATCH static double row_##D##_##S(const mx_ctx *k, size_t i, const double *u,   \
                                                 double *const G[3])                           \
    {                                                                                          \
        return divergence_row(k, D, S, i, u, G);                                               \
    }                                                                                          \
    PST_ISA_DISPATCH static double direct_##D##_##S(const mx_ctx *k, size_t i, const double *u) \
    {                                                                                          \
        return divergence_row_direct(k, D, S, i, u);                                           \
    }                                                                                          \
    PST_ISA_DISPATCH static void grad_##D##_##S(const mx_ctx *k, size_t i, const double *u,    \
                                                double g[3])                                   \
    {                                                                                          \
        grad_row(k, D, S, i, u, g);                                                            \
    }                                                                                          \
    PST_ISA_DISPATCH static void emit_##D##_##S(const mx_ctx *k, const int64_t *po,            \
                                                const uint32_t *pi, size_t i, double *w)       \
    {                                                                                          \
        emit_t(k, D, S, po, pi, i, w);                                                         \
    }
MX_INST(2, 0)
MX_INST(2, 1)
MX_INST(2, 2)
MX_INST(3, 0)
MX_INST(3, 1)
MX_INST(3, 2)
#define MX_FNS(D, S) {row_##D##_##S, direct_##D##_##S, grad_##D##_##S, emit_##D##_##S}
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
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; ++i) { /* Dirichlet rows too: their neighbours read G there */
        double g[3];
        f->grad(&k, i, u, g);
        for (int a = 0; a < k.c.dim; ++a)
            G[a][i] = pst_mob(&k.c, a, i) * g[a];
    }
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
