/* The mixed schemes' fits (kernels/mixed.c): the precompute, per particle the volume V~
 * (mixed0), the moments of the weighted Taylor fit and their inversion with its fallback chain;
 * and the mixed2 Hessian, refitted from the same moments. */
#include "check.h"
#include "isa.h"
#include "mixed.h"
#include "small_matrix.h"
#include "wls_sums.h"

#include <omp.h>
#include <stdlib.h>
#include <string.h>

/* Particles per block of the moment/inversion passes: bounds the moment scratch (55 doubles
 * per particle in 3D quadratic, 3.6 MB per block) while keeping the two passes separate. */
#define MX_BLOCK 8192

/* The precompute's data, released (pst_scheme.free_data). */
void pst_mx_free(void *p)
{
    mx_data *d = p;
    if (!d)
        return;
    pst_free(d->Q);
    pst_free(d->mode);
    pst_free(d->Vn);
    free(d);
}

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
    0, 1, 4, 2, 5, 7, 3, 6, 8, 9, 4, 10, 11, 12, 20, 7, 13, 16, 17, 23, 30, 9, 15, 18, 19, 25, 32,
    34, 5, 11, 13, 14, 21, 26, 28, 23, 6, 12, 14, 15, 22, 27, 29, 24, 25, 8, 14, 17, 18, 24, 31,
    33, 27, 28, 32};

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

int pst_mx_precompute(pst_op *op, int which, char *err)
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

/* mixed2: the second-derivative coefficients of the quadratic fit, refitted here in
 * difference form a = M^-1 sum_j w_j p_j (u_j - u_I) (not stored: 18 / 60 more doubles per
 * particle for a diagnostic). 0 where the quadratic fit was not used. */
void pst_mx_hessian(const pst_op *op, const double *u, double *const hess[6])
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
