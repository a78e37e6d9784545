/* Verlet lists (pst_nlist_build_skin, pst_nlist_update): after each move of the particles the
 * updated list is entry for entry a fresh build's, for 1 and 2 threads; the list is filtered
 * while the rule allows and built again exactly when it does not (displacement, growth of h, a
 * permuted cloud); a plain list rebuilds; bad arguments are refused. */
#include "check.h"
#include "support.h"

#include "pstencil.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#define SUPPORT 3.0

/* 1 when a and b hold the same rows in the same order. */
static int same_list(const pst_nlist *a, const pst_nlist *b)
{
    size_t n = pst_nlist_rows(a);
    if (n != pst_nlist_rows(b) || pst_nlist_pairs(a) != pst_nlist_pairs(b))
        return 0;
    return memcmp(pst_nlist_offsets(a), pst_nlist_offsets(b), (n + 1) * sizeof(int64_t)) == 0 &&
           memcmp(pst_nlist_indices(a), pst_nlist_indices(b),
                  (size_t)pst_nlist_pairs(a) * sizeof(uint32_t)) == 0;
}

/* 1 when nl equals a fresh build on c. */
static int fresh(const pst_nlist *nl, const pst_cloud *c)
{
    pst_nlist *f = test_nlist(c, SUPPORT);
    int same = same_list(nl, f);
    pst_nlist_destroy(f);
    return same;
}

/* Move every particle by dt times a smooth swirl (|v| <= about 1); returns the largest
 * displacement of this move. */
static double swirl(pst_cloud *c, double dt)
{
    int dim = pst_cloud_dim(c);
    double *x = pst_cloud_coord(c, 0), *y = pst_cloud_coord(c, 1);
    double *z = dim == 3 ? pst_cloud_coord(c, 2) : NULL;
    double big = 0;
    for (size_t i = 0; i < pst_cloud_size(c); ++i) {
        double vx = sin(3 * y[i]) * cos(2 * x[i]), vy = -cos(3 * x[i]) * sin(2 * y[i]);
        double vz = z ? 0.5 * sin(2 * x[i] + y[i]) : 0;
        x[i] += dt * vx;
        y[i] += dt * vy;
        if (z)
            z[i] += dt * vz;
        big = fmax(big, dt * sqrt(vx * vx + vy * vy + vz * vz));
    }
    return big;
}

/* Many small steps: each update equals a fresh build; most are filters; a rebuild happens
 * exactly when the rule says, and the moved distance it reports is the true one. */
static void test_moves(int dim, int vary_h)
{
    double s0 = dim == 3 ? 1.0 / 15 : 1.0 / 40, skin = 0.5;
    pst_cloud *c = test_lattice(dim, 0, 1, s0, 1.2, 0.3, 7, 0);
    pst_cloud_morton_sort(c, SUPPORT * 1.2 * s0, NULL);
    if (vary_h) {
        double *h = pst_cloud_h_per_particle(c);
        for (size_t i = 0; i < pst_cloud_size(c); ++i)
            h[i] *= 1 + 0.2 * sin(17.0 * (double)i);
    }
    pst_nlist *nl = NULL;
    char err[PST_ERRLEN] = "";
    CHECK(pst_nlist_build_skin(&nl, c, SUPPORT, skin, err) == PST_OK);
    CHECK(pst_nlist_skin(nl) == skin);
    CHECK(fresh(nl, c));
    size_t n = pst_cloud_size(c);
    int dims = dim;
    double *x0 = malloc((size_t)dims * n * sizeof *x0);
    for (int d = 0; d < dims; ++d)
        memcpy(x0 + (size_t)d * n, pst_cloud_coord(c, d), n * sizeof *x0);
    int filters = 0, rebuilds = 0, all_fresh = 1, moved_ok = 1;
    for (int step = 0; step < 24; ++step) {
        swirl(c, 0.1 * s0);
        double m2 = 0; /* the largest displacement since the last wide build */
        for (size_t i = 0; i < n; ++i) {
            double s = 0;
            for (int d = 0; d < dims; ++d) {
                double t = pst_cloud_coord(c, d)[i] - x0[(size_t)d * n + i];
                s += t * t;
            }
            m2 = fmax(m2, s);
        }
        pst_nlist_update_info info;
        CHECK(pst_nlist_update(nl, c, &info, err) == PST_OK);
        moved_ok &= fabs(info.moved - sqrt(m2)) <= 1e-12;
        CHECK(info.grown == 0);
        CHECK_INT(info.rebuilt, !(2 * info.moved <= info.budget));
        all_fresh &= fresh(nl, c);
        CHECK_INT(info.pairs, pst_nlist_pairs(nl));
        if (info.rebuilt) {
            rebuilds++;
            for (int d = 0; d < dims; ++d)
                memcpy(x0 + (size_t)d * n, pst_cloud_coord(c, d), n * sizeof *x0);
        } else {
            filters++;
        }
        CHECK_INT(info.rebuilds, rebuilds + 1);
        CHECK_INT(info.filters, filters + rebuilds + 1);
    }
    CHECK(all_fresh);
    CHECK(moved_ok);
    /* skin 0.5 h (0.6 s0, less where h varies) against up to 0.1 s0 a step: both paths */
    CHECK(rebuilds >= 2 && filters >= rebuilds);
    printf("%dD%s: %d filters, %d rebuilds in 24 steps\n", dim, vary_h ? " (h varies)" : "",
           filters, rebuilds);
    free(x0);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
}

/* h growing past the budget rebuilds; a cloud permuted since the build rebuilds. */
static void test_growth_and_order(void)
{
    double s0 = 1.0 / 30;
    pst_cloud *c = test_lattice(2, 0, 1, s0, 1.2, 0.3, 3, 0);
    pst_nlist *nl = NULL;
    char err[PST_ERRLEN] = "";
    CHECK(pst_nlist_build_skin(&nl, c, SUPPORT, 0.3, err) == PST_OK);
    double *h = pst_cloud_h_per_particle(c);
    size_t n = pst_cloud_size(c);
    pst_nlist_update_info info;
    h[n / 2] *= 1.01; /* support * 0.012 s0 < 0.3 * 1.2 s0: still a filter */
    CHECK(pst_nlist_update(nl, c, &info, err) == PST_OK);
    CHECK(!info.rebuilt && info.grown > 0 && fresh(nl, c));
    h[n / 3] *= 1.2; /* support * 0.24 s0 > 0.36 s0: the wide list no longer covers it */
    CHECK(pst_nlist_update(nl, c, &info, err) == PST_OK);
    CHECK(info.rebuilt && fresh(nl, c));
    CHECK(pst_nlist_update(nl, c, &info, err) == PST_OK);
    CHECK(!info.rebuilt && info.moved == 0 && info.grown == 0 && fresh(nl, c));
    uint32_t *perm = malloc(n * sizeof *perm);
    for (size_t i = 0; i < n; ++i)
        perm[i] = (uint32_t)(n - 1 - i);
    CHECK(pst_cloud_permute(c, perm, err) == PST_OK);
    CHECK(pst_nlist_update(nl, c, &info, err) == PST_OK);
    CHECK(info.rebuilt && fresh(nl, c));
    free(perm);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
}

/* The same updates with 1 and 2 threads give the same lists (and both a fresh build's). */
static void test_update_threads(void)
{
    int lists_equal = 1;
    pst_nlist *nl[2] = {NULL, NULL};
    pst_cloud *c = test_lattice(3, 0, 1, 1.0 / 12, 1.2, 0.3, 11, 0);
    for (int t = 0; t < 2; ++t) {
        omp_set_num_threads(t + 1);
        CHECK(pst_nlist_build_skin(&nl[t], c, SUPPORT, 0.4, NULL) == PST_OK);
    }
    for (int step = 0; step < 6; ++step) {
        swirl(c, 0.02);
        for (int t = 0; t < 2; ++t) {
            omp_set_num_threads(t + 1);
            CHECK(pst_nlist_update(nl[t], c, NULL, NULL) == PST_OK);
        }
        lists_equal &= same_list(nl[0], nl[1]) && fresh(nl[0], c);
    }
    CHECK(lists_equal);
    omp_set_num_threads(2);
    pst_nlist_destroy(nl[0]);
    pst_nlist_destroy(nl[1]);
    pst_cloud_destroy(c);
}

/* A plain list (no skin) rebuilds on every update; memory statistics count the skin list. */
static void test_plain_and_stats(void)
{
    pst_cloud *c = test_lattice(2, 0, 1, 1.0 / 20, 1.2, 0.3, 5, 0);
    pst_nlist *plain = test_nlist(c, SUPPORT), *skinned = NULL;
    CHECK(pst_nlist_skin(plain) == 0);
    CHECK(pst_nlist_build_skin(&skinned, c, SUPPORT, 0.5, NULL) == PST_OK);
    pst_nlist_stats a, b;
    pst_nlist_get_stats(plain, &a);
    pst_nlist_get_stats(skinned, &b);
    CHECK(a.pairs == b.pairs && b.bytes > a.bytes + a.pairs * sizeof(uint32_t));
    swirl(c, 0.005);
    pst_nlist_update_info info;
    CHECK(pst_nlist_update(plain, c, &info, NULL) == PST_OK);
    CHECK(info.rebuilt && fresh(plain, c));
    pst_nlist_destroy(plain);
    pst_nlist_destroy(skinned);
    pst_cloud_destroy(c);
}

static void test_refusals(void)
{
    pst_cloud *c = test_lattice(2, 0, 1, 1.0 / 20, 1.2, 0.3, 5, 0);
    pst_cloud *small = test_lattice(2, 0, 1, 1.0 / 10, 1.2, 0.3, 5, 0);
    pst_nlist *nl = NULL, *half = NULL;
    char err[PST_ERRLEN] = "";
    CHECK(pst_nlist_build_skin(&nl, c, SUPPORT, -0.1, err) == PST_EINVAL && strstr(err, "skin"));
    CHECK(pst_nlist_build_skin(&nl, c, SUPPORT, SUPPORT * 1.5, err) == PST_EINVAL);
    CHECK(pst_nlist_build_skin(&nl, c, SUPPORT, NAN, err) == PST_EINVAL && !nl);
    CHECK(pst_nlist_build_skin(&nl, c, SUPPORT, 0.5, err) == PST_OK);
    CHECK(pst_nlist_update(nl, small, NULL, err) == PST_EINVAL && strstr(err, "particles"));
    CHECK(pst_nlist_halve(&half, nl, err) == PST_OK);
    CHECK(pst_nlist_update(half, c, NULL, err) == PST_EINVAL && strstr(err, "half"));
    pst_cloud_coord(c, 0)[7] = NAN;
    CHECK(pst_nlist_update(nl, c, NULL, err) == PST_EINPUT && strstr(err, "not finite"));
    pst_cloud_coord(c, 0)[7] = 0.5;
    CHECK(pst_nlist_update(nl, c, NULL, err) == PST_OK && fresh(nl, c));
    pst_nlist_destroy(half);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(small);
    pst_cloud_destroy(c);
}

int main(void)
{
    test_moves(2, 0);
    test_moves(2, 1);
    test_moves(3, 0);
    test_growth_and_order();
    test_update_threads();
    test_plain_and_stats();
    test_refusals();
    return check_summary("test_nlist_update");
}
