/* The weighted-least-squares engine of the quadric fits (docs/schemes/lsmps.md, lpmps.md): the
 * moment pass, the moment matrix, the fallback levels and the precompute; its rows (matrix-free
 * apply, half-list rows, emission) are in wls_rows.c, the fit at the particles (gradient,
 * Hessian, the data pass) in wls_derivs.c, interpolation at points in wls_points.c, what they
 * share in wls_common.h. A scheme supplies only its factorisation of the moment matrix
 * (kernels/lsmps.c: LDL^T; kernels/lpmps.c: the Schur complement); qsfdi and the mixed schemes
 * use the vectorised moment sums (pst_wls_msums).
 *
 * Row I fits a full quadratic in the scaled offsets x^ = (x_j - x_I) / h_I (r_s = h,
 * choice 3) by weighted least squares with the quintic weight w_j = f(|x^_j|) (QSFDI eq. 9; the
 * normalising constant cancels, so f is used without it):
 *     type B (variant 0): basis p^ = (1, x, y, xx, yy, xy)          6 / 10 (3D) unknowns, the
 *                         centre particle included with w(0) = f(0) = 66 in the constant moment;
 *     type A (variant 1): basis p  = (x, y, xx, yy, xy), data u_j - u_I   5 / 9 unknowns
 * (3D: 1, x, y, z, xx, yy, zz, xy, xz, yz). With M = sum_j w_j p_j p_j^T (+ w(0) e_0 e_0^T for
 * type B) the Laplacian weights are a_Ij = w_j lambda_I . p_j with lambda_I = M^-1 h^, h^ = 2/h_I^2
 * on the squares and 0 elsewhere; Neumann rows use h^ = n_I / h_I on the linear entries, the
 * fit's own n . grad u. Per particle only lambda (nb doubles) is kept: the matrix-free apply
 * recomputes x^, w and p from the positions. The precompute runs in blocks of particles, each
 * block as three threaded passes timed separately: moments (the distinct weighted monomial sums
 * of degree 0 (B) / 2 (A) to 4, one neighbour pass: the neighbours gathered into arrays, then
 * one vectorised reduction loop per degree), inversion (the scheme's factorisation) and weights
 * (the solve for lambda, or the fallback chain; with opts.keep the derivatives' kappas of the
 * same level, wls_derivs.c). Fallback chain: quadric fit (status ok or ill-conditioned) -> the
 * linear-exact fit on (x, y, |x|^2) (1 included for type B) -> a radial row a_Ij = w_j |x^_j|^2
 * 2D / (h^2 sum w |x^|^4) (exact for |x|^2) -> an empty row (no weighted neighbour). Never NaN. */
#include "isa.h"
#include "lanes.h"
#include "small_matrix.h"
#include "wls_common.h"
#include "wls_sums.h"

#include <omp.h>
#include <stdlib.h>
#include <string.h>

/* Particles per block of the precompute: bounds the memory of the moments and factors kept
 * between passes (3D type B: 32768 x 235 doubles, 62 MB) and the number of parallel regions;
 * rows are dealt in dynamic chunks of 128 (each row is still computed by one thread, so the
 * results do not depend on the thread count). */
#define WLS_BLOCK 32768

/* The monomial index of the product of type-B basis entries a and b: M[a][b] = mom[sum]. */
static const signed char wls_sum2[6][6] = {
    {0, 1, 2, 3, 4, 5},    {1, 3, 5, 6, 8, 7},     {2, 5, 4, 7, 9, 8},
    {3, 6, 7, 10, 12, 11}, {4, 8, 9, 12, 14, 13}, {5, 7, 8, 11, 13, 12}};
static const signed char wls_sum3[10][10] = {
    {0, 1, 2, 3, 4, 5, 6, 7, 8, 9},
    {1, 4, 7, 8, 10, 13, 15, 11, 12, 14},
    {2, 7, 5, 9, 11, 16, 18, 13, 14, 17},
    {3, 8, 9, 6, 12, 17, 19, 14, 15, 18},
    {4, 10, 11, 12, 20, 23, 25, 21, 22, 24},
    {5, 13, 16, 17, 23, 30, 32, 26, 27, 31},
    {6, 15, 18, 19, 25, 32, 34, 28, 29, 33},
    {7, 11, 13, 14, 21, 26, 28, 23, 24, 27},
    {8, 12, 14, 15, 22, 27, 29, 24, 25, 28},
    {9, 14, 17, 18, 24, 31, 33, 27, 28, 32}};

/* The same sums for qsfdi.c (wls.h), in the widest vector ISA. */
PST_ISA_DISPATCH void pst_wls_msums(int dim, int deg, int n, const double *r, int stride,
                                    const double *w,
                   double *s)
{
    const double *x = r, *y = r + stride, *z = dim == 3 ? r + 2 * stride : NULL;
    if (dim == 2) {
        switch (deg) {
        case 1: wls_msum1(2, n, x, y, z, w, s); break;
        case 2: wls_msum2(2, n, x, y, z, w, s); break;
        case 3: wls_msum3(2, n, x, y, z, w, s); break;
        default: wls_msum4(2, n, x, y, z, w, s); break;
        }
    } else {
        switch (deg) {
        case 1: wls_msum1(3, n, x, y, z, w, s); break;
        case 2: wls_msum2(3, n, x, y, z, w, s); break;
        case 3: wls_msum3(3, n, x, y, z, w, s); break;
        default: wls_msum4(3, n, x, y, z, w, s); break;
        }
    }
}

/* The weighted monomial sums of row i (degree 0..4 for B, 2..4 for A: mom[k - first]). Per
 * neighbour: the gather, one sqrt and ~19 flops of kernel (gather()), then 2 flops per moment
 * plus the shared products (15 / 35 moments for B, 12 / 31 for A) in the vectorised loops of
 * wls_msum*: compute-bound. Measured (3D, 1 thread, type B / A): 8.8 / 8.1 ns per neighbour
 * with default flags, 6.0 / 5.5 native (was ~26 ns). */
PST_KHOT void moments_row(const wls_ctx *k, int D, int B, pst_kernel K, size_t i, double *mom)
{
    const int nm = WLS_NMOM(D), first = B ? 0 : D + 1;
    const int o2 = D + 1, o3 = o2 + D * (D + 1) / 2, o4 = o3 + (D == 2 ? 4 : 10);
    double acc[35] = {0}, xc[3], ih = 1.0 / pst_h(&k->c, i);
    centre_of(k, D, i, xc);
    for (int64_t c0 = k->c.off[i]; c0 < k->c.off[i + 1]; c0 += WLS_CHUNK) {
        int n = (int)(k->c.off[i + 1] - c0 < WLS_CHUNK ? k->c.off[i + 1] - c0 : WLS_CHUNK);
        double r[3][WLS_CHUNK], w[WLS_CHUNK];
        gather(k, D, K, xc, ih, k->c.idx + c0, n, r, w);
        if (B) { /* degree 0 and 1: the same sums as the basis' first entries */
            wls_msum0(n, w, acc);
            wls_msum1(D, n, r[0], r[1], r[2], w, acc + 1);
        }
        double g[6] = {0};
        wls_msum2(D, n, r[0], r[1], r[2], w, g);
        for (int e = 0; e < o3 - o2; ++e)
            acc[o2 + e] += g[wls_gl2b(D, e)];
        wls_msum3(D, n, r[0], r[1], r[2], w, acc + o3);
        wls_msum4(D, n, r[0], r[1], r[2], w, acc + o4);
    }
    if (B) /* the centre particle: p^(0) = e_0, weight f(0) */
        acc[0] += pst_sph_shape(K, D, 0.0, 0);
    for (int m = first; m < nm; ++m)
        mom[m - first] = acc[m];
}

void wls_build_matrix(int D, int B, const double *mom, double *M)
{
    const int nb = D + D * (D + 1) / 2 + B, first = B ? 0 : D + 1;
    for (int a = 0; a < nb; ++a)
        for (int c = 0; c < nb; ++c) {
            int s = D == 2 ? wls_sum2[a + 1 - B][c + 1 - B] : wls_sum3[a + 1 - B][c + 1 - B];
            M[a * nb + c] = mom[s - first];
        }
}

/* ---- the fallback levels ------------------------------------------------------------------ */

/* The reduced (linear-exact) fit on (1,) x, y[, z], rho = |x^|^2: Mr = R^T M R with R mapping
 * rho onto the squares. Factorises Mr into fr ((D+1+B)^2) and returns 1 when usable. */
static int reduced_factor(int D, int B, const double *M, double *fr, double rank_tol)
{
    const int nb = D + D * (D + 1) / 2 + B, nl = B + D, nr = nl + 1;
    for (int a = 0; a < nl; ++a) {
        double s = 0;
        for (int c = 0; c < nl; ++c)
            fr[a * nr + c] = M[a * nb + c];
        for (int t = nl; t < nl + D; ++t)
            s += M[a * nb + t];
        fr[a * nr + nl] = fr[nl * nr + a] = s;
    }
    double s = 0;
    for (int t = nl; t < nl + D; ++t)
        for (int c = nl; c < nl + D; ++c)
            s += M[t * nb + c];
    fr[nl * nr + nl] = s;
    return pst_ldlt_factor(nr, fr) > rank_tol;
}

/* Solve the reduced system for the right-hand side R^T b (b in the full basis) and expand the
 * solution back: linear entries as they are, every square the rho coefficient, crosses 0. */
static void reduced_solve(int D, int B, const double *fr, double *b)
{
    const int nb = D + D * (D + 1) / 2 + B, nl = B + D, nr = nl + 1;
    double r[WLS_NBMAX];
    for (int a = 0; a < nl; ++a)
        r[a] = b[a];
    r[nl] = 0;
    for (int t = nl; t < nl + D; ++t)
        r[nl] += b[t];
    pst_ldlt_solve(nr, fr, r);
    for (int a = 0; a < nb; ++a)
        b[a] = a < nl ? r[a] : a < nl + D ? r[nl] : 0.0;
}

/* The radial level: b in the full basis becomes D b_lin / S2 on the linear entries and
 * (sum of b on the squares) / S4 on every square, S2 = sum w |x^|^2 and S4 = sum w |x^|^4 read
 * from M. Returns 0 (b zeroed) when the row has no weighted neighbour. */
static int radial_solve(int D, int B, const double *M, double *b)
{
    const int nb = D + D * (D + 1) / 2 + B, nl = B + D;
    double S2 = 0, S4 = 0, bs = 0;
    for (int a = B; a < nl; ++a)
        S2 += M[a * nb + a];
    for (int t = nl; t < nl + D; ++t) {
        bs += b[t];
        for (int c = nl; c < nl + D; ++c)
            S4 += M[t * nb + c];
    }
    int ok = S2 > 0 && S4 > 0;
    for (int a = 0; a < nb; ++a)
        b[a] = !ok ? 0.0 : a >= B && a < nl ? D * b[a] / S2 : a >= nl && a < nl + D ? bs / S4 : 0;
    return ok;
}

/* The reduced fit's factor is formed afresh (a fallback row is rare). */
void wls_solve_level(const wls_data *d, int level, const double *M, const double *fac,
                     double rank_tol, double *b)
{
    int D = d->dim, B = d->typeB;
    double fr[(WLS_NBMAX - 3) * (WLS_NBMAX - 3)];
    if (level == LVL_QUADRIC)
        d->solve(D, d->nb, M, fac, b);
    else if (level == LVL_REDUCED && reduced_factor(D, B, M, fr, rank_tol))
        reduced_solve(D, B, fr, b);
    else
        radial_solve(D, B, M, b);
}

/* ---- precompute --------------------------------------------------------------------------- */

static inline uint8_t cond_status(const pst_op *op, double cond)
{
    if (!(cond * op->opts.rank_tol < 1.0))
        return PST_ROW_RANK_DEFICIENT;
    return cond > op->opts.cond_max ? PST_ROW_ILL_CONDITIONED : PST_ROW_OK;
}

/* choice 6 (docs/choices.md): a quadratic fit needs 5 (2D) / 9 (3D) neighbours j != I */
int pst_wls_min_neighbours(int dim) { return dim == 2 ? 5 : 9; }

/* Rows per call of a dispatched moment function (isa.h), dealt dynamically to the threads. */
#define WLS_ROWS 128
typedef void (*moments_fn)(const wls_ctx *, size_t, size_t, double *);
#define WLS_MOMENTS(D, B, K)                                                                   \
    PST_ISA_DISPATCH static void mrows_##D##_##B##_##K(const wls_ctx *k, size_t i0, size_t i1,  \
                                                       size_t b0, double *mom)                 \
    {                                                                                          \
        const int nm = WLS_NMOM(D) - (B ? 0 : D + 1);                                          \
        for (size_t i = i0; i < i1; ++i)                                                       \
            moments_row(k, D, B, (pst_kernel)K, i, mom + (size_t)nm * (i - b0));               \
    }                                                                                          \
    static void moments_##D##_##B##_##K(const wls_ctx *k, size_t b0, size_t b1, double *mom)    \
    {                                                                                          \
        _Pragma("omp parallel for schedule(dynamic, 1)")                                        \
        for (size_t c = b0; c < b1; c += WLS_ROWS)                                             \
            mrows_##D##_##B##_##K(k, c, c + WLS_ROWS < b1 ? c + WLS_ROWS : b1, b0, mom);       \
    }
#define WLS_MOMENTS_K(D, B)                                                                    \
    WLS_MOMENTS(D, B, 0) WLS_MOMENTS(D, B, 1) WLS_MOMENTS(D, B, 2) WLS_MOMENTS(D, B, 3)
WLS_MOMENTS_K(2, 0)
WLS_MOMENTS_K(2, 1)
WLS_MOMENTS_K(3, 0)
WLS_MOMENTS_K(3, 1)
static const moments_fn moments_table[2][2][4] = {
    {{moments_2_0_0, moments_2_0_1, moments_2_0_2, moments_2_0_3},
     {moments_2_1_0, moments_2_1_1, moments_2_1_2, moments_2_1_3}},
    {{moments_3_0_0, moments_3_0_1, moments_3_0_2, moments_3_0_3},
     {moments_3_1_0, moments_3_1_1, moments_3_1_2, moments_3_1_3}}};
typedef void (*mrows_fn)(const wls_ctx *, size_t, size_t, size_t, double *);
static const mrows_fn mrows_table[2][2][4] = {
    {{mrows_2_0_0, mrows_2_0_1, mrows_2_0_2, mrows_2_0_3},
     {mrows_2_1_0, mrows_2_1_1, mrows_2_1_2, mrows_2_1_3}},
    {{mrows_3_0_0, mrows_3_0_1, mrows_3_0_2, mrows_3_0_3},
     {mrows_3_1_0, mrows_3_1_1, mrows_3_1_2, mrows_3_1_3}}};

void wls_row_moments(const wls_ctx *k, size_t i, double *mom)
{
    const wls_data *d = k->d;
    mrows_table[d->dim - 2][d->typeB][d->kernel](k, i, i + 1, i, mom);
}

void pst_wls_free(void *p)
{
    wls_data *d = p;
    if (!d)
        return;
    pst_free(d->lam);
    pst_free(d->level);
    pst_free(d->gkap);
    pst_free(d->hkap);
    free(d);
}

/* The right-hand side of row i: the Laplacian h^ (2/h^2 on the squares) or, on a Neumann row,
 * n_I / h on the linear entries. */
static void row_rhs(const wls_ctx *k, size_t i, double *r)
{
    const wls_data *d = k->d;
    int D = d->dim, B = d->typeB;
    double ih = 1.0 / pst_h(&k->c, i);
    for (int a = 0; a < d->nb; ++a)
        r[a] = 0;
    for (int a = 0; a < D; ++a) {
        if (k->c.kind[i] == PST_NEUMANN)
            r[B + a] = k->c.normal[a][i] * ih;
        else
            r[B + D + a] = 2.0 * ih * ih;
    }
}

int pst_wls_precompute(pst_op *op, int typeB, wls_factor_fn factor, wls_solve_fn solve,
                       char *err)
{
    double t0 = omp_get_wtime();
    size_t n = op->n;
    int D = op->dim;
    wls_data *d = pst_op_data(op, sizeof *d);
    if (!d)
        return PST_ENOMEM;
    d->dim = D;
    d->typeB = typeB;
    d->nb = D + D * (D + 1) / 2 + typeB;
    d->kernel = op->kernel;
    d->factor = factor;
    d->solve = solve;
    int nb = d->nb, nm = WLS_NMOM(D) - (typeB ? 0 : D + 1);
    size_t blk = n < WLS_BLOCK ? n : WLS_BLOCK;
    /* 8 doubles past the last row: the half-list rows read 2D rows 8 at a time */
    if (!d->lam && PST_DATA_ARRAY(d->lam, (n * (size_t)nb + PST_LANES) * sizeof *d->lam))
        memset(d->lam + n * (size_t)nb, 0, PST_LANES * sizeof *d->lam);
    PST_DATA_ARRAY(d->level, n);
    const int nh = D * (D + 1) / 2;
    int kept = 1;
    if (op->opts.keep & PST_KEEP_GRADIENT)
        kept = PST_DATA_ARRAY(d->gkap, n * (size_t)(D * nb) * sizeof *d->gkap) != NULL;
    if (op->opts.keep & PST_KEEP_HESSIAN)
        kept = kept && PST_DATA_ARRAY(d->hkap, n * (size_t)(nh * nb) * sizeof *d->hkap) != NULL;
    double *mom = pst_alloc(blk * (size_t)nm * sizeof *mom);
    double *Mb = pst_alloc(blk * (size_t)(nb * nb) * sizeof *Mb);
    double *fac = pst_alloc(blk * (size_t)(nb * nb) * sizeof *fac);
    if (!d->lam || !d->level || !kept || !mom || !Mb || !fac) {
        pst_free(mom);
        pst_free(Mb);
        pst_free(fac);
        pst_set_err(err, "%s: cannot allocate the per-particle data of %zu particles",
                    op->scheme->name, n);
        return PST_ENOMEM;
    }
    wls_ctx k = make_ctx(op);
    moments_fn moments = moments_table[D - 2][typeB][op->kernel];
    int minn = pst_wls_min_neighbours(D);
    double rank_tol = op->opts.rank_tol;
    /* the pair geometry and weights are fused into the moment pass (recomputing them is
     * cheaper than storing them): this phase is the setup only */
    op->phase[PST_PHASE_GEOMETRY] = omp_get_wtime() - t0;
    for (size_t b0 = 0; b0 < n; b0 += blk) {
        size_t b1 = b0 + blk < n ? b0 + blk : n;
        double t = omp_get_wtime();
        moments(&k, b0, b1, mom);
        op->phase[PST_PHASE_MOMENTS] += omp_get_wtime() - t;

        /* Bound by the factorisations: ~nb^3/6 flops per particle, no neighbour access. */
        t = omp_get_wtime();
#pragma omp parallel for schedule(dynamic, 128)
        for (size_t i = b0; i < b1; ++i) {
            double *M = Mb + (size_t)(nb * nb) * (i - b0);
            wls_build_matrix(D, typeB, mom + (size_t)nm * (i - b0), M);
            if (k.c.off[i + 1] - k.c.off[i] < minn) {
                op->status[i] = PST_ROW_TOO_FEW;
                continue;
            }
            op->status[i] = cond_status(op, factor(D, nb, M, fac + (size_t)(nb * nb) * (i - b0)));
        }
        op->phase[PST_PHASE_INVERSION] += omp_get_wtime() - t;

        /* Bound by the triangular solves: ~nb^2 flops per particle. */
        t = omp_get_wtime();
#pragma omp parallel for schedule(dynamic, 128)
        for (size_t i = b0; i < b1; ++i) {
            const double *M = Mb + (size_t)(nb * nb) * (i - b0);
            double *lam = d->lam + (size_t)nb * i, fr[(WLS_NBMAX - 3) * (WLS_NBMAX - 3)];
            row_rhs(&k, i, lam);
            uint8_t lvl = LVL_QUADRIC;
            if (op->status[i] >= PST_ROW_RANK_DEFICIENT) {
                lvl = reduced_factor(D, typeB, M, fr, rank_tol) ? LVL_REDUCED : LVL_RADIAL;
                if (lvl == LVL_REDUCED)
                    reduced_solve(D, typeB, fr, lam);
                else if (!radial_solve(D, typeB, M, lam))
                    lvl = LVL_EMPTY;
            } else {
                solve(D, nb, M, fac + (size_t)(nb * nb) * (i - b0), lam);
            }
            d->level[i] = lvl;
            if (d->gkap || d->hkap) /* the derivatives' kappas of the same level (opts.keep) */
                wls_kappas(d, lvl, M, fac + (size_t)(nb * nb) * (i - b0), rank_tol,
                           1.0 / pst_h(&k.c, i), d->gkap ? d->gkap + (size_t)(D * nb) * i : NULL,
                           d->hkap ? d->hkap + (size_t)(nh * nb) * i : NULL);
        }
        op->phase[PST_PHASE_WEIGHTS] += omp_get_wtime() - t;
        pst_tally_add(op->tally, b1 - b0); /* the block's rows are done */
    }
    pst_free(mom);
    pst_free(Mb);
    pst_free(fac);
    return PST_OK;
}

/* The reduced fit is linear-exact and so has no diagonal on a flat neighbourhood that misses
 * I: the row drops to the radial row, which is non-negative and exact for |x|^2. The moments
 * are recomputed (a flat row is rare; keeping them would cost nm doubles per particle). */
void pst_wls_degrade(pst_op *op, size_t i)
{
    wls_ctx k = make_ctx(op);
    wls_data *d = op->data;
    int D = d->dim, B = d->typeB, nb = d->nb, nh = D * (D + 1) / 2;
    double mom[35], M[WLS_NBMAX * WLS_NBMAX], *lam = d->lam + (size_t)nb * i;
    wls_row_moments(&k, i, mom);
    wls_build_matrix(D, B, mom, M);
    row_rhs(&k, i, lam);
    d->level[i] = radial_solve(D, B, M, lam) ? LVL_RADIAL : LVL_EMPTY;
    if (d->gkap || d->hkap) /* kept kappas follow the row's level, as a refit would */
        wls_kappas(d, d->level[i], M, NULL, op->opts.rank_tol, 1.0 / pst_h(&k.c, i),
                   d->gkap ? d->gkap + (size_t)(D * nb) * i : NULL,
                   d->hkap ? d->hkap + (size_t)(nh * nb) * i : NULL);
}
