/* The Lukyanov–Vuik family (docs/schemes/, equation numbers of the published paper):
 * Brookshaw (27), corrected Brookshaw (51), Schwaiger (52)-(55) and the two-point scheme
 * "M-SPH" (69)-(71) in transmissibility form (90)-(91), for scalar and diagonal-tensor mobility,
 * with the four kernel-gradient variants G1-G4 (15)-(18) and the Neumann rows (100).
 *
 * Every row is two-point, (L u)_I = sum_J w_IJ (u_J - u_I), with
 *     scalar m:  w_IJ = s_I V_J (m_I + m_J) [F_IJ - eta_I . g_IJ]
 *     tensor M:  w_IJ = s_I V_J sum_a (M^a_I + M^a_J) [x^a g^a / d^2 - zeta^a (C_I g)^a]
 * where g_IJ is the kernel gradient of the chosen variant, F_IJ = x_IJ . g_IJ / d^2, and
 *     brookshaw: s = 1,                 zeta = 0
 *     cb:        s = tr C / n,          zeta = 0
 *     schwaiger: s = tr(Gamma^-1) / n,  zeta = N      (53), Gamma (55)
 *     lv:        s = tr(Gamma-bar^-1)/n, zeta = N~    (65), Gamma-bar = Gamma* (71) where it is
 *                strictly diagonally dominant with a positive diagonal, else Gamma (fallback)
 * and eta = C^T zeta (so eta . g = zeta . C g; for radial variants F - eta.g = F (1 - eta.x),
 * the bracket of (91)). C = (A^T)^-1, A = sum_J V_J x (x) g (23)-(25).
 * The pair mobility (m_I + m_J) is the paper's arithmetic sum (29); with opts.mobility_mean =
 * PST_MEAN_HARMONIC (an extension, not in the paper) it is 4 m_I m_J / (m_I + m_J) instead, per
 * component for tensors (pair_mobility in lv_family.h; 0 when m_I + m_J <= 0).
 * Fallback chain (docs/schemes/): too few neighbours or a singular C / Gamma -> the Brookshaw
 * row (s = 1, zeta = 0); Neumann rows with a singular C use C = I. Never NaN. */
#include "lv_family.h"
#include "isa.h"
#include "lanes.h"
#include "small_matrix.h"
#include "sph_kernels.h"

#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

static lv_ctx make_ctx(const pst_op *op)
{
    return (lv_ctx){.c = pst_kctx_of(op), .variant = op->opts.gradient,
                    .harmonic = op->opts.mobility_mean == PST_MEAN_HARMONIC, .d = op->data};
}

/* Whether the gradient variant G reads the kernel value W (G2 and G4), else only W'. */
static inline int needs_w(int G) { return G == PST_GRAD_G2 || G == PST_GRAD_G4; }

/* The pair geometry of (i, j): x = r_j - r_i, d^2, h~ = (h_i + h_j)/2 (26), the kernel value W
 * (only when needW) and a = -dW/dr / d >= 0, so that the G1 gradient (15) is a x. Degenerate
 * pairs get a = W = 0. */
PST_KHOT double pair_geometry(const lv_ctx *k, int D, int needW, size_t i, size_t j, double x[3],
                            double *d2out, double *W)
{
    double d2 = pst_pair_offset(&k->c, D, i, j, x);
    double ht = 0.5 * (pst_h(&k->c, i) + pst_h(&k->c, j));
    double d = sqrt(d2);
    int ok = pst_pair_live(&k->c, d, ht);
    *d2out = d2;
    *W = ok && needW ? pst_sph_w(k->c.kernel, D, d, ht) : 0.0;
    return pair_a(k->c.kernel, D, d, ht, k->c.pair_eps);
}

/* The kernel gradient g_IJ of variant G (15)-(18) at pair (i, j), and F_IJ = x . g / d^2
 * (returned; 0 for a degenerate pair), from the pair's offset x, d2 and pair_geometry's a and
 * W. For the radial variants g = f x and F = f exactly. Needs nu (G2-G4) and grad nu (G2) of
 * i. Branch-free (selects), so that the loops over a chunk of pairs vectorise. */
PST_KHOT double gradient_from(const lv_ctx *k, int D, int G, size_t i, size_t j,
                              const double *x, int xs, double d2, double a, double W,
                              double g[3])
{
    double f = a; /* the radial factor */
    if (G != PST_GRAD_G1) {
        double inu = 1.0 / k->d->nu[i];
        f = a * inu;
        if (G == PST_GRAD_G4)
            f *= 1.0 - W * k->c.V[j] * inu;
    }
    for (int c = 0; c < D; ++c)
        g[c] = f * x[c * xs];
    if (G != PST_GRAD_G2)
        return f;
    /* G2 (16): minus W grad nu / nu^2, not along x. Where a == 0 (a degenerate pair, or q at
     * the support's edge) W is 0 too, so g is unchanged but perhaps for the sign of a zero, and
     * F = f = 0 cuts the pair. No select on a here: GCC 12 made the grad nu load a masked load
     * under it and vectorised no G2 loop (about 7 ns per pair in the 3D apply, now 3). */
    double inu = 1.0 / k->d->nu[i], t = W * inu * inu, xg = 0;
    for (int c = 0; c < D; ++c) {
        g[c] -= t * k->d->gnu[(size_t)D * i + c];
        xg += x[c * xs] * g[c];
    }
    double F = xg / d2;
    return a == 0 ? f : F;
}

/* The same at pair (i, j) from the positions. */
PST_KHOT double pair_gradient(const lv_ctx *k, int D, int G, size_t i, size_t j, double x[3],
                            double g[3], double *d2)
{
    double W, a = pair_geometry(k, D, needs_w(G), i, j, x, d2, &W);
    return gradient_from(k, D, G, i, j, x, 1, *d2, a, W, g);
}

/* w_IJ of a scheme row (see the file comment) from the pair's geometry (gradient_from's
 * arguments; x and mj at stride xs) and the mobilities of I and J (mi, mj: 1 value, D for a
 * tensor): scalar_weight or tensor_weight, as the G1 lane rows call them. Shared by the chunk
 * rows (apply, emission) and the half-list rows, so that their weights agree bit for bit. */
PST_KHOT double weight_from(const lv_ctx *k, int D, int G, int T, int H, size_t i, size_t j,
                            const double *x, int xs, double d2, double a, double W,
                            const double *mi, const double *mj, double *Fout)
{
    double g[3];
    double F = *Fout = gradient_from(k, D, G, i, j, x, xs, d2, a, W, g);
    const lv_data *d = k->d;
    double Vs = d->s[i] * k->c.V[j], w;
    if (!T) {
        w = scalar_weight(D, Vs, pair_mobility(mi[0], mj[0], H), F, d->eta + (size_t)D * i, g[0],
                          g[1], D == 3 ? g[2] : 0.0);
    } else {
        double z = D == 3 ? x[2 * xs] : 0.0, gz = D == 3 ? g[2] : 0.0;
        w = tensor_weight(D, H, Vs, mi, mj[0], mj[xs], D == 3 ? mj[2 * xs] : 0.0, d2,
                          d->C + (size_t)D * D * i, d->zeta + (size_t)D * i, x[0], x[xs], z,
                          g[0], g[1], gz);
    }
    return w;
}

/* w_IJ of a Neumann row (100) from the pair's geometry: V_J (M_I n_I) . C_I g_IJ, the outward
 * flux; mn = M_I n_I. */
PST_KHOT double neumann_from(const lv_ctx *k, int D, int G, size_t i, size_t j, const double *x,
                             int xs, double d2, double a, double W, const double *mn, double *F)
{
    double g[3];
    *F = gradient_from(k, D, G, i, j, x, xs, d2, a, W, g);
    const double *C = k->d->C + (size_t)D * D * i;
    double w = 0;
    for (int b = 0; b < D; ++b) {
        double Cg = 0;
        for (int e = 0; e < D; ++e)
            Cg += C[b * D + e] * g[e];
        w += mn[b] * Cg;
    }
    return k->c.V[j] * w;
}

/* The row constants of row i: mi, the mobility of I as weight_from reads it, and on a Neumann
 * row mn = M_I n_I (neumann_from; only Neumann rows have normals). */
PST_KHOT void row_mobility(const lv_ctx *k, int D, int T, size_t i, double mi[3], double mn[3])
{
    int neumann = k->c.kind[i] == PST_NEUMANN;
    for (int b = 0; b < D; ++b) {
        mi[b] = T ? k->c.mob[b][i] : pst_mob(&k->c, 0, i);
        mn[b] = neumann ? pst_mob(&k->c, b, i) * k->c.normal[b][i] : 0.0;
    }
}

/* w_IJ of row i (Neumann or not) at pair (i, j) from the positions: the half-list rows. */
PST_KHOT double row_weight(const lv_ctx *k, int D, int G, int T, int H, size_t i, size_t j)
{
    double x[3], d2, W, mi[3], mn[3], mj[3] = {0, 0, 0}, F, w;
    double a = pair_geometry(k, D, needs_w(G), i, j, x, &d2, &W);
    row_mobility(k, D, T, i, mi, mn);
    if (k->c.kind[i] == PST_NEUMANN) {
        w = neumann_from(k, D, G, i, j, x, 1, d2, a, W, mn, &F);
    } else {
        for (int b = 0; b < (T ? D : 1); ++b)
            mj[b] = pst_mob(&k->c, b, j);
        w = weight_from(k, D, G, T, H, i, j, x, 1, d2, a, W, mi, mj, &F);
    }
    return F == 0.0 ? 0.0 : w; /* a degenerate pair */
}

/* The geometry of a chunk of pairs (i, idx[c]), c < n, in arrays: x, d2, and pair_geometry's
 * a and W (W only with needW). */
#define LV_CHUNK 256
typedef struct {
    double x[3][LV_CHUNK], d2[LV_CHUNK], a[LV_CHUNK], W[LV_CHUNK];
} lv_chunk;

/* a and W of a chunk from d = sqrt(d2) for the constant kernel K (pair_geometry's
 * arithmetic), h~ of pair c at ht[c * hs]. The loop waits on the divider (the sqrt and the
 * division by d): the sqrt runs here, beside the kernel's multiplications, rather than in a
 * loop of its own; W (needW) in the same loop, where its powers of (s - q) share those of W'
 * (G2 and G4); and with hs = 0 (one h in the cloud) the kernel's 1 / h~ and its powers are
 * computed once per chunk instead of once per pair (the same values). */
PST_KHOT void chunk_kernel(pst_kernel K, int D, int needW, int n, const double *ht, int hs,
                           double eps, lv_chunk *ch)
{
#pragma omp simd
    for (int c = 0; c < n; ++c) {
        double d = sqrt(ch->d2[c]);
        ch->a[c] = pair_a(K, D, d, ht[c * hs], eps);
        if (needW) {
            double wv = pst_sph_w(K, D, d, ht[c * hs]);
            ch->W[c] = d > eps * ht[c * hs] ? wv : 0.0;
        }
    }
}

/* chunk_kernel with the kernel and the stride of h~ as constants. */
PST_KHOT void chunk_kernel_hs(pst_kernel K, int D, int needW, int n, const double *ht, int hs,
                              double eps, lv_chunk *ch)
{
    if (hs)
        chunk_kernel(K, D, needW, n, ht, 1, eps, ch);
    else
        chunk_kernel(K, D, needW, n, ht, 0, eps, ch);
}

/* Separate loops, so that the sqrt (the library is built without math errno) with the kernel
 * (one loop per kernel, the switch outside) vectorise. The offsets come from the positions,
 * or with L (the matrix-free apply) from its packed rows (pst_lanes_gather), u_J - u_I with
 * them into du. */
PST_KHOT void chunk_geometry(const lv_ctx *k, int D, int needW, size_t i, const uint32_t *idx,
                             int n, lv_chunk *ch, const pst_lanes *L, double *du)
{
    double ht[LV_CHUNK], hi = pst_h(&k->c, i);
    if (L)
        pst_lanes_gather(L, idx, n, ch->x[0], LV_CHUNK, du);
    else
        for (int c = 0; c < n; ++c)
            for (int b = 0; b < D; ++b)
                ch->x[b][c] = pst_offset(&k->c, b, k->c.x[b][idx[c]], k->c.x[b][i]);
    for (int c = 0; c < n; ++c) {
        double d2 = 0;
        for (int b = 0; b < D; ++b)
            d2 += ch->x[b][c] * ch->x[b][c];
        ch->d2[c] = d2;
    }
    int hs = k->c.h != NULL;
    if (hs)
        for (int c = 0; c < n; ++c)
            ht[c] = 0.5 * (hi + k->c.h[idx[c]]);
    else
        ht[0] = 0.5 * (hi + k->c.h_uniform);
    const double eps = k->c.pair_eps;
    switch (k->c.kernel) {
    case PST_KERNEL_CUBIC:
        chunk_kernel_hs(PST_KERNEL_CUBIC, D, needW, n, ht, hs, eps, ch);
        break;
    case PST_KERNEL_QUINTIC:
        chunk_kernel_hs(PST_KERNEL_QUINTIC, D, needW, n, ht, hs, eps, ch);
        break;
    case PST_KERNEL_WENDLAND_C2:
        chunk_kernel_hs(PST_KERNEL_WENDLAND_C2, D, needW, n, ht, hs, eps, ch);
        break;
    default: chunk_kernel_hs(PST_KERNEL_WENDLAND_C4, D, needW, n, ht, hs, eps, ch); break;
    }
}

/* The weights (uncut) and F of a scheme row's chunk (weight_from). */
PST_KHOT void chunk_row_weights(const lv_ctx *k, int D, int G, int T, int H, size_t i,
                                const uint32_t *idx, int n, const lv_chunk *ch, const double *mi,
                                double *F, double *t)
{
    double mj[3][LV_CHUNK];
    for (int b = 0; b < (T ? D : 1); ++b)
        if (k->c.ncomp)
            for (int c = 0; c < n; ++c)
                mj[b][c] = k->c.mob[k->c.ncomp == 1 ? 0 : b][idx[c]];
        else
            for (int c = 0; c < n; ++c)
                mj[b][c] = 1.0;
#pragma omp simd
    for (int c = 0; c < n; ++c)
        t[c] = weight_from(k, D, G, T, H, i, idx[c], &ch->x[0][c], LV_CHUNK, ch->d2[c],
                           ch->a[c], ch->W[c], mi, &mj[0][c], &F[c]);
}

/* The cut of degenerate pairs (F = 0) from a chunk's weights t, as a loop of its own: inside
 * the weight loop GCC would sink the weight into a branch of it, and that loop would not
 * vectorise below AVX-512. */
PST_KHOT void chunk_cut(int n, const double *F, double *t)
{
    for (int c = 0; c < n; ++c)
        t[c] = F[c] == 0.0 ? 0.0 : t[c];
}

/* The weights of row i for the chunk of neighbours idx[0..n) whose geometry is ch, into t:
 * a Neumann row's (neumann_from) or a scheme row's (chunk_row_weights), 0 for degenerate
 * pairs (F = 0). */
PST_KHOT void chunk_weights_of(const lv_ctx *k, int D, int G, int T, int H, size_t i,
                               const uint32_t *idx, int n, const lv_chunk *ch, double *t)
{
    double mi[3], mn[3], F[LV_CHUNK];
    row_mobility(k, D, T, i, mi, mn);
    if (k->c.kind[i] == PST_NEUMANN) {
#pragma omp simd
        for (int c = 0; c < n; ++c)
            t[c] = neumann_from(k, D, G, i, idx[c], &ch->x[0][c], LV_CHUNK, ch->d2[c], ch->a[c],
                                ch->W[c], mn, &F[c]);
    } else {
        chunk_row_weights(k, D, G, T, H, i, idx, n, ch, mi, F, t);
    }
    chunk_cut(n, F, t);
}

/* The weights of row i for its neighbours idx[0..n) into t (with L: chunk_geometry's). */
PST_KHOT void chunk_weights(const lv_ctx *k, int D, int G, int T, int H, size_t i,
                            const uint32_t *idx, int n, double *t, const pst_lanes *L,
                            double *du)
{
    lv_chunk ch;
    chunk_geometry(k, D, needs_w(G), i, idx, n, &ch, L, du);
    chunk_weights_of(k, D, G, T, H, i, idx, n, &ch, t);
}

/* The weights w_JI of the pairs (J = idx[c], i) of a half-list chunk into t, each as row J's
 * own rows form it: weight_from reading row J's data by its index, with the pair's geometry ch
 * seen from J (x_JI = -x_IJ exactly; d^2, h~, a and W are the same both ways). GCC 12 leaves
 * the weight loop scalar ("no vectype for stmt"); the shared geometry is the gain (row J's
 * data copied per lane first vectorised it, at no clear gain: docs/operators.md). A Neumann row
 * J's weight a pair at a time (row_weight); degenerate pairs 0, as in chunk_weights_of. */
PST_KHOT void chunk_reverse_weights(const lv_ctx *k, int D, int G, int T, int H, size_t i,
                                    const uint32_t *idx, int n, const lv_chunk *ch, double *t)
{
    /* mrow: row J's own mobility (row_mobility's); mcol: I's, as J's pair reads its column */
    double x[3][LV_CHUNK], mrow[LV_CHUNK][3], mcol[3][LV_CHUNK], F[LV_CHUNK];
    for (int b = 0; b < D; ++b)
        for (int c = 0; c < n; ++c)
            x[b][c] = -ch->x[b][c];
    for (int b = 0; b < (T ? D : 1); ++b) {
        double m = pst_mob(&k->c, b, i);
        for (int c = 0; c < n; ++c) {
            mrow[c][b] = T ? k->c.mob[b][idx[c]] : pst_mob(&k->c, 0, idx[c]);
            mcol[b][c] = m;
        }
    }
#pragma omp simd
    for (int c = 0; c < n; ++c)
        t[c] = weight_from(k, D, G, T, H, idx[c], i, &x[0][c], LV_CHUNK, ch->d2[c], ch->a[c],
                           ch->W[c], mrow[c], &mcol[0][c], &F[c]);
    chunk_cut(n, F, t);
    for (int c = 0; c < n; ++c)
        if (k->c.kind[idx[c]] == PST_NEUMANN)
            t[c] = row_weight(k, D, G, T, H, idx[c], i);
}

/* Row i into y (apply, from the packed rows: pst_lanes_gather) or its weights into w
 * (emission, from the positions), a chunk of neighbours at a time: the chunk's geometry and
 * weights in vector lanes (chunk_weights), then their dot product with u_J - u_I in the lanes
 * of pst_lanes_dot_blocks. The apply runs every loop of a chunk over whole blocks of 8, so
 * that none has a scalar tail (19-20 % of the 3D apply; bench/README.md): the lanes past the
 * row take the next row's neighbours, whose weights are computed and never summed; the list's
 * last row, with nothing after it, computes its own pairs only and zeros the rest. */
PST_KHOT void row_t(const lv_ctx *k, const int64_t *off, const uint32_t *idx, size_t i,
                    double *y, double *w, int D, int G, int T, int H)
{
    double t[LV_CHUNK], du[LV_CHUNK];
    pst_v8 acc = pst_v8_splat(0.0);
    for (int64_t c0 = off[i]; c0 < off[i + 1]; c0 += LV_CHUNK) {
        int n = (int)(off[i + 1] - c0 < LV_CHUNK ? off[i + 1] - c0 : LV_CHUNK);
        if (w) {
            chunk_weights(k, D, G, T, H, i, idx + c0, n, w + (c0 - off[i]), NULL, NULL);
        } else {
            int m = (n + PST_LANES - 1) / PST_LANES * PST_LANES, whole = c0 + m <= k->list_end;
            pst_lanes L = pst_lanes_row(&k->c, i, 1.0);
            chunk_weights(k, D, G, T, H, i, idx + c0, whole ? m : n, t, &L, du);
            for (int c = whole ? m : n; c < m; ++c)
                t[c] = 0.0;
            acc = pst_lanes_dot_blocks(n, t, du, acc);
        }
    }
    if (!w)
        y[i] = pst_v8_sum(acc);
}

/* Row i of a half list (operator.h, half_rows), for constant D, G, T, H, a chunk of its pairs
 * (i, j > i) at a time: the geometry once for both directions (chunk_geometry from the
 * positions, as the emission), w_IJ as the whole-list rows form it (chunk_weights_of) and w_JI
 * as row J's (chunk_reverse_weights); then, in list order, y_I += sum_J w_IJ (u_J - u_I)
 * unless I is a Dirichlet row and y_J -= w_JI (u_J - u_I) for each non-Dirichlet J.
 * The G1 rows but Neumann ones take lv_half_lanes.c's rows instead. */
PST_KHOT void half_row_t(const lv_ctx *k, const int64_t *off, const uint32_t *idx, size_t i,
                         const double *u, double *y, int D, int G, int T, int H)
{
    const uint8_t *kind = k->c.kind;
    const double ui = u[i];
    double s = 0;
    for (int64_t c0 = off[i]; c0 < off[i + 1]; c0 += LV_CHUNK) {
        int n = (int)(off[i + 1] - c0 < LV_CHUNK ? off[i + 1] - c0 : LV_CHUNK);
        const uint32_t *ic = idx + c0;
        lv_chunk ch;
        double wij[LV_CHUNK], wji[LV_CHUNK];
        chunk_geometry(k, D, needs_w(G), i, ic, n, &ch, NULL, NULL);
        chunk_weights_of(k, D, G, T, H, i, ic, n, &ch, wij);
        chunk_reverse_weights(k, D, G, T, H, i, ic, n, &ch, wji);
        for (int c = 0; c < n; ++c) {
            double du = u[ic[c]] - ui;
            s += wij[c] * du;
            if (kind[ic[c]] != PST_DIRICHLET)
                y[ic[c]] -= wji[c] * du;
        }
    }
    if (kind[i] != PST_DIRICHLET)
        y[i] += s;
}

/* Row i: of the whole list (apply, emission) or, with half = 1, of a half list. */
typedef void (*row_fn)(const lv_ctx *, const int64_t *, const uint32_t *, size_t,
                       const double *, double *, double *, int half);
#define LV_ROW(D, G, T, H)                                                                     \
    PST_ISA_DISPATCH static void row_##D##_##G##_##T##_##H(                                    \
        const lv_ctx *k, const int64_t *off, const uint32_t *idx, size_t i, const double *u,   \
        double *y, double *w, int half)                                                        \
    {                                                                                          \
        if (half)                                                                              \
            half_row_t(k, off, idx, i, u, y, D, G, T, H);                                      \
        else                                                                                   \
            row_t(k, off, idx, i, y, w, D, G, T, H);                                           \
    }
#define LV_ROWS_H(D, G) LV_ROW(D, G, 0, 0) LV_ROW(D, G, 0, 1) LV_ROW(D, G, 1, 0) LV_ROW(D, G, 1, 1)
#define LV_ROWS_G(D) LV_ROWS_H(D, 1) LV_ROWS_H(D, 2) LV_ROWS_H(D, 3) LV_ROWS_H(D, 4)
LV_ROWS_G(2)
LV_ROWS_G(3)
#define LV_ENTRY(D, G)                                                                         \
    {{row_##D##_##G##_0_0, row_##D##_##G##_0_1}, {row_##D##_##G##_1_0, row_##D##_##G##_1_1}}
static const row_fn row_table[2][4][2][2] = {
    {LV_ENTRY(2, 1), LV_ENTRY(2, 2), LV_ENTRY(2, 3), LV_ENTRY(2, 4)},
    {LV_ENTRY(3, 1), LV_ENTRY(3, 2), LV_ENTRY(3, 3), LV_ENTRY(3, 4)}};

/* The instantiation for this operator: a diagonal tensor (T) when the mobility has dim > 1
 * components; the harmonic pair mobility (H) when asked for. */
static row_fn row_for(const lv_ctx *k)
{
    return row_table[k->c.dim - 2][k->variant - 1][k->c.ncomp > 1][k->harmonic];
}

/* ---- precompute ------------------------------------------------------------------------ */

static void lv_free(void *p)
{
    lv_data *d = p;
    if (!d)
        return;
    pst_free(d->nu);
    pst_free(d->gnu);
    pst_free(d->C);
    pst_free(d->zeta);
    pst_free(d->eta);
    pst_free(d->s);
    free(d);
}

static int min_neighbours(int which, int dim)
{
    /* choice 6, docs/choices.md */
    return which == LV_BROOKSHAW ? 1 : which == LV_CB ? dim : dim + 1;
}

static int lv_min_brookshaw(int dim) { return min_neighbours(LV_BROOKSHAW, dim); }
static int lv_min_cb(int dim) { return min_neighbours(LV_CB, dim); }
static int lv_min_schwaiger(int dim) { return min_neighbours(LV_SCHWAIGER, dim); }
static int lv_min_msph(int dim) { return min_neighbours(LV_MSPH, dim); }

/* Shepard nu_I (with the self term W(0, h_I) V_I) and, for G2, grad nu_I = sum_K V_K grad W_IK
 * (G1 gradients; the self term has none). */
static void shepard(const lv_ctx *k, size_t i, const int64_t *off, const uint32_t *idx,
                    double *nu, double *gnu)
{
    double s = pst_sph_w(k->c.kernel, k->c.dim, 0.0, pst_h(&k->c, i)) * k->c.V[i];
    double gs[3] = {0, 0, 0};
    for (int64_t e = off[i]; e < off[i + 1]; ++e) {
        size_t j = idx[e];
        double x[3], d2, W, a = pair_geometry(k, k->c.dim, 1, i, j, x, &d2, &W);
        s += W * k->c.V[j];
        for (int c = 0; c < k->c.dim; ++c)
            gs[c] += k->c.V[j] * a * x[c];
    }
    *nu = s;
    if (gnu)
        for (int c = 0; c < k->c.dim; ++c)
            gnu[c] = gs[c];
}

/* The sums of a row's precompute (53), (55), (65), (71), row-major D x D: the first pass
 * A = sum V x (x) g, N = sum V g, N~ = sum V F x, Gamma = sum V F x x^T; the second (M-SPH)
 * Gamma* = sum V x (g - x (xi . g))^T. */
typedef struct {
    double A[9], N[3], Nt[3], G[9], Gs[9];
} lv_sums;

/* sum_c p_c q_c over a chunk in 8 partial sums (pst_lanes_dot_blocks, pst_v8_sum): vector
 * lanes, and one order for every vector width and thread count, so that the precompute is the
 * same in every build (the stability table's solve counts depend on its last bits). */
PST_KHOT double chunk_dot(int n, const double *restrict p, const double *restrict q)
{
    return pst_v8_sum(pst_lanes_dot_blocks(n, p, q, pst_v8_splat(0.0)));
}

/* One chunk of a row's pairs as the precompute's sums read them: the geometry, the
 * gradients g and F (gradient_from, the applies' arithmetic), v = V_J and v x. */
typedef struct {
    lv_chunk ch;
    double g[3][LV_CHUNK], F[LV_CHUNK], v[LV_CHUNK], vx[3][LV_CHUNK];
} lv_pairs;

PST_KHOT void chunk_pairs(const lv_ctx *k, int D, int G, size_t i, const uint32_t *ic, int n,
                          lv_pairs *p)
{
    double du[LV_CHUNK];
    pst_lanes L = pst_lanes_row(&k->c, i, 1.0); /* its u (0 or an apply's) is not read */
    chunk_geometry(k, D, needs_w(G), i, ic, n, &p->ch, &L, du);
#pragma omp simd
    for (int c = 0; c < n; ++c) {
        double gc[3];
        p->F[c] = gradient_from(k, D, G, i, ic[c], &p->ch.x[0][c], LV_CHUNK, p->ch.d2[c],
                                p->ch.a[c], p->ch.W[c], gc);
        for (int b = 0; b < D; ++b)
            p->g[b][c] = gc[b];
    }
    for (int c = 0; c < n; ++c)
        p->v[c] = k->c.V[ic[c]];
    for (int a = 0; a < D; ++a)
        for (int c = 0; c < n; ++c)
            p->vx[a][c] = p->v[c] * p->ch.x[a][c];
}

/* The first pass's sums of a chunk (A, N, N~, Gamma: the upper triangle of the symmetric
 * Gamma), added to s. */
PST_KHOT void chunk_sums(int D, int n, const lv_pairs *p, lv_sums *s)
{
    double t[LV_CHUNK];
    for (int c = 0; c < n; ++c)
        t[c] = p->v[c] * p->F[c];
    for (int a = 0; a < D; ++a) {
        s->N[a] += chunk_dot(n, p->v, p->g[a]);
        s->Nt[a] += chunk_dot(n, t, p->ch.x[a]);
        for (int b = 0; b < D; ++b)
            s->A[a * D + b] += chunk_dot(n, p->vx[a], p->g[b]);
        double tx[LV_CHUNK];
        for (int c = 0; c < n; ++c)
            tx[c] = t[c] * p->ch.x[a][c];
        for (int b = a; b < D; ++b)
            s->G[a * D + b] += chunk_dot(n, tx, p->ch.x[b]);
    }
}

/* Gamma* of a chunk, sum V x (g - x (xi . g))^T, added to s->Gs. */
PST_KHOT void chunk_star(int D, int n, const lv_pairs *p, const double *xi, lv_sums *s)
{
    double t[LV_CHUNK];
    for (int c = 0; c < n; ++c) {
        double xg = 0;
        for (int b = 0; b < D; ++b)
            xg += xi[b] * p->g[b][c];
        t[c] = xg;
    }
    for (int b = 0; b < D; ++b) {
        double gb[LV_CHUNK];
        for (int c = 0; c < n; ++c)
            gb[c] = p->g[b][c] - p->ch.x[b][c] * t[c];
        for (int a = 0; a < D; ++a)
            s->Gs[a * D + b] += chunk_dot(n, p->vx[a], gb);
    }
}

/* The sums of row i for constant D and G, a chunk of neighbours at a time: the chunk's pairs
 * in vector lanes (chunk_pairs, the offsets from the packed rows), then each sum as its own
 * vectorised dot product over the chunk; the first pass without xi, the Gamma* pass with it.
 * A chunk's count is rounded up to a multiple of 8 with the row's own particle, a degenerate
 * pair: g = F = x = 0 there, so every product it adds is exactly 0, the sums are those of the
 * chunk itself bit for bit, and chunk_dot runs no scalar tail. A row of one chunk (3D ~55
 * neighbours) keeps its pairs in *p from the first pass for the second, which then costs its
 * 9 sums only. Per neighbour (3D, first pass): the gather, a sqrt, a division, ~25 flops of
 * kernel and gradient and 2 per each of the 21 sums (Gamma is symmetric: its upper triangle,
 * mirrored) - compute-bound, like qsfdi's moments. */
PST_KHOT void row_sums_t(const lv_ctx *k, int D, int G, size_t i, const int64_t *off,
                         const uint32_t *idx, const double *xi, lv_sums *s, lv_pairs *p)
{
    if (xi)
        memset(s->Gs, 0, sizeof s->Gs);
    else
        memset(s, 0, offsetof(lv_sums, Gs));
    const int one_chunk = off[i + 1] - off[i] <= LV_CHUNK;
    for (int64_t c0 = off[i]; c0 < off[i + 1]; c0 += LV_CHUNK) {
        const int m = (int)(off[i + 1] - c0 < LV_CHUNK ? off[i + 1] - c0 : LV_CHUNK);
        const int n = (m + PST_LANES - 1) / PST_LANES * PST_LANES;
        if (!xi || !one_chunk) {
            uint32_t ic[LV_CHUNK];
            for (int c = 0; c < n; ++c)
                ic[c] = c < m ? idx[c0 + c] : (uint32_t)i;
            chunk_pairs(k, D, G, i, ic, n, p);
        }
        if (xi)
            chunk_star(D, n, p, xi, s);
        else
            chunk_sums(D, n, p, s);
    }
    if (!xi)
        for (int a = 0; a < D; ++a)
            for (int b = 0; b < a; ++b)
                s->G[a * D + b] = s->G[b * D + a];
}

/* row_sums_t instantiated for each dimension and gradient variant, in the widest vector ISA. */
typedef void (*sums_fn)(const lv_ctx *, size_t, const int64_t *, const uint32_t *,
                        const double *, lv_sums *, lv_pairs *);
#define LV_SUMS(D, G)                                                                          \
    PST_ISA_DISPATCH static void sums_##D##_##G(const lv_ctx *k, size_t i, const int64_t *off,  \
                                                const uint32_t *idx, const double *xi,          \
                                                lv_sums *s, lv_pairs *p)                        \
    {                                                                                          \
        row_sums_t(k, D, G, i, off, idx, xi, s, p);                                            \
    }
LV_SUMS(2, 1) LV_SUMS(2, 2) LV_SUMS(2, 3) LV_SUMS(2, 4)
LV_SUMS(3, 1) LV_SUMS(3, 2) LV_SUMS(3, 3) LV_SUMS(3, 4)
static const sums_fn sums_table[2][4] = {{sums_2_1, sums_2_2, sums_2_3, sums_2_4},
                                         {sums_3_1, sums_3_2, sums_3_3, sums_3_4}};

/* Worse of two statuses (the enum is ordered by severity). */
static inline uint8_t worse(uint8_t a, uint8_t b) { return a > b ? a : b; }

/* Classify an inversion by its condition number. */
static uint8_t cond_status(const pst_op *op, double cond)
{
    if (!(cond * op->opts.rank_tol < 1.0))
        return PST_ROW_RANK_DEFICIENT;
    return cond > op->opts.cond_max ? PST_ROW_ILL_CONDITIONED : PST_ROW_OK;
}

static double trace(int dim, const double *a)
{
    double t = 0;
    for (int c = 0; c < dim; ++c)
        t += a[c * dim + c];
    return t;
}

/* Per-particle data of row i. */
static uint8_t particle(const pst_op *op, const lv_ctx *k, size_t i, const int64_t *off,
                        const uint32_t *idx)
{
    lv_data *d = op->data;
    int dim = k->c.dim, nn = dim * dim, which = d->which;
    double *C = d->C + (size_t)nn * i, *zeta = d->zeta + (size_t)dim * i,
           *eta = d->eta + (size_t)dim * i;
    uint8_t st = PST_ROW_OK;
    /* defaults: the Brookshaw row, C = I */
    d->s[i] = 1.0;
    for (int a = 0; a < nn; ++a)
        C[a] = a % (dim + 1) == 0 ? 1.0 : 0.0;
    for (int a = 0; a < dim; ++a)
        zeta[a] = eta[a] = 0.0;
    int64_t count = off[i + 1] - off[i];
    if (count < min_neighbours(which, dim))
        return PST_ROW_TOO_FEW;
    int needs_C = which != LV_BROOKSHAW || k->c.kind[i] == PST_NEUMANN;
    if (!needs_C)
        return PST_ROW_OK;

    /* A = sum V x (x) g, N = sum V g (53), N~ = sum V F x (65), Gamma = sum V F x x^T (55) */
    sums_fn sums = sums_table[dim - 2][k->variant - 1];
    lv_sums S;
    lv_pairs pairs; /* the row's pairs, kept from the first pass for the Gamma* pass */
    sums(k, i, off, idx, NULL, &S, &pairs);
    double *A = S.A, *N = S.N, *Nt = S.Nt, *G = S.G;
    if (k->variant == PST_GRAD_G2) /* the self term of (16) in (53): makes N = 0 exactly */
        for (int a = 0; a < dim; ++a)
            N[a] -= k->c.V[i] * pst_sph_w(k->c.kernel, dim, 0.0, pst_h(&k->c, i)) *
                    d->gnu[(size_t)dim * i + a] / (d->nu[i] * d->nu[i]);
    double At[9], Cinv[9];
    for (int a = 0; a < dim; ++a)
        for (int b = 0; b < dim; ++b)
            At[a * dim + b] = A[b * dim + a];
    uint8_t cs = cond_status(op, pst_mat_inverse(dim, At, Cinv));
    if (cs == PST_ROW_RANK_DEFICIENT)
        return cs; /* C = I, Brookshaw row */
    st = worse(st, cs);
    memcpy(C, Cinv, (size_t)nn * sizeof *C);
    if (which == LV_BROOKSHAW || k->c.kind[i] == PST_NEUMANN)
        return st;
    if (which == LV_CB) {
        double s = trace(dim, C) / dim;
        if (!(s > 0))
            return worse(st, PST_ROW_FALLBACK); /* tr C <= 0 would flip the row's sign */
        d->s[i] = s;
        return st;
    }

    /* Schwaiger and M-SPH: the bracket vector and the normalising matrix */
    const double *z = which == LV_SCHWAIGER ? N : Nt;
    double xi[3];
    for (int b = 0; b < dim; ++b) {
        xi[b] = 0;
        for (int a = 0; a < dim; ++a)
            xi[b] += C[a * dim + b] * z[a];
    }
    double norm[9];
    memcpy(norm, G, sizeof norm);
    if (which == LV_MSPH) {
        /* Gamma* (71) = sum V x (g - x (xi . g))^T, with xi = C^T N~ */
        sums(k, i, off, idx, xi, &S, &pairs);
        const double *Gs = S.Gs;
        if (pst_mat_sdd_positive(dim, Gs))
            memcpy(norm, Gs, sizeof norm);
        else
            st = worse(st, PST_ROW_FALLBACK); /* Gamma-bar = Gamma (70) */
    }
    double inv[9];
    uint8_t gs = cond_status(op, pst_mat_inverse(dim, norm, inv));
    double s = gs == PST_ROW_RANK_DEFICIENT ? 0 : trace(dim, inv) / dim;
    if (!(s > 0)) /* singular or a negative trace: keep the Brookshaw row */
        return worse(st, gs == PST_ROW_RANK_DEFICIENT ? gs : PST_ROW_FALLBACK);
    st = worse(st, gs);
    d->s[i] = s;
    for (int a = 0; a < dim; ++a) {
        zeta[a] = z[a];
        eta[a] = xi[a];
    }
    return st;
}

static int precompute(pst_op *op, int which, char *err)
{
    size_t n = op->n;
    int dim = op->dim, variant = op->opts.gradient;
    lv_data *d = pst_op_data(op, sizeof *d);
    if (!d)
        return PST_ENOMEM;
    d->which = which;
    /* 8 doubles past the last row: the half-list tensor rows read 2D rows 8 at a time */
    if (!d->C && PST_DATA_ARRAY(d->C, (n * (size_t)(dim * dim) + PST_LANES) * sizeof *d->C))
        memset(d->C + n * (size_t)(dim * dim), 0, PST_LANES * sizeof *d->C);
    PST_DATA_ARRAY(d->zeta, n * (size_t)dim * sizeof *d->zeta);
    PST_DATA_ARRAY(d->eta, n * (size_t)dim * sizeof *d->eta);
    PST_DATA_ARRAY(d->s, n * sizeof *d->s);
    if (variant != PST_GRAD_G1)
        PST_DATA_ARRAY(d->nu, n * sizeof *d->nu);
    if (variant == PST_GRAD_G2)
        PST_DATA_ARRAY(d->gnu, n * (size_t)dim * sizeof *d->gnu);
    if (!d->C || !d->zeta || !d->eta || !d->s || (variant != PST_GRAD_G1 && !d->nu) ||
        (variant == PST_GRAD_G2 && !d->gnu)) {
        pst_set_err(err, "%s: cannot allocate the per-particle data of %zu particles",
                    op->scheme->name, n);
        return PST_ENOMEM;
    }
    lv_ctx k = make_ctx(op);
    const int64_t *off = pst_nlist_offsets(op->nl);
    const uint32_t *idx = pst_nlist_indices(op->nl);
    /* One pass: every quantity of row i needs only row i (nu_I sums over I's neighbours). */
#pragma omp parallel for schedule(dynamic, 1)
    for (size_t b = 0; b < pst_chunks(n, PST_CHUNK); ++b)
        PST_CHUNK_ROWS(op->tally, b, n, PST_CHUNK, i) {
            if (d->nu)
                shepard(&k, i, off, idx, &d->nu[i], d->gnu ? d->gnu + (size_t)dim * i : NULL);
            op->status[i] = particle(op, &k, i, off, idx);
        }
    return PST_OK;
}

static int pre_brookshaw(pst_op *op, char *err) { return precompute(op, LV_BROOKSHAW, err); }
static int pre_cb(pst_op *op, char *err) { return precompute(op, LV_CB, err); }
static int pre_schwaiger(pst_op *op, char *err) { return precompute(op, LV_SCHWAIGER, err); }
static int pre_msph(pst_op *op, char *err) { return precompute(op, LV_MSPH, err); }

/* ---- apply, emission and the rest of the table ------------------------------------------ */

/* Matrix-free apply: recompute each pair's geometry and weight from the positions and the
 * per-particle data, 8 pairs at a time (the G1 rows, kernels/lv_lanes.c) or a chunk of
 * neighbours at a time (row_t: G2-G4 and the Neumann rows), in vector lanes. Compute-bound: a
 * sqrt, two divisions and ~40 flops per pair (more for G2/G4 and tensors) against 4 bytes of
 * list and the packed row of J; measured (3D 10^6, G1, 1 thread, 2026-12-06) 2.2 ns per pair
 * in the lane rows (2.6 in the chunk rows, ~10 scalar), 3.4-3.5x the stored apply
 * (bench/README.md, "Which bound"). */
#define LANE_BLOCK 256 /* rows per call of a lane worker (as qsfdi): enough blocks for 16 threads */
static void lv_apply(const pst_op *op, const double *u, double *y)
{
    lv_ctx k = make_ctx(op);
    row_fn row = row_for(&k);
    const int64_t *off = pst_nlist_offsets(op->nl);
    const uint32_t *idx = pst_nlist_indices(op->nl);
    lv_lane_rows_fn lanes = lv_lane_rows_for(&k);
    k.list_end = off[op->n];
    size_t nb = (op->n + LANE_BLOCK - 1) / LANE_BLOCK;
#pragma omp parallel for schedule(static)
    for (size_t b = 0; b < nb; ++b) {
        size_t i0 = b * LANE_BLOCK, i1 = i0 + LANE_BLOCK < op->n ? i0 + LANE_BLOCK : op->n;
        if (lanes)
            lanes(&k, off, idx, i0, i1, y);
        for (size_t i = i0; i < i1; ++i)
            if (k.c.kind[i] != PST_DIRICHLET && (!lanes || k.c.kind[i] == PST_NEUMANN))
                row(&k, off, idx, i, u, y, NULL, 0);
    }
}

/* Rows [i0, i1) of a half list (operator.h, half_rows): in lanes where lv_half_lane_rows_for
 * serves the operator (its Neumann rows then after the others, in chunks: still an order fixed
 * by the list), else every row in chunks (half_row_t). */
static void lv_half_rows(const pst_op *op, const int64_t *off, const uint32_t *idx, size_t i0,
                         size_t i1, const double *u, double *y)
{
    lv_ctx k = make_ctx(op);
    row_fn row = row_for(&k);
    lv_lane_rows_fn lanes = lv_half_lane_rows_for(&k);
    if (lanes)
        lanes(&k, off, idx, i0, i1, y);
    for (size_t i = i0; i < i1; ++i)
        if (!lanes || k.c.kind[i] == PST_NEUMANN)
            row(&k, off, idx, i, u, y, NULL, 1);
}

double lv_row_weight(const lv_ctx *k, size_t i, size_t j)
{
    return row_weight(k, k->c.dim, k->variant, k->c.ncomp > 1, k->harmonic, i, j);
}

static void lv_emit_row(const pst_op *op, size_t i, double *w)
{
    lv_ctx k = make_ctx(op);
    row_for(&k)(&k, pst_nlist_offsets(op->nl), pst_nlist_indices(op->nl), i, NULL, NULL, w, 0);
}

static double lv_scale(const pst_op *op, size_t i)
{
    const lv_data *d = op->data;
    return d->s[i];
}

/* <grad u>_I = sum_J V_J (u_J - u_I) C_I g_IJ (54). */
static void lv_gradient(const pst_op *op, const double *u, double *const grad[3])
{
    lv_ctx k = make_ctx(op);
    const int64_t *off = pst_nlist_offsets(op->nl);
    const uint32_t *idx = pst_nlist_indices(op->nl);
    int dim = k.c.dim;
#pragma omp parallel for schedule(static)
    for (size_t b = 0; b < pst_chunks(op->n, PST_CHUNK); ++b)
        PST_CHUNK_ROWS(op->tally, b, op->n, PST_CHUNK, i) {
            const double *C = k.d->C + (size_t)dim * dim * i;
            double acc[3] = {0, 0, 0};
            for (int64_t e = off[i]; e < off[i + 1]; ++e) {
                size_t j = idx[e];
                double x[3], g[3], d2;
                pair_gradient(&k, dim, k.variant, i, j, x, g, &d2);
                double du = k.c.V[j] * (u[j] - u[i]);
                for (int c = 0; c < dim; ++c)
                    acc[c] += du * g[c];
            }
            for (int a = 0; a < dim; ++a) {
                double v = 0;
                for (int c = 0; c < dim; ++c)
                    v += C[a * dim + c] * acc[c];
                grad[a][i] = v;
            }
        }
}

/* Lemma 3 diagnostics of row i: do the brackets F - eta . g (F (1 - xi . x) for radial
 * variants) share one sign (92), and is |xi_I| max_J d_IJ < 1 (the sufficient check)? */
static void lv_lemma3(const pst_op *op, size_t i, int *sign_mixed, int *xi_large)
{
    lv_ctx k = make_ctx(op);
    const int64_t *off = pst_nlist_offsets(op->nl);
    const uint32_t *idx = pst_nlist_indices(op->nl);
    int dim = k.c.dim;
    const double *eta = k.d->eta + (size_t)dim * i;
    int pos = 0, neg = 0;
    double dmax = 0, xi2 = 0;
    for (int c = 0; c < dim; ++c)
        xi2 += eta[c] * eta[c];
    for (int64_t e = off[i]; e < off[i + 1]; ++e) {
        double x[3], g[3], d2, F = pair_gradient(&k, dim, k.variant, i, idx[e], x, g, &d2);
        double t = F;
        for (int c = 0; c < dim; ++c)
            t -= eta[c] * g[c];
        pos += t > 0;
        neg += t < 0;
        dmax = d2 > dmax ? d2 : dmax;
    }
    *sign_mixed = pos > 0 && neg > 0;
    *xi_large = xi2 * dmax >= 1.0;
}

/* A flat neighbourhood (pst_op_check_flat_rows): a linear-exact row has no diagonal there, so
 * the row becomes the Brookshaw row (zeta = eta = 0) normalised to be exact for |x - x_I|^2,
 * s = n / sum_J V_J F_IJ d_IJ^2 (about 1 with a full support; a flat, one-sided neighbourhood
 * would otherwise give a row too weak to pin u_I). C stays, for the gradient (it is regular
 * when the flat set misses I). */
static void lv_degrade(pst_op *op, size_t i)
{
    lv_ctx k = make_ctx(op);
    lv_data *d = op->data;
    const int dim = op->dim;
    const int64_t *off = pst_nlist_offsets(op->nl);
    const uint32_t *idx = pst_nlist_indices(op->nl);
    double sum = 0;
    for (int64_t e = off[i]; e < off[i + 1]; ++e) {
        double x[3], g[3], d2, F = pair_gradient(&k, dim, k.variant, i, idx[e], x, g, &d2);
        sum += k.c.V[idx[e]] * F * d2;
    }
    d->s[i] = sum > 0 ? dim / sum : 1.0;
    for (int a = 0; a < dim; ++a)
        d->zeta[(size_t)dim * i + a] = d->eta[(size_t)dim * i + a] = 0.0;
}

#define LV_SCHEME(ID, NAME, DESC, FALLBACK, DEG, DEGL, PRE, MIN, GRAD, LEMMA, DEGRADE)       \
    const pst_scheme ID = {.name = NAME,                                                      \
                           .description = DESC,                                               \
                           .fallback = FALLBACK,                                              \
                           .default_kernel = PST_KERNEL_CUBIC,                                \
                           .degree = DEG,                                                     \
                           .degree_lattice = DEGL,                                            \
                           .pair_mobility = 1,                                                \
                           .mobility = 1,                                                     \
                           .min_neighbours = MIN,                                             \
                           .precompute = PRE,                                                 \
                           .apply = lv_apply,                                                 \
                           .lanes = 1,                                                        \
                           .half_rows = lv_half_rows,                                         \
                           .emit_row = lv_emit_row,                                           \
                           .scale = lv_scale,                                                 \
                           .gradient = GRAD,                                                  \
                           .lemma3 = LEMMA,                                                   \
                           .degrade = DEGRADE,                                                \
                           .free_data = lv_free,                                              \
                           .data_bytes = {96, 160}} /* C, zeta, eta, s, nu, grad nu */

LV_SCHEME(pst_scheme_brookshaw, "brookshaw", "Brookshaw 1985, m_I + m_J (LV eq. 27)",
          "no neighbour -> zero row (the Brookshaw row is the other schemes' last resort)", 0, 0,
          pre_brookshaw, lv_min_brookshaw, NULL, NULL, NULL);
LV_SCHEME(pst_scheme_cb, "cb", "corrected Brookshaw, times tr C / n (LV eq. 51)",
          "too few neighbours, C singular or tr C <= 0 -> Brookshaw row -> zero row", 0, 3, pre_cb,
          lv_min_cb, lv_gradient, NULL, NULL);
LV_SCHEME(pst_scheme_schwaiger, "schwaiger", "Schwaiger 2008 (LV eqs. 52-55)",
          "too few neighbours, C or Gamma singular, tr Gamma^-1 <= 0 -> Brookshaw row -> zero "
          "row; flat neighbours off the particle -> normalised Brookshaw row",
          1, 1, pre_schwaiger, lv_min_schwaiger, lv_gradient, lv_lemma3, lv_degrade);
LV_SCHEME(pst_scheme_lv, "lv", "Lukyanov-Vuik two-point scheme M-SPH (LV eqs. 69-71, 90-91)",
          "Gamma* not SDD -> Gamma-bar = Gamma (eq. 70); too few neighbours, C or Gamma-bar "
          "singular, tr Gamma-bar^-1 <= 0 -> Brookshaw row -> zero row; flat neighbours off the "
          "particle -> normalised Brookshaw row",
          1, 1, pre_msph, lv_min_msph, lv_gradient, lv_lemma3, lv_degrade);
