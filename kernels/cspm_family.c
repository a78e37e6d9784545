/* The CSPM family of the QSFDI paper's comparison schemes (spec qsfdi.md §2.1-§2.4, equation
 * numbers of Yan, Ma & Wang 2020): CSPM (38)-(41), ICSPM (7) = (47)-(48) with the Schur
 * complement M_2,ICSPM, and CSPH2Gamma (45), with the quintic kernel (9) and the volumes
 * V_j = 1 / sum_k W_jk (self term included) of a separate pre-pass.
 *
 * Notation: r = x_j - x_I, d = |r|, W' and W'' the radial derivatives of W(d, h_I) (I's own h
 * for I's fit), B_j = V_j W'/d, A_j = V_j (W'' - W'/d)/d^2, C_j = B_j/d^2, so that
 *     V grad W = B r,   V d_a d_b W = A r_a r_b + B delta_ab,   V check-grad W = C r^(2s).
 * Every row, whatever the scheme, its fallback or a Neumann row, has the weight
 *     a_Ij = V_j [ (W''/d^2) Q_lam(r) + (W'/d^3) Q_sig(r) + (W'/d) (c0 - mu . r) ]
 * with Q_c(r) = sum_p c_p r_a(p) r_b(p) over the packed second-derivative components p
 * (2D: xx, xy, yy; 3D: xx, xy, xz, yy, yz, zz) and per-particle coefficients (lam, sig, mu,
 * c0): 9 doubles in 2D, 16 in 3D. For CSPM / ICSPM lam = 2 X^-T I, mu = M1^-1 N21^T lam,
 * sig = -lam, c0 = tr lam (X = M2 or its Schur complement); for CSPH2Gamma lam = 0,
 * sig = 2 M2C^-T 1 on the diagonal slots, mu = M1^-1 Ncr^T sig, c0 = 0; the Brookshaw row is
 * c0 = -2 and the rest 0.
 * Fallback chain (docs/schemes/cspm.md): icspm -> cspm -> csph2g -> Brookshaw; a singular M1
 * gives the Brookshaw row directly. Never NaN. */
#include "kernel_common.h"
#include "small_matrix.h"
#include "sph_kernels.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

/* Levels of the fallback chain; a scheme starts at its own level. */
enum { CS_ICSPM = 0, CS_CSPM = 1, CS_CSPH = 2, CS_BROOK = 3 };


/* Particles per block of the precompute: the moments and inverses of one block are kept
 * between the timed passes (about 7 MB in 3D). */
#define CS_BLOCK 8192

/* Monomials of degree 1..4, ordered by degree, then by descending exponent of x, then of y
 * (2D: 14, 3D: 34). Moments are stored in this order. */
#define CS_NM_MAX 34
static const int cs_exp2[14][3] = {{1, 0, 0}, {0, 1, 0}, {2, 0, 0}, {1, 1, 0}, {0, 2, 0},
                                   {3, 0, 0}, {2, 1, 0}, {1, 2, 0}, {0, 3, 0}, {4, 0, 0},
                                   {3, 1, 0}, {2, 2, 0}, {1, 3, 0}, {0, 4, 0}};
static const int cs_exp3[34][3] = {
    {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {2, 0, 0}, {1, 1, 0}, {1, 0, 1}, {0, 2, 0},
    {0, 1, 1}, {0, 0, 2}, {3, 0, 0}, {2, 1, 0}, {2, 0, 1}, {1, 2, 0}, {1, 1, 1},
    {1, 0, 2}, {0, 3, 0}, {0, 2, 1}, {0, 1, 2}, {0, 0, 3}, {4, 0, 0}, {3, 1, 0},
    {3, 0, 1}, {2, 2, 0}, {2, 1, 1}, {2, 0, 2}, {1, 3, 0}, {1, 2, 1}, {1, 1, 2},
    {1, 0, 3}, {0, 4, 0}, {0, 3, 1}, {0, 2, 2}, {0, 1, 3}, {0, 0, 4}};
/* First index of each degree 0..5 (degree 0 unused). */
static const int cs_deg2[6] = {0, 0, 2, 5, 9, 14};
static const int cs_deg3[6] = {0, 0, 3, 9, 19, 34};

/* Packed second-derivative components p = (pa, pb), the order of (38)-(41). */
static const int cs_pa2[3] = {0, 0, 1}, cs_pb2[3] = {0, 1, 1};
static const int cs_pa3[6] = {0, 0, 0, 1, 1, 2}, cs_pb3[6] = {0, 1, 2, 1, 2, 2};

static inline int cs_nm(int D) { return D == 2 ? 14 : 34; }
static inline int cs_n2(int D) { return D * (D + 1) / 2; }
static inline int cs_ncoef(int D) { return D * (D + 1) + D + 1; }
static inline const int *cs_exp(int D, int k) { return D == 2 ? cs_exp2[k] : cs_exp3[k]; }
static inline int cs_deg(int D, int n) { return D == 2 ? cs_deg2[n] : cs_deg3[n]; }
static inline int cs_pa(int D, int p) { return D == 2 ? cs_pa2[p] : cs_pa3[p]; }
static inline int cs_pb(int D, int p) { return D == 2 ? cs_pb2[p] : cs_pb3[p]; }

/* Index of the monomial x^a y^b z^c (a + b + c in 1..4) in the order above. */
static inline int cs_index(int D, int a, int b, int c)
{
    int n = a + b + c;
    return D == 2 ? cs_deg2[n] + (n - a) : cs_deg3[n] + (n - a) * (n - a + 1) / 2 + (n - a - b);
}

typedef struct {
    int which;   /* CS_ICSPM, CS_CSPM or CS_CSPH                                  */
    double *V;   /* V_j = 1 / sum_k W(d_jk, h_j), self term included             */
    double *K;   /* cs_ncoef(dim) coefficients per particle: lam, sig, mu, c0    */
} cs_data;

/* Everything the pair functions read, gathered once per call. */
typedef struct {
    pst_kctx c;
    int which;            /* cs_data's */
    const double *V, *K;  /* cs_data's volumes (not the cloud's c.V) and coefficients */
} cs_ctx;

static cs_ctx make_ctx(const pst_op *op)
{
    const cs_data *d = op->data;
    return (cs_ctx){.c = pst_kctx_of(op), .which = d->which, .V = d->V, .K = d->K};
}

/* Hot functions (PST_KHOT) take the dimension D (and the scheme) as constants at their call
 * sites. */

/* Pair (i, j) with i's h: r = x_j - x_i, d, W'(d) and W''(d). Returns 0 for a degenerate pair
 * (d <= min_pair_distance h) or one beyond the support (then W' = W'' = 0 and it contributes nothing). */
PST_KHOT int pair_kernel(const cs_ctx *k, int D, size_t i, size_t j, double hi, double r[3],
                       double *d2, double *d, double *w1, double *w2)
{
    *d2 = pst_pair_offset(&k->c, D, i, j, r);
    *d = sqrt(*d2);
    if (!pst_pair_live(&k->c, *d, hi) || !(*d < pst_sph_support[k->c.kernel] * hi))
        return 0;
    *w1 = pst_sph_dw(k->c.kernel, D, *d, hi);
    *w2 = pst_sph_d2w(k->c.kernel, D, *d, hi);
    return 1;
}

/* a_Ij of the file comment. Shared by apply, emit_row and nothing else, so that the two apply
 * paths agree bit for bit. */
PST_KHOT double pair_weight(const cs_ctx *k, int D, size_t i, size_t j, double hi,
                          const double *Ki)
{
    double r[3], d2, d, w1, w2;
    if (!pair_kernel(k, D, i, j, hi, r, &d2, &d, &w1, &w2))
        return 0.0;
    const int n2 = cs_n2(D);
    const double *lam = Ki, *sig = Ki + n2, *mu = Ki + 2 * n2, c0 = Ki[2 * n2 + D];
    double ql = 0, qs = 0, mr = 0;
    for (int p = 0; p < n2; ++p) {
        double m = r[cs_pa(D, p)] * r[cs_pb(D, p)];
        ql += lam[p] * m;
        qs += sig[p] * m;
    }
    for (int a = 0; a < D; ++a)
        mr += mu[a] * r[a];
    double id2 = 1.0 / d2, a1 = w1 / d;
    return k->V[j] * ((w2 * ql + a1 * qs) * id2 + a1 * (c0 - mr));
}

/* Row i into y (apply) or its weights into w (emission). */
PST_KHOT void row_t(const cs_ctx *k, int D, size_t i, const double *u, double *y, double *w)
{
    const double *Ki = k->K + (size_t)cs_ncoef(D) * i;
    double hi = pst_h(&k->c, i);
    PST_ROW_LOOP(k->c.off, k->c.idx, i, u, y, w, j, pair_weight(k, D, i, j, hi, Ki));
}

static void row_2(const cs_ctx *k, size_t i, const double *u, double *y, double *w)
{
    row_t(k, 2, i, u, y, w);
}
static void row_3(const cs_ctx *k, size_t i, const double *u, double *y, double *w)
{
    row_t(k, 3, i, u, y, w);
}

/* ---- moments ------------------------------------------------------------------------------ */

/* Raw moments of row i: sum B m_k over degrees 1..3 (1..2 without ICSPM), sum A m_k and
 * sum C m_k over degrees 3..4, and, with data du (u_j - u_i), S1 = sum B r du and
 * S2_p = sum (A r_pa r_pb + B delta_p) du. Returns the number of contributing neighbours. */
PST_KHOT int moments_t(const cs_ctx *k, int D, int which, size_t i, double *mB, double *mA,
                     double *mC, const double *u, double *S1, double *S2)
{
    const int nm = cs_nm(D), d3 = cs_deg(D, 3), d5 = cs_deg(D, 5);
    const int nB = which == CS_ICSPM ? cs_deg(D, 4) : d3, needA = which != CS_CSPH;
    double hi = pst_h(&k->c, i);
    int count = 0;
    for (int m = 0; m < nm; ++m)
        mB[m] = mA[m] = mC[m] = 0;
    if (u) {
        for (int a = 0; a < D; ++a)
            S1[a] = 0;
        for (int p = 0; p < cs_n2(D); ++p)
            S2[p] = 0;
    }
    for (int64_t e = k->c.off[i]; e < k->c.off[i + 1]; ++e) {
        size_t j = k->c.idx[e];
        double r[3], d2, d, w1, w2;
        if (!pair_kernel(k, D, i, j, hi, r, &d2, &d, &w1, &w2))
            continue;
        ++count;
        double id2 = 1.0 / d2, B = k->V[j] * w1 / d, A = k->V[j] * (w2 - w1 / d) * id2,
               C = B * id2;
        double px[5] = {1, r[0], r[0] * r[0], 0, 0}, py[5] = {1, r[1], r[1] * r[1], 0, 0},
               pz[5] = {1, D == 3 ? r[2] : 0, D == 3 ? r[2] * r[2] : 0, 0, 0};
        for (int q = 3; q < 5; ++q) {
            px[q] = px[q - 1] * r[0];
            py[q] = py[q - 1] * r[1];
            pz[q] = pz[q - 1] * pz[1];
        }
        double mono[CS_NM_MAX];
        for (int m = 0; m < nm; ++m) {
            const int *ex = cs_exp(D, m);
            mono[m] = px[ex[0]] * py[ex[1]] * pz[ex[2]];
        }
        for (int m = 0; m < nB; ++m)
            mB[m] += B * mono[m];
        for (int m = d3; m < d5; ++m) {
            if (needA)
                mA[m] += A * mono[m];
            mC[m] += C * mono[m];
        }
        if (u) {
            double du = u[j] - u[i];
            for (int a = 0; a < D; ++a)
                S1[a] += B * r[a] * du;
            for (int p = 0; p < cs_n2(D); ++p)
                S2[p] += (A * r[cs_pa(D, p)] * r[cs_pb(D, p)] +
                          (cs_pa(D, p) == cs_pb(D, p) ? B : 0.0)) * du;
        }
    }
    return count;
}

/* One instantiation per (D, scheme); m holds the B, A and C moments back to back. */
typedef int (*moments_fn)(const cs_ctx *, size_t, double *, const double *, double *,
                          double *);
#define CS_MOM(D, W)                                                                           \
    static int moments_##D##_##W(const cs_ctx *k, size_t i, double *m, const double *u,        \
                                 double *S1, double *S2)                                       \
    {                                                                                          \
        return moments_t(k, D, W, i, m, m + cs_nm(D), m + 2 * cs_nm(D), u, S1, S2);            \
    }
CS_MOM(2, 0) CS_MOM(2, 1) CS_MOM(2, 2) CS_MOM(3, 0) CS_MOM(3, 1) CS_MOM(3, 2)
static const moments_fn moments_table[2][3] = {{moments_2_0, moments_2_1, moments_2_2},
                                               {moments_3_0, moments_3_1, moments_3_2}};

/* ---- the dense per-particle step --------------------------------------------------------- */

/* The inverses a row's coefficients need, kept between the inversion and weights passes. */
typedef struct {
    double M1inv[9];  /* M1^-1, or -I when M1 is singular (the kernel gradient)          */
    double Xinv[36];  /* inverse of M2,ICSPM (48), M2 (41) or M2,CSPH (45) of the level  */
    double N21[18];   /* sum V grad2 W r^T (n2 x D); for CS_CSPH Ncr = sum V chk W r^T     */
    double N12[18];   /* sum V grad W r^(2)T (D x n2), ICSPM only                          */
    int level;
    uint8_t status;
} cs_inv;

/* Minimum neighbours of each level (spec choice 6). */
static int level_min(int level, int D)
{
    return level == CS_ICSPM ? (D == 2 ? 5 : 9)
           : level == CS_CSPM ? (D == 2 ? 3 : 6)
           : level == CS_CSPH ? D
                              : 1;
}

static int cs_min_icspm(int dim) { return level_min(CS_ICSPM, dim); }
static int cs_min_cspm(int dim) { return level_min(CS_CSPM, dim); }
static int cs_min_csph(int dim) { return level_min(CS_CSPH, dim); }

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
static inline double lu_inverse(int n, const double *a, double *inv)
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

/* Moment of the monomial with exponents e. */
static inline double mom(int D, const double *m, const int e[3])
{
    return m[cs_index(D, e[0], e[1], e[2])];
}

/* Exponent vector of r_a r_b ... (up to four axes; -1 ends the list). */
static inline void exps(int e[3], int a, int b, int c, int d)
{
    e[0] = e[1] = e[2] = 0;
    e[a]++;
    e[b]++;
    if (c >= 0)
        e[c]++;
    if (d >= 0)
        e[d]++;
}

/* The fallback chain of row i from its moments: M1 first, then the scheme's level and the
 * ones below it until an invertible matrix is found. Neumann rows need only the gradient
 * (ICSPM's when it exists, else CSPM's). */
static void invert(const pst_op *op, int D, int which, int neumann, int count, const double *mB,
                   const double *mA, const double *mC, cs_inv *v)
{
    const int n2 = cs_n2(D);
    int e[3];
    double M1[9] = {0};
    uint8_t st = PST_ROW_OK;
    for (int a = 0; a < D; ++a)
        for (int b = 0; b < D; ++b) {
            exps(e, a, b, -1, -1);
            M1[a * D + b] = mom(D, mB, e);
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
            for (int a = 0; a < D; ++a)
                for (int b = 0; b < D; ++b) {
                    exps(e, a, a, b, b);
                    X[a * D + b] = mom(D, mC, e);
                    exps(e, a, a, b, -1);
                    v->N21[a * D + b] = mom(D, mC, e); /* Ncr[a][b] = sum C r_a^2 r_b */
                }
        } else {
            for (int p = 0; p < n2; ++p) {
                int pa = cs_pa(D, p), pb = cs_pb(D, p), diag = pa == pb;
                for (int c = 0; c < D; ++c) {
                    exps(e, pa, pb, c, -1);
                    double v21 = mom(D, mA, e);
                    if (diag) { /* + delta_p sum B r_c */
                        e[0] = e[1] = e[2] = 0;
                        e[c] = 1;
                        v21 += mom(D, mB, e);
                    }
                    v->N21[p * D + c] = v21;
                }
                for (int q = 0; q < n2; ++q) {
                    int qa = cs_pa(D, q), qb = cs_pb(D, q);
                    double f = qa == qb ? 1.0 : 2.0;
                    exps(e, pa, pb, qa, qb);
                    double m2 = mom(D, mA, e);
                    if (diag) {
                        exps(e, qa, qb, -1, -1);
                        m2 += mom(D, mB, e);
                    }
                    X[p * n2 + q] = f * m2;
                }
            }
            if (lev == CS_ICSPM) {
                /* N12[a][q] = f_q sum B r_a r_qa r_qb; X -= N21 M1^-1 N12 (48) */
                for (int a = 0; a < D; ++a)
                    for (int q = 0; q < n2; ++q) {
                        exps(e, a, cs_pa(D, q), cs_pb(D, q), -1);
                        v->N12[a * n2 + q] =
                            (cs_pa(D, q) == cs_pb(D, q) ? 1.0 : 2.0) * mom(D, mB, e);
                    }
                double T[18];
                for (int p = 0; p < n2; ++p)
                    for (int b = 0; b < D; ++b) {
                        double s = 0;
                        for (int c = 0; c < D; ++c)
                            s += v->N21[p * D + c] * v->M1inv[c * D + b];
                        T[p * D + b] = s;
                    }
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

/* The coefficients of row i (file comment) from its inverses. */
static void coefficients(const cs_ctx *k, int D, size_t i, const cs_inv *v, double *Ki)
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

/* ---- precompute --------------------------------------------------------------------------- */

static void cs_free(void *p)
{
    cs_data *d = p;
    if (!d)
        return;
    pst_free(d->V);
    pst_free(d->K);
    free(d);
}

/* V_j = 1 / (W(0, h_j) + sum_k W(d_jk, h_j)): j's number density with its own h. Bound by the
 * kernel evaluation (a sqrt and ~25 flops per pair). */
static void volumes(const cs_ctx *k, double *V, size_t n)
{
    const int D = k->c.dim;
#pragma omp parallel for schedule(dynamic, 512)
    for (size_t j = 0; j < n; ++j) {
        double hj = pst_h(&k->c, j), s = pst_sph_w(k->c.kernel, D, 0.0, hj);
        for (int64_t e = k->c.off[j]; e < k->c.off[j + 1]; ++e) {
            size_t m = k->c.idx[e];
            double d2 = 0;
            for (int a = 0; a < D; ++a) {
                double t = k->c.x[a][m] - k->c.x[a][j];
                d2 += t * t;
            }
            s += pst_sph_w(k->c.kernel, D, sqrt(d2), hj);
        }
        V[j] = 1.0 / s; /* s >= W(0) > 0 */
    }
}

/* The moments pass of one block, bound by the per-pair kernel and 14-69 FMAs (2D-3D). */
static void moments_block(const cs_ctx *k, size_t b0, size_t b1, double *mom_blk, int *count)
{
    const int D = k->c.dim, nm = cs_nm(D);
    /* the moments of row i depend on row i's neighbours only: no write is shared */
#pragma omp parallel for schedule(dynamic, 64)
    for (size_t i = b0; i < b1; ++i) {
        double *m = mom_blk + (size_t)3 * nm * (i - b0);
        if (k->c.kind[i] == PST_DIRICHLET) {
            count[i - b0] = 0;
            continue;
        }
        int c = moments_table[D - 2][k->which](k, i, m, NULL, NULL, NULL);
        count[i - b0] = c;
    }
}

static int precompute(pst_op *op, int which, char *err)
{
    size_t n = op->n;
    int D = op->dim, nm = cs_nm(D), nc = cs_ncoef(D);
    cs_data *d = calloc(1, sizeof *d);
    if (!d)
        return PST_ENOMEM;
    op->data = d;
    d->which = which;
    d->V = pst_alloc(n * sizeof *d->V);
    d->K = pst_alloc(n * (size_t)nc * sizeof *d->K);
    size_t blk = n < CS_BLOCK ? n : CS_BLOCK;
    double *mom_blk = pst_alloc((blk ? blk : 1) * (size_t)(3 * nm) * sizeof *mom_blk);
    cs_inv *inv_blk = pst_alloc((blk ? blk : 1) * sizeof *inv_blk);
    int *count = pst_alloc((blk ? blk : 1) * sizeof *count);
    if (!d->V || !d->K || !mom_blk || !inv_blk || !count) {
        pst_free(mom_blk);
        pst_free(inv_blk);
        pst_free(count);
        pst_set_err(err, "%s: cannot allocate the per-particle data of %zu particles",
                    op->scheme->name, n);
        return PST_ENOMEM;
    }
    cs_ctx k = make_ctx(op);
    double t = omp_get_wtime();
    volumes(&k, d->V, n);
    op->phase[PST_PHASE_GEOMETRY] += omp_get_wtime() - t;
    for (size_t b0 = 0; b0 < n; b0 += blk) {
        size_t b1 = b0 + blk < n ? b0 + blk : n;
        t = omp_get_wtime();
        moments_block(&k, b0, b1, mom_blk, count);
        op->phase[PST_PHASE_MOMENTS] += omp_get_wtime() - t;
        t = omp_get_wtime();
        /* per particle a 2x2/3x3 and a 3x3/6x6 inversion; bound by the LU (~300 flops 3D) */
#pragma omp parallel for schedule(static)
        for (size_t i = b0; i < b1; ++i) {
            const double *m = mom_blk + (size_t)3 * nm * (i - b0);
            if (k.c.kind[i] == PST_DIRICHLET)
                continue;
            invert(op, D, which, k.c.kind[i] == PST_NEUMANN, count[i - b0], m, m + nm,
                   m + 2 * nm, &inv_blk[i - b0]);
        }
        op->phase[PST_PHASE_INVERSION] += omp_get_wtime() - t;
        t = omp_get_wtime();
#pragma omp parallel for schedule(static)
        for (size_t i = b0; i < b1; ++i) {
            double *Ki = d->K + (size_t)nc * i;
            if (k.c.kind[i] == PST_DIRICHLET) {
                memset(Ki, 0, (size_t)nc * sizeof *Ki);
                continue;
            }
            coefficients(&k, D, i, &inv_blk[i - b0], Ki);
            op->status[i] = inv_blk[i - b0].status;
        }
        op->phase[PST_PHASE_WEIGHTS] += omp_get_wtime() - t;
    }
    pst_free(mom_blk);
    pst_free(inv_blk);
    pst_free(count);
    return PST_OK;
}

static int pre_icspm(pst_op *op, char *err) { return precompute(op, CS_ICSPM, err); }
static int pre_cspm(pst_op *op, char *err) { return precompute(op, CS_CSPM, err); }
static int pre_csph(pst_op *op, char *err) { return precompute(op, CS_CSPH, err); }

/* ---- apply, emission, gradient, Hessian ---------------------------------------------------- */

/* Matrix-free apply: each pair's weight from the positions, V_j and the row's coefficients.
 * Compute-bound: a sqrt, two divisions and ~60 flops (2D) / ~75 (3D) per pair against 4 bytes
 * of list, 8 of V_j and 8 of u_J gathered. */
static void cs_apply(const pst_op *op, const double *u, double *y)
{
    cs_ctx k = make_ctx(op);
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < op->n; ++i)
        if (k.c.kind[i] != PST_DIRICHLET) {
            if (k.c.dim == 2)
                row_2(&k, i, u, y, NULL);
            else
                row_3(&k, i, u, y, NULL);
        }
}

static void cs_emit_row(const pst_op *op, size_t i, double *w)
{
    cs_ctx k = make_ctx(op);
    if (k.c.dim == 2)
        row_2(&k, i, NULL, NULL, w);
    else
        row_3(&k, i, NULL, NULL, w);
}

/* Gradient and packed second derivatives of row i, refitted from the moments and the data
 * sums with the same chain as the precompute: ICSPM (47) on its level, the CSPM gradient (40)
 * elsewhere (the kernel gradient where M1 is singular); second derivatives from X (ICSPM's
 * Schur complement, or CSPM's M2 on that level; 0 on the others). */
static void refit(const pst_op *op, const cs_ctx *k, size_t i, const double *u, double *g,
                  double *hs)
{
    const int D = k->c.dim, nm = cs_nm(D), n2 = cs_n2(D);
    double m[3 * CS_NM_MAX], S1[3], S2[6];
    int count = moments_table[D - 2][k->which](k, i, m, u, S1, S2);
    cs_inv v;
    invert(op, D, k->which, k->c.kind[i] == PST_NEUMANN, count, m, m + nm, m + 2 * nm, &v);
    double H[6] = {0, 0, 0, 0, 0, 0}, t[6], gs[3];
    if (v.level == CS_ICSPM || v.level == CS_CSPM) {
        /* H = 2 X^-1 (S2 - N21 M1^-1 S1) */
        for (int a = 0; a < D; ++a) {
            gs[a] = 0;
            for (int c = 0; c < D; ++c)
                gs[a] += v.M1inv[a * D + c] * S1[c];
        }
        for (int p = 0; p < n2; ++p) {
            t[p] = S2[p];
            for (int c = 0; c < D; ++c)
                t[p] -= v.N21[p * D + c] * gs[c];
        }
        for (int p = 0; p < n2; ++p) {
            for (int q = 0; q < n2; ++q)
                H[p] += v.Xinv[p * n2 + q] * t[q];
            H[p] *= 2.0;
        }
    }
    double s[3];
    for (int a = 0; a < D; ++a)
        s[a] = S1[a];
    if (v.level == CS_ICSPM) /* (47): S1 - N12 H / 2 */
        for (int a = 0; a < D; ++a)
            for (int q = 0; q < n2; ++q)
                s[a] -= 0.5 * v.N12[a * n2 + q] * H[q];
    for (int a = 0; a < D; ++a) {
        g[a] = 0;
        for (int c = 0; c < D; ++c)
            g[a] += v.M1inv[a * D + c] * s[c];
    }
    if (hs)
        for (int p = 0; p < n2; ++p)
            hs[p] = H[p];
}

static void cs_gradient(const pst_op *op, const double *u, double *const grad[3])
{
    cs_ctx k = make_ctx(op);
#pragma omp parallel for schedule(dynamic, 256)
    for (size_t i = 0; i < op->n; ++i) {
        double g[3];
        refit(op, &k, i, u, g, NULL);
        for (int a = 0; a < k.c.dim; ++a)
            grad[a][i] = g[a];
    }
}

/* pst_op_hessian's layout: 2D xx, yy, xy; 3D xx, yy, zz, xy, xz, yz (from the packed order). */
static void cs_hessian(const pst_op *op, const double *u, double *const hess[6])
{
    static const int out2[3] = {0, 2, 1}, out3[6] = {0, 3, 4, 1, 5, 2};
    cs_ctx k = make_ctx(op);
    int n2 = cs_n2(k.c.dim);
#pragma omp parallel for schedule(dynamic, 256)
    for (size_t i = 0; i < op->n; ++i) {
        double g[3], hs[6];
        refit(op, &k, i, u, g, hs);
        for (int p = 0; p < n2; ++p)
            hess[k.c.dim == 2 ? out2[p] : out3[p]][i] = hs[p];
    }
}

/* A flat neighbourhood (pst_op_check_flat_rows): every level of the chain but the last is
 * linear-exact and so has no diagonal there; the row becomes the Brookshaw row normalised to
 * be exact for |x - x_I|^2, c0 = -2D / sum_J V_J (-W') d (-2 with a full support; a flat,
 * one-sided neighbourhood would otherwise give a row too weak to pin u_I). The gradient and
 * Hessian hooks refit from scratch and do not read K. */
static void cs_degrade(pst_op *op, size_t i)
{
    cs_ctx k = make_ctx(op);
    cs_data *d = op->data;
    const int D = op->dim, nc = cs_ncoef(D);
    double hi = pst_h(&k.c, i), sum = 0;
    for (int64_t e = k.c.off[i]; e < k.c.off[i + 1]; ++e) {
        double r[3], d2, dd, w1, w2;
        if (pair_kernel(&k, D, i, k.c.idx[e], hi, r, &d2, &dd, &w1, &w2))
            sum -= k.V[k.c.idx[e]] * w1 * dd;
    }
    double *Ki = d->K + (size_t)nc * i;
    for (int q = 0; q < nc - 1; ++q)
        Ki[q] = 0.0;
    Ki[nc - 1] = sum > 0 ? -2.0 * D / sum : 0.0;
}

#define CS_SCHEME(ID, NAME, DESC, FALLBACK, DEG, PRE, MIN, HESS)                              \
    const pst_scheme ID = {.name = NAME,                                                      \
                           .description = DESC,                                               \
                           .fallback = FALLBACK,                                              \
                           .default_kernel = PST_KERNEL_QUINTIC,                              \
                           .degree = DEG,                                                     \
                           .degree_lattice = 2,                                               \
                           .min_neighbours = MIN,                                             \
                           .precompute = PRE,                                                 \
                           .apply = cs_apply,                                                 \
                           .emit_row = cs_emit_row,                                           \
                           .gradient = cs_gradient,                                           \
                           .hessian = HESS,                                                   \
                           .degrade = cs_degrade,                                             \
                           .free_data = cs_free,                                              \
                           .data_bytes = {80, 136}} /* V and cs_ncoef = 9 / 16 doubles */

CS_SCHEME(pst_scheme_cspm, "cspm", "CSPM, Chen et al. 1999 (QSFDI eqs. 38-41)",
          "too few neighbours or singular -> csph2g row -> Brookshaw row -> zero row; flat "
          "neighbours off the particle -> normalised Brookshaw row",
          1, pre_cspm, cs_min_cspm, NULL);
CS_SCHEME(pst_scheme_icspm, "icspm", "improved CSPM, quadratic-exact (QSFDI eqs. 7, 47-48)",
          "too few neighbours or singular -> cspm row -> csph2g row -> Brookshaw row -> zero "
          "row; flat neighbours off the particle -> normalised Brookshaw row",
          2, pre_icspm, cs_min_icspm, cs_hessian);
CS_SCHEME(pst_scheme_csph2g, "csph2g", "CSPH2Gamma, Schwaiger's variant (QSFDI eq. 45)",
          "too few neighbours or singular -> Brookshaw row -> zero row; flat neighbours off "
          "the particle -> normalised Brookshaw row",
          1, pre_csph, cs_min_csph, NULL);

/* The volumes of a CSPM-family operator (NULL for other schemes). Internal: for the tests. */
const double *pst_cspm_volumes(const pst_op *op);
const double *pst_cspm_volumes(const pst_op *op)
{
    return op->scheme->free_data == cs_free ? ((const cs_data *)op->data)->V : NULL;
}
