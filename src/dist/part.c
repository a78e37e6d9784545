/* A rank's part of a cloud (docs/distributed.md): the contiguous range of the cloud's order it
 * owns and the ghosts within reach of it, as one local cloud in the cloud's order. Keeping the
 * order keeps every owned row's neighbours in the order the whole cloud's list has them
 * (rows are sorted by index), so the part's operator rows are the whole cloud's bit for bit.
 *
 * The ghosts are found in two steps, each on local data only: the candidates are the particles
 * within `hops` reaches (support * largest h) of the owned particles' bounding box; a neighbour
 * list of owned + candidates then keeps the candidates within `hops` links of an owned
 * particle, ring by ring. A scheme whose rows read their neighbours' own results (the CSPM
 * family's volumes, the mixed schemes' gradients) needs those neighbours' whole lists: two
 * rings (three for mixed0), pst_scheme_halo. */
#include "check.h"
#include "cloud_layout.h"
#include "pstencil/dist.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

struct pst_part {
    int ranks, rank, hops;
    size_t n;        /* particles of the whole cloud                                  */
    size_t lo, hi;   /* owned: [lo, hi) of the cloud's order                         */
    size_t own0;     /* local index of the first owned particle                      */
    size_t nlocal;   /* owned + ghosts                                                */
    size_t *global;  /* local -> cloud index, ascending                               */
    pst_cloud *local;
};

/* Distance from coordinate x to the interval [lo, hi]; along a periodic axis (period P > 0)
 * the nearest of x's images counts. */
static double axis_gap(double x, double lo, double hi, double P)
{
    double g = x < lo ? lo - x : x > hi ? x - hi : 0.0;
    if (P > 0)
        for (int s = -1; s <= 1; s += 2) {
            double y = x + s * P;
            g = fmin(g, y < lo ? lo - y : y > hi ? y - hi : 0.0);
        }
    return g;
}

/* The boundary a part copies: kinds and normals over the whole cloud. */
typedef struct {
    const uint8_t *kind;
    const double *normal[3];
} boundary;

/* A cloud of the m particles idx[] of c (ascending), with every per-particle array copied, the
 * kinds and normals from bd, and the particles outside [lo, hi) of c made Dirichlet: their
 * rows are not computed. */
static int extract(const pst_cloud *c, const boundary *bd, const size_t *idx, size_t m,
                   size_t lo, size_t hi, pst_cloud **out, char *err)
{
    pst_cloud *s = NULL;
    PST_TRY(pst_cloud_create(&s, c->dim, m, err));
    int st = PST_OK;
    if (!c->h_uniform && !pst_cloud_h_per_particle(s))
        st = PST_ENOMEM;
    if (st == PST_OK && c->h_uniform)
        st = pst_cloud_set_h_uniform(s, c->h_uniform, err);
    if (st == PST_OK && c->mob_ncomp)
        st = pst_cloud_set_mobility(s, c->mob_ncomp, err);
    int per[3];
    double blo[3], bhi[3];
    if (st == PST_OK && pst_cloud_periodic(c, per, blo, bhi))
        st = pst_cloud_set_periodic(s, per, blo, bhi, err);
    if (st != PST_OK) {
        pst_cloud_destroy(s);
        PST_CHECK(st == PST_ENOMEM, PST_ENOMEM, err, "part: out of memory for %zu particles", m);
        return st;
    }
    for (size_t k = 0; k < m; ++k) {
        size_t i = idx[k];
        for (int d = 0; d < c->dim; ++d) {
            s->x[d][k] = c->x[d][i];
            s->normal[d][k] = bd->normal[d][i];
        }
        for (int q = 0; q < c->mob_ncomp; ++q)
            s->mob[q][k] = c->mob[q][i];
        if (s->h)
            s->h[k] = c->h[i];
        s->V[k] = c->V[i];
        s->kind[k] = i >= lo && i < hi ? bd->kind[i] : (uint8_t)PST_DIRICHLET;
        s->id[k] = c->id[i];
    }
    *out = s;
    return PST_OK;
}

/* The owned particles and the candidates (ascending) into *idx: every particle of [lo, hi)
 * and those within `reach` of the owned bounding box. */
static int candidates(const pst_cloud *c, size_t lo, size_t hi, double reach, size_t **idx,
                      size_t *m, char *err)
{
    double blo[3] = {0, 0, 0}, bhi[3] = {0, 0, 0}, P[3] = {0, 0, 0}, plo[3], phi[3];
    int per[3];
    pst_cloud_periodic(c, per, plo, phi);
    for (int d = 0; d < c->dim; ++d) {
        blo[d] = INFINITY;
        bhi[d] = -INFINITY;
        for (size_t i = lo; i < hi; ++i) {
            blo[d] = fmin(blo[d], c->x[d][i]);
            bhi[d] = fmax(bhi[d], c->x[d][i]);
        }
        P[d] = per[d] ? phi[d] - plo[d] : 0.0;
    }
    size_t *out = malloc((c->n ? c->n : 1) * sizeof *out), k = 0;
    PST_CHECK_ALLOC(out, err, "part: out of memory for the candidates");
    for (size_t i = 0; i < c->n; ++i) {
        int near = 1;
        for (int d = 0; d < c->dim && near && (i < lo || i >= hi); ++d)
            near = axis_gap(c->x[d][i], blo[d], bhi[d], P[d]) <= reach;
        if (near)
            out[k++] = i;
    }
    size_t *fit = realloc(out, (k ? k : 1) * sizeof *out); /* the part, not the cloud */
    *idx = fit ? fit : out;
    *m = k;
    return PST_OK;
}

/* Keep in idx[0..m) the owned particles and the candidates within `hops` links of one in the
 * list of the candidates' cloud: ring 1 is what an owned row reaches, ring r + 1 what a row of
 * ring r reaches. *m becomes their count. */
static int keep_reached(const pst_cloud *c, const boundary *bd, size_t lo, size_t hi,
                        double support, int hops, size_t *idx, size_t *m, char *err)
{
    pst_cloud *cand = NULL;
    pst_nlist *nl = NULL;
    uint8_t *ring = malloc(*m ? *m : 1); /* 0: owned, r: ring r, UINT8_MAX: not reached */
    PST_CHECK_ALLOC(ring, err, "part: out of memory for the ghost marks");
    int st = extract(c, bd, idx, *m, lo, hi, &cand, err);
    if (st == PST_OK)
        st = pst_nlist_build(&nl, cand, support, err);
    if (st == PST_OK) {
        const int64_t *off = pst_nlist_offsets(nl);
        const uint32_t *nb = pst_nlist_indices(nl);
        for (size_t k = 0; k < *m; ++k)
            ring[k] = idx[k] >= lo && idx[k] < hi ? 0 : UINT8_MAX;
        for (int r = 0; r < hops; ++r)
            for (size_t k = 0; k < *m; ++k)
                if (ring[k] == r)
                    for (int64_t e = off[k]; e < off[k + 1]; ++e)
                        if (ring[nb[e]] == UINT8_MAX)
                            ring[nb[e]] = (uint8_t)(r + 1);
        size_t kept = 0;
        for (size_t k = 0; k < *m; ++k)
            if (ring[k] != UINT8_MAX)
                idx[kept++] = idx[k];
        *m = kept;
    }
    pst_nlist_destroy(nl);
    pst_cloud_destroy(cand);
    free(ring);
    return st;
}

int pst_part_create(pst_part **out, const pst_cloud *c, const uint8_t *kind,
                    const double *const normal[3], int ranks, int rank, double support,
                    int hops, char *err)
{
    PST_CHECK(!out || !c, PST_EINVAL, err, "part: NULL argument");
    boundary bd = {kind ? kind : c->kind, {NULL, NULL, NULL}};
    for (int d = 0; d < c->dim; ++d)
        bd.normal[d] = normal && normal[0] ? normal[d] : c->normal[d];
    *out = NULL;
    PST_CHECK(ranks < 1 || ranks > PST_PART_MAX_RANKS || rank < 0 || rank >= ranks, PST_EINVAL,
              err, "part: rank %d of %d ranks (1 to %d ranks)", rank, ranks, PST_PART_MAX_RANKS);
    PST_CHECK(!(support > 0) || !isfinite(support), PST_EINVAL, err,
              "part: the support must be finite and > 0 (got %g)", support);
    PST_CHECK(hops < 1 || hops > PST_PART_MAX_HOPS, PST_EINVAL, err,
              "part: %d rings of ghosts (1 to %d)", hops, PST_PART_MAX_HOPS);
    pst_part *p = calloc(1, sizeof *p);
    PST_CHECK_ALLOC(p, err, "part: out of memory");
    p->ranks = ranks;
    p->rank = rank;
    p->hops = hops;
    p->n = c->n;
    p->lo = c->n * (size_t)rank / (size_t)ranks;
    p->hi = c->n * (size_t)(rank + 1) / (size_t)ranks;
    size_t m = 0;
    int st = candidates(c, p->lo, p->hi, hops * support * pst_cloud_h_max(c), &p->global, &m,
                        err);
    if (st == PST_OK && p->hi > p->lo)
        st = keep_reached(c, &bd, p->lo, p->hi, support, hops, p->global, &m, err);
    else if (st == PST_OK)
        m = 0; /* nothing owned: nothing to reach */
    if (st == PST_OK)
        st = extract(c, &bd, p->global, m, p->lo, p->hi, &p->local, err);
    if (st != PST_OK) {
        pst_part_destroy(p);
        return st;
    }
    p->nlocal = m;
    while (p->own0 < m && p->global[p->own0] < p->lo)
        p->own0++;
    *out = p;
    return PST_OK;
}

void pst_part_destroy(pst_part *p)
{
    if (!p)
        return;
    pst_cloud_destroy(p->local);
    free(p->global);
    free(p);
}

const pst_cloud *pst_part_cloud(const pst_part *p) { return p->local; }

void pst_part_layout(const pst_part *p, pst_part_info *info)
{
    *info = (pst_part_info){.ranks = p->ranks, .rank = p->rank, .hops = p->hops, .n = p->n,
                            .lo = p->lo, .hi = p->hi, .own0 = p->own0, .nlocal = p->nlocal,
                            .nghost = p->nlocal - (p->hi - p->lo)};
}

const size_t *pst_part_global(const pst_part *p) { return p->global; }

void pst_part_take(const pst_part *p, const double *whole, double *local)
{
    for (size_t k = 0; k < p->nlocal; ++k)
        local[k] = whole[p->global[k]];
}
