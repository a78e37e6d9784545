/* Morton keys and the Morton sort: known interleavings, monotonicity, the sort as a stable
 * permutation applied to every field, input-order round trip, thread-count independence. */
#include "cells.h"
#include "check.h"
#include "support.h"

#include <omp.h>
#include <stdlib.h>
#include <string.h>


/* Bit-by-bit reference interleave. */
static uint64_t ref_key(int dim, uint32_t ix, uint32_t iy, uint32_t iz)
{
    uint32_t v[3] = {ix, iy, iz};
    int bits = dim == 3 ? 21 : 32;
    uint64_t k = 0;
    for (int b = 0; b < bits; ++b)
        for (int d = 0; d < dim; ++d)
            k |= (uint64_t)((v[d] >> b) & 1) << (b * dim + d);
    return k;
}

static void test_keys(void)
{
    CHECK(pst_morton_key(3, 1, 0, 0) == 1);
    CHECK(pst_morton_key(3, 0, 1, 0) == 2);
    CHECK(pst_morton_key(3, 0, 0, 1) == 4);
    CHECK(pst_morton_key(3, 2, 0, 0) == 8);
    CHECK(pst_morton_key(3, 3, 5, 6) == 0x1ab); /* (z y x) per bit: 110, 101, 011 */
    CHECK(pst_morton_key(3, 0x1fffff, 0, 0) == 0x1249249249249249ULL);
    CHECK(pst_morton_key(3, 0x1fffff, 0x1fffff, 0x1fffff) == 0x7fffffffffffffffULL);
    CHECK(pst_morton_key(2, 1, 0, 7) == 1); /* iz ignored in 2D */
    CHECK(pst_morton_key(2, 0, 1, 0) == 2);
    CHECK(pst_morton_key(2, 3, 3, 0) == 15);
    CHECK(pst_morton_key(2, 0xffffffffu, 0, 0) == 0x5555555555555555ULL);
    CHECK(pst_morton_key(2, 0xffffffffu, 0xffffffffu, 0) == UINT64_MAX);
    test_rng_seed(1);
    int bad = 0;
    for (int t = 0; t < 10000; ++t) {
        uint32_t a = (uint32_t)test_rnd64(), b = (uint32_t)test_rnd64(), c = (uint32_t)test_rnd64();
        bad |= pst_morton_key(2, a, b, 0) != ref_key(2, a, b, 0);
        a &= 0x1fffff, b &= 0x1fffff, c &= 0x1fffff;
        bad |= pst_morton_key(3, a, b, c) != ref_key(3, a, b, c);
    }
    CHECK(!bad);
    /* strictly increasing along each axis with the other coordinates fixed */
    for (int dim = 2; dim <= 3; ++dim)
        for (int axis = 0; axis < dim; ++axis) {
            uint32_t v[3] = {(uint32_t)test_rnd64() & 0xfffff, (uint32_t)test_rnd64() & 0xfffff,
                             (uint32_t)test_rnd64() & 0xfffff};
            uint64_t prev = 0;
            int mono = 1;
            for (uint32_t s = 0; s < 5000; ++s) {
                v[axis] = 1000000 + s;
                uint64_t k = pst_morton_key(dim, v[0], v[1], v[2]);
                mono &= s == 0 || k > prev;
                prev = k;
            }
            CHECK(mono);
        }
}

/* A shuffled jittered lattice with every field set to a function of the input index. */
static pst_cloud *make_cloud(int dim, int side, uint64_t seed)
{
    test_rng_seed(seed);
    size_t n = 1;
    for (int d = 0; d < dim; ++d)
        n *= (size_t)side;
    pst_cloud *c;
    pst_cloud_create(&c, dim, n, NULL);
    for (size_t i = 0; i < n; ++i) {
        size_t s = (size_t)(test_rnd() * (double)n); /* random lattice slots: duplicates allowed */
        for (int d = 0; d < dim; ++d) {
            pst_cloud_coord(c, d)[i] = (double)(s % (size_t)side) + 0.4 * (2 * test_rnd() - 1);
            pst_cloud_normal(c, d)[i] = (double)i + 0.25 * d;
            s /= (size_t)side;
        }
        pst_cloud_volume(c)[i] = 1.0 + (double)i;
        pst_cloud_kinds(c)[i] = (uint8_t)(i % 3);
    }
    double *h = pst_cloud_h_per_particle(c);
    pst_cloud_set_mobility(c, dim, NULL);
    double *f;
    pst_cloud_add_field(c, "u", &f, NULL);
    for (size_t i = 0; i < n; ++i) {
        h[i] = 2.0 + (double)i;
        f[i] = -(double)i;
        for (int d = 0; d < dim; ++d)
            pst_cloud_mobility(c, d)[i] = 3.0 + (double)i + d;
    }
    return c;
}

static void test_sort(void)
{
    for (int dim = 2; dim <= 3; ++dim) {
        int side = dim == 2 ? 150 : 28;
        double cell = 1.5;
        pst_cloud *c = make_cloud(dim, side, 7);
        pst_cloud *orig = make_cloud(dim, side, 7);
        size_t n = pst_cloud_size(c);
        double lo[3], hi[3];
        pst_cloud_bbox(c, lo, hi);
        CHECK_INT(pst_cloud_morton_sort(c, cell, NULL), PST_OK);
        const int64_t *id = pst_cloud_ids_const(c);
        /* a permutation */
        uint8_t *seen = calloc(n, 1);
        int perm_ok = 1;
        for (size_t i = 0; i < n; ++i) {
            perm_ok &= id[i] >= 0 && (size_t)id[i] < n && !seen[id[i]];
            if (perm_ok)
                seen[id[i]] = 1;
        }
        CHECK(perm_ok);
        free(seen);
        if (!perm_ok) {
            pst_cloud_destroy(c);
            pst_cloud_destroy(orig);
            continue;
        }
        /* keys nondecreasing; equal keys keep input order; every field moved with its id */
        uint32_t dims[3] = {1, 1, 1};
        for (int d = 0; d < dim; ++d)
            dims[d] = (uint32_t)floor((hi[d] - lo[d]) * (1.0 / cell)) + 1;
        int keys_ok = 1, fields_ok = 1;
        uint64_t prev = 0;
        for (size_t i = 0; i < n; ++i) {
            uint32_t k[3] = {0, 0, 0};
            for (int d = 0; d < dim; ++d)
                k[d] = pst_cell_coord(pst_cloud_coord(c, d)[i], lo[d], 1.0 / cell, dims[d]);
            uint64_t key = pst_morton_key(dim, k[0], k[1], k[2]);
            keys_ok &= i == 0 || key > prev || (key == prev && id[i] > id[i - 1]);
            prev = key;
            size_t o = (size_t)id[i];
            for (int d = 0; d < dim; ++d) {
                fields_ok &= pst_cloud_coord(c, d)[i] == pst_cloud_coord(orig, d)[o];
                fields_ok &= pst_cloud_normal(c, d)[i] == pst_cloud_normal(orig, d)[o];
                fields_ok &= pst_cloud_mobility(c, d)[i] == pst_cloud_mobility(orig, d)[o];
            }
            fields_ok &= pst_cloud_volume(c)[i] == pst_cloud_volume(orig)[o];
            fields_ok &= pst_cloud_kinds(c)[i] == pst_cloud_kinds(orig)[o];
            fields_ok &= pst_cloud_h_array(c)[i] == pst_cloud_h_array(orig)[o];
            fields_ok &= pst_cloud_field_by_name(c, "u")[i] == -(double)o;
        }
        CHECK(keys_ok);
        CHECK(fields_ok);
        /* the sort moved something (the input is shuffled) */
        CHECK(memcmp(pst_cloud_coord(c, 0), pst_cloud_coord(orig, 0), n * sizeof(double)) != 0);
        /* round trip to input order */
        double *back = malloc(n * sizeof *back);
        for (int d = 0; d < dim; ++d) {
            pst_cloud_to_input_order(c, pst_cloud_coord(c, d), back);
            CHECK(memcmp(back, pst_cloud_coord(orig, d), n * sizeof *back) == 0);
        }
        free(back);
        pst_cloud_destroy(c);
        pst_cloud_destroy(orig);
    }
}

static void test_threads_and_limits(void)
{
    int saved = omp_get_max_threads();
    for (int dim = 2; dim <= 3; ++dim) {
        int side = dim == 2 ? 200 : 30;
        pst_cloud *a = make_cloud(dim, side, 9), *b = make_cloud(dim, side, 9);
        size_t n = pst_cloud_size(a);
        omp_set_num_threads(1);
        CHECK_INT(pst_cloud_morton_sort(a, 0.7, NULL), PST_OK);
        omp_set_num_threads(2);
        CHECK_INT(pst_cloud_morton_sort(b, 0.7, NULL), PST_OK);
        CHECK(memcmp(pst_cloud_ids(a), pst_cloud_ids(b), n * sizeof(int64_t)) == 0);
        pst_cloud_destroy(a);
        pst_cloud_destroy(b);

        /* a cell far too small for the key width is coarsened by doubling: the same order as
         * sorting with the coarsened size directly */
        a = make_cloud(dim, side, 13);
        b = make_cloud(dim, side, 13);
        double lo[3], hi[3], tiny = 1e-9, cell = tiny;
        pst_cloud_bbox(a, lo, hi);
        double maxcells = dim == 3 ? 2097152.0 : 4294967295.0;
        for (;;) {
            int fits = 1;
            for (int d = 0; d < dim; ++d)
                fits &= floor((hi[d] - lo[d]) * (1.0 / cell)) + 1.0 <= maxcells;
            if (fits)
                break;
            cell *= 2;
        }
        CHECK(cell > tiny);
        CHECK_INT(pst_cloud_morton_sort(a, tiny, NULL), PST_OK);
        CHECK_INT(pst_cloud_morton_sort(b, cell, NULL), PST_OK);
        CHECK(memcmp(pst_cloud_ids(a), pst_cloud_ids(b), n * sizeof(int64_t)) == 0);
        pst_cloud_destroy(a);
        pst_cloud_destroy(b);
    }
    omp_set_num_threads(saved);

    pst_cloud *c;
    pst_cloud_create(&c, 3, 0, NULL);
    CHECK_INT(pst_cloud_morton_sort(c, 1.0, NULL), PST_OK);
    pst_cloud_destroy(c);
    pst_cloud_create(&c, 2, 1, NULL);
    CHECK_INT(pst_cloud_morton_sort(c, 1.0, NULL), PST_OK);
    CHECK_INT(pst_cloud_morton_sort(c, 0.0, NULL), PST_EINVAL);
    CHECK_INT(pst_cloud_morton_sort(c, -1.0, NULL), PST_EINVAL);
    char why[PST_ERRLEN] = "";
    CHECK_INT(pst_cloud_morton_sort(c, NAN, why), PST_EINVAL);
    CHECK(strlen(why) > 0);
    pst_cloud_destroy(c);
}

/* Finite coordinates whose extent overflows (+-1e308) are refused by the validation, the Morton
 * sort and the cell grid, where the coarsening loops once never ended (issue 16); an extent
 * just inside the range sorts, even from the smallest cell size. */
static void test_wide_extent(void)
{
    for (int dim = 2; dim <= 3; ++dim) {
        pst_cloud *c;
        pst_cloud_create(&c, dim, 2, NULL);
        pst_cloud_coord(c, 0)[0] = -1e308;
        pst_cloud_coord(c, 0)[1] = 1e308;
        char err[PST_ERRLEN] = "";
        CHECK_INT(pst_cloud_validate(c, err), PST_EINPUT);
        CHECK(strstr(err, "extent overflows") != NULL);
        err[0] = 0;
        CHECK_INT(pst_cloud_morton_sort(c, 1.0, err), PST_EINPUT);
        CHECK(strstr(err, "extent overflows") != NULL);
        pst_cells g;
        err[0] = 0;
        CHECK_INT(pst_cells_build(&g, c, 1.0, err), PST_EINPUT);
        CHECK(strstr(err, "extent overflows") != NULL);
        CHECK_INT(pst_cells_build(&g, c, INFINITY, err), PST_EINPUT);
        pst_cloud_coord(c, 0)[0] = -8e307;
        pst_cloud_coord(c, 0)[1] = 8e307;
        CHECK_INT(pst_cloud_validate(c, NULL), PST_OK);
        CHECK_INT(pst_cloud_morton_sort(c, 5e-324, NULL), PST_OK);
        CHECK_INT(pst_cells_build(&g, c, 5e-324, NULL), PST_OK);
        CHECK(g.ncells <= 8 * 2 + 1024);
        pst_cells_free(&g);
        pst_cloud_destroy(c);
    }
}

int main(void)
{
    test_keys();
    test_sort();
    test_threads_and_limits();
    test_wide_extent();
    return check_summary("test_morton");
}
