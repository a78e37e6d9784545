/* What the files of the weighted-least-squares engine share (kernels/wls.c: the fit, its
 * fallback levels and the precompute; wls_rows.c: the matrix-free apply, the half-list rows and
 * the emission; wls_points.c: interpolation at points): the per-particle data, the context the
 * pair functions read, the kernel weight of a pair, a chunk's gather and the weight of a pair
 * in a row's coefficients, so that every path forms a weight bit for bit alike. Internal. */
#ifndef PSTENCIL_WLS_COMMON_H
#define PSTENCIL_WLS_COMMON_H

#include "kernel_common.h"
#include "sph_kernels.h"
#include "wls.h"

#include <math.h>

/* Largest basis (3D type B) and number of monomials of degree 0..4 in 2D / 3D. */
#define WLS_NBMAX 10
#define WLS_NMOM(D) ((D) == 2 ? 15 : 35)

/* Fit levels of a row (the fallback chain in wls.c's file comment). */
enum { LVL_QUADRIC = 0, LVL_REDUCED = 1, LVL_RADIAL = 2, LVL_EMPTY = 3 };

typedef struct {
    int dim, typeB, nb;    /* nb = basis size: D + D(D+1)/2, plus 1 for type B */
    pst_kernel kernel;
    wls_factor_fn factor;
    wls_solve_fn solve;
    double *lam;           /* nb per particle: a_Ij = w_j lam_I . p_j            */
    uint8_t *level;        /* LVL_* per particle                                 */
    double *gkap, *hkap;   /* opts.keep: D (nh) x nb kappas per particle, or NULL */
} wls_data;

/* Everything the pair functions read, gathered once per call (the rows are those of the
 * neighbour list, c.off / c.idx: the engine keeps the default pattern). */
typedef struct {
    pst_kctx c;
    const wls_data *d;
} wls_ctx;

static inline wls_ctx make_ctx(const pst_op *op)
{
    return (wls_ctx){.c = pst_kctx_of(op), .d = op->data};
}

/* The hot functions (PST_KHOT) take the dimension D, the type flag B and the kernel K as
 * arguments; the instantiations (wls.c, wls_rows.c) call them with constants, so the pair
 * loops carry no branches on them. */
/* The kernel weight f(q) of a scaled distance q, 0 outside the support and for degenerate
 * pairs (q <= eps): a select, so that the lane loops stay branch-free. */
PST_KHOT double cut_weight(int D, pst_kernel K, double q, double supp, double eps)
{
    double w = pst_sph_shape(K, D, q, 0);
    return ((q < supp) & (q > eps)) ? w : 0.0;
}

/* The moment passes gather a row's neighbours, a chunk at a time, into stack arrays (structure
 * of arrays), then form the sums as separate reduction loops over them that the compiler
 * vectorises. The order of a vectorised sum is fixed by the code, the same for every row and
 * thread: results do not depend on the thread count. A 3D row (~190 neighbours) is one chunk. */
#define WLS_CHUNK 256

/* The index among the degree-2 sums of graded lexicographic order (xx xy yy / xx xy xz yy yz
 * zz) of basis entry e's square or cross (basis order xx yy xy / xx yy zz xy xz yz). */
static inline int wls_gl2b(int D, int e)
{
    static const unsigned char order[2][6] = {{0, 2, 1}, {0, 3, 5, 1, 2, 4}};
    return order[D - 2][e];
}

/* Scaled offsets r[a][c] of the neighbours idx[0..n) of xc and their weights w (cut_weight's
 * values). Separate loops, so that the sqrt runs in vector instructions (the library is built
 * without math errno: a scalar sqrt with its errno check cost ~2.8 ns per neighbour, a vector
 * one ~0.3 ns with AVX-512) and the kernel loop has no select: GCC would sink the kernel into a
 * branch of it. Bound by the gather of x_J. */
PST_KHOT void gather(const wls_ctx *k, int D, pst_kernel K, const double *xc, double ih,
                    const uint32_t *idx, int n, double (*r)[WLS_CHUNK], double *w)
{
    double q[WLS_CHUNK];
    for (int c = 0; c < n; ++c)
        for (int a = 0; a < D; ++a)
            r[a][c] = pst_offset(&k->c, a, k->c.x[a][idx[c]], xc[a]) * ih;
    for (int c = 0; c < n; ++c)
        w[c] = r[0][c] * r[0][c] + r[1][c] * r[1][c] + (D == 3 ? r[2][c] * r[2][c] : 0.0);
    for (int c = 0; c < n; ++c)
        q[c] = sqrt(w[c]);
#pragma omp simd
    for (int c = 0; c < n; ++c)
        w[c] = pst_sph_shape(K, D, q[c], 0);
    const double supp = pst_sph_support[K], eps = k->c.pair_eps;
#pragma omp simd
    for (int c = 0; c < n; ++c)
        w[c] = ((q[c] < supp) & (q[c] > eps)) ? w[c] : 0.0;
}

PST_KHOT void centre_of(const wls_ctx *k, int D, size_t i, double xc[3])
{
    for (int a = 0; a < D; ++a)
        xc[a] = k->c.x[a][i];
}

/* w lam . p(x, y, z): the weight of a pair with scaled offset (x, y, z) (z unused in 2D) and
 * kernel weight w in the row of coefficients lam, the quadratic part in Horner order: 10
 * multiplications in 3D where the monomials and the dot product take 16 (the multiplications
 * bound the matrix-free apply, lane_rows_t). Scalars, not the basis array, so that GCC
 * vectorises the loops over a chunk that call it. lambda_m is lam[m * stride]: a row's
 * (stride 1), or one lane of coefficient vectors (pst_lanes_coefs, stride 8). */
PST_KHOT double basis_weight_strided(int D, int B, double w, double x, double y, double z,
                                     const double *lam, int stride)
{
#define L(m) lam[(B + (m)) * stride]
    double s;
    if (D == 2)
        s = x * (L(2) * x + L(4) * y + L(0)) + y * (L(3) * y + L(1));
    else
        s = x * (L(3) * x + L(6) * y + L(7) * z + L(0)) + y * (L(4) * y + L(8) * z + L(1)) +
            z * (L(5) * z + L(2));
#undef L
    return w * (B ? lam[0] + s : s);
}

PST_KHOT double basis_weight_xyz(int D, int B, double w, double x, double y, double z,
                                 const double *lam)
{
    return basis_weight_strided(D, B, w, x, y, z, lam, 1);
}

/* kernels/wls.c: the weighted monomial sums of row i (the precompute's, in the CPU's widest
 * ISA); M (nb x nb) of a row from its moments; M c = b solved at a row's level (b in, c out:
 * the coefficients of the fit in scaled coordinates; fac holds the scheme's factor of M, read
 * on LVL_QUADRIC only). */
void wls_row_moments(const wls_ctx *k, size_t i, double *mom);
void wls_build_matrix(int D, int B, const double *mom, double *M);
void wls_solve_level(const wls_data *d, int level, const double *M, const double *fac,
                     double rank_tol, double *b);

/* kernels/wls_derivs.c: the fit coefficients c of row i for data u (scaled coordinates), at
 * the row's level; the kappas of the row's gradient (gk, D x nb) and second derivatives (hk,
 * nh x nb; either may be NULL) at the given level, with ih = 1 / h_I: the derivatives are
 * kappa . b, b the row's data vector. */
void wls_fit_row(const pst_op *op, const wls_ctx *k, size_t i, const double *u, double *c);
void wls_kappas(const wls_data *d, int level, const double *M, const double *fac,
                double rank_tol, double ih, double *gk, double *hk);

#endif /* PSTENCIL_WLS_COMMON_H */
