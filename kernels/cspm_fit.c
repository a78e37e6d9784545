/* The CSPM family's dense per-particle step (kernels/cspm_family.c): the fallback chain's
 * inversions from a row's moments, the row's coefficients from them, the blocked precompute
 * that runs the passes, and the normalised Brookshaw row of a flat neighbourhood. */
#include "check.h"
#include "cspm_family.h"
#include "isa.h"
#include "small_matrix.h"

#include <omp.h>
#include <stdlib.h>
#include <string.h>

/* Particles per block of the precompute: the moments and inverses of one block are kept
 * between the timed passes (about 7 MB in 3D). */
#define CS_BLOCK 8192

static inline uint8_t worse(uint8_t a, uint8_t b) { return a > b ? a : b; }

/* Classify an inversion by its 1-norm condition number. */
static inline uint8_t cond_status(const pst_op *op, double cond)
{
    if (!(cond * op->opts.rank_tol < 1.0))
        return PST_ROW_RANK_DEFICIENT;
    return cond > op->opts.cond_max ? PST_ROW_ILL_CONDITIONED : PST_ROW_OK;
}

/* inv = a^-1 (n <= 6, general) by LU with partial pivoting; returns ||a||_1 ||a^-1||_1, or
 * INFINITY when a is singular or the result is not finite. */
PST_KHOT double lu_inverse(int n, const double *a, double *inv)
{
    double f[36], col[6];
    int piv[6];
    memcpy(f, a, (size_t)(n * n) * sizeof *f);
    if (!(pst_lu_factor(n, f, piv) > 0))
        return INFINITY;
    for (int c = 0; c < n; ++c) {
        for (int r = 0; r < n; ++r)
            col[r] = r == c;
        pst_lu_solve(n, f, piv, col);
        for (int r = 0; r < n; ++r)
            inv[r * n + c] = col[r];
    }
    double cond = pst_mat_norm1(n, a) * pst_mat_norm1(n, inv);
    return isfinite(cond) ? cond : INFINITY;
}

/* Moment of r_a r_b r_c r_d (axes; -1 drops an axis): the exponents by counting, in
 * registers. */
static inline double mom(int D, const double *m, int a, int b, int c, int d)
{
    int e[3];
    for (int t = 0; t < 3; ++t)
        e[t] = (a == t) + (b == t) + (c == t) + (d == t);
    return m[cs_index(D, e[0], e[1], e[2])];
}

/* The fallback chain of row i from its moments: M1 first, then the scheme's level and the
 * ones below it until an invertible matrix is found. Neumann rows need only the gradient
 * (ICSPM's when it exists, else CSPM's). */
PST_KHOT void invert_t(const pst_op *op, const cs_ctx *k, int D, int which, size_t i,
                       int neumann, int count, const double *mB, const double *mA,
                       const double *mC, cs_inv *v)
{
    const int n2 = cs_n2(D);
    double M1[9] = {0};
    uint8_t st = PST_ROW_OK;
    for (int a = 0; a < D; ++a)
        for (int b = 0; b < D; ++b) {
            M1[a * D + b] = mom(D, mB, a, b, -1, -1);
        }
    double cond = pst_mat_inverse(D, M1, v->M1inv);
    uint8_t cs = count < D ? PST_ROW_TOO_FEW : cond_status(op, cond);
    st = worse(st, cs);
    v->level = CS_BROOK;
    if (cs >= PST_ROW_RANK_DEFICIENT) {
        for (int a = 0; a < D * D; ++a)
            v->M1inv[a] = a % (D + 1) == 0 ? -1.0 : 0.0;
        v->status = count == 0 ? PST_ROW_TOO_FEW : st;
        return;
    }
    int last = neumann ? CS_ICSPM : CS_CSPH; /* Neumann: only ICSPM needs a second matrix */
    for (int lev = which; lev <= last; ++lev) {
        if (count < level_min(lev, D)) {
            st = worse(st, PST_ROW_TOO_FEW);
            continue;
        }
        double X[36];
        int n = lev == CS_CSPH ? D : n2;
        if (lev == CS_CSPH) {
            double mc[3 * CS_NM_MAX];
            if (which != CS_CSPH) { /* the C moments of a fallback row, as csph2g forms them */
                pst_cs_moments(k, CS_CSPH, i, mc);
                mC = mc + 2 * cs_nm(D);
            }
            for (int a = 0; a < D; ++a)
                for (int b = 0; b < D; ++b) {
                    X[a * D + b] = mom(D, mC, a, a, b, b);
                    v->N21[a * D + b] = mom(D, mC, a, a, b, -1); /* Ncr = sum C r_a^2 r_b */
                }
        } else {
            for (int p = 0; p < n2; ++p) {
                int pa = cs_pa(D, p), pb = cs_pb(D, p), diag = pa == pb;
                for (int c = 0; c < D; ++c) {
                    double v21 = mom(D, mA, pa, pb, c, -1);
                    if (diag) /* + delta_p sum B r_c */
                        v21 += mom(D, mB, c, -1, -1, -1);
                    v->N21[p * D + c] = v21;
                }
                for (int q = 0; q < n2; ++q) {
                    int qa = cs_pa(D, q), qb = cs_pb(D, q);
                    double f = qa == qb ? 1.0 : 2.0;
                    double m2 = mom(D, mA, pa, pb, qa, qb);
                    if (diag)
                        m2 += mom(D, mB, qa, qb, -1, -1);
                    X[p * n2 + q] = f * m2;
                }
            }
            if (lev == CS_ICSPM) {
                /* N12[a][q] = f_q sum B r_a r_qa r_qb; X -= N21 M1^-1 N12 (48) */
                for (int a = 0; a < D; ++a)
                    for (int q = 0; q < n2; ++q)
                        v->N12[a * n2 + q] = (cs_pa(D, q) == cs_pb(D, q) ? 1.0 : 2.0) *
                                             mom(D, mB, a, cs_pa(D, q), cs_pb(D, q), -1);
                double T[18];
                cs_n21_m1inv(D, v, T);
                for (int p = 0; p < n2; ++p)
                    for (int q = 0; q < n2; ++q) {
                        double s = 0;
                        for (int b = 0; b < D; ++b)
                            s += T[p * D + b] * v->N12[b * n2 + q];
                        X[p * n2 + q] -= s;
                    }
            }
        }
        uint8_t xs = cond_status(op, lev == CS_CSPH ? pst_mat_inverse(n, X, v->Xinv)
                                                    : lu_inverse(n, X, v->Xinv));
        st = worse(st, xs);
        if (xs == PST_ROW_RANK_DEFICIENT)
            continue;
        v->level = lev;
        break;
    }
    v->status = st;
}

/* The fallback chain of row i from its moments m (B, A and C back to back), per dimension so
 * that the index arithmetic folds to constants, compiled per ISA. */
PST_ISA_DISPATCH void pst_cs_invert(const pst_op *op, const cs_ctx *k, size_t i, int neumann,
                                   int count, const double *m, cs_inv *v)
{
    if (k->c.dim == 2)
        invert_t(op, k, 2, k->which, i, neumann, count, m, m + cs_nm(2), m + 2 * cs_nm(2), v);
    else
        invert_t(op, k, 3, k->which, i, neumann, count, m, m + cs_nm(3), m + 2 * cs_nm(3), v);
}

/* lam = 2 X^-T I over the diagonal components (n2 entries; D for CS_CSPH). */
static inline void lambda_of(int D, const cs_inv *v, double *lam)
{
    const int n2 = cs_n2(D);
    if (v->level == CS_CSPH) {
        for (int b = 0; b < D; ++b) {
            double s = 0;
            for (int a = 0; a < D; ++a)
                s += v->Xinv[a * D + b];
            lam[b] = 2.0 * s;
        }
        return;
    }
    for (int q = 0; q < n2; ++q) {
        double s = 0;
        for (int p = 0; p < n2; ++p)
            if (cs_pa(D, p) == cs_pb(D, p))
                s += v->Xinv[p * n2 + q];
        lam[q] = 2.0 * s;
    }
}

/* out = M1^-1 N^T lam with N = N21 (n2 x D) or Ncr (D x D): nr rows. */
static inline void mu_of(int D, const cs_inv *v, int nr, const double *lam, double *out)
{
    double t[3] = {0, 0, 0};
    for (int c = 0; c < D; ++c)
        for (int p = 0; p < nr; ++p)
            t[c] += v->N21[p * D + c] * lam[p];
    for (int a = 0; a < D; ++a) {
        out[a] = 0;
        for (int c = 0; c < D; ++c)
            out[a] += v->M1inv[a * D + c] * t[c];
    }
}

/* The coefficients of row i (cspm_family.c's head comment) from its inverses. */
PST_KHOT void coefficients_t(const cs_ctx *k, int D, size_t i, const cs_inv *v, double *Ki)
{
    const int n2 = cs_n2(D), nc = cs_ncoef(D);
    double *lam = Ki, *sig = Ki + n2, *mu = Ki + 2 * n2;
    for (int c = 0; c < nc; ++c)
        Ki[c] = 0;
    if (k->c.kind[i] == PST_NEUMANN) {
        /* n . (gradient weights): psi = M1^-1 n; ICSPM (47) adds the Hessian's share */
        double nv[3], psi[3];
        for (int a = 0; a < D; ++a)
            nv[a] = k->c.normal[a][i];
        for (int a = 0; a < D; ++a) {
            psi[a] = 0;
            for (int c = 0; c < D; ++c)
                psi[a] += v->M1inv[a * D + c] * nv[c];
        }
        for (int a = 0; a < D; ++a)
            mu[a] = -psi[a];
        if (v->level != CS_ICSPM)
            return;
        double t[6], kap[6], extra[3];
        for (int q = 0; q < n2; ++q) {
            t[q] = 0;
            for (int a = 0; a < D; ++a)
                t[q] += v->N12[a * n2 + q] * psi[a];
        }
        for (int p = 0; p < n2; ++p) { /* kappa = X^-T N12^T psi */
            kap[p] = 0;
            for (int q = 0; q < n2; ++q)
                kap[p] += v->Xinv[q * n2 + p] * t[q];
        }
        mu_of(D, v, n2, kap, extra);
        for (int p = 0; p < n2; ++p) {
            lam[p] = -kap[p];
            sig[p] = kap[p];
            if (cs_pa(D, p) == cs_pb(D, p))
                Ki[nc - 1] -= kap[p];
        }
        for (int a = 0; a < D; ++a)
            mu[a] -= extra[a];
        return;
    }
    if (v->level == CS_BROOK) {
        Ki[nc - 1] = -2.0; /* Brookshaw: -2 V W'/d >= 0 */
        return;
    }
    double l[6];
    lambda_of(D, v, l);
    if (v->level == CS_CSPH) {
        mu_of(D, v, D, l, mu);
        for (int a = 0, p = 0; p < n2; ++p)
            if (cs_pa(D, p) == cs_pb(D, p))
                sig[p] = l[a++];
        return;
    }
    mu_of(D, v, n2, l, mu);
    for (int p = 0; p < n2; ++p) {
        lam[p] = l[p];
        sig[p] = -l[p];
        if (cs_pa(D, p) == cs_pb(D, p))
            Ki[nc - 1] += l[p];
    }
}

PST_ISA_DISPATCH static void coefficients(const cs_ctx *k, size_t i, const cs_inv *v, double *Ki)
{
    if (k->c.dim == 2)
        coefficients_t(k, 2, i, v, Ki);
    else
        coefficients_t(k, 3, i, v, Ki);
}

void pst_cs_free(void *p)
{
    cs_data *d = p;
    if (!d)
        return;
    pst_free(d->V);
    pst_free(d->K);
    pst_free(d->G);
    pst_free(d->Hm);
    free(d);
}

/* Whether row i is fitted: every row but a Dirichlet one (the identity), which is fitted too
 * when derivatives are kept (its gradient is still wanted). */
static inline int fitted(const cs_ctx *k, int keep, size_t i)
{
    return keep || k->c.kind[i] != PST_DIRICHLET;
}

/* The moments pass of one block (moments_t), over the fitted rows. */
static void moments_block(const cs_ctx *k, int keep, size_t b0, size_t b1, double *mom_blk,
                          int *count)
{
    const int D = k->c.dim, nm = cs_nm(D);
    /* the moments of row i depend on row i's neighbours only: no write is shared */
#pragma omp parallel for schedule(dynamic, 64)
    for (size_t i = b0; i < b1; ++i) {
        double *m = mom_blk + (size_t)3 * nm * (i - b0);
        count[i - b0] = fitted(k, keep, i) ? pst_cs_moments(k, k->which, i, m) : 0;
    }
}

int pst_cs_precompute(pst_op *op, int which, char *err)
{
    size_t n = op->n;
    int D = op->dim, nm = cs_nm(D), nc = cs_ncoef(D);
    cs_data *d = pst_op_data(op, sizeof *d);
    if (!d)
        return PST_ENOMEM;
    d->which = which;
    const int keep = op->opts.keep, ng = cs_ng(D, which), nh = cs_n2(D) * cs_ns(D);
    PST_DATA_ARRAY(d->V, n * sizeof *d->V);
    PST_DATA_ARRAY(d->K, n * (size_t)nc * sizeof *d->K);
    int kept = 1;
    if (keep & PST_KEEP_GRADIENT)
        kept = PST_DATA_ARRAY(d->G, n * (size_t)(D * ng) * sizeof *d->G) != NULL;
    if (keep & PST_KEEP_HESSIAN)
        kept = kept && PST_DATA_ARRAY(d->Hm, n * (size_t)nh * sizeof *d->Hm) != NULL;
    size_t blk = n < CS_BLOCK ? n : CS_BLOCK;
    double *mom_blk = pst_alloc((blk ? blk : 1) * (size_t)(3 * nm) * sizeof *mom_blk);
    cs_inv *inv_blk = pst_alloc((blk ? blk : 1) * sizeof *inv_blk);
    int *count = pst_alloc((blk ? blk : 1) * sizeof *count);
    if (!d->V || !d->K || !kept || !mom_blk || !inv_blk || !count) {
        pst_free(mom_blk);
        pst_free(inv_blk);
        pst_free(count);
        pst_set_err(err, "%s: cannot allocate the per-particle data of %zu particles",
                    op->scheme->name, n);
        return PST_ENOMEM;
    }
    cs_ctx k = make_ctx(op);
    double t = omp_get_wtime();
    pst_cs_volumes(&k, d->V, n);
    op->phase[PST_PHASE_GEOMETRY] += omp_get_wtime() - t;
    for (size_t b0 = 0; b0 < n; b0 += blk) {
        size_t b1 = b0 + blk < n ? b0 + blk : n;
        t = omp_get_wtime();
        moments_block(&k, keep, b0, b1, mom_blk, count);
        op->phase[PST_PHASE_MOMENTS] += omp_get_wtime() - t;
        t = omp_get_wtime();
        /* per particle a 2x2/3x3 and a 3x3/6x6 inversion; bound by the LU (~300 flops 3D) */
#pragma omp parallel for schedule(static)
        for (size_t i = b0; i < b1; ++i) {
            const double *m = mom_blk + (size_t)3 * nm * (i - b0);
            if (!fitted(&k, keep, i))
                continue;
            pst_cs_invert(op, &k, i, k.c.kind[i] == PST_NEUMANN, count[i - b0], m,
                          &inv_blk[i - b0]);
        }
        op->phase[PST_PHASE_INVERSION] += omp_get_wtime() - t;
        t = omp_get_wtime();
#pragma omp parallel for schedule(static)
        for (size_t i = b0; i < b1; ++i) {
            double *Ki = d->K + (size_t)nc * i;
            if (keep)
                pst_cs_fold(D, ng, &inv_blk[i - b0], d->G ? d->G + (size_t)(D * ng) * i : NULL,
                            d->Hm ? d->Hm + (size_t)nh * i : NULL);
            if (k.c.kind[i] == PST_DIRICHLET) {
                memset(Ki, 0, (size_t)nc * sizeof *Ki);
                continue;
            }
            coefficients(&k, i, &inv_blk[i - b0], Ki);
            op->status[i] = inv_blk[i - b0].status;
        }
        op->phase[PST_PHASE_WEIGHTS] += omp_get_wtime() - t;
        pst_tally_add(op->tally, b1 - b0); /* the block's rows are done */
    }
    pst_free(mom_blk);
    pst_free(inv_blk);
    pst_free(count);
    return PST_OK;
}

/* A flat neighbourhood (pst_op_check_flat_rows): every level of the chain but the last is
 * linear-exact and so has no diagonal there; the row becomes the Brookshaw row normalised to
 * be exact for |x - x_I|^2, c0 = -2D / sum_J V_J (-W') d (-2 with a full support; a flat,
 * one-sided neighbourhood would otherwise give a row too weak to pin u_I). The gradient and
 * the Hessian do not read K: they take the fit's own matrices (kept or refitted). */
void pst_cs_degrade(pst_op *op, size_t i)
{
    cs_ctx k = make_ctx(op);
    cs_data *d = op->data;
    const int D = op->dim, nc = cs_ncoef(D);
    double hi = pst_h(&k.c, i), sum = 0;
    for (int64_t e = k.c.off[i]; e < k.c.off[i + 1]; ++e) {
        double r[3], dd = sqrt(pst_pair_offset(&k.c, D, i, k.c.idx[e], r));
        if (pst_pair_live(&k.c, dd, hi)) /* W' is 0 beyond the support */
            sum -= k.V[k.c.idx[e]] * pst_sph_dw(k.c.kernel, D, dd, hi) * dd;
    }
    double *Ki = d->K + (size_t)nc * i;
    for (int q = 0; q < nc - 1; ++q)
        Ki[q] = 0.0;
    Ki[nc - 1] = sum > 0 ? -2.0 * D / sum : 0.0;
}
