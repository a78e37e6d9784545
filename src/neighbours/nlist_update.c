/* Verlet lists: a neighbour list kept across moves of the particles (docs/neighbours.md,
 * "Moving particles"). Beside the list of radius support * (h_i + h_j) / 2 it keeps a wide
 * list built with support + skin and the positions and h of that build. While every pair that
 * can now be within its radius was within the wide radius then, the list is the wide list's
 * pairs filtered by the true rule (nlist_rule.h, the build's own test), entry for entry the
 * list a fresh build would give; otherwise the wide list is built again.
 *
 * The rule: with D the largest displacement since the wide build and G >= 0 the largest growth
 * of any h, a pair now within support * (h'_i + h'_j) / 2 was within
 * support * (h_i + h_j) / 2 + 2 D + support * G, which the wide radius covers while
 * 2 D + support * G <= skin * min h (the margin of the narrowest pair), less a rounding
 * allowance. The filter marks and counts the kept pairs of every row (the distance tests,
 * vectorised), sums the counts into offsets and copies the marked entries: every entry goes to
 * a fixed place, so the list is identical for every thread count. */
#include "check.h"
#include "cloud_layout.h"
#include "isa.h"
#include "nlist_layout.h"
#include "nlist_rule.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

struct pst_verlet {
    double skin;            /* in units of h, > 0                                        */
    pst_nlist *wide;        /* the list of support + skin at the last rebuild            */
    double *x0;             /* the positions then: dim blocks of n                       */
    double *h0;             /* per-particle h then, or NULL when h was uniform           */
    double h0_uniform;      /* uniform h then (0 when per particle)                      */
    double budget;          /* skin * min h then, less the rounding allowance            */
    int64_t capacity;       /* entries the list's index array holds                      */
    uint8_t *keep;          /* the filter's mark per wide pair                           */
    int64_t keep_capacity;
    uint64_t permutations;  /* the cloud's pst_cloud_permute count then                  */
    pst_image box;          /* the cloud's periodic box then                             */
    uint64_t rebuilds, filters;
    int dim;
};

void pst_verlet_free(struct pst_verlet *v)
{
    if (!v)
        return;
    pst_nlist_destroy(v->wide);
    pst_free(v->x0);
    pst_free(v->h0);
    pst_free(v->keep);
    free(v);
}

size_t pst_verlet_bytes(const struct pst_verlet *v, size_t n)
{
    if (!v)
        return 0;
    size_t wide = v->wide ? (n + 1) * sizeof(int64_t) +
                                (size_t)v->wide->offset[n] * sizeof(uint32_t) + sizeof *v->wide
                          : 0;
    size_t kept = (v->x0 ? (size_t)v->dim : 0) + (v->h0 != NULL);
    return sizeof *v + wide + kept * n * sizeof(double) +
           (size_t)v->capacity * sizeof(uint32_t) + (size_t)v->keep_capacity;
}

/* Record the positions and h of the wide build, and the displacement budget they allow. */
static int snapshot(struct pst_verlet *v, const pst_cloud *c, double support, char *err)
{
    size_t n = c->n;
    int dim = c->dim;
    if (!v->x0)
        v->x0 = pst_alloc((size_t)dim * n * sizeof *v->x0);
    if (c->h && !v->h0)
        v->h0 = pst_alloc(n * sizeof *v->h0);
    if (!c->h) {
        pst_free(v->h0);
        v->h0 = NULL;
    }
    PST_CHECK(!v->x0 || (c->h && !v->h0), PST_ENOMEM, err,
              "neighbour list: cannot keep the positions of %zu particles for its update", n);
    double hmin = c->h ? INFINITY : c->h_uniform, hmax = pst_cloud_h_max(c), maxabs = 0;
#pragma omp parallel for schedule(static) reduction(min : hmin) reduction(max : maxabs)
    for (size_t i = 0; i < n; ++i) {
        for (int d = 0; d < dim; ++d) {
            v->x0[(size_t)d * n + i] = c->x[d][i];
            maxabs = fmax(maxabs, fabs(c->x[d][i]));
        }
        if (c->h) {
            v->h0[i] = c->h[i];
            hmin = fmin(hmin, c->h[i]);
        }
    }
    v->h0_uniform = c->h ? 0 : c->h_uniform;
    v->dim = dim;
    /* the build's and the filter's distance tests each round by a few ulps of the coordinates
     * and of the radius: the allowance covers both, far below any useful skin */
    double allowance = 1024 * DBL_EPSILON * (maxabs + (support + v->skin) * hmax);
    v->budget = n ? v->skin * hmin - allowance : 0;
    v->permutations = c->permutations;
    v->box = pst_cloud_image(c);
    return PST_OK;
}

/* The cloud is as the last wide build saw it: not permuted since, the same periodic box. */
static int same_layout(const struct pst_verlet *v, const pst_cloud *c)
{
    pst_image now = pst_cloud_image(c);
    int same = v->permutations == c->permutations;
    for (int d = 0; d < 3; ++d)
        same = same && now.P[d] == v->box.P[d];
    return same;
}

/* The largest displacement since the snapshot and the largest growth of h (0 if none). */
static void movement(const struct pst_verlet *v, const pst_cloud *c, double *moved,
                     double *grown)
{
    size_t n = c->n;
    int dim = c->dim;
    const pst_image im = pst_cloud_image(c);
    double m2 = 0, g = 0;
#pragma omp parallel for schedule(static) reduction(max : m2, g)
    for (size_t i = 0; i < n; ++i) {
        double s = 0;
        for (int d = 0; d < dim; ++d) {
            /* a particle folded back into a periodic box moved by its minimum image */
            double t = pst_min_image(c->x[d][i] - v->x0[(size_t)d * n + i], im.P[d], im.hP[d]);
            s += t * t;
        }
        m2 = fmax(m2, s);
        double h0 = v->h0 ? v->h0[i] : v->h0_uniform;
        g = fmax(g, pst_cloud_h_at(c, i) - h0);
    }
    *moved = sqrt(m2);
    *grown = g;
}

#define MARK_CHUNK 64

/* Mark the pairs of the wide list's rows [i0, i1) that the rule keeps (keep[q] = 0 or 1) and
 * count them per row into count[i + 1]. A chunk of a row's neighbours is gathered into small
 * arrays (in cache: a Morton-ordered cloud's rows overlap), then tested by the build's own rule
 * over them, a loop that vectorises: bound by the gathers' loads, about 4 per pair. */
PST_ISA_DISPATCH static void mark_rows(const pst_cloud *c, const pst_nlist *wide, double support,
                                       size_t i0, size_t i1, uint8_t *restrict keep,
                                       int64_t *restrict count)
{
    const double *X = c->x[0], *Y = c->x[1], *Z = c->x[2], *H = c->h;
    double hu = c->h_uniform, r2u = (support * hu) * (support * hu), halfs = 0.5 * support;
    int dim = c->dim, varh = H != NULL;
    const pst_image im = pst_cloud_image(c);
    double gx[MARK_CHUNK], gy[MARK_CHUNK], gz[MARK_CHUNK], gh[MARK_CHUNK];
    for (size_t i = i0; i < i1; ++i) {
        double xi[3] = {X[i], Y[i], dim == 3 ? Z[i] : 0}, hi = pst_cloud_h_at(c, i);
        int64_t k = 0;
        for (int64_t q0 = wide->offset[i]; q0 < wide->offset[i + 1]; q0 += MARK_CHUNK) {
            int len = (int)(wide->offset[i + 1] - q0 < MARK_CHUNK ? wide->offset[i + 1] - q0
                                                                  : MARK_CHUNK);
            const uint32_t *idx = wide->index + q0;
            for (int e = 0; e < len; ++e) {
                gx[e] = X[idx[e]];
                gy[e] = Y[idx[e]];
                gz[e] = dim == 3 ? Z[idx[e]] : 0;
                gh[e] = varh ? H[idx[e]] : 0;
            }
            size_t hits = 0;
#define MARK(D, PER)                                                                           \
    for (int e = 0; e < len; ++e) {                                                            \
        size_t hit = pair_hit(gx, gy, gz, gh, xi, hi, halfs, r2u, D, varh, PER, &im, (size_t)e); \
        keep[q0 + e] = (uint8_t)hit;                                                           \
        hits += hit;                                                                           \
    }
            if (dim == 3) {
                if (im.any)
                    MARK(3, 1)
                else
                    MARK(3, 0)
            } else {
                if (im.any)
                    MARK(2, 1)
                else
                    MARK(2, 0)
            }
#undef MARK
            k += (int64_t)hits;
        }
        count[i + 1] = k;
    }
}

/* Row i's marked entries of the wide list, in order, into out. Branch-free (a mark is a coin
 * toss to the branch predictor) through a chunk buffer, since a compaction stores one entry
 * past its last hit and out's next entry belongs to another row. */
static void compact_row(const pst_nlist *wide, const uint8_t *keep, size_t i, uint32_t *out)
{
    uint32_t buf[MARK_CHUNK + 1];
    for (int64_t q0 = wide->offset[i]; q0 < wide->offset[i + 1]; q0 += MARK_CHUNK) {
        int len = (int)(wide->offset[i + 1] - q0 < MARK_CHUNK ? wide->offset[i + 1] - q0
                                                              : MARK_CHUNK);
        int m = 0;
        for (int e = 0; e < len; ++e) {
            buf[m] = wide->index[q0 + e];
            m += keep[q0 + e];
        }
        memcpy(out, buf, (size_t)m * sizeof *out);
        out += m;
    }
}

/* nl = the wide list's pairs within nl's own radius: the marks and counts, the offsets, then
 * each row's marked entries copied in order. The index array is kept while it is large enough
 * (an eighth more is taken when it grows), the marks likewise. */
static int filter(pst_nlist *nl, const pst_cloud *c, char *err)
{
    struct pst_verlet *v = nl->verlet;
    const pst_nlist *wide = v->wide;
    size_t n = nl->n, block = 1024;
    int64_t wide_pairs = wide->offset[n];
    if (wide_pairs > v->keep_capacity) {
        pst_free(v->keep);
        v->keep = pst_alloc((size_t)(wide_pairs + wide_pairs / 8));
        v->keep_capacity = v->keep ? wide_pairs + wide_pairs / 8 : 0;
        PST_CHECK(!v->keep, PST_ENOMEM, err,
                  "neighbour list: cannot allocate the marks of %lld pairs",
                  (long long)wide_pairs);
    }
    nl->offset[0] = 0;
#pragma omp parallel for schedule(dynamic, 1)
    for (size_t b = 0; b < (n + block - 1) / block; ++b)
        mark_rows(c, wide, nl->support, b * block, b * block + block < n ? b * block + block : n,
                  v->keep, nl->offset);
    for (size_t i = 0; i < n; ++i)
        nl->offset[i + 1] += nl->offset[i];
    int64_t total = nl->offset[n];
    if (total > v->capacity || !nl->index) {
        int64_t cap = total + total / 8;
        pst_free(nl->index);
        nl->index = pst_alloc((size_t)cap * sizeof *nl->index);
        v->capacity = nl->index ? cap : 0;
        PST_CHECK(!nl->index, PST_ENOMEM, err,
                  "neighbour list: cannot allocate %lld entries", (long long)cap);
    }
#pragma omp parallel for schedule(dynamic, 256)
    for (size_t i = 0; i < n; ++i)
        compact_row(wide, v->keep, i, nl->index + nl->offset[i]);
    v->filters++;
    return PST_OK;
}

/* Build the wide list again, record the cloud's state and filter. */
static int rebuild_wide(pst_nlist *nl, const pst_cloud *c, char *err)
{
    struct pst_verlet *v = nl->verlet;
    /* the old wide list goes first (the peak holds one); a failed build leaves none and a
     * budget that makes the next update build again */
    pst_nlist_destroy(v->wide);
    v->wide = NULL;
    v->budget = -1;
    PST_TRY(pst_nlist_build(&v->wide, c, nl->support + v->skin, err));
    PST_TRY(snapshot(v, c, nl->support, err));
    v->rebuilds++;
    return filter(nl, c, err);
}

/* A list without a skin: a fresh build whose arrays replace nl's. */
static int rebuild_plain(pst_nlist *nl, const pst_cloud *c, char *err)
{
    pst_nlist *fresh = NULL;
    PST_TRY(pst_nlist_build(&fresh, c, nl->support, err));
    pst_nlist_adopt(nl, fresh);
    return PST_OK;
}

int pst_nlist_build_skin(pst_nlist **out, const pst_cloud *c, double support, double skin,
                         char *err)
{
    *out = NULL;
    PST_CHECK(!(support > 0) || !isfinite(support), PST_EINVAL, err,
              "neighbour list: support must be finite and > 0 (got %g)", support);
    PST_CHECK(!(skin >= 0) || !(skin <= support), PST_EINVAL, err,
              "neighbour list: skin must be in [0, support = %g] (got %g)", support, skin);
    if (skin == 0)
        return pst_nlist_build(out, c, support, err);
    pst_nlist *nl = calloc(1, sizeof *nl);
    if (nl) {
        nl->offset = pst_calloc(c->n + 1, sizeof *nl->offset);
        nl->verlet = calloc(1, sizeof *nl->verlet);
    }
    if (!nl || !nl->offset || !nl->verlet) {
        pst_nlist_destroy(nl);
        pst_set_err(err, "neighbour list: cannot allocate the offsets of %zu rows", c->n);
        return PST_ENOMEM;
    }
    nl->n = c->n;
    nl->support = support;
    nl->cut = 1;
    nl->verlet->skin = skin;
    int st = rebuild_wide(nl, c, err);
    if (st != PST_OK) {
        pst_nlist_destroy(nl);
        return st;
    }
    *out = nl;
    return PST_OK;
}

int pst_nlist_update(pst_nlist *nl, const pst_cloud *c, pst_nlist_update_info *info, char *err)
{
    PST_CHECK(nl->half || nl->cut != 1, PST_EINVAL, err,
              "neighbour list update: a half or cut list cannot be updated; update the whole "
              "list and derive it again");
    PST_CHECK(nl->from_csr, PST_EINVAL, err,
              "neighbour list update: the list holds the caller's pairs (pst_nlist_from_csr), "
              "which the library cannot recompute; give it the new pairs with "
              "pst_nlist_set_csr");
    PST_CHECK(c->n != nl->n, PST_EINVAL, err,
              "neighbour list update: the cloud has %zu particles, the list %zu rows", c->n,
              nl->n);
    struct pst_verlet *v = nl->verlet;
    pst_nlist_update_info r = {.rebuilt = 1};
    int st;
    if (!v) {
        st = rebuild_plain(nl, c, err);
    } else {
        PST_TRY(pst_nlist_check_cloud(c, nl->support + v->skin, err));
        int same = same_layout(v, c);
        if (same && v->x0)
            movement(v, c, &r.moved, &r.grown);
        /* the negation rebuilds on a NaN too */
        r.rebuilt = !same ||
                    !(2 * r.moved + nl->support * r.grown <= v->budget);
        r.budget = v->budget;
        st = r.rebuilt ? rebuild_wide(nl, c, err) : filter(nl, c, err);
        r.rebuilds = v->rebuilds;
        r.filters = v->filters;
    }
    if (st == PST_OK)
        r.pairs = nl->offset[nl->n];
    if (info)
        *info = r;
    return st;
}

double pst_nlist_skin(const pst_nlist *nl) { return nl->verlet ? nl->verlet->skin : 0; }
