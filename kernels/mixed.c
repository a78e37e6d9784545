/* The least-squares mixed schemes of seed 003 (docs/schemes/mixed.md): the mixed ordinary method
 * (Model 3, `mixed0`), the mixed first-order least squares (Model 4, `mixed1`) and the mixed
 * second-order least squares (Model 5, `mixed2`).
 *
 * The paper solves the first-order system for F = (f, f_x, f_y[, f_z]) by collocation; with the
 * gradient rows kept at every node it is the nested operator on u alone (docs/schemes/mixed.md,
 * "Equations"):
 *     (L u)_I = sum_a D_a (M^a D_a u)_I,   (D_a u)_I = sum_{j in N(I)} phi^a_Ij (u_j - u_I)
 * with M^a the mobility (1, a scalar m, or a diagonal tensor component). D is the derivative row
 * of a weighted least-squares Taylor fit about I that includes I itself (eqs. 15-24, rebuilt):
 *     M_I = sum_{j in N(I) + I} w_j p_j p_j^T,   phi^a_Ij = w_j (M_I^-1 p_j)_{1+a}
 *     mixed0: p = (1, x),               w_j = W(d_Ij, h_I) V~_j, V~_j = 1 / sum_k W_jk (eq. 4)
 *     mixed1: p = (1, x),               w_j = W(d_Ij, h_I)
 *     mixed2: p = (1, x, x^2/2, x y ...) w_j = W(d_Ij, h_I)
 * The derivative rows sum to zero (constants are reproduced), so the difference form is exact.
 * Per particle only Q_I = rows 1..D of M_I^-1 (basis unscaled, see inversion()) is stored; the
 * pair weight phi is recomputed from positions and Q by one inline function that the matrix-free
 * apply, emit_row and the gradient share. The matrix-free apply is two one-ring sweeps over the
 * neighbour list. The stored rows' stencil is the neighbours of neighbours (~1500 columns per
 * row in 3D): that pattern is built only when operator.c asks for it (the wide_pattern hook:
 * stored weights, assembly, diagonal, audit), never by the precompute, and emit_row writes the
 * composed weights in it.
 *
 * Fallback chain (docs/schemes/mixed.md): quadratic fit (mixed2) -> linear fit -> "no fit": the
 * particle's gradient is the uncorrected kernel gradient sum_J V_J (u_J - u_I) grad W_IJ (cloud
 * volumes) and its interior row is the Brookshaw row V_J sum_a (M^a_I + M^a_J) a_IJ x_a^2 / d^2.
 * Neumann rows are n . M_I . (D u)_I with the particle's gradient. Never NaN. */
#include "check.h"
#include "isa.h"
#include "kernel_common.h"
#include "small_matrix.h"
#include "sph_kernels.h"
#include "wls_sums.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

enum { MX_ORDINARY, MX_LINEAR, MX_QUADRATIC };

/* Per-particle fit actually used: the scheme's, the linear one (mixed2 fallback), none. */
enum { MX_FIT = 0, MX_LINEAR_FIT = 1, MX_NOFIT = 2 };


/* Particles per block of the moment/inversion passes: bounds the moment scratch (55 doubles
 * per particle in 3D quadratic, 3.6 MB per block) while keeping the two passes separate. */
#define MX_BLOCK 8192

typedef struct {
    int which; /* MX_* */
    int m;     /* basis size: D+1 (linear) or (D+1)(D+2)/2 (quadratic) */
    double *Q; /* D*m per particle: d/dx_a weights in the unscaled basis, 1/h folded in  */
    uint8_t *mode;   /* MX_FIT / MX_LINEAR_FIT / MX_NOFIT                               */
    double *Vn;      /* mixed0: number-density volumes 1/sum W (eq. 4), else NULL        */
} mx_data;

/* Everything the pair functions read, gathered once per call: c.off / c.idx are the
 * neighbour list, not the neighbours-of-neighbours pattern. */
typedef struct {
    pst_kctx c;
    const mx_data *d;
} mx_ctx;

static mx_ctx make_ctx(const pst_op *op) { return (mx_ctx){.c = pst_kctx_of(op), .d = op->data}; }

/* The hot functions (PST_KHOT) take the dimension D and the scheme S as arguments; the applies
 * call them with constants (one instantiation per combination), so pair loops carry no branch
 * on them. */
static inline int basis_size(int D, int S) { return S == MX_QUADRATIC ? (D + 1) * (D + 2) / 2 : D + 1; }

/* Taylor basis at offset x: 1, x_a, then (quadratic) x_a^2/2 and the cross products in the
 * order of pst_op_hessian (2D: xx, yy, xy; 3D: xx, yy, zz, xy, xz, yz). */
PST_KHOT void basis(int D, int S, const double x[3], double *p)
{
    p[0] = 1.0;
    for (int a = 0; a < D; ++a)
        p[1 + a] = x[a];
    if (S != MX_QUADRATIC)
        return;
    for (int a = 0; a < D; ++a)
        p[1 + D + a] = 0.5 * x[a] * x[a];
    p[1 + 2 * D] = x[0] * x[1];
    if (D == 3) {
        p[8] = x[0] * x[2];
        p[9] = x[1] * x[2];
    }
}

/* Offset x = r_j - r_i, its length, and whether the pair is non-degenerate. */
PST_KHOT int pair_offset(const mx_ctx *k, int D, size_t i, size_t j, double x[3], double *d)
{
    *d = sqrt(pst_pair_offset(&k->c, D, i, j, x));
    return pst_pair_live(&k->c, *d, pst_h(&k->c, i));
}

/* The LS fit weight w_j of pair (i, j) (the head comment), 0 when degenerate. */
PST_KHOT double fit_weight(const mx_ctx *k, int D, int S, size_t i, size_t j, double x[3])
{
    double d;
    if (!pair_offset(k, D, i, j, x, &d))
        return 0.0;
    double W = pst_sph_w(k->c.kernel, D, d, pst_h(&k->c, i));
    return S == MX_ORDINARY ? W * k->d->Vn[j] : W;
}

/* a_ij = -dW/dr / d >= 0 with h_I: the uncorrected kernel gradient is a x. */
PST_KHOT double radial_factor(const mx_ctx *k, int D, size_t i, size_t j, double x[3], double *d2)
{
    double d;
    int ok = pair_offset(k, D, i, j, x, &d);
    *d2 = d * d;
    return ok ? -pst_sph_dw(k->c.kernel, D, d, pst_h(&k->c, i)) / d : 0.0;
}

/* phi^a_ij, the derivative weights of pair (i, j) with i's fit (or its fallback gradient).
 * Shared by the applies, emit_row and the gradient, so all of them use the same numbers. */
PST_KHOT void deriv_weights(const mx_ctx *k, int D, int S, size_t i, size_t j, double phi[3])
{
    double x[3];
    if (k->d->mode[i] == MX_NOFIT) {
        double d2, a = radial_factor(k, D, i, j, x, &d2) * k->c.V[j];
        for (int c = 0; c < D; ++c)
            phi[c] = a * x[c];
        return;
    }
    double w = fit_weight(k, D, S, i, j, x), p[10];
    int m = basis_size(D, S);
    basis(D, S, x, p);
    const double *Q = k->d->Q + (size_t)D * m * i;
    for (int a = 0; a < D; ++a) {
        double s = 0;
        for (int c = 0; c < m; ++c)
            s += Q[a * m + c] * p[c];
        phi[a] = w * s;
    }
}

/* The Brookshaw weight of the fallback row: V_J a sum_a (M^a_I + M^a_J) x_a^2 / d^2. */
PST_KHOT double brookshaw_weight(const mx_ctx *k, int D, size_t i, size_t j)
{
    double x[3], d2, a = radial_factor(k, D, i, j, x, &d2);
    if (a == 0.0)
        return 0.0;
    double s = 0;
    for (int c = 0; c < D; ++c)
        s += (pst_mob(&k->c, c, i) + pst_mob(&k->c, c, j)) * x[c] * x[c];
    return k->c.V[j] * a * s / d2;
}

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
#define MX_FNS(D, S) {sweep_##D##_##S, row_##D##_##S, direct_##D##_##S, grad_##D##_##S, emit_##D##_##S}
static const mx_fns fns_table[2][3] = {{MX_FNS(2, 0), MX_FNS(2, 1), MX_FNS(2, 2)},
                                       {MX_FNS(3, 0), MX_FNS(3, 1), MX_FNS(3, 2)}};

static const mx_fns *fns_for(const mx_ctx *k) { return &fns_table[k->c.dim - 2][k->d->which]; }

/* ---- precompute ------------------------------------------------------------------------ */

static void mx_free(void *p)
{
    mx_data *d = p;
    if (!d)
        return;
    pst_free(d->Q);
    pst_free(d->mode);
    pst_free(d->Vn);
    free(d);
}

/* Choice 6 (docs/choices.md) by analogy: the fit of m unknowns includes I, so it needs m - 1
 * neighbours: D for the linear fits (the cspm-like count), 5 / 9 for the quadratic one (as
 * lsmps). */
static int mx_min_linear(int dim) { return dim; }
static int mx_min_quadratic(int dim) { return dim == 2 ? 5 : 9; }

static inline uint8_t worse(uint8_t a, uint8_t b) { return a > b ? a : b; }

/* ---- the moment and volume passes: the neighbours a chunk at a time ---------------------- */

/* A row's neighbours are gathered, a chunk at a time, into stack arrays (structure of arrays),
 * then summed in wls_sums.h's vectorised reduction loops, as qsfdi and the WLS schemes do; the
 * order of a sum is fixed by the code, the same for every row and thread count. A 3D row (~190
 * neighbours) is one chunk. */
#define MX_CHUNK 256

/* W(d_c, h) of a chunk, 0 for degenerate pairs (d <= eps h): pst_sph_w per element (its
 * uncut value, then its cut) with the kernel K a constant, so these are fit_weight's numbers
 * bit for bit. */
PST_KHOT void chunk_w(pst_kernel K, int D, int n, const double *d, double h, double eh,
                      double *w)
{
    const double cut = pst_sph_support[K] * h;
#pragma omp simd
    for (int c = 0; c < n; ++c)
        w[c] = pst_sph_uncut(K, D, d[c], h, 0);
#pragma omp simd
    for (int c = 0; c < n; ++c)
        w[c] = ((d[c] < cut) & (d[c] > eh)) ? w[c] : 0.0;
}

/* Offsets x_j - x_I of the neighbours idx[0..n) of the point xi into r (scaled by ih unless ih is
 * 0) and their weights into w: pair_offset's distance and live rule and pst_sph_w with h, so
 * w is fit_weight's value bit for bit (times vn[j] when vn is given: mixed0). Separate loops,
 * so that the sqrt runs in vector instructions (no math errno) and the kernel loop has no
 * gather in it. Bound by the gather of x_j and the kernel's ~20 flops. */
PST_KHOT void mx_gather(const mx_ctx *k, int D, const double xi[3], double h, double ih,
                        const uint32_t *idx, int n, const double *vn, double (*r)[MX_CHUNK],
                        double *w)
{
    double d[MX_CHUNK];
    for (int c = 0; c < n; ++c)
        for (int a = 0; a < D; ++a)
            r[a][c] = pst_offset(&k->c, a, k->c.x[a][idx[c]], xi[a]);
    for (int c = 0; c < n; ++c) /* pst_pair_offset's sum, in its order */
        d[c] = sqrt(r[0][c] * r[0][c] + r[1][c] * r[1][c] + (D == 3 ? r[2][c] * r[2][c] : 0.0));
    const double eh = k->c.pair_eps * h;
    switch (k->c.kernel) { /* one vectorised instantiation per kernel */
    case PST_KERNEL_CUBIC: chunk_w(PST_KERNEL_CUBIC, D, n, d, h, eh, w); break;
    case PST_KERNEL_QUINTIC: chunk_w(PST_KERNEL_QUINTIC, D, n, d, h, eh, w); break;
    case PST_KERNEL_WENDLAND_C2: chunk_w(PST_KERNEL_WENDLAND_C2, D, n, d, h, eh, w); break;
    default: chunk_w(PST_KERNEL_WENDLAND_C4, D, n, d, h, eh, w); break;
    }
    if (vn)
        for (int c = 0; c < n; ++c)
            w[c] *= vn[idx[c]];
    if (ih != 0.0)
        for (int a = 0; a < D; ++a)
            for (int c = 0; c < n; ++c)
                r[a][c] *= ih;
}

/* V~_i = 1 / (W(0) + sum_j W_ij), h_i (eq. 4, as choice 3): mx_gather's weights summed in
 * wls_msum0's loop. Bound like the moments by the gather and the kernel. Measured (3D, 1
 * thread, AVX-512 clone): 1.8 ns per neighbour (was 7.3 as a scalar pair loop). */
PST_ISA_DISPATCH static double volume_row(const mx_ctx *k, size_t i)
{
    int D = k->c.dim;
    double xi[3] = {0, 0, 0}, h = pst_h(&k->c, i), s = 0;
    for (int a = 0; a < D; ++a)
        xi[a] = k->c.x[a][i];
    for (int64_t c0 = k->c.off[i]; c0 < k->c.off[i + 1]; c0 += MX_CHUNK) {
        int n = (int)(k->c.off[i + 1] - c0 < MX_CHUNK ? k->c.off[i + 1] - c0 : MX_CHUNK);
        double r[3][MX_CHUNK], w[MX_CHUNK];
        if (D == 2)
            mx_gather(k, 2, xi, h, 0.0, k->c.idx + c0, n, NULL, r, w);
        else
            mx_gather(k, 3, xi, h, 0.0, k->c.idx + c0, n, NULL, r, w);
        wls_msum0(n, w, &s);
    }
    s += pst_sph_w(k->c.kernel, D, 0.0, h);
    return s > 0 ? 1.0 / s : 0.0;
}

/* GEOMETRY (mixed0 only): the volumes V~ of every particle. */
static void volumes(const mx_ctx *k, size_t n, double *Vn)
{
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; ++i)
        Vn[i] = volume_row(k, i);
}

/* The monomial (index into the sums of degree 0..4 in graded lexicographic order, wls_sums.h)
 * of each entry of the packed lower triangle of p p^T, p the quadratic basis; the linear
 * basis's triangle is its leading (D+1)(D+2)/2 entries. Generated by a script. */
static const unsigned char mx_tri2[21] = {0, 1, 3, 2, 4, 5, 3, 6, 7, 10, 5,
                                          8, 9, 12, 14, 4, 7, 8, 11, 13, 12};
static const unsigned char mx_tri3[55] = {
    0, 1, 4, 2, 5, 7, 3, 6, 8, 9, 4, 10, 11, 12, 20, 7, 13, 16, 17, 23, 30, 9, 15, 18, 19, 25, 32, 34,
    5, 11, 13, 14, 21, 26, 28, 23, 6, 12, 14, 15, 22, 27, 29, 24, 25, 8, 14, 17, 18, 24, 31, 33, 27,
    28, 32};

/* MOMENTS of particle i: the packed lower triangle of M_I in the basis scaled by h_I (x/h), so
 * that its condition number does not depend on the units, from the distinct weighted monomial
 * sums (degree 0..2: 6 / 10; 0..4 for the quadratic basis: 15 / 35), the halves of x^2/2
 * applied after (exact). Per neighbour: the gather, one sqrt and ~20 flops of kernel
 * (mx_gather), then 2 flops per sum plus the shared products in wls_msum*'s loops:
 * compute-bound. Measured (3D, 169 neighbours, 1 thread, AVX-512 clone): 2.6 ns per neighbour
 * for the linear fits, 3.9 for mixed2 (was 21 / 33 as a scalar pair loop). */
PST_KHOT void moments_t(const mx_ctx *k, int D, int S, size_t i, double *tri)
{
    const int m = basis_size(D, S), o2 = 1 + D, o3 = o2 + D * (D + 1) / 2;
    const int o4 = o3 + (D == 2 ? 4 : 10);
    const double *vn = S == MX_ORDINARY ? k->d->Vn : NULL;
    double acc[35] = {0}, xi[3] = {0, 0, 0}, h = pst_h(&k->c, i), ih = 1.0 / h;
    for (int a = 0; a < D; ++a)
        xi[a] = k->c.x[a][i];
    for (int64_t c0 = k->c.off[i]; c0 < k->c.off[i + 1]; c0 += MX_CHUNK) {
        int n = (int)(k->c.off[i + 1] - c0 < MX_CHUNK ? k->c.off[i + 1] - c0 : MX_CHUNK);
        double r[3][MX_CHUNK], w[MX_CHUNK];
        mx_gather(k, D, xi, h, ih, k->c.idx + c0, n, vn, r, w);
        wls_msum0(n, w, acc);
        wls_msum1(D, n, r[0], r[1], r[2], w, acc + 1);
        wls_msum2(D, n, r[0], r[1], r[2], w, acc + o2);
        if (S == MX_QUADRATIC) {
            wls_msum3(D, n, r[0], r[1], r[2], w, acc + o3);
            wls_msum4(D, n, r[0], r[1], r[2], w, acc + o4);
        }
    }
    double w0 = pst_sph_w(k->c.kernel, D, 0.0, h);
    acc[0] += S == MX_ORDINARY ? w0 * k->d->Vn[i] : w0; /* the self term, p = e_0 */
    const unsigned char *mono = D == 2 ? mx_tri2 : mx_tri3;
    for (int r = 0, t = 0; r < m; ++r)
        for (int c = 0; c <= r; ++c, ++t) {
            double s = (r > D && r <= 2 * D ? 0.5 : 1.0) * (c > D && c <= 2 * D ? 0.5 : 1.0);
            tri[t] = s * acc[mono[t]];
        }
}

/* moments_t in the widest vector ISA (isa.h), for the precompute's region and mx_hessian. */
PST_ISA_DISPATCH static void moments(const mx_ctx *k, int S, size_t i, double *tri)
{
    if (k->c.dim == 2) {
        if (S == MX_ORDINARY)
            moments_t(k, 2, MX_ORDINARY, i, tri);
        else if (S == MX_LINEAR)
            moments_t(k, 2, MX_LINEAR, i, tri);
        else
            moments_t(k, 2, MX_QUADRATIC, i, tri);
    } else {
        if (S == MX_ORDINARY)
            moments_t(k, 3, MX_ORDINARY, i, tri);
        else if (S == MX_LINEAR)
            moments_t(k, 3, MX_LINEAR, i, tri);
        else
            moments_t(k, 3, MX_QUADRATIC, i, tri);
    }
}

/* The inverse of a symmetric m x m matrix from its LDL^T factor f (pst_ldlt_factor), as
 * L^-T D^-1 L^-1: the rows of X = L^-1 (row r is e_r - sum_k<r L_rk X_k), then row r of the
 * inverse as sum_k>=r X_kr / D_k X_k. Whole-row updates of constant length (the zeros above
 * the diagonal of X included), which vectorise, in place of m solves against the unit
 * vectors; no reduction is reordered, so every ISA clone gives the same numbers. */
PST_KHOT void ldlt_inverse(int m, const double *f, double *inv)
{
    double X[100];
    for (int r = 0; r < m; ++r) {
        double x[10];
        for (int c = 0; c < m; ++c)
            x[c] = c == r ? 1.0 : 0.0;
        for (int k = 0; k < r; ++k) {
            const double l = f[r * m + k], *xk = X + k * m;
#pragma omp simd
            for (int c = 0; c < m; ++c)
                x[c] -= l * xk[c];
        }
        for (int c = 0; c < m; ++c)
            X[r * m + c] = x[c];
    }
    for (int r = 0; r < m; ++r) {
        double v[10] = {0};
        for (int k = r; k < m; ++k) {
            const double xr = X[k * m + r] / f[k * m + k], *xk = X + k * m;
#pragma omp simd
            for (int c = 0; c < m; ++c)
                v[c] += xr * xk[c];
        }
        for (int c = 0; c < m; ++c)
            inv[r * m + c] = v[c];
    }
}

/* Invert the leading m x m block of the scaled moments (packed triangle): LDL^T, the full
 * inverse and its 1-norm condition number ||A||_1 ||A^-1||_1. Fills Q (row length qm) with
 * rows 1..D of the inverse in the unscaled basis: Q[a][c] = inv[1+a][c] / h^(1 + deg c).
 * Returns the status of the inversion. m and qm are constants in every instantiation. Bound by
 * the factor's chain of dependent steps (pst_ldlt_factor, ~45% of it) and the first write of
 * Q; measured 10x10 (3D mixed2, 1 thread): 0.42 us per row (was 1.1 with m solves). */
PST_KHOT uint8_t invert(const pst_op *op, int D, const double *tri, int m, double h, double *Q,
                        int qm)
{
    double a[100], f[100], inv[100];
    for (int r = 0, t = 0; r < m; ++r)
        for (int c = 0; c <= r; ++c, ++t)
            a[r * m + c] = a[c * m + r] = f[r * m + c] = tri[t];
    if (!(pst_ldlt_factor(m, f) > 0))
        return PST_ROW_RANK_DEFICIENT;
    ldlt_inverse(m, f, inv);
    double cond = pst_mat_norm1(m, a) * pst_mat_norm1(m, inv);
    if (!(cond * op->opts.rank_tol < 1.0)) /* also catches NaN and inf */
        return PST_ROW_RANK_DEFICIENT;
    double ih = 1.0 / h;
    for (int r = 0; r < D; ++r)
        for (int c = 0; c < qm; ++c) {
            int deg = c == 0 ? 0 : c <= D ? 1 : 2;
            double s = ih;
            for (int e = 0; e < deg; ++e)
                s *= ih;
            Q[r * qm + c] = c < m ? inv[(1 + r) * m + c] * s : 0.0;
        }
    return cond > op->opts.cond_max ? PST_ROW_ILL_CONDITIONED : PST_ROW_OK;
}

/* INVERSION of particle i: the scheme's fit, else the linear fit (mixed2), else no fit. */
PST_KHOT uint8_t inversion_t(const pst_op *op, const mx_ctx *k, int D, int S, size_t i,
                             const double *tri)
{
    mx_data *d = op->data;
    const int m = basis_size(D, S);
    double *Q = d->Q + (size_t)D * m * i;
    int64_t count = k->c.off[i + 1] - k->c.off[i];
    uint8_t st = PST_ROW_OK;
    d->mode[i] = MX_FIT;
    if (S == MX_QUADRATIC) {
        if (count < mx_min_quadratic(D))
            st = PST_ROW_TOO_FEW;
        else {
            uint8_t s = invert(op, D, tri, m, pst_h(&k->c, i), Q, m);
            if (s != PST_ROW_RANK_DEFICIENT)
                return s;
            st = s;
        }
        d->mode[i] = MX_LINEAR_FIT;
    }
    /* the linear fit; for mixed2 its moments are the leading block of the packed triangle */
    if (count < mx_min_linear(D)) {
        st = worse(st, PST_ROW_TOO_FEW);
    } else {
        uint8_t s = invert(op, D, tri, D + 1, pst_h(&k->c, i), Q, m);
        if (s != PST_ROW_RANK_DEFICIENT)
            return worse(st, s);
        st = worse(st, s);
    }
    d->mode[i] = MX_NOFIT;
    memset(Q, 0, (size_t)(D * m) * sizeof *Q);
    return st;
}

/* inversion_t in the widest vector ISA (called from the OpenMP region, which the clones do not
 * reach), with the dimension and the basis size constants. */
PST_ISA_DISPATCH static uint8_t inversion(const pst_op *op, const mx_ctx *k, size_t i,
                                          const double *tri)
{
    int S = ((const mx_data *)op->data)->which;
    if (k->c.dim == 2)
        return S == MX_QUADRATIC ? inversion_t(op, k, 2, MX_QUADRATIC, i, tri)
                                 : inversion_t(op, k, 2, MX_LINEAR, i, tri);
    return S == MX_QUADRATIC ? inversion_t(op, k, 3, MX_QUADRATIC, i, tri)
                             : inversion_t(op, k, 3, MX_LINEAR, i, tri);
}

/* In-place sort of a short row of column indices: insertion sort below 16, else quicksort on
 * the median of three. Bound by the comparisons, ~log2(len) per entry. */
static void sort_u32(uint32_t *a, int64_t n)
{
    while (n > 16) {
        uint32_t x = a[0], y = a[n / 2], z = a[n - 1];
        uint32_t piv = x < y ? (y < z ? y : (x < z ? z : x)) : (x < z ? x : (y < z ? z : y));
        int64_t lo = 0, hi = n - 1;
        while (lo <= hi) {
            while (a[lo] < piv)
                ++lo;
            while (a[hi] > piv)
                --hi;
            if (lo <= hi) {
                uint32_t t = a[lo];
                a[lo++] = a[hi];
                a[hi--] = t;
            }
        }
        if (hi + 1 < n - lo) { /* recurse on the smaller part, loop on the larger */
            sort_u32(a, hi + 1);
            a += lo;
            n -= lo;
        } else {
            sort_u32(a + lo, n - lo);
            n = hi + 1;
        }
    }
    for (int64_t r = 1; r < n; ++r) {
        uint32_t v = a[r];
        int64_t s = r;
        for (; s > 0 && a[s - 1] > v; --s)
            a[s] = a[s - 1];
        a[s] = v;
    }
}

/* The columns of row i of the pattern, N(i) and N(j) for j in N(i), without i, unsorted; with
 * out == NULL only counted. mark[] (one per thread) holds the last row that took a column. */
static int64_t ring2(const mx_ctx *k, size_t i, uint32_t *mark, uint32_t *out)
{
    const int64_t *off = k->c.off;
    const uint32_t *idx = k->c.idx;
    int64_t c = 0;
    mark[i] = (uint32_t)i;
    for (int64_t e = off[i]; e < off[i + 1]; ++e) {
        uint32_t j = idx[e];
        if (mark[j] != i) {
            mark[j] = (uint32_t)i;
            if (out)
                out[c] = j;
            ++c;
        }
        for (int64_t f = off[j]; f < off[j + 1]; ++f) {
            uint32_t l = idx[f];
            if (mark[l] != i) {
                mark[l] = (uint32_t)i;
                if (out)
                    out[c] = l;
                ++c;
            }
        }
    }
    return c;
}

/* Every thread's marker array reset (i < n <= UINT32_MAX never equals the reset value). */
static void reset_marks(uint32_t *marks, size_t len)
{
    for (size_t t = 0; t < len; ++t)
        marks[t] = UINT32_MAX;
}

/* The wide_pattern hook: the neighbours-of-neighbours pattern, a counting pass and (with pidx)
 * a filling pass, so memory stays one copy of it. Bound by the |N|^2 gathers of mark[] per row,
 * then the sort. Nothing is left allocated on failure. */
static int mx_wide_pattern(const pst_op *op, int64_t **poff, uint32_t **pidx, char *err)
{
    mx_ctx k = make_ctx(op);
    size_t n = op->n, nm = (size_t)omp_get_max_threads() * n;
    uint32_t *marks = pst_alloc(nm * sizeof *marks), *idx = NULL;
    int64_t *off = pst_alloc((n + 1) * sizeof *off);
    int st = PST_OK;
    PST_CHECK_GOTO(!marks || !off, st, PST_ENOMEM, fail, err,
                   "%s: cannot allocate the stencil pattern of %zu particles", op->scheme->name,
                   n);
    reset_marks(marks, nm);
    off[0] = 0;
#pragma omp parallel
    {
        uint32_t *mark = marks + (size_t)omp_get_thread_num() * n;
#pragma omp for schedule(dynamic, 256)
        for (size_t i = 0; i < n; ++i)
            off[i + 1] = ring2(&k, i, mark, NULL);
    }
    for (size_t i = 0; i < n; ++i)
        off[i + 1] += off[i];
    if (pidx) {
        idx = pst_alloc((size_t)off[n] * sizeof *idx);
        PST_CHECK_GOTO(!idx, st, PST_ENOMEM, fail, err,
                       "%s: cannot allocate the stencil pattern (%lld entries)",
                       op->scheme->name, (long long)off[n]);
        reset_marks(marks, nm);
#pragma omp parallel
        {
            uint32_t *mark = marks + (size_t)omp_get_thread_num() * n;
#pragma omp for schedule(dynamic, 256)
            for (size_t i = 0; i < n; ++i) {
                ring2(&k, i, mark, idx + off[i]);
                sort_u32(idx + off[i], off[i + 1] - off[i]);
            }
        }
        *pidx = idx;
    }
    pst_free(marks);
    *poff = off;
    return PST_OK;
fail:
    pst_free(marks);
    pst_free(off);
    return st;
}

static int precompute(pst_op *op, int which, char *err)
{
    size_t n = op->n;
    int dim = op->dim;
    mx_data *d = pst_op_data(op, sizeof *d);
    if (!d)
        return PST_ENOMEM;
    d->which = which;
    d->m = basis_size(dim, which);
    int m = d->m, ntri = m * (m + 1) / 2;
    PST_DATA_ARRAY(d->Q, n * (size_t)(dim * m) * sizeof *d->Q);
    PST_DATA_ARRAY(d->mode, n);
    if (which == MX_ORDINARY)
        PST_DATA_ARRAY(d->Vn, n * sizeof *d->Vn);
    double *tri = pst_alloc((size_t)MX_BLOCK * ntri * sizeof *tri);
    if (!d->Q || !d->mode || !tri || (which == MX_ORDINARY && !d->Vn)) {
        pst_free(tri);
        pst_set_err(err, "%s: cannot allocate the per-particle data of %zu particles",
                    op->scheme->name, n);
        return PST_ENOMEM;
    }
    mx_ctx k = make_ctx(op);
    double t0 = omp_get_wtime();
    if (which == MX_ORDINARY)
        volumes(&k, n, d->Vn);
    op->phase[PST_PHASE_GEOMETRY] += omp_get_wtime() - t0;
    /* Moments and inversions as separate passes, block by block (the moment scratch is one
     * block): each row reads only its own neighbours, so any thread count gives the same. */
    for (size_t b = 0; b < n; b += MX_BLOCK) {
        size_t e = b + MX_BLOCK < n ? b + MX_BLOCK : n;
        t0 = omp_get_wtime();
#pragma omp parallel for schedule(dynamic, 64)
        for (size_t i = b; i < e; ++i)
            moments(&k, which, i, tri + (i - b) * (size_t)ntri);
        double t1 = omp_get_wtime();
        op->phase[PST_PHASE_MOMENTS] += t1 - t0;
#pragma omp parallel for schedule(dynamic, 64)
        for (size_t i = b; i < e; ++i)
            op->status[i] = inversion(op, &k, i, tri + (i - b) * (size_t)ntri);
        op->phase[PST_PHASE_INVERSION] += omp_get_wtime() - t1;
        pst_tally_add(op->tally, e - b); /* the block's rows are done */
    }
    pst_free(tri);
    return PST_OK; /* no WEIGHTS phase: the weights are formed by the applies or on emission */
}

static int pre_ordinary(pst_op *op, char *err) { return precompute(op, MX_ORDINARY, err); }
static int pre_linear(pst_op *op, char *err) { return precompute(op, MX_LINEAR, err); }
static int pre_quadratic(pst_op *op, char *err) { return precompute(op, MX_QUADRATIC, err); }

/* ---- apply, emission and the rest of the table ------------------------------------------ */

/* Matrix-free apply: sweep 1 (G = M D u) into a buffer of D*n doubles, then sweep 2 (the
 * divergence). The buffer is this apply's one allocation: sweep 2 reads G of every neighbour,
 * so all of G must exist before any row, and it depends on u while the operator stays
 * read-only. If it cannot be allocated, each row recomputes its neighbours' gradients (|N|
 * times the work, the same result to rounding), so an apply never fails. */
static void mx_apply(const pst_op *op, const double *u, double *y)
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

static void mx_emit_row(const pst_op *op, size_t i, double *w)
{
    mx_ctx k = make_ctx(op);
    fns_for(&k)->emit(&k, op->poff, op->pidx, i, w);
}

/* The LS gradient (D u)_I (the fallback gradient on rows without a fit). */
static void mx_gradient(const pst_op *op, const double *u, double *const grad[3])
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

/* mixed2: the second-derivative coefficients of the quadratic fit, refitted here in
 * difference form a = M^-1 sum_j w_j p_j (u_j - u_I) (not stored: 18 / 60 more doubles per
 * particle for a diagnostic). 0 where the quadratic fit was not used. */
static void mx_hessian(const pst_op *op, const double *u, double *const hess[6])
{
    mx_ctx k = make_ctx(op);
    int D = k.c.dim, m = basis_size(D, MX_QUADRATIC), nh = m - 1 - D;
    const mx_data *d = op->data;
#pragma omp parallel for schedule(dynamic, 1)
    for (size_t b = 0; b < pst_chunks(op->n, PST_CHUNK); ++b)
        PST_CHUNK_ROWS(op->tally, b, op->n, PST_CHUNK, i) {
            double tri[55], a[100], r[10] = {0};
            for (int c = 0; c < nh; ++c)
                hess[c][i] = 0.0;
            if (d->mode[i] != MX_FIT)
                continue;
            moments(&k, MX_QUADRATIC, i, tri);
            double ih = 1.0 / pst_h(&k.c, i);
            for (int64_t e = k.c.off[i]; e < k.c.off[i + 1]; ++e) {
                size_t j = k.c.idx[e];
                double x[3] = {0, 0, 0}, p[10], w = fit_weight(&k, D, MX_QUADRATIC, i, j, x);
                for (int c = 0; c < D; ++c)
                    x[c] *= ih;
                basis(D, MX_QUADRATIC, x, p);
                for (int c = 0; c < m; ++c)
                    r[c] += w * p[c] * (u[j] - u[i]);
            }
            for (int q = 0, t = 0; q < m; ++q)
                for (int c = 0; c <= q; ++c, ++t)
                    a[q * m + c] = a[c * m + q] = tri[t];
            if (!(pst_ldlt_factor(m, a) > 0))
                continue;
            pst_ldlt_solve(m, a, r);
            for (int c = 0; c < nh; ++c)
                hess[c][i] = isfinite(r[1 + D + c]) ? r[1 + D + c] * ih * ih : 0.0;
        }
}

#define MX_FALLBACK_LINEAR                                                                     \
    "linear fit: too few neighbours or singular -> kernel gradient and Brookshaw row -> zero row"

/* HALO, the hops a row reaches (pst_scheme.halo): 2, the neighbours' gradients, whose fits read
 * their own neighbours; 3 for mixed0, whose fits weigh those neighbours by volumes V~ that come
 * from the next ring. */
#define MX_SCHEME(ID, NAME, DESC, FALLBACK, DEG, HALO, PRE, MIN, HESS, BYTES2, BYTES3)        \
    const pst_scheme ID = {.name = NAME,                                                       \
                           .description = DESC,                                                \
                           .fallback = FALLBACK,                                               \
                           .default_kernel = PST_KERNEL_QUINTIC,                               \
                           .degree = DEG,                                                      \
                           .degree_lattice = 2,                                                \
                           .mobility = 1,                                                      \
                           .halo = HALO,                                                       \
                           .min_neighbours = MIN,                                              \
                           .precompute = PRE,                                                  \
                           .wide_pattern = mx_wide_pattern,                                    \
                           .apply = mx_apply,                                                  \
                           .emit_row = mx_emit_row,                                            \
                           .gradient = mx_gradient,                                            \
                           .hessian = HESS,                                                    \
                           .free_data = mx_free,                                               \
                           .data_bytes = {BYTES2, BYTES3}} /* Q, mode, Vn (mixed0) */

MX_SCHEME(pst_scheme_mixed0, "mixed0",
          "mixed ordinary method, nested LS gradient with W V weights (seed 003 Model 3)",
          MX_FALLBACK_LINEAR, 1, 3, pre_ordinary, mx_min_linear, NULL, 57, 105);
MX_SCHEME(pst_scheme_mixed1, "mixed1",
          "mixed least squares 1st order, nested linear LS gradient (seed 003 Model 4)",
          MX_FALLBACK_LINEAR, 1, 2, pre_linear, mx_min_linear, NULL, 49, 97);
MX_SCHEME(pst_scheme_mixed2, "mixed2",
          "mixed least squares 2nd order, nested quadratic LS gradient (seed 003 Model 5)",
          "quadratic fit: too few neighbours or singular -> linear fit -> kernel gradient and "
          "Brookshaw row -> zero row",
          2, 2, pre_quadratic, mx_min_quadratic, mx_hessian, 97, 241);
