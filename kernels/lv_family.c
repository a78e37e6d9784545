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
 * row (s = 1, zeta = 0); Neumann rows with a singular C use C = I. Never NaN.
 * This file: the precompute, the applies' dispatch and the scheme table. The rows are in
 * lv_lanes.c and lv_half_lanes.c (G1, a block of pairs at a time) and lv_rows.c and
 * lv_half_rows.c (the rest, a chunk at a time), the pair arithmetic they share in lv_family.h
 * and lv_chunks.h. */
#include "isa.h"
#include "lv_chunks.h"
#include "small_matrix.h"

#include <stddef.h>
#include <stdlib.h>
#include <string.h>

static lv_ctx make_ctx(const pst_op *op)
{
    return (lv_ctx){.c = pst_kctx_of(op), .variant = op->opts.gradient,
                    .harmonic = op->opts.mobility_mean == PST_MEAN_HARMONIC, .d = op->data};
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
 * per-particle data, a block of pairs at a time (the G1 rows, kernels/lv_lanes.c) or a chunk of
 * neighbours at a time (row_t, kernels/lv_rows.c: G2-G4 and the Neumann rows), in vector
 * lanes. Compute-bound: a sqrt, two divisions and ~40 flops per pair (more for G2/G4 and
 * tensors) against 4 bytes of list and the packed row of J; measured (3D 10^6, G1, 1 thread,
 * 2026-12-06) 2.2 ns per pair in the lane rows (2.6 in the chunk rows, ~10 scalar), 3.4-3.5x
 * the stored apply (bench/README.md, "Which bound"). */
#define LANE_BLOCK 256 /* rows per call of a lane worker (as qsfdi): enough blocks for 16 threads */
static void lv_apply(const pst_op *op, const double *u, double *y)
{
    (void)u; /* read from op->xyzu */
    lv_ctx k = make_ctx(op);
    lv_row_fn row = lv_row_for(&k);
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
                row(&k, off, idx, i, y, NULL);
    }
}

/* Rows [i0, i1) of a half list (operator.h, half_rows): in lanes where lv_half_lane_rows_for
 * serves the operator (its Neumann rows then after the others, in chunks: still an order fixed
 * by the list), else every row in chunks (half_row_t, kernels/lv_half_rows.c). */
static void lv_half_rows(const pst_op *op, const int64_t *off, const uint32_t *idx, size_t i0,
                         size_t i1, const double *u, double *y)
{
    lv_ctx k = make_ctx(op);
    lv_half_row_fn row = lv_half_row_for(&k);
    lv_lane_rows_fn lanes = lv_half_lane_rows_for(&k);
    if (lanes)
        lanes(&k, off, idx, i0, i1, y);
    for (size_t i = i0; i < i1; ++i)
        if (!lanes || k.c.kind[i] == PST_NEUMANN)
            row(&k, off, idx, i, u, y);
}

static void lv_emit_row(const pst_op *op, size_t i, double *w)
{
    lv_ctx k = make_ctx(op);
    lv_row_for(&k)(&k, pst_nlist_offsets(op->nl), pst_nlist_indices(op->nl), i, NULL, w);
}

static double lv_scale(const pst_op *op, size_t i)
{
    const lv_data *d = op->data;
    return d->s[i];
}

/* <grad u>_I = sum_J V_J (u_J - u_I) C_I g_IJ (54): one pass over the neighbours with the kept
 * C_I, a chunk at a time (lv_rows.c). */
static void lv_gradient(const pst_op *op, const double *u, double *const grad[3])
{
    lv_ctx k = make_ctx(op);
    const int64_t *off = pst_nlist_offsets(op->nl);
    const uint32_t *idx = pst_nlist_indices(op->nl);
    const lv_gradient_row_fn row = lv_gradient_row_for(&k);
    int dim = k.c.dim;
#pragma omp parallel for schedule(static)
    for (size_t b = 0; b < pst_chunks(op->n, PST_CHUNK); ++b)
        PST_CHUNK_ROWS(op->tally, b, op->n, PST_CHUNK, i) {
            double g[3];
            row(&k, off, idx, i, u, g);
            for (int a = 0; a < dim; ++a)
                grad[a][i] = g[a];
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
