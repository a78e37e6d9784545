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
