/* Neighbour lists: exact agreement with an O(N^2) search (same rows, same order) on random and
 * degenerate clouds, strict < at distance exactly R, scale invariance, Morton-sorted vs
 * unsorted clouds, thread-count independence, argument errors. */
#include "check.h"
#include "internal.h"
#include "nlist_layout.h"

#include <omp.h>
#include <stdlib.h>
#include <string.h>

static uint64_t rng_state;
static double rnd(void) /* splitmix64 -> [0, 1) */
{
    uint64_t z = (rng_state += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    z ^= z >> 31;
    return (double)(z >> 11) * 0x1p-53;
}

/* A jittered lattice of side^dim points (spacing s0, jitter K*s0*[-1,1]), in a shuffled order
 * when `shuffle`; h = hfac*s0, times a factor in [1, 2) per particle when `vary_h`. */
static pst_cloud *lattice(int dim, int side, double s0, double K, int shuffle, double hfac,
                          int vary_h, uint64_t seed)
{
    rng_state = seed;
    size_t n = 1;
    for (int d = 0; d < dim; ++d)
        n *= (size_t)side;
    pst_cloud *c;
    if (pst_cloud_create(&c, dim, n, NULL) != PST_OK)
        return NULL;
    size_t *slot = malloc(n * sizeof *slot);
    for (size_t i = 0; i < n; ++i)
        slot[i] = i;
    for (size_t i = n; shuffle && i > 1; --i) {
        size_t j = (size_t)(rnd() * (double)i);
        size_t t = slot[i - 1];
        slot[i - 1] = slot[j];
        slot[j] = t;
    }
    for (size_t i = 0; i < n; ++i) {
        size_t s = slot[i];
        for (int d = 0; d < dim; ++d) {
            double jit = K * (2 * rnd() - 1);
            pst_cloud_coord(c, d)[i] = ((double)(s % (size_t)side) + jit) * s0;
            s /= (size_t)side;
        }
    }
    free(slot);
    pst_cloud_set_h_uniform(c, hfac * s0, NULL);
    if (vary_h) {
        double *h = pst_cloud_h_per_particle(c);
        for (size_t i = 0; i < n; ++i)
            h[i] = hfac * s0 * (1 + rnd());
    }
    return c;
}

typedef struct {
    int64_t *off;
    uint32_t *idx;
} ref_list;

/* The rule of choice 1 (docs/choices.md), written out directly. */
static ref_list brute(pst_cloud *c, double support)
{
    size_t n = pst_cloud_size(c);
    int dim = pst_cloud_dim(c);
    const double *x[3] = {NULL, NULL, NULL};
    for (int d = 0; d < dim; ++d)
        x[d] = pst_cloud_coord_const(c, d);
    const double *h = pst_cloud_h_array(c);
    double hu = pst_cloud_h_uniform(c);
    ref_list r = {calloc(n + 1, sizeof(int64_t)), NULL};
    size_t cap = 1024, len = 0;
    r.idx = malloc(cap * sizeof *r.idx);
    for (size_t i = 0; i < n; ++i) {
        for (size_t j = 0; j < n; ++j) {
            if (j == i)
                continue;
            double dx = x[0][j] - x[0][i], dy = x[1][j] - x[1][i];
            double d2 = dx * dx + dy * dy;
            if (dim == 3) {
                double dz = x[2][j] - x[2][i];
                d2 += dz * dz;
            }
            double R = h ? support * (h[i] + h[j]) / 2 : support * hu;
            if (d2 < R * R) {
                if (len == cap)
                    r.idx = realloc(r.idx, (cap *= 2) * sizeof *r.idx);
                r.idx[len++] = (uint32_t)j;
            }
        }
        r.off[i + 1] = (int64_t)len;
    }
    return r;
}

static int same_list(const pst_nlist *nl, ref_list r, size_t n)
{
    if (pst_nlist_rows(nl) != n || pst_nlist_pairs(nl) != r.off[n])
        return 0;
    return memcmp(pst_nlist_offsets(nl), r.off, (n + 1) * sizeof(int64_t)) == 0 &&
           memcmp(pst_nlist_indices(nl), r.idx, (size_t)r.off[n] * sizeof(uint32_t)) == 0;
}

static int same_nlists(const pst_nlist *a, const pst_nlist *b)
{
    size_t n = pst_nlist_rows(a);
    return n == pst_nlist_rows(b) && pst_nlist_pairs(a) == pst_nlist_pairs(b) &&
           memcmp(pst_nlist_offsets(a), pst_nlist_offsets(b), (n + 1) * sizeof(int64_t)) == 0 &&
           memcmp(pst_nlist_indices(a), pst_nlist_indices(b),
                  (size_t)pst_nlist_pairs(a) * sizeof(uint32_t)) == 0;
}

/* Build, compare with brute force, return the list (NULL on failure). */
static pst_nlist *check_against_brute(pst_cloud *c, double support)
{
    pst_nlist *nl = NULL;
    char err[PST_ERRLEN] = "";
    int st = pst_nlist_build(&nl, c, support, err);
    CHECK_INT(st, PST_OK);
    if (st != PST_OK) {
        fprintf(stderr, "  %s\n", err);
        return NULL;
    }
    ref_list r = brute(c, support);
    CHECK(same_list(nl, r, pst_cloud_size(c)));
    free(r.off);
    free(r.idx);
    return nl;
}

static void test_random_clouds(void)
{
    for (int dim = 2; dim <= 3; ++dim)
        for (int vary = 0; vary <= 1; ++vary)
            for (int k = 0; k < 3; ++k) {
                double K = k == 0 ? 0.0 : k == 1 ? 0.5 : 0.9;
                int side = dim == 2 ? 60 : 15;
                double support = k == 2 ? 2.0 : 3.0;
                pst_cloud *c = lattice(dim, side, 0.01, K, k == 1, 1.2, vary,
                                       (uint64_t)(100 * dim + 10 * vary + k));
                pst_nlist *nl = check_against_brute(c, support);
                if (nl) {
                    pst_nlist_stats s;
                    pst_nlist_get_stats(nl, &s);
                    CHECK(s.mean > (dim == 2 ? 8 : 20)); /* the test is not vacuous */
                    CHECK_INT(s.pairs % 2, 0);           /* symmetric rule */
                    CHECK_INT(s.bytes, sizeof(struct pst_nlist) +
                                           sizeof(int64_t) * (pst_cloud_size(c) + 1) +
                                           sizeof(uint32_t) * (size_t)s.pairs);
                }
                pst_nlist_destroy(nl);
                pst_cloud_destroy(c);
            }
}

/* Uniformly random points (no lattice), including pairs far closer than the spacing. */
static void test_uniform_random(void)
{
    for (int dim = 2; dim <= 3; ++dim) {
        size_t n = 3000;
        pst_cloud *c;
        pst_cloud_create(&c, dim, n, NULL);
        rng_state = 77 + (uint64_t)dim;
        for (int d = 0; d < dim; ++d)
            for (size_t i = 0; i < n; ++i)
                pst_cloud_coord(c, d)[i] = rnd() * (d == 0 ? 3.0 : 1.0) - 0.5;
        double *h = pst_cloud_h_per_particle(c);
        for (size_t i = 0; i < n; ++i)
            h[i] = 0.02 * (1 + rnd());
        pst_nlist_destroy(check_against_brute(c, 3.0));
        pst_cloud_destroy(c);
    }
}

/* Lattices whose spacing is the cell size (particles on every cell face) and whose axis
 * neighbours sit at exactly R: strict < excludes them. s0 and h are powers of two, so every
 * distance is exact. */
static void test_exact_distances(void)
{
    for (int dim = 2; dim <= 3; ++dim) {
        int side = dim == 2 ? 20 : 8;
        /* R = 3 * h = 3 * s0/3 is not exact; use support 2, h = s0/2: R = s0 */
        pst_cloud *c = lattice(dim, side, 0.25, 0.0, 0, 0.5, 0, 5);
        pst_nlist *nl = check_against_brute(c, 2.0);
        if (nl)
            CHECK_INT(pst_nlist_pairs(nl), 0); /* every neighbour is at distance >= R */
        pst_nlist_destroy(nl);
        /* R = 2 s0: axis neighbours at s0 and the diagonals (sqrt 2, sqrt 3 s0) are in, the
         * axis neighbours at exactly 2 s0 are out */
        pst_cloud_set_h_uniform(c, 0.25, NULL);
        nl = check_against_brute(c, 2.0);
        if (nl) {
            /* a particle far from the faces: 2D 3x3 - 1 = 8 (the 4 at 2 s0 excluded), plus the
             * 8 at sqrt(5) s0 > 2 s0 out: 8. 3D: 3^3 - 1 = 26 */
            size_t mid = 0;
            for (int d = dim - 1; d >= 0; --d)
                mid = mid * (size_t)side + (size_t)side / 2;
            const int64_t *o = pst_nlist_offsets(nl);
            CHECK_INT(o[mid + 1] - o[mid], dim == 2 ? 8 : 26);
        }
        pst_nlist_destroy(nl);
        pst_cloud_destroy(c);
    }
}

/* Coordinates and h scaled by 1e-6 and 1e+6 still match brute force; a power-of-two scaling
 * (also with a far-away offset) gives exactly the unscaled list. */
static void test_scaling(void)
{
    for (int dim = 2; dim <= 3; ++dim) {
        int side = dim == 2 ? 40 : 12;
        pst_cloud *ref = lattice(dim, side, 1.0, 0.7, 1, 1.2, 1, 11);
        pst_nlist *base = check_against_brute(ref, 3.0);
        const double scales[4] = {1e-6, 1e6, 0x1p-20, 0x1p20};
        for (int s = 0; s < 4; ++s) {
            pst_cloud *c = lattice(dim, side, 1.0, 0.7, 1, 1.2, 1, 11);
            for (int d = 0; d < dim; ++d)
                for (size_t i = 0; i < pst_cloud_size(c); ++i)
                    pst_cloud_coord(c, d)[i] *= scales[s];
            double *h = pst_cloud_h_per_particle(c);
            for (size_t i = 0; i < pst_cloud_size(c); ++i)
                h[i] *= scales[s];
            pst_nlist *nl = check_against_brute(c, 3.0);
            if (s >= 2 && nl && base)
                CHECK(same_nlists(nl, base));
            pst_nlist_destroy(nl);
            pst_cloud_destroy(c);
        }
        pst_nlist_destroy(base);
        pst_cloud_destroy(ref);
    }
}

static void test_tiny_clouds(void)
{
    for (int dim = 2; dim <= 3; ++dim) {
        for (size_t n = 0; n <= 2; ++n) {
            pst_cloud *c;
            pst_cloud_create(&c, dim, n, NULL);
            if (n == 2)
                pst_cloud_coord(c, 0)[1] = 0.5; /* h = 1, support 1: neighbours */
            pst_nlist *nl = NULL;
            CHECK_INT(pst_nlist_build(&nl, c, 1.0, NULL), PST_OK);
            if (nl) {
                CHECK_INT(pst_nlist_rows(nl), n);
                CHECK_INT(pst_nlist_pairs(nl), n == 2 ? 2 : 0);
                CHECK_INT(pst_nlist_offsets(nl)[0], 0);
                pst_nlist_stats s;
                pst_nlist_get_stats(nl, &s);
                CHECK_INT(s.isolated, n == 2 ? 0 : n);
                if (n == 2)
                    CHECK(pst_nlist_indices(nl)[0] == 1 && pst_nlist_indices(nl)[1] == 0);
            }
            pst_nlist_destroy(nl);
            pst_cloud_destroy(c);
        }
    }
}

/* The same cloud unsorted and Morton-sorted (several cell sizes, including ones that do not
 * match the neighbour grid): the same neighbour sets once relabelled through the ids. */
static void test_sorted_vs_unsorted(void)
{
    for (int dim = 2; dim <= 3; ++dim) {
        int side = dim == 2 ? 50 : 14;
        double s0 = 0.1, support = 3.0;
        const double cells[3] = {support * 1.2 * s0, support * 1.2 * s0 / 4, 0.37 * s0};
        for (int v = 0; v < 3; ++v) {
            pst_cloud *c = lattice(dim, side, s0, 0.5, 1, 1.2, v == 2, 21);
            size_t n = pst_cloud_size(c);
            pst_nlist *un = NULL, *so = NULL;
            CHECK_INT(pst_nlist_build(&un, c, support, NULL), PST_OK);
            CHECK_INT(pst_cloud_morton_sort(c, cells[v], NULL), PST_OK);
            pst_nlist *nl = check_against_brute(c, support); /* rows sorted on sorted clouds */
            pst_nlist_destroy(nl);
            CHECK_INT(pst_nlist_build(&so, c, support, NULL), PST_OK);
            if (!un || !so) {
                pst_nlist_destroy(un);
                pst_nlist_destroy(so);
                pst_cloud_destroy(c);
                continue;
            }
            const int64_t *id = pst_cloud_ids_const(c);
            const int64_t *ou = pst_nlist_offsets(un), *os = pst_nlist_offsets(so);
            const uint32_t *iu = pst_nlist_indices(un), *is = pst_nlist_indices(so);
            CHECK_INT(pst_nlist_pairs(un), pst_nlist_pairs(so));
            /* mark the unsorted row of ids[i] and look up the sorted row's relabelled entries */
            int bad = 0;
            uint8_t *mark = calloc(n, 1);
            for (size_t i = 0; i < n && !bad; ++i) {
                size_t u = (size_t)id[i];
                for (int64_t e = ou[u]; e < ou[u + 1]; ++e)
                    mark[iu[e]] = 1;
                bad |= (ou[u + 1] - ou[u]) != (os[i + 1] - os[i]);
                for (int64_t e = os[i]; e < os[i + 1]; ++e)
                    bad |= !mark[id[is[e]]];
                for (int64_t e = ou[u]; e < ou[u + 1]; ++e)
                    mark[iu[e]] = 0;
            }
            CHECK(!bad);
            free(mark);
            pst_nlist_destroy(un);
            pst_nlist_destroy(so);
            pst_cloud_destroy(c);
        }
    }
}

static void test_threads(void)
{
    int saved = omp_get_max_threads();
    for (int dim = 2; dim <= 3; ++dim)
        for (int vary = 0; vary <= 1; ++vary) {
            pst_cloud *c = lattice(dim, dim == 2 ? 120 : 24, 1.0, 0.9, 1, 1.2, vary, 31);
            static const int threads[3] = {1, 2, 5};
            pst_nlist *nl[3] = {NULL, NULL, NULL};
            for (int k = 0; k < 3; ++k) {
                omp_set_num_threads(threads[k]);
                CHECK_INT(pst_nlist_build(&nl[k], c, 3.0, NULL), PST_OK);
            }
            for (int k = 1; k < 3; ++k)
                if (nl[0] && nl[k])
                    CHECK(same_nlists(nl[0], nl[k]));
            for (int k = 0; k < 3; ++k)
                pst_nlist_destroy(nl[k]);
            pst_cloud_destroy(c);
        }
    omp_set_num_threads(saved);
}

static void test_errors(void)
{
    pst_cloud *c = lattice(2, 5, 1.0, 0.1, 0, 1.2, 0, 3);
    pst_nlist *nl = (pst_nlist *)&nl;
    char err[PST_ERRLEN] = "";
    const double bad[4] = {0.0, -1.0, NAN, INFINITY};
    for (int k = 0; k < 4; ++k) {
        err[0] = 0;
        CHECK_INT(pst_nlist_build(&nl, c, bad[k], err), PST_EINVAL);
        CHECK(nl == NULL);
        CHECK(strlen(err) > 0);
    }
    pst_cloud_h_per_particle(c)[3] = 0.0;
    err[0] = 0;
    CHECK_INT(pst_nlist_build(&nl, c, 2.0, err), PST_EINPUT);
    CHECK(strstr(err, "particle 3") != NULL);
    /* an h whose kernel powers leave a double's range is bad data too (issue 16) */
    pst_cloud_h_per_particle(c)[3] = 1e300;
    CHECK_INT(pst_nlist_build(&nl, c, 2.0, err), PST_EINPUT);
    CHECK(strstr(err, "particle 3: smoothing length h = 1e+300") != NULL);
    pst_cloud_h_per_particle(c)[3] = 1.0;
    pst_cloud_coord(c, 1)[4] = NAN;
    CHECK_INT(pst_nlist_build(&nl, c, 2.0, err), PST_EINPUT);
    pst_cloud_destroy(c);
}

/* The half list of nl (pst_nlist_halve) keeps row i's neighbours above i, for 1 and 2 threads;
 * its cut at `cut` is the whole list's entry for entry, fallback rows included, and its cut at
 * 1 is nl again. */
static void check_half(const pst_cloud *c, const pst_nlist *nl, double cut)
{
    int saved = omp_get_max_threads();
    pst_nlist *half[2] = {NULL, NULL}, *hc[2] = {NULL, NULL}, *back = NULL;
    size_t full[2] = {0, 0}, fw = 0, fb = 0;
    for (int t = 0; t < 2; ++t) {
        omp_set_num_threads(t + 1);
        CHECK_INT(pst_nlist_halve(&half[t], nl, NULL), PST_OK);
        CHECK_INT(pst_nlist_cut(&hc[t], c, half[t], cut, &full[t], NULL), PST_OK);
    }
    omp_set_num_threads(saved);
    size_t n = nl->n, bad = 0;
    for (size_t i = 0; i < n; ++i) {
        int64_t q = half[0]->offset[i];
        for (int64_t e = nl->offset[i]; e < nl->offset[i + 1]; ++e)
            if (nl->index[e] > i)
                bad += q >= half[0]->offset[i + 1] || half[0]->index[q++] != nl->index[e];
        bad += q != half[0]->offset[i + 1];
    }
    CHECK(bad == 0 && half[0]->half && 2 * pst_nlist_pairs(half[0]) == pst_nlist_pairs(nl));
    CHECK(same_nlists(half[0], half[1]) && same_nlists(hc[0], hc[1]) && full[0] == full[1]);
    pst_nlist *wc = NULL;
    CHECK_INT(pst_nlist_cut(&wc, c, nl, cut, &fw, NULL), PST_OK);
    CHECK(wc && same_nlists(hc[0], wc) && full[0] == fw && !hc[0]->half);
    CHECK_INT(pst_nlist_cut(&back, c, half[0], 1.0, &fb, NULL), PST_OK);
    CHECK(same_nlists(back, nl) && fb == 0);
    for (int t = 0; t < 2; ++t) {
        pst_nlist_destroy(half[t]);
        pst_nlist_destroy(hc[t]);
    }
    pst_nlist_destroy(wc);
    pst_nlist_destroy(back);
}

/* The cut list (pst_nlist_cut, the AMG proxy's stencil) is the list of the cut radius: the same
 * rows as a list built with support cut * support, for any thread count; a row with no pair
 * inside the cut keeps its whole row and is counted; a bad cut is refused. */
static void test_cut(void)
{
    int saved = omp_get_max_threads();
    for (int dim = 2; dim <= 3; ++dim)
        for (int vary = 0; vary <= 1; ++vary) {
            pst_cloud *c = lattice(dim, dim == 2 ? 60 : 14, 1.0, 0.4, 1, 1.2, vary, 7);
            pst_nlist *nl = NULL, *cut[2] = {NULL, NULL};
            CHECK_INT(pst_nlist_build(&nl, c, 3.0, NULL), PST_OK);
            size_t full[2] = {1, 1};
            for (int t = 0; t < 2; ++t) {
                omp_set_num_threads(t + 1);
                CHECK_INT(pst_nlist_cut(&cut[t], c, nl, 0.55, &full[t], NULL), PST_OK);
            }
            CHECK(full[0] == 0 && full[1] == 0);
            ref_list r = brute(c, 0.55 * 3.0);
            CHECK(cut[0] && same_list(cut[0], r, pst_cloud_size(c)));
            CHECK(cut[0] && cut[1] && same_nlists(cut[0], cut[1]));
            CHECK(cut[0] && pst_nlist_support(cut[0]) == 3.0 && cut[0]->cut == 0.55);
            check_half(c, nl, 0.55);
            free(r.off);
            free(r.idx);
            pst_nlist_destroy(cut[0]);
            pst_nlist_destroy(cut[1]);
            pst_nlist_destroy(nl);
            pst_cloud_destroy(c);
        }
    omp_set_num_threads(saved);

    /* an unjittered lattice of spacing 1, R = 2.4: cut 0.3 (0.72) reaches no neighbour, so every
     * row keeps its whole row; cut 0.5 (1.2) keeps the four axis neighbours of inner rows */
    pst_cloud *c = lattice(2, 9, 1.0, 0.0, 0, 1.2, 0, 3);
    pst_nlist *nl = NULL, *cut = NULL;
    CHECK_INT(pst_nlist_build(&nl, c, 2.0, NULL), PST_OK);
    size_t full = 0;
    CHECK_INT(pst_nlist_cut(&cut, c, nl, 0.3, &full, NULL), PST_OK);
    CHECK(full == 81 && cut && same_nlists(cut, nl));
    check_half(c, nl, 0.3);
    pst_nlist_destroy(cut);
    CHECK_INT(pst_nlist_cut(&cut, c, nl, 0.5, &full, NULL), PST_OK);
    CHECK(full == 0 && cut && cut->offset[41] - cut->offset[40] == 4);
    pst_nlist_destroy(cut);
    char err[PST_ERRLEN] = "";
    const double bad[4] = {0.0, -0.5, 1.5, NAN};
    for (int k = 0; k < 4; ++k) {
        cut = (pst_nlist *)&cut;
        CHECK_INT(pst_nlist_cut(&cut, c, nl, bad[k], &full, err), PST_EINVAL);
        CHECK(cut == NULL && strstr(err, "cut") != NULL);
    }
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
}

int main(void)
{
    test_random_clouds();
    test_uniform_random();
    test_exact_distances();
    test_scaling();
    test_tiny_clouds();
    test_sorted_vs_unsorted();
    test_threads();
    test_errors();
    test_cut();
    return check_summary("test_nlist");
}
