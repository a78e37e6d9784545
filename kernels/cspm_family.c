/* The CSPM family of the QSFDI paper's comparison schemes (docs/schemes/cspm.md, equation
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
#include "isa.h"
#include "kernel_common.h"
#include "small_matrix.h"
#include "sph_kernels.h"
#include "wls_sums.h"

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
/* First index of each degree 0..5 (degree 0 unused). */
static const int cs_deg2[6] = {0, 0, 2, 5, 9, 14};
static const int cs_deg3[6] = {0, 0, 3, 9, 19, 34};

/* Packed second-derivative components p = (pa, pb), the order of (38)-(41). */
static const int cs_pa2[3] = {0, 0, 1}, cs_pb2[3] = {0, 1, 1};
static const int cs_pa3[6] = {0, 0, 0, 1, 1, 2}, cs_pb3[6] = {0, 1, 2, 1, 2, 2};

static inline int cs_nm(int D) { return D == 2 ? 14 : 34; }
static inline int cs_n2(int D) { return D * (D + 1) / 2; }
static inline int cs_ncoef(int D) { return D * (D + 1) + D + 1; }
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

/* ---- the pair pass ------------------------------------------------------------------------ */

/* Every pass over a row's neighbours (volumes, moments, weights) gathers them, a chunk at a
 * time, into stack arrays (structure of arrays), evaluates the kernel once per pair in one
 * vectorised loop and forms its sums as separate vectorised reduction loops, as qsfdi.c does.
 * The order of a vectorised sum is fixed by the code, the same for every row and thread:
 * results do not depend on the thread count. A 3D row (~190 neighbours) is one chunk. */
#define CS_CHUNK 256

typedef struct {
    double r[3][CS_CHUNK];                        /* r = x_j - x_i                        */
    double b[CS_CHUNK], a[CS_CHUNK], c[CS_CHUNK]; /* V_j, d^2, d; then B, A, C            */
} cs_chunk;

/* The row's kernel constants: 1/h, sigma h^-(D+1) and sigma h^-(D+2) (pst_sph_eval's factors,
 * so W' and W'' are its values bit for bit), the live range (eps h, support h). */
typedef struct {
    double ih, s1, s2, lo, hi;
} cs_kc;

static inline cs_kc kc_of(const cs_ctx *k, int D, double h)
{
    const double ih = 1.0 / h, sg = pst_sph_sigma[k->c.kernel][D - 1];
    return (cs_kc){.ih = ih, .s1 = sg * pst_sph_ipow(ih, D + 1), .s2 = sg * pst_sph_ipow(ih, D + 2),
                   .lo = k->c.pair_eps * h, .hi = pst_sph_support[k->c.kernel] * h};
}

/* F(kernel, ...) with the kernel a constant: one vectorised instantiation per kernel. */
#define CS_BY_KERNEL(K, F, ...)                                                                \
    ((K) == PST_KERNEL_CUBIC           ? F(PST_KERNEL_CUBIC, __VA_ARGS__)                      \
     : (K) == PST_KERNEL_QUINTIC       ? F(PST_KERNEL_QUINTIC, __VA_ARGS__)                    \
     : (K) == PST_KERNEL_WENDLAND_C2   ? F(PST_KERNEL_WENDLAND_C2, __VA_ARGS__)                \
                                       : F(PST_KERNEL_WENDLAND_C4, __VA_ARGS__))

/* r, d^2 and d of the neighbours idx[0..n) of xi into g, with V_j (withV) into g->b. Three
 * loops, so that only the sqrt stays scalar (GCC does not vectorise sqrt while it may set
 * errno, the default -fmath-errno). d is pst_pair_offset's, bit for bit. */
PST_KHOT void cs_gather(const cs_ctx *k, int D, int withV, const double xi[3],
                        const uint32_t *idx, int n, cs_chunk *g)
{
    for (int c = 0; c < n; ++c) {
        for (int a = 0; a < D; ++a)
            g->r[a][c] = pst_offset(&k->c, a, k->c.x[a][idx[c]], xi[a]);
        if (withV)
            g->b[c] = k->V[idx[c]];
    }
    for (int c = 0; c < n; ++c)
        g->a[c] = g->r[0][c] * g->r[0][c] + g->r[1][c] * g->r[1][c] +
                  (D == 3 ? g->r[2][c] * g->r[2][c] : 0.0);
    for (int c = 0; c < n; ++c)
        g->c[c] = sqrt(g->a[c]);
}

/* The live mask of a pair at distance d and, with it, 1/d (0 for a dead pair, never a
 * division by 0): arithmetic on the mask rather than selects of computed values, which GCC
 * turns back into branches (it may not speculate the division). */
#define CS_LIVE(kc, d, in, id)                                                                 \
    double in = (((d) > (kc)->lo) & ((d) < (kc)->hi)) ? 1.0 : 0.0;                             \
    double id = in / ((d) + (1.0 - in))

/* B, A and C (file comment) of the chunk from V_j (g->b) and d (g->c), in place; 0 for a dead
 * pair. Returns the live pairs (counted in a double: an integer count of double compares does
 * not vectorise with SSE2). One division per pair. */
PST_KHOT int cs_bac(pst_kernel K, int D, const cs_kc *kc, int n, cs_chunk *g)
{
    double live = 0;
#pragma omp simd reduction(+ : live)
    for (int c = 0; c < n; ++c) {
        const double d = g->c[c], V = g->b[c], q = d * kc->ih;
        CS_LIVE(kc, d, in, id);
        double w1 = kc->s1 * pst_sph_shape(K, D, q, 1), w2 = kc->s2 * pst_sph_shape(K, D, q, 2);
        double id2 = id * id, a1 = w1 * id, B = V * a1;
        g->b[c] = B;
        g->a[c] = V * (w2 - a1) * id2;
        g->c[c] = B * id2;
        live += in;
    }
    return (int)live;
}

/* a_Ij of the file comment for the chunk (V_j in g->b, d in g->c) into w; 0 for a dead pair.
 * Shared by apply and emit_row, so that the two apply paths agree bit for bit (elementwise
 * IEEE arithmetic: every ISA clone gives the same weights). */
PST_KHOT void cs_weights(pst_kernel K, int D, const cs_kc *kc, const double *Ki, int n,
                         const cs_chunk *g, double *restrict w)
{
    const int n2 = cs_n2(D);
    const double *lam = Ki, *sig = Ki + n2, *mu = Ki + 2 * n2, c0 = Ki[2 * n2 + D];
#pragma omp simd
    for (int c = 0; c < n; ++c) {
        const double d = g->c[c], q = d * kc->ih;
        CS_LIVE(kc, d, in, id);
        double w1 = kc->s1 * pst_sph_shape(K, D, q, 1), w2 = kc->s2 * pst_sph_shape(K, D, q, 2);
        double ql = 0, qs = 0, mr = 0;
        for (int p = 0; p < n2; ++p) {
            double m = g->r[cs_pa(D, p)][c] * g->r[cs_pb(D, p)][c];
            ql += lam[p] * m;
            qs += sig[p] * m;
        }
        for (int a = 0; a < D; ++a)
            mr += mu[a] * g->r[a][c];
        double id2 = id * id, a1 = w1 * id;
        w[c] = g->b[c] * ((w2 * ql + a1 * qs) * id2 + a1 * (c0 - mr));
    }
}

/* s[e] += the e-th accumulator. */
#define CS_ADD(s, ...)                                                                         \
    do {                                                                                       \
        const double acc_[] = {__VA_ARGS__};                                                   \
        for (size_t e_ = 0; e_ < sizeof acc_ / sizeof *acc_; ++e_)                             \
            (s)[e_] += acc_[e_];                                                               \
    } while (0)

/* s[.] += sum_c w_c m(r_c) over the monomials m of degree 1 and 2 (2D: 5, 3D: 9) in the moment
 * order. One accumulator per monomial, so the
 * reduction loops vectorise with independent add chains. */
PST_KHOT void cs_sum12(int D, int n, const cs_chunk *g, const double *w, double *s)
{
    const double *x = g->r[0], *y = g->r[1], *z = g->r[2];
    if (D == 2) {
        double a0 = 0, a1 = 0, a2 = 0, a3 = 0, a4 = 0;
#pragma omp simd reduction(+ : a0, a1, a2, a3, a4)
        for (int c = 0; c < n; ++c) {
            double wx = w[c] * x[c], wy = w[c] * y[c];
            a0 += wx;
            a1 += wy;
            a2 += wx * x[c];
            a3 += wx * y[c];
            a4 += wy * y[c];
        }
        CS_ADD(s, a0, a1, a2, a3, a4);
        return;
    }
    double a0 = 0, a1 = 0, a2 = 0, a3 = 0, a4 = 0, a5 = 0, a6 = 0, a7 = 0, a8 = 0;
#pragma omp simd reduction(+ : a0, a1, a2, a3, a4, a5, a6, a7, a8)
    for (int c = 0; c < n; ++c) {
        double wx = w[c] * x[c], wy = w[c] * y[c], wz = w[c] * z[c];
        a0 += wx;
        a1 += wy;
        a2 += wz;
        a3 += wx * x[c];
        a4 += wx * y[c];
        a5 += wx * z[c];
        a6 += wy * y[c];
        a7 += wy * z[c];
        a8 += wz * z[c];
    }
    CS_ADD(s, a0, a1, a2, a3, a4, a5, a6, a7, a8);
}

/* Degree 3 and 4: the WLS engine's sums over the same arrays (wls_sums.h). */
PST_KHOT void cs_sum3(int D, int n, const cs_chunk *g, const double *w, double *s)
{
    wls_msum3(D, n, g->r[0], g->r[1], g->r[2], w, s);
}

PST_KHOT void cs_sum4(int D, int n, const cs_chunk *g, const double *w, double *s)
{
    wls_msum4(D, n, g->r[0], g->r[1], g->r[2], w, s);
}

/* Row i into y (apply) or its weights into w (emission), a chunk at a time. */
PST_KHOT void row_t(const cs_ctx *k, int D, size_t i, const double *u, double *y, double *w)
{
    const double *Ki = k->K + (size_t)cs_ncoef(D) * i;
    const double xi[3] = {k->c.x[0][i], k->c.x[1][i], D == 3 ? k->c.x[2][i] : 0.0};
    const cs_kc kc = kc_of(k, D, pst_h(&k->c, i));
    const int64_t e0 = k->c.off[i], e1 = k->c.off[i + 1];
    double s = 0, ui = u ? u[i] : 0, wb[CS_CHUNK];
    for (int64_t c0 = e0; c0 < e1; c0 += CS_CHUNK) {
        const int n = (int)(e1 - c0 < CS_CHUNK ? e1 - c0 : CS_CHUNK);
        const uint32_t *idx = k->c.idx + c0;
        cs_chunk g;
        cs_gather(k, D, 1, xi, idx, n, &g);
        double *wc = w ? w + (c0 - e0) : wb;
        CS_BY_KERNEL(k->c.kernel, cs_weights, D, &kc, Ki, n, &g, wc);
        if (!w) {
#pragma omp simd reduction(+ : s)
            for (int c = 0; c < n; ++c)
                s += wb[c] * (u[idx[c]] - ui);
        }
    }
    if (!w)
        y[i] = s;
}

PST_ISA_DISPATCH static void row(const cs_ctx *k, size_t i, const double *u, double *y, double *w)
{
    if (k->c.dim == 2)
        row_t(k, 2, i, u, y, w);
    else
        row_t(k, 3, i, u, y, w);
}

/* ---- moments ------------------------------------------------------------------------------ */

/* Raw moments of row i: sum B m_k over degrees 1..3 (1..2 without ICSPM), sum A m_k (not for
 * CSPH) and sum C m_k (CSPH only: the others need them only on a fallback to CSPH, where
 * invert_t computes them) over degrees 3..4, and, with data du (u_j - u_i), S1 = sum B r du and
 * S2_p = sum (A r_pa r_pb + B delta_p) du. Returns the number of contributing neighbours. One
 * pass: per chunk the kernel loop, then 3 (csph2g) to 4 (icspm) reduction loops of 4-15 sums.
 * Compute-bound, the scalar sqrt ~30 % of it (perf, 1 thread). The whole precompute, 3D 10^6 at
 * 2 threads: 21 (csph2g) / 24 (cspm) / 22 (icspm) ns per neighbour and thread, qsfdi 23, was
 * 70-88 (bench/README.md). */
PST_KHOT int moments_t(const cs_ctx *k, int D, int which, size_t i, double *mB, double *mA,
                     double *mC, const double *u, double *S1, double *S2)
{
    const int nm = cs_nm(D), n2 = cs_n2(D), d3 = cs_deg(D, 3), d4 = cs_deg(D, 4);
    const double xi[3] = {k->c.x[0][i], k->c.x[1][i], D == 3 ? k->c.x[2][i] : 0.0};
    const cs_kc kc = kc_of(k, D, pst_h(&k->c, i));
    const int64_t e0 = k->c.off[i], e1 = k->c.off[i + 1];
    double dB[9] = {0}, dA[9] = {0}, sB = 0; /* the data sums: sum (B, A) du m, sum B du */
    int count = 0;
    for (int m = 0; m < nm; ++m)
        mB[m] = mA[m] = mC[m] = 0;
    for (int64_t c0 = e0; c0 < e1; c0 += CS_CHUNK) {
        const int n = (int)(e1 - c0 < CS_CHUNK ? e1 - c0 : CS_CHUNK);
        const uint32_t *idx = k->c.idx + c0;
        cs_chunk g;
        cs_gather(k, D, 1, xi, idx, n, &g);
        count += CS_BY_KERNEL(k->c.kernel, cs_bac, D, &kc, n, &g);
        cs_sum12(D, n, &g, g.b, mB);
        if (which == CS_ICSPM)
            cs_sum3(D, n, &g, g.b, mB + d3);
        if (which != CS_CSPH) {
            cs_sum3(D, n, &g, g.a, mA + d3);
            cs_sum4(D, n, &g, g.a, mA + d4);
        }
        if (which == CS_CSPH) {
            cs_sum3(D, n, &g, g.c, mC + d3);
            cs_sum4(D, n, &g, g.c, mC + d4);
        }
        if (u) {
            double bu[CS_CHUNK], au[CS_CHUNK];
            for (int c = 0; c < n; ++c) {
                double du = u[idx[c]] - u[i];
                bu[c] = g.b[c] * du;
                au[c] = g.a[c] * du;
                sB += bu[c];
            }
            cs_sum12(D, n, &g, bu, dB);
            cs_sum12(D, n, &g, au, dA);
        }
    }
    if (u) {
        for (int a = 0; a < D; ++a)
            S1[a] = dB[a];
        for (int p = 0; p < n2; ++p)
            S2[p] = dA[D + p] + (cs_pa(D, p) == cs_pb(D, p) ? sB : 0.0);
    }
    return count;
}

/* One instantiation per (D, scheme), each compiled per ISA; m holds the B, A and C moments
 * back to back. */
typedef int (*moments_fn)(const cs_ctx *, size_t, double *, const double *, double *,
                          double *);
#define CS_MOM(D, W)                                                                           \
    PST_ISA_DISPATCH static int moments_##D##_##W(const cs_ctx *k, size_t i, double *m,        \
                                                  const double *u, double *S1, double *S2)     \
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

/* Minimum neighbours of each level (choice 6, docs/choices.md). */
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
                moments_table[D - 2][CS_CSPH](k, i, mc, NULL, NULL, NULL);
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

/* The fallback chain of row i from its moments m (B, A and C back to back), per dimension so
 * that the index arithmetic folds to constants, compiled per ISA. */
PST_ISA_DISPATCH static void invert(const pst_op *op, const cs_ctx *k, size_t i, int neumann,
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

/* The coefficients of row i (file comment) from its inverses. */
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

/* sum_k f(d_jk / h_j) over the chunk's distances (g->c) within the support, for the kernel
 * shape f (the constant sigma / h^D is applied once, by the caller). */
PST_KHOT double shape_sum(pst_kernel K, int D, const cs_kc *kc, int n, const cs_chunk *g)
{
    double s = 0;
#pragma omp simd reduction(+ : s)
    for (int c = 0; c < n; ++c) {
        double in = g->c[c] < kc->hi ? 1.0 : 0.0;
        s += in * pst_sph_shape(K, D, g->c[c] * kc->ih, 0);
    }
    return s;
}

PST_KHOT double volume_t(const cs_ctx *k, int D, size_t j)
{
    const double xj[3] = {k->c.x[0][j], k->c.x[1][j], D == 3 ? k->c.x[2][j] : 0.0};
    const double h = pst_h(&k->c, j);
    const cs_kc kc = kc_of(k, D, h);
    const int64_t e0 = k->c.off[j], e1 = k->c.off[j + 1];
    double s = 0;
    for (int64_t c0 = e0; c0 < e1; c0 += CS_CHUNK) {
        const int n = (int)(e1 - c0 < CS_CHUNK ? e1 - c0 : CS_CHUNK);
        cs_chunk g;
        cs_gather(k, D, 0, xj, k->c.idx + c0, n, &g);
        s += CS_BY_KERNEL(k->c.kernel, shape_sum, D, &kc, n, &g);
    }
    double sg = pst_sph_sigma[k->c.kernel][D - 1] * pst_sph_ipow(kc.ih, D);
    return 1.0 / (pst_sph_w(k->c.kernel, D, 0.0, h) + sg * s); /* >= W(0) > 0 */
}

/* V_j = 1 / (W(0, h_j) + sum_k W(d_jk, h_j)): j's number density with its own h. */
PST_ISA_DISPATCH static double volume_of(const cs_ctx *k, size_t j)
{
    return k->c.dim == 2 ? volume_t(k, 2, j) : volume_t(k, 3, j);
}

/* Bound by the scalar sqrt per pair (~60 % of the pass, perf) and the gather. */
static void volumes(const cs_ctx *k, double *V, size_t n)
{
#pragma omp parallel for schedule(dynamic, 512)
    for (size_t j = 0; j < n; ++j)
        V[j] = volume_of(k, j);
}

/* The moments pass of one block (moments_t). */
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
    cs_data *d = pst_op_data(op, sizeof *d);
    if (!d)
        return PST_ENOMEM;
    d->which = which;
    PST_DATA_ARRAY(d->V, n * sizeof *d->V);
    PST_DATA_ARRAY(d->K, n * (size_t)nc * sizeof *d->K);
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
            invert(op, &k, i, k.c.kind[i] == PST_NEUMANN, count[i - b0], m, &inv_blk[i - b0]);
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

static int pre_icspm(pst_op *op, char *err) { return precompute(op, CS_ICSPM, err); }
static int pre_cspm(pst_op *op, char *err) { return precompute(op, CS_CSPM, err); }
static int pre_csph(pst_op *op, char *err) { return precompute(op, CS_CSPH, err); }

/* ---- apply, emission, gradient, Hessian ---------------------------------------------------- */

/* Matrix-free apply: each pair's weight from the positions, V_j and the row's coefficients.
 * Compute-bound: a sqrt, one division and ~70 flops (2D) / ~90 (3D) per pair against 4 bytes
 * of list, 8 of V_j and 8 of u_J gathered; 3D 10^6 at 2 threads 6 ns per pair and thread (was
 * 19; qsfdi's apply 13). */
static void cs_apply(const pst_op *op, const double *u, double *y)
{
    cs_ctx k = make_ctx(op);
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < op->n; ++i)
        if (k.c.kind[i] != PST_DIRICHLET)
            row(&k, i, u, y, NULL);
}

static void cs_emit_row(const pst_op *op, size_t i, double *w)
{
    cs_ctx k = make_ctx(op);
    row(&k, i, NULL, NULL, w);
}

/* Gradient and packed second derivatives of row i, refitted from the moments and the data
 * sums with the same chain as the precompute: ICSPM (47) on its level, the CSPM gradient (40)
 * elsewhere (the kernel gradient where M1 is singular); second derivatives from X (ICSPM's
 * Schur complement, or CSPM's M2 on that level; 0 on the others). */
static void refit(const pst_op *op, const cs_ctx *k, size_t i, const double *u, double *g,
                  double *hs)
{
    const int D = k->c.dim, n2 = cs_n2(D);
    double m[3 * CS_NM_MAX], S1[3], S2[6];
    int count = moments_table[D - 2][k->which](k, i, m, u, S1, S2);
    cs_inv v;
    invert(op, k, i, k->c.kind[i] == PST_NEUMANN, count, m, &v);
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
#pragma omp parallel for schedule(dynamic, 1)
    for (size_t b = 0; b < pst_chunks(op->n, PST_CHUNK); ++b)
        PST_CHUNK_ROWS(op->tally, b, op->n, PST_CHUNK, i) {
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
#pragma omp parallel for schedule(dynamic, 1)
    for (size_t b = 0; b < pst_chunks(op->n, PST_CHUNK); ++b)
        PST_CHUNK_ROWS(op->tally, b, op->n, PST_CHUNK, i) {
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
        double r[3], dd = sqrt(pst_pair_offset(&k.c, D, i, k.c.idx[e], r));
        if (pst_pair_live(&k.c, dd, hi)) /* W' is 0 beyond the support */
            sum -= k.V[k.c.idx[e]] * pst_sph_dw(k.c.kernel, D, dd, hi) * dd;
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
                           .halo = 2, /* the neighbours' volumes */                           \
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
