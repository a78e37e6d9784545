/* The fit at the particles of the weighted-least-squares engine (kernels/wls.c): the data
 * vector of a row, its fit coefficients, and the gradient and Hessian, from kappas kept by the
 * precompute (opts.keep) or refitted per call.
 *
 * Row I's fit is c = M^-1 b with b = sum_j w_j p_j (u_j - u_I) (type B: the centre's constant
 * included through M), at the row's level (quadric, reduced or radial: each a symmetric linear
 * map S of b). A derivative is one entry of c scaled: u_a = c_a / h, u_aa = 2 c_aa / h^2,
 * u_ab = c_ab / h^2, i.e. e . S b = (S e) . b for the scaled unit vector e of the entry, since
 * S is symmetric. So each derivative is kappa . b with kappa = S e, one more solve per entry
 * with the row's factor: the precompute can keep the kappas (D x nb doubles per particle for
 * the gradient, nh x nb for the Hessian) and a call is then the one pass that forms b. Without
 * them a call refits the row (moments, factor, kappas at the row's level) and forms b with the
 * same pass, so the two paths give the same bits. */
#include "isa.h"
#include "wls_common.h"
#include "wls_sums.h"

#include <string.h>

/* s[0..nb) += sum_c w_c p(r_c), p the basis ((1,) x, y[, z], squares, crosses). */
PST_KHOT void basis_sums(int D, int B, int n, const double *x, const double *y, const double *z,
                         const double *w, double *s)
{
    double g[6] = {0};
    if (B)
        wls_msum0(n, w, s);
    wls_msum1(D, n, x, y, z, w, s + B);
    wls_msum2(D, n, x, y, z, w, g);
    for (int e = 0; e < D * (D + 1) / 2; ++e)
        s[B + D + e] += g[wls_gl2b(D, e)];
}

/* The data vector b = sum_j w_j p_j (u_j - u_I) of row i (nb entries): per neighbour the moment
 * pass's gather and kernel, then nb weighted sums (2 flops each). */
PST_KHOT void data_row(const wls_ctx *k, int D, int B, pst_kernel K, size_t i, const double *u,
                       double *b)
{
    const int nb = D + D * (D + 1) / 2 + B;
    double xc[3], ih = 1.0 / pst_h(&k->c, i);
    for (int e = 0; e < nb; ++e)
        b[e] = 0;
    centre_of(k, D, i, xc);
    for (int64_t c0 = k->c.off[i]; c0 < k->c.off[i + 1]; c0 += WLS_CHUNK) {
        int n = (int)(k->c.off[i + 1] - c0 < WLS_CHUNK ? k->c.off[i + 1] - c0 : WLS_CHUNK);
        double r[3][WLS_CHUNK], w[WLS_CHUNK];
        gather(k, D, K, xc, ih, k->c.idx + c0, n, r, w);
        for (int c = 0; c < n; ++c)
            w[c] *= u[k->c.idx[c0 + c]] - u[i];
        basis_sums(D, B, n, r[0], r[1], r[2], w, b);
    }
}

/* One instantiation per (D, B, kernel), each compiled per ISA. */
typedef void (*data_fn)(const wls_ctx *, size_t, const double *, double *);
#define WLS_DATA(D, B, K)                                                                      \
    PST_ISA_DISPATCH static void data_##D##_##B##_##K(const wls_ctx *k, size_t i,               \
                                                      const double *u, double *b)              \
    {                                                                                          \
        data_row(k, D, B, (pst_kernel)K, i, u, b);                                             \
    }
#define WLS_DATA_K(D, B) WLS_DATA(D, B, 0) WLS_DATA(D, B, 1) WLS_DATA(D, B, 2) WLS_DATA(D, B, 3)
WLS_DATA_K(2, 0)
WLS_DATA_K(2, 1)
WLS_DATA_K(3, 0)
WLS_DATA_K(3, 1)
static const data_fn data_table[2][2][4] = {
    {{data_2_0_0, data_2_0_1, data_2_0_2, data_2_0_3},
     {data_2_1_0, data_2_1_1, data_2_1_2, data_2_1_3}},
    {{data_3_0_0, data_3_0_1, data_3_0_2, data_3_0_3},
     {data_3_1_0, data_3_1_1, data_3_1_2, data_3_1_3}}};

static void data_vector(const wls_ctx *k, size_t i, const double *u, double *b)
{
    const wls_data *d = k->d;
    data_table[d->dim - 2][d->typeB][d->kernel](k, i, u, b);
}

void wls_kappas(const wls_data *d, int level, const double *M, const double *fac,
                double rank_tol, double ih, double *gk, double *hk)
{
    const int D = d->dim, B = d->typeB, nb = d->nb;
    for (int a = 0; gk && a < D; ++a) {
        double *kap = gk + a * nb;
        memset(kap, 0, (size_t)nb * sizeof *kap);
        kap[B + a] = ih;
        wls_solve_level(d, level, M, fac, rank_tol, kap);
    }
    for (int e = 0; hk && e < D * (D + 1) / 2; ++e) {
        double *kap = hk + e * nb;
        memset(kap, 0, (size_t)nb * sizeof *kap);
        kap[B + D + e] = (e < D ? 2.0 : 1.0) * ih * ih; /* squares: u_aa / 2 */
        wls_solve_level(d, level, M, fac, rank_tol, kap);
    }
}

/* M of row i from its moments and its level, with the scheme's factor for a quadric row. */
static int refit_matrix(const pst_op *op, const wls_ctx *k, size_t i, double *M, double *fac)
{
    const wls_data *d = k->d;
    double mom[35];
    wls_row_moments(k, i, mom);
    wls_build_matrix(d->dim, d->typeB, mom, M);
    int lvl = d->level[i];
    if (lvl == LVL_QUADRIC && !(d->factor(d->dim, d->nb, M, fac) * op->opts.rank_tol < 1.0))
        lvl = LVL_REDUCED; /* cannot happen for a row classified as quadric; keeps c finite */
    return lvl;
}

void wls_fit_row(const pst_op *op, const wls_ctx *k, size_t i, const double *u, double *c)
{
    double M[WLS_NBMAX * WLS_NBMAX], fac[WLS_NBMAX * WLS_NBMAX];
    int lvl = refit_matrix(op, k, i, M, fac);
    data_vector(k, i, u, c);
    wls_solve_level(k->d, lvl, M, fac, op->opts.rank_tol, c);
}

/* The gradient (hessian 0, D entries) or the packed second derivatives (nh entries, the layout
 * of pst_op_hessian) of every row: the kept kappas, or the row refitted into kap. */
static void derivatives(const pst_op *op, const double *u, int hessian, double *const out[6])
{
    wls_ctx k = make_ctx(op);
    const wls_data *d = k.d;
    const int D = d->dim, nb = d->nb, ne = hessian ? D * (D + 1) / 2 : D;
    const double *kept = hessian ? d->hkap : d->gkap;
#pragma omp parallel for schedule(static)
    for (size_t b = 0; b < pst_chunks(op->n, PST_CHUNK); ++b)
        PST_CHUNK_ROWS(op->tally, b, op->n, PST_CHUNK, i) {
            double kap[6 * WLS_NBMAX], bv[WLS_NBMAX];
            const double *ki = kept ? kept + (size_t)(ne * nb) * i : kap;
            if (!kept) {
                double M[WLS_NBMAX * WLS_NBMAX], fac[WLS_NBMAX * WLS_NBMAX];
                int lvl = refit_matrix(op, &k, i, M, fac);
                wls_kappas(d, lvl, M, fac, op->opts.rank_tol, 1.0 / pst_h(&k.c, i),
                           hessian ? NULL : kap, hessian ? kap : NULL);
            }
            data_vector(&k, i, u, bv);
            for (int e = 0; e < ne; ++e) {
                double s = 0;
                for (int m = 0; m < nb; ++m)
                    s += ki[e * nb + m] * bv[m];
                out[e][i] = s;
            }
        }
}

void pst_wls_gradient(const pst_op *op, const double *u, double *const grad[3])
{
    double *out[6] = {grad[0], grad[1], grad[2], NULL, NULL, NULL};
    derivatives(op, u, 0, out);
}

void pst_wls_hessian(const pst_op *op, const double *u, double *const hess[6])
{
    derivatives(op, u, 1, hess);
}
