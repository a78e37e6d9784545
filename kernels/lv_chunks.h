/* The Lukyanov-Vuik family's pair arithmetic from the positions (pair_geometry, gradient_from,
 * weight_from, neumann_from) and the geometry and weights of a chunk of a row's pairs in
 * arrays: what the precompute (lv_family.c) and the chunk rows (lv_rows.c for the whole list,
 * lv_half_rows.c for a half list) share, so that every row and the stored weights agree bit for
 * bit. Internal; every function is inlined into its caller. */
#ifndef PSTENCIL_LV_CHUNKS_H
#define PSTENCIL_LV_CHUNKS_H

#include "lanes.h"
#include "lv_family.h"
#include "sph_kernels.h"

#include <math.h>

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

#endif /* PSTENCIL_LV_CHUNKS_H */
