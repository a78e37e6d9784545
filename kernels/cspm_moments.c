/* The CSPM family's pair passes other than the rows' (kernels/cspm_family.c): the precompute's
 * volumes V_j (j's number density with its own h) and raw moments of a row, and the data sums
 * of a row that the derivatives read. */
#include "cspm_family.h"
#include "isa.h"
#include "wls_sums.h"

#include <omp.h>

/* B, A and C (cspm_family.c's head comment) of the chunk from V_j (g->b) and d (g->c), in
 * place; 0 for a dead pair. Returns the live pairs (counted in a double: an integer count of
 * double compares does not vectorise with SSE2). One division per pair. */
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

/* Raw moments of row i: sum B m_k over degrees 1..3 (1..2 without ICSPM), sum A m_k (not for
 * CSPH) and sum C m_k (CSPH only: the others need them only on a fallback to CSPH, where
 * invert_t computes them) over degrees 3..4. Returns the number of contributing neighbours. One
 * pass: per chunk the kernel loop, then 3 (csph2g) to 4 (icspm) reduction loops of 4-15 sums.
 * Compute-bound, the scalar sqrt ~30 % of it (perf, 1 thread). The whole precompute, 3D 10^6 at
 * 2 threads: 21 (csph2g) / 24 (cspm) / 22 (icspm) ns per neighbour and thread, qsfdi 23, was
 * 70-88 (bench/README.md). */
PST_KHOT int moments_t(const cs_ctx *k, int D, int which, size_t i, double *mB, double *mA,
                       double *mC)
{
    const int nm = cs_nm(D), d3 = cs_deg(D, 3), d4 = cs_deg(D, 4);
    const double xi[3] = {k->c.x[0][i], k->c.x[1][i], D == 3 ? k->c.x[2][i] : 0.0};
    const cs_kc kc = kc_of(k, D, pst_h(&k->c, i));
    const int64_t e0 = k->c.off[i], e1 = k->c.off[i + 1];
    int count = 0;
    for (int m = 0; m < nm; ++m)
        mB[m] = mA[m] = mC[m] = 0;
    for (int64_t c0 = e0; c0 < e1; c0 += CS_CHUNK) {
        const int n = (int)(e1 - c0 < CS_CHUNK ? e1 - c0 : CS_CHUNK);
        cs_chunk g;
        cs_gather(k, D, 1, xi, k->c.idx + c0, n, &g);
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
    }
    return count;
}

/* One instantiation per (D, scheme), each compiled per ISA; m holds the B, A and C moments
 * back to back. */
typedef int (*moments_fn)(const cs_ctx *, size_t, double *);
#define CS_MOM(D, W)                                                                           \
    PST_ISA_DISPATCH static int moments_##D##_##W(const cs_ctx *k, size_t i, double *m)        \
    {                                                                                          \
        return moments_t(k, D, W, i, m, m + cs_nm(D), m + 2 * cs_nm(D));                       \
    }
CS_MOM(2, 0) CS_MOM(2, 1) CS_MOM(2, 2) CS_MOM(3, 0) CS_MOM(3, 1) CS_MOM(3, 2)
static const moments_fn moments_table[2][3] = {{moments_2_0, moments_2_1, moments_2_2},
                                               {moments_3_0, moments_3_1, moments_3_2}};

/* The data sums S = (S1, S2) of row i (cspm_family.h's cs_ns), or S1 alone (full 0): the
 * moment pass's kernel loop, then the products with du = u_j - u_i in one or two reductions of
 * 5 (2D) / 9 (3D) sums and one of du B. Per pair about the apply's work; the derivatives dot S
 * with a row's matrices. */
PST_KHOT void data_sums_t(const cs_ctx *k, int D, int full, size_t i, const double *u,
                          double *S)
{
    const int n2 = cs_n2(D);
    const double xi[3] = {k->c.x[0][i], k->c.x[1][i], D == 3 ? k->c.x[2][i] : 0.0};
    const cs_kc kc = kc_of(k, D, pst_h(&k->c, i));
    const int64_t e0 = k->c.off[i], e1 = k->c.off[i + 1];
    double dB[9] = {0}, dA[9] = {0}, sB = 0; /* sum (B, A) du m over degrees 1, 2; sum B du */
    for (int64_t c0 = e0; c0 < e1; c0 += CS_CHUNK) {
        const int n = (int)(e1 - c0 < CS_CHUNK ? e1 - c0 : CS_CHUNK);
        const uint32_t *idx = k->c.idx + c0;
        cs_chunk g;
        double bu[CS_CHUNK], au[CS_CHUNK];
        cs_gather(k, D, 1, xi, idx, n, &g);
        CS_BY_KERNEL(k->c.kernel, cs_bac, D, &kc, n, &g);
        for (int c = 0; c < n; ++c) {
            double du = u[idx[c]] - u[i];
            bu[c] = g.b[c] * du;
            if (full) {
                au[c] = g.a[c] * du;
                sB += bu[c];
            }
        }
        cs_sum12(D, n, &g, bu, dB);
        if (full)
            cs_sum12(D, n, &g, au, dA);
    }
    for (int a = 0; a < D; ++a)
        S[a] = dB[a];
    for (int p = 0; full && p < n2; ++p)
        S[D + p] = dA[D + p] + (cs_pa(D, p) == cs_pb(D, p) ? sB : 0.0);
}

PST_ISA_DISPATCH void pst_cs_data_sums(const cs_ctx *k, size_t i, const double *u, int ns,
                                       double *S)
{
    if (k->c.dim == 2)
        ns == 2 ? data_sums_t(k, 2, 0, i, u, S) : data_sums_t(k, 2, 1, i, u, S);
    else
        ns == 3 ? data_sums_t(k, 3, 0, i, u, S) : data_sums_t(k, 3, 1, i, u, S);
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
void pst_cs_volumes(const cs_ctx *k, double *V, size_t n)
{
#pragma omp parallel for schedule(dynamic, 512)
    for (size_t j = 0; j < n; ++j)
        V[j] = volume_of(k, j);
}

int pst_cs_moments(const cs_ctx *k, int which, size_t i, double *m)
{
    return moments_table[k->c.dim - 2][which](k, i, m);
}
