/* The CSPM family's shared parts (kernels/cspm_family.c has the schemes, their equations and
 * notation): the data, the context, the monomial and component orders, the chunked gather every
 * pair pass starts with (volumes and moments in cspm_moments.c, the rows in cspm_rows.c), the
 * inverses that the precompute (cspm_fit.c) and the derivatives (cspm_derivs.c) form, and what
 * each file exports. Internal. */
#ifndef PSTENCIL_CSPM_FAMILY_H
#define PSTENCIL_CSPM_FAMILY_H

#include "kernel_common.h"
#include "sph_kernels.h"

#include <math.h>
#include <stddef.h>
#include <stdint.h>

/* Levels of the fallback chain; a scheme starts at its own level. */
enum { CS_ICSPM = 0, CS_CSPM = 1, CS_CSPH = 2, CS_BROOK = 3 };

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

/* The data sums of a row that its derivatives are linear in: S = (S1, S2) with S1 = sum B r du
 * (D) and S2_p = sum (A r_pa r_pb + B delta_p) du (n2), du = u_j - u_i. Only ICSPM's gradient
 * reads S2 (and its Hessian); the other levels' gradient is M1^-1 S1, so the gradient matrix
 * of a scheme has cs_ng columns. */
static inline int cs_ns(int D) { return D + cs_n2(D); }
static inline int cs_ng(int D, int which) { return which == CS_ICSPM ? cs_ns(D) : D; }

typedef struct {
    int which;   /* CS_ICSPM, CS_CSPM or CS_CSPH                                  */
    double *V;   /* V_j = 1 / sum_k W(d_jk, h_j), self term included             */
    double *K;   /* cs_ncoef(dim) coefficients per particle: lam, sig, mu, c0    */
    /* opts.keep: per particle the gradient's D x cs_ng and the Hessian's n2 x cs_ns matrix
     * that take the data sums S to the derivatives (pst_cs_fold), or NULL */
    double *G, *Hm;
} cs_data;

/* Everything the pair functions read, gathered once per call. */
typedef struct {
    pst_kctx c;
    int which;            /* cs_data's */
    const double *V, *K;  /* cs_data's volumes (not the cloud's c.V) and coefficients */
} cs_ctx;

static inline cs_ctx make_ctx(const pst_op *op)
{
    const cs_data *d = op->data;
    return (cs_ctx){.c = pst_kctx_of(op), .which = d->which, .V = d->V, .K = d->K};
}

/* Hot functions (PST_KHOT) take the dimension D (and the scheme) as constants at their call
 * sites. */

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
 * loops: the gather, d^2, then the sqrt in a loop of its own (vectorised: the library is built
 * without math errno). d is pst_pair_offset's, bit for bit. */
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

/* a_Ij of cspm_family.c's head comment for one pair: offset (x, y, z) (z not read in 2D), its
 * length d, V_j, with the row's kernel constants kc and coefficients Ki; 0 for a dead pair. The
 * chunk rows (cs_weights, the emission) and the lane rows (cspm_lanes.c, the apply) both call
 * it, so the two applies have the same weights bit for bit; the components are scalars (the
 * form that vectorises across neighbours). Per pair the two kernel shapes (~30 flops), the
 * n2 quadratic monomials in two forms, mu . r, one division. */
PST_KHOT double cs_weight_xyz(pst_kernel K, int D, const cs_kc *kc, const double *Ki, double x,
                              double y, double z, double d, double V)
{
    const int n2 = cs_n2(D);
    const double *lam = Ki, *sig = Ki + n2, *mu = Ki + 2 * n2, c0 = Ki[2 * n2 + D];
    const double q = d * kc->ih;
    CS_LIVE(kc, d, in, id);
    double w1 = kc->s1 * pst_sph_shape(K, D, q, 1), w2 = kc->s2 * pst_sph_shape(K, D, q, 2);
    /* the packed components in cs_pa / cs_pb's order: 2D xx, xy, yy; 3D xx, xy, xz, yy, yz, zz */
    const double m[6] = {x * x, x * y, D == 3 ? x * z : y * y, D == 3 ? y * y : 0.0,
                         D == 3 ? y * z : 0.0, D == 3 ? z * z : 0.0};
    double ql = 0, qs = 0, mr = 0;
    for (int p = 0; p < n2; ++p) {
        ql += lam[p] * m[p];
        qs += sig[p] * m[p];
    }
    mr += mu[0] * x;
    mr += mu[1] * y;
    if (D == 3)
        mr += mu[2] * z;
    double id2 = id * id, a1 = w1 * id;
    return V * ((w2 * ql + a1 * qs) * id2 + a1 * (c0 - mr));
}

/* The inverses a row's coefficients need, kept between the inversion and weights passes. */
typedef struct {
    double M1inv[9];  /* M1^-1, or -I when M1 is singular (the kernel gradient)          */
    double Xinv[36];  /* inverse of M2,ICSPM (48), M2 (41) or M2,CSPH (45) of the level  */
    double N21[18];   /* sum V grad2 W r^T (n2 x D); for CS_CSPH Ncr = sum V chk W r^T     */
    double N12[18];   /* sum V grad W r^(2)T (D x n2), ICSPM only                          */
    int level;
    uint8_t status;
} cs_inv;

/* T = N21 M1^-1 (n2 x D), a product of the Schur complement (48) and of the derivatives' fold. */
static inline void cs_n21_m1inv(int D, const cs_inv *v, double *T)
{
    for (int p = 0; p < cs_n2(D); ++p)
        for (int b = 0; b < D; ++b) {
            double s = 0;
            for (int c = 0; c < D; ++c)
                s += v->N21[p * D + c] * v->M1inv[c * D + b];
            T[p * D + b] = s;
        }
}

/* Minimum neighbours of each level (choice 6, docs/choices.md). */
static inline int level_min(int level, int D)
{
    return level == CS_ICSPM ? (D == 2 ? 5 : 9)
           : level == CS_CSPM ? (D == 2 ? 3 : 6)
           : level == CS_CSPH ? D
                              : 1;
}

/* cspm_moments.c: the volumes V_j of every particle; the raw moments of row i for the level
 * `which` (B, A and C back to back in m), returning the contributing neighbours; the first ns
 * data sums of row i for the field u (ns: D, S1 alone, or cs_ns). */
void pst_cs_volumes(const cs_ctx *k, double *V, size_t n);
int pst_cs_moments(const cs_ctx *k, int which, size_t i, double *m);
void pst_cs_data_sums(const cs_ctx *k, size_t i, const double *u, int ns, double *S);

/* cspm_fit.c: the fallback chain of row i from its moments m; the precompute of the scheme
 * `which`; a flat row's normalised Brookshaw row (pst_scheme.degrade); the data's release. */
void pst_cs_invert(const pst_op *op, const cs_ctx *k, size_t i, int neumann, int count,
                   const double *m, cs_inv *v);
int pst_cs_precompute(pst_op *op, int which, char *err);
void pst_cs_degrade(pst_op *op, size_t i);
void pst_cs_free(void *p);

/* cspm_rows.c: the emission of a stored row (the apply: cspm_lanes.h). */
void pst_cs_emit_row(const pst_op *op, size_t i, double *w);

/* cspm_derivs.c: the matrices that take row i's data sums to its gradient (G, D x ng, ng =
 * cs_ng of the scheme) and second derivatives (Hm, n2 x cs_ns; either may be NULL) from its
 * inverses; the gradient and the Hessian, from the kept matrices or from a refit. */
void pst_cs_fold(int D, int ng, const cs_inv *v, double *G, double *Hm);
void pst_cs_gradient(const pst_op *op, const double *u, double *const grad[3]);
void pst_cs_hessian(const pst_op *op, const double *u, double *const hess[6]);

#endif
