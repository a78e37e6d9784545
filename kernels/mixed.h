/* The least-squares mixed schemes' shared parts (kernels/mixed.c has the schemes and their
 * equations): the data, the context and the pair functions that the applies and the emission
 * (mixed_rows.c) and the fits (mixed_fit.c) share, so that all of them use the same numbers,
 * and what each file exports. Internal. */
#ifndef PSTENCIL_MIXED_H
#define PSTENCIL_MIXED_H

#include "kernel_common.h"
#include "sph_kernels.h"

#include <math.h>
#include <stddef.h>
#include <stdint.h>

enum { MX_ORDINARY, MX_LINEAR, MX_QUADRATIC };

/* Per-particle fit actually used: the scheme's, the linear one (mixed2 fallback), none. */
enum { MX_FIT = 0, MX_LINEAR_FIT = 1, MX_NOFIT = 2 };

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

static inline mx_ctx make_ctx(const pst_op *op)
{
    return (mx_ctx){.c = pst_kctx_of(op), .d = op->data};
}

/* The hot functions (PST_KHOT) take the dimension D and the scheme S as arguments; the applies
 * call them with constants (one instantiation per combination), so pair loops carry no branch
 * on them. */
static inline int basis_size(int D, int S)
{
    return S == MX_QUADRATIC ? (D + 1) * (D + 2) / 2 : D + 1;
}

/* Taylor basis at offset (x, y, z): 1, x_a, then (quadratic) x_a^2/2 and the cross products in
 * the order of pst_op_hessian (2D: xx, yy, xy; 3D: xx, yy, zz, xy, xz, yz); z is not read in
 * 2D. The components as scalars, not an array: the form that vectorises across neighbours
 * (GCC 12 finds no vector type for an array built from a chunk's columns). */
PST_KHOT void basis_xyz(int D, int S, double x, double y, double z, double *p)
{
    p[0] = 1.0;
    p[1] = x;
    p[2] = y;
    if (D == 3)
        p[3] = z;
    if (S != MX_QUADRATIC)
        return;
    p[1 + D] = 0.5 * x * x;
    p[2 + D] = 0.5 * y * y;
    if (D == 3)
        p[3 + D] = 0.5 * z * z;
    p[1 + 2 * D] = x * y;
    if (D == 3) {
        p[8] = x * z;
        p[9] = y * z;
    }
}

PST_KHOT void basis(int D, int S, const double x[3], double *p)
{
    basis_xyz(D, S, x[0], x[1], D == 3 ? x[2] : 0.0, p);
}

/* Offset x = r_j - r_i, its length, and whether the pair is non-degenerate. */
PST_KHOT int pair_offset(const mx_ctx *k, int D, size_t i, size_t j, double x[3], double *d)
{
    *d = sqrt(pst_pair_offset(&k->c, D, i, j, x));
    return pst_pair_live(&k->c, *d, pst_h(&k->c, i));
}

/* The LS fit weight w_j of pair (i, j) (mixed.c's head comment), 0 when degenerate. */
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

/* The passes over a row's neighbours (the fits' moments and volumes, the rows' derivative
 * weights) gather them, a chunk at a time, into stack arrays (structure of arrays) and evaluate
 * the kernel in vector loops; their sums have an order fixed by the code, the same for every
 * row and thread count. A 3D row (~190 neighbours) is one chunk. */
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

/* Choice 6 (docs/choices.md) by analogy: the fit of m unknowns includes I, so it needs m - 1
 * neighbours: D for the linear fits (the cspm-like count), 5 / 9 for the quadratic one (as
 * lsmps). */
static inline int mx_min_linear(int dim) { return dim; }
static inline int mx_min_quadratic(int dim) { return dim == 2 ? 5 : 9; }

/* mixed_rows.c: the matrix-free apply (two sweeps), the emission of a stored row in the
 * neighbours-of-neighbours pattern, the LS gradient. */
void pst_mx_apply(const pst_op *op, const double *u, double *y);
void pst_mx_emit_row(const pst_op *op, size_t i, double *w);
void pst_mx_gradient(const pst_op *op, const double *u, double *const grad[3]);

/* mixed_fit.c: the precompute (volumes, moments, inversions) of the scheme `which` (MX_*), the
 * mixed2 Hessian refit, and the data's release. */
int pst_mx_precompute(pst_op *op, int which, char *err);
void pst_mx_hessian(const pst_op *op, const double *u, double *const hess[6]);
void pst_mx_free(void *p);

/* mixed_pattern.c: the neighbours-of-neighbours pattern (pst_scheme.wide_pattern). */
int pst_mx_wide_pattern(const pst_op *op, int64_t **poff, uint32_t **pidx, char *err);

#endif
