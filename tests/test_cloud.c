/* Cloud storage, the counter-based RNG and the two generators: counts, positions, jitter
 * bounds, reproducibility across seeds and thread counts, boundary layers, face particles,
 * rotation, option checking, permutation, validation, fields and mobility. */
#include "check.h"
#include "cloud_layout.h"
#include "internal.h"
#include "pstencil.h"

#include <omp.h>
#include <stdlib.h>
#include <string.h>

static const double PI = 3.14159265358979323846;

static pst_lattice_opts opts2(double s0, double K)
{
    pst_lattice_opts o;
    pst_lattice_defaults(&o);
    o.s0 = s0;
    o.jitter = K;
    return o;
}

static pst_lattice_opts opts3(double s0, double K)
{
    pst_lattice_opts o = opts2(s0, K);
    o.dim = 3;
    return o;
}

/* Bitwise equality of everything a generator fills. */
static int same_cloud(pst_cloud *a, pst_cloud *b)
{
    if (pst_cloud_dim(a) != pst_cloud_dim(b) || pst_cloud_size(a) != pst_cloud_size(b))
        return 0;
    size_t n = pst_cloud_size(a);
    for (int d = 0; d < pst_cloud_dim(a); ++d)
        if (memcmp(pst_cloud_coord(a, d), pst_cloud_coord(b, d), n * sizeof(double)) ||
            memcmp(pst_cloud_normal(a, d), pst_cloud_normal(b, d), n * sizeof(double)))
            return 0;
    return !memcmp(pst_cloud_volume(a), pst_cloud_volume(b), n * sizeof(double)) &&
           !memcmp(pst_cloud_kinds(a), pst_cloud_kinds(b), n) &&
           pst_cloud_h_uniform(a) == pst_cloud_h_uniform(b);
}

static void test_rng(void)
{
    double sum = 0, lo = 1, hi = -1;
    int n = 200000, differ = 0;
    for (int i = 0; i < n; ++i) {
        double u = pst_rng_symmetric(42, (uint64_t)i, 0);
        sum += u;
        lo = u < lo ? u : lo;
        hi = u > hi ? u : hi;
        differ += u != pst_rng_symmetric(42, (uint64_t)i, 1);
    }
    CHECK(lo > -1 && hi < 1);
    CHECK(lo < -0.999 && hi > 0.999);
    CHECK(fabs(sum / n) < 0.01); /* std of the mean 0.0013 */
    CHECK_INT(differ, n);
    CHECK(pst_rng_symmetric(7, 3, 2) == pst_rng_symmetric(7, 3, 2));
    CHECK(pst_rng_symmetric(7, 3, 2) != pst_rng_symmetric(8, 3, 2));
    CHECK(pst_rng_symmetric(7, 3, 2) != pst_rng_symmetric(7, 2, 3));
    CHECK(pst_rng_symmetric(0, 0, 0) != pst_rng_symmetric(0, 1, 0));
}

static void test_defaults(void)
{
    pst_lattice_opts o;
    memset(&o, 0xff, sizeof o);
    pst_lattice_defaults(&o);
    CHECK_INT(o.dim, 2);
    CHECK(o.lo[0] == 0 && o.lo[1] == 0 && o.hi[0] == 1 && o.hi[1] == 1);
    CHECK(o.s0 == 0.1 && o.jitter == 0 && o.h_ratio == 1.2 && o.angle == 0);
    CHECK_INT(o.seed, 1);
    CHECK_INT(o.boundary_layer, 0);
}

static void test_lattice_plain(void)
{
    pst_lattice_opts o = opts2(0.1, 0);
    pst_cloud *c;
    char err[PST_ERRLEN] = "";
    CHECK_INT(pst_cloud_lattice(&c, &o, err), PST_OK);
    CHECK_INT(pst_cloud_size(c), 121);
    CHECK_INT(pst_cloud_dim(c), 2);
    const double *x = pst_cloud_coord(c, 0), *y = pst_cloud_coord(c, 1);
    CHECK(x[0] == 0 && y[0] == 0);
    CHECK(x[120] == 1 && y[120] == 1);
    CHECK(x[1] == 0.1 && y[1] == 0);   /* x runs fastest */
    CHECK(x[11] == 0 && y[11] == 0.1);
    CHECK(x[3] == 3 * 0.1);
    CHECK_NEAR(pst_cloud_volume(c)[57], 0.01, 1e-17);
    CHECK(pst_cloud_h_is_uniform(c));
    CHECK_NEAR(pst_cloud_h_uniform(c), 0.12, 1e-16);
    int interior = 0;
    for (size_t i = 0; i < 121; ++i)
        interior += pst_cloud_kinds(c)[i] == PST_INTERIOR && pst_cloud_normal(c, 0)[i] == 0;
    CHECK_INT(interior, 121);
    CHECK_INT(pst_cloud_validate(c, NULL), PST_OK);
    pst_cloud_destroy(c);

    /* 3D, an off-origin box with different lengths per axis */
    o = opts3(0.25, 0);
    o.lo[0] = -1, o.lo[1] = 0, o.lo[2] = 2;
    o.hi[0] = 1, o.hi[1] = 1, o.hi[2] = 3;
    CHECK_INT(pst_cloud_lattice(&c, &o, err), PST_OK);
    CHECK_INT(pst_cloud_size(c), 9 * 5 * 5);
    CHECK(pst_cloud_coord(c, 0)[0] == -1 && pst_cloud_coord(c, 1)[0] == 0 &&
          pst_cloud_coord(c, 2)[0] == 2);
    size_t last = 9 * 5 * 5 - 1;
    CHECK(pst_cloud_coord(c, 0)[last] == 1 && pst_cloud_coord(c, 1)[last] == 1 &&
          pst_cloud_coord(c, 2)[last] == 3);
    CHECK(pst_cloud_coord(c, 2)[9 * 5] == 2.25);
    CHECK(pst_cloud_volume(c)[0] == 0.015625);
    CHECK(pst_cloud_h_uniform(c) == 1.2 * 0.25);
    double lo[3], hi[3];
    pst_cloud_bbox(c, lo, hi);
    CHECK(lo[0] == -1 && hi[0] == 1 && lo[2] == 2 && hi[2] == 3);
    pst_cloud_destroy(c);
}

static void test_lattice_jitter(void)
{
    const double s0 = 0.01, K = 0.4;
    pst_lattice_opts o = opts2(s0, K);
    o.seed = 12345;
    pst_cloud *c, *c0;
    CHECK_INT(pst_cloud_lattice(&c, &o, NULL), PST_OK);
    o.jitter = 0;
    CHECK_INT(pst_cloud_lattice(&c0, &o, NULL), PST_OK);
    size_t n = pst_cloud_size(c);
    CHECK_INT(n, 101 * 101);
    double maxd = 0, sum[2] = {0, 0};
    int bounded = 1, reproduced = 1;
    for (int d = 0; d < 2; ++d)
        for (size_t i = 0; i < n; ++i) {
            double x0 = pst_cloud_coord(c0, d)[i], disp = pst_cloud_coord(c, d)[i] - x0;
            bounded = bounded && fabs(disp) <= K * s0 * (1 + 1e-9);
            maxd = fabs(disp) > maxd ? fabs(disp) : maxd;
            sum[d] += disp / (K * s0);
            double expect = x0 + K * pst_rng_symmetric(12345, i, (uint64_t)d) * s0;
            reproduced = reproduced && fabs(pst_cloud_coord(c, d)[i] - expect) <= 1e-15;
        }
    CHECK(bounded);
    CHECK(maxd > 0.99 * K * s0);
    CHECK(fabs(sum[0] / n) < 0.03 && fabs(sum[1] / n) < 0.03); /* std of the mean 0.0057 */
    CHECK(reproduced);
    CHECK_INT(pst_cloud_validate(c, NULL), PST_OK);

    /* same seed: the same cloud; another seed: another cloud */
    pst_cloud *c2, *c3;
    o.jitter = K;
    CHECK_INT(pst_cloud_lattice(&c2, &o, NULL), PST_OK);
    CHECK(same_cloud(c, c2));
    o.seed = 12346;
    CHECK_INT(pst_cloud_lattice(&c3, &o, NULL), PST_OK);
    CHECK(!same_cloud(c, c3));
    pst_cloud_destroy(c);
    pst_cloud_destroy(c0);
    pst_cloud_destroy(c2);
    pst_cloud_destroy(c3);
}

/* 1 when gen builds o with 1 and with 2 threads, and both clouds are the same bit for bit. */
static int same_for_1_and_2_threads(int (*gen)(pst_cloud **, const pst_lattice_opts *, char *),
                                    const pst_lattice_opts *o)
{
    int saved = omp_get_max_threads();
    pst_cloud *a = NULL, *b = NULL;
    omp_set_num_threads(1);
    int ok = gen(&a, o, NULL) == PST_OK;
    omp_set_num_threads(2);
    ok = gen(&b, o, NULL) == PST_OK && ok && same_cloud(a, b);
    omp_set_num_threads(saved);
    pst_cloud_destroy(a);
    pst_cloud_destroy(b);
    return ok;
}

static void test_threads(void)
{
    pst_lattice_opts o = opts3(0.05, 0.3);
    o.boundary_layer = 1;
    o.angle = 0.3;
    CHECK(same_for_1_and_2_threads(pst_cloud_lattice, &o));
    CHECK(same_for_1_and_2_threads(pst_cloud_cell_centred, &o));
}

/* Boundary layer: on the box, unjittered, Dirichlet, unit outward normals. */
static void check_boundary_layer(int dim)
{
    const double s0 = 0.1;
    pst_lattice_opts o = dim == 2 ? opts2(s0, 0.45) : opts3(s0, 0.45);
    o.boundary_layer = 1;
    pst_cloud *c, *c0;
    CHECK_INT(pst_cloud_lattice(&c, &o, NULL), PST_OK);
    o.jitter = 0;
    CHECK_INT(pst_cloud_lattice(&c0, &o, NULL), PST_OK);
    size_t n = pst_cloud_size(c), nb = 0, bad = 0, moved = 0, corner_ok = 0;
    for (size_t i = 0; i < n; ++i) {
        int on_box = 0, faces = 0, still = 1;
        double len2 = 0, dot = 0;
        for (int d = 0; d < dim; ++d) {
            double x = pst_cloud_coord(c, d)[i], x0 = pst_cloud_coord(c0, d)[i];
            double nd = pst_cloud_normal(c, d)[i];
            on_box = on_box || x0 == 0 || x0 == 1;
            faces += x0 == 0 || x0 == 1;
            still = still && x == x0;
            len2 += nd * nd;
            dot += nd * (x - 0.5);
        }
        if (on_box) {
            ++nb;
            bad += !still || pst_cloud_kinds(c)[i] != PST_DIRICHLET ||
                   fabs(len2 - 1) > 1e-15 || !(dot > 0);
            if (faces == dim) /* a corner: the normalised diagonal */
                corner_ok += fabs(fabs(pst_cloud_normal(c, 0)[i]) - 1 / sqrt(dim)) < 1e-15;
        } else {
            bad += pst_cloud_kinds(c)[i] != PST_INTERIOR || len2 != 0;
            moved += !still;
        }
    }
    size_t inner = dim == 2 ? 81 : 729;
    CHECK_INT(nb, n - inner);
    CHECK_INT(bad, 0);
    CHECK_INT(moved, inner);
    CHECK_INT(corner_ok, dim == 2 ? 4 : 8);
    /* an edge (3D) or face node: axis-aligned normal at (0, 0.5[, 0.5]) */
    size_t mid = dim == 2 ? 5 * 11 : 5 * 11 + 5 * 121;
    CHECK(pst_cloud_normal(c, 0)[mid] == -1 && pst_cloud_normal(c, 1)[mid] == 0);
    if (dim == 3) { /* edge x = 0, y = 0: (-1, -1, 0)/sqrt 2 */
        size_t edge = 5 * 121;
        CHECK_NEAR(pst_cloud_normal(c, 0)[edge], -sqrt(0.5), 1e-15);
        CHECK_NEAR(pst_cloud_normal(c, 1)[edge], -sqrt(0.5), 1e-15);
        CHECK(pst_cloud_normal(c, 2)[edge] == 0);
    }
    pst_cloud_destroy(c);
    pst_cloud_destroy(c0);
}

static void check_cell_centred(int dim)
{
    const double s0 = 0.25, K = 0.3;
    const size_t m = 4; /* cells per axis */
    pst_lattice_opts o = dim == 2 ? opts2(s0, K) : opts3(s0, K);
    o.boundary_layer = 1; /* ignored by this layout */
    pst_cloud *c, *c0;
    char err[PST_ERRLEN] = "";
    CHECK_INT(pst_cloud_cell_centred(&c, &o, err), PST_OK);
    o.jitter = 0;
    CHECK_INT(pst_cloud_cell_centred(&c0, &o, err), PST_OK);
    size_t nint = dim == 2 ? m * m : m * m * m, nface = dim == 2 ? 4 * m : 6 * m * m;
    size_t n = pst_cloud_size(c);
    CHECK_INT(n, nint + nface);
    CHECK(pst_cloud_h_uniform(c) == 1.2 * s0);
    size_t bad = 0, per_face[6] = {0};
    for (size_t i = 0; i < n; ++i) {
        bad += pst_cloud_volume(c)[i] != (dim == 2 ? s0 * s0 : s0 * s0 * s0);
        if (i < nint) {
            size_t rest = i;
            for (int d = 0; d < dim; ++d, rest /= m) {
                double x0 = (double)(rest % m + 0.5) * s0;
                bad += pst_cloud_coord(c0, d)[i] != x0;
                bad += fabs(pst_cloud_coord(c, d)[i] - x0) > K * s0 * (1 + 1e-12);
                bad += pst_cloud_normal(c, d)[i] != 0;
            }
            bad += pst_cloud_kinds(c)[i] != PST_INTERIOR;
            continue;
        }
        /* a face particle: exactly on one face, strictly inside the others, never moved */
        int faces = 0;
        for (int d = 0; d < dim; ++d) {
            double x = pst_cloud_coord(c, d)[i], nd = pst_cloud_normal(c, d)[i];
            bad += x != pst_cloud_coord(c0, d)[i];
            if (x == 0 || x == 1) {
                ++faces;
                bad += nd != (x == 0 ? -1.0 : 1.0);
                per_face[2 * d + (x == 1)]++;
            } else {
                bad += nd != 0 || !(x > 0 && x < 1);
                bad += fmod(x / s0 - 0.5, 1.0) != 0; /* at a cell-face centre */
            }
        }
        bad += faces != 1 || pst_cloud_kinds(c)[i] != PST_DIRICHLET;
    }
    CHECK_INT(bad, 0);
    for (int f = 0; f < 2 * dim; ++f)
        CHECK_INT(per_face[f], dim == 2 ? m : m * m);
    /* the documented order: the x = lo face comes first, y fastest */
    CHECK(pst_cloud_coord(c, 0)[nint] == 0 && pst_cloud_coord(c, 1)[nint] == 0.5 * s0);
    CHECK(pst_cloud_coord(c, 1)[nint + 1] == 1.5 * s0);
    CHECK(pst_cloud_coord(c, 0)[nint + nface / (2 * dim)] == 1);
    CHECK_INT(pst_cloud_validate(c, NULL), PST_OK);
    pst_cloud_destroy(c);
    pst_cloud_destroy(c0);
}

static double dist(pst_cloud *c, int dim, size_t i, size_t j)
{
    double s = 0;
    for (int d = 0; d < dim; ++d) {
        double t = pst_cloud_coord(c, d)[i] - pst_cloud_coord(c, d)[j];
        s += t * t;
    }
    return sqrt(s);
}

static void check_rotation(int dim)
{
    pst_lattice_opts o = dim == 2 ? opts2(1.0 / 6, 0.2) : opts3(0.25, 0.2);
    o.lo[0] = 2, o.hi[0] = 3, o.lo[1] = 2, o.hi[1] = 3; /* LV §4.1: [2, 3]^2 */
    o.boundary_layer = 1;
    pst_cloud *c, *r;
    CHECK_INT(pst_cloud_lattice(&c, &o, NULL), PST_OK);
    o.angle = PI / 4;
    CHECK_INT(pst_cloud_lattice(&r, &o, NULL), PST_OK);
    size_t n = pst_cloud_size(c);
    CHECK_INT(pst_cloud_size(r), n);
    double worst = 0;
    for (size_t i = 0; i < n; ++i)
        for (size_t j = i + 1; j < n; ++j)
            worst = fmax(worst, fabs(dist(c, dim, i, j) - dist(r, dim, i, j)));
    CHECK(worst < 1e-14);
    /* without jitter: the centre node stays put, a corner and its normal turn by 45 deg */
    o.jitter = 0;
    pst_cloud *u;
    CHECK_INT(pst_cloud_lattice(&u, &o, NULL), PST_OK);
    size_t centre = dim == 2 ? 3 + 7 * 3 : 2 + 5 * 2 + 25 * 2;
    CHECK_NEAR(pst_cloud_coord(u, 0)[centre], 2.5, 1e-15);
    CHECK_NEAR(pst_cloud_coord(u, 1)[centre], 2.5, 1e-15);
    /* the corner (2, 2) goes to (2.5, 2.5 - sqrt(1/2)); its 2D normal to (0, -1) */
    CHECK_NEAR(pst_cloud_coord(u, 0)[0], 2.5, 1e-15);
    CHECK_NEAR(pst_cloud_coord(u, 1)[0], 2.5 - sqrt(0.5), 1e-15);
    double nrm_z = dim == 3 ? pst_cloud_normal(u, 2)[0] : 0;
    CHECK_NEAR(pst_cloud_normal(u, 0)[0], 0, 1e-15);
    CHECK_NEAR(pst_cloud_normal(u, 1)[0], dim == 2 ? -1 : -sqrt(2.0 / 3), 1e-15);
    CHECK_NEAR(nrm_z, dim == 2 ? 0 : -1 / sqrt(3), 1e-15);
    if (dim == 3) { /* about z: z is untouched */
        int same_z = !memcmp(pst_cloud_coord(c, 2), pst_cloud_coord(r, 2), n * sizeof(double));
        CHECK(same_z);
    }
    /* the cell-centred layout rotates too: a face normal turns by 45 degrees */
    pst_cloud *cc;
    CHECK_INT(pst_cloud_cell_centred(&cc, &o, NULL), PST_OK);
    size_t first_face = dim == 2 ? 36 : 64;
    CHECK_NEAR(pst_cloud_normal(cc, 0)[first_face], -sqrt(0.5), 1e-15);
    CHECK_NEAR(pst_cloud_normal(cc, 1)[first_face], -sqrt(0.5), 1e-15);
    pst_cloud_destroy(c);
    pst_cloud_destroy(r);
    pst_cloud_destroy(u);
    pst_cloud_destroy(cc);
}

typedef int (*generator)(pst_cloud **, const pst_lattice_opts *, char *);

static void expect_einval(generator gen, const pst_lattice_opts *o, const char *needle)
{
    pst_cloud *c = (pst_cloud *)&c; /* any non-NULL value: must come back NULL */
    char err[PST_ERRLEN] = "";
    CHECK_INT(gen(&c, o, err), PST_EINVAL);
    CHECK(c == NULL);
    CHECK(strstr(err, needle) != NULL);
    if (!strstr(err, needle))
        fprintf(stderr, "  message was: %s\n", err);
}

static void test_bad_options(void)
{
    generator gens[2] = {pst_cloud_lattice, pst_cloud_cell_centred};
    for (int g = 0; g < 2; ++g) {
        pst_lattice_opts o = opts2(0.1, 0);
        o.dim = 4;
        expect_einval(gens[g], &o, "dim");
        o = opts2(0, 0);
        expect_einval(gens[g], &o, "s0");
        o = opts2(-0.1, 0);
        expect_einval(gens[g], &o, "s0");
        o = opts2(0.3, 0); /* 1/0.3 spacings */
        expect_einval(gens[g], &o, "whole number");
        o = opts2(0.1, 0);
        o.hi[1] = 1 + 1e-6; /* 10.00001 spacings: beyond 1e-9 relative */
        expect_einval(gens[g], &o, "along y");
        o = opts2(0.1, 0);
        o.hi[0] = 0;
        expect_einval(gens[g], &o, "hi > lo");
        o = opts2(0.1, -0.1);
        expect_einval(gens[g], &o, "jitter");
        o = opts2(0.1, NAN);
        expect_einval(gens[g], &o, "jitter");
        o = opts2(0.1, 0);
        o.h_ratio = 0;
        expect_einval(gens[g], &o, "h_ratio");
        o = opts2(0.1, 0);
        o.angle = INFINITY;
        expect_einval(gens[g], &o, "angle");
        o = opts2(0.1, 0);
        o.boundary_layer = 2;
        expect_einval(gens[g], &o, "boundary_layer");
        o = opts3(1e-4, 0); /* 10^12 particles */
        expect_einval(gens[g], &o, "particles");
        o = opts2(1e-10, 0); /* 10^10 spacings along one axis */
        expect_einval(gens[g], &o, "too many");
        expect_einval(gens[g], NULL, "options");
    }
    /* a box that is a whole number of spacings up to rounding is accepted */
    pst_lattice_opts o = opts2(1.0 / 3, 0);
    pst_cloud *c;
    CHECK_INT(pst_cloud_lattice(&c, &o, NULL), PST_OK);
    CHECK_INT(pst_cloud_size(c), 16);
    CHECK(pst_cloud_coord(c, 0)[3] == 1);
    pst_cloud_destroy(c);
}

static void test_permute(void)
{
    pst_lattice_opts o = opts2(0.25, 0.3);
    o.boundary_layer = 1;
    pst_cloud *c, *ref;
    CHECK_INT(pst_cloud_lattice(&c, &o, NULL), PST_OK);
    CHECK_INT(pst_cloud_lattice(&ref, &o, NULL), PST_OK);
    double *u;
    CHECK_INT(pst_cloud_add_field(c, "u", &u, NULL), PST_OK);
    CHECK_INT(pst_cloud_set_mobility(c, 1, NULL), PST_OK);
    size_t n = pst_cloud_size(c);
    double *h = pst_cloud_h_per_particle(c);
    for (size_t i = 0; i < n; ++i) {
        u[i] = (double)i * 1.5;
        h[i] = 0.3 + 0.001 * (double)i;
        pst_cloud_mobility(c, 0)[i] = 1 + (double)i;
    }
    uint32_t *perm = malloc(n * sizeof *perm);
    for (size_t i = 0; i < n; ++i)
        perm[i] = (uint32_t)((7 * i + 3) % n); /* 7 is prime to n = 25 */
    CHECK_INT(pst_cloud_permute(c, perm, NULL), PST_OK);
    int ok = 1;
    for (size_t i = 0; i < n; ++i) {
        size_t p = perm[i];
        ok = ok && pst_cloud_ids(c)[i] == (int64_t)p;
        ok = ok && pst_cloud_coord(c, 0)[i] == pst_cloud_coord(ref, 0)[p];
        ok = ok && pst_cloud_normal(c, 1)[i] == pst_cloud_normal(ref, 1)[p];
        ok = ok && pst_cloud_kinds(c)[i] == pst_cloud_kinds(ref)[p];
        ok = ok && pst_cloud_field_by_name(c, "u")[i] == 1.5 * (double)p;
        ok = ok && pst_cloud_h_array(c)[i] == 0.3 + 0.001 * (double)p;
        ok = ok && pst_cloud_mobility(c, 0)[i] == 1 + (double)p;
    }
    CHECK(ok);
    double *back = malloc(n * sizeof *back);
    pst_cloud_to_input_order(c, pst_cloud_coord(c, 1), back);
    CHECK(!memcmp(back, pst_cloud_coord(ref, 1), n * sizeof *back));
    perm[0] = perm[1];
    char why[PST_ERRLEN];
    CHECK_INT(pst_cloud_permute(c, perm, why), PST_EINVAL);
    CHECK(strstr(why, "permutation") != NULL);
    perm[0] = (uint32_t)n;
    CHECK_INT(pst_cloud_permute(c, perm, NULL), PST_EINVAL);
    free(back);
    free(perm);
    pst_cloud_destroy(c);
    pst_cloud_destroy(ref);
}

static void test_validate(void)
{
    pst_lattice_opts o = opts2(0.25, 0.1);
    pst_cloud *c;
    CHECK_INT(pst_cloud_lattice(&c, &o, NULL), PST_OK);
    CHECK_INT(pst_cloud_validate(c, NULL), PST_OK);
    double *x = pst_cloud_coord(c, 0), *y = pst_cloud_coord(c, 1), keep = x[4];
    x[4] = NAN;
    char why[PST_ERRLEN];
    CHECK_INT(pst_cloud_validate(c, why), PST_EINPUT);
    CHECK(strstr(why, "particle 4") && strstr(why, "finite"));
    x[4] = keep;
    pst_cloud_volume(c)[6] = 0;
    CHECK_INT(pst_cloud_validate(c, why), PST_EINPUT);
    CHECK(strstr(why, "particle 6") && strstr(why, "volume"));
    pst_cloud_volume(c)[6] = -1;
    CHECK_INT(pst_cloud_validate(c, NULL), PST_EINPUT);
    pst_cloud_volume(c)[6] = 1;
    x[9] = x[3];
    y[9] = y[3];
    CHECK_INT(pst_cloud_validate(c, why), PST_EINPUT);
    CHECK(strstr(why, "particles 3 and 9") != NULL);
    pst_cloud_destroy(c);
}

static void test_fields_and_mobility(void)
{
    pst_cloud *c;
    CHECK_INT(pst_cloud_create(&c, 3, 10, NULL), PST_OK);
    double *a, *b;
    CHECK_INT(pst_cloud_add_field(c, "u_exact", &a, NULL), PST_OK);
    CHECK_INT(pst_cloud_add_field(c, "rhs2", &b, NULL), PST_OK);
    CHECK(a && b && a[9] == 0);
    CHECK_INT(pst_cloud_nfields(c), 2);
    CHECK(strcmp(pst_cloud_field_name(c, 1), "rhs2") == 0);
    CHECK(pst_cloud_field_name(c, 2) == NULL);
    CHECK(pst_cloud_field_by_name(c, "rhs2") == b);
    CHECK(pst_cloud_field(c, 0) == a);
    CHECK(pst_cloud_field_by_name(c, "nope") == NULL);
    const char *bad[] = {"u_exact", "2x", "x", "kind", "mz", "id", "a-b", "", "a b"};
    for (size_t k = 0; k < sizeof bad / sizeof *bad; ++k) {
        double *p = a;
        CHECK_INT(pst_cloud_add_field(c, bad[k], &p, NULL), PST_EINVAL);
        CHECK(p == NULL);
    }
    CHECK_INT(pst_cloud_add_field(c, NULL, NULL, NULL), PST_EINVAL);
    CHECK_INT(pst_cloud_nfields(c), 2);

    CHECK_INT(pst_cloud_mobility_ncomp(c), 0);
    CHECK(pst_cloud_mobility(c, 0) == NULL);
    CHECK_INT(pst_cloud_set_mobility(c, 1, NULL), PST_OK);
    CHECK(pst_cloud_mobility(c, 0)[9] == 1 && pst_cloud_mobility(c, 1) == NULL);
    CHECK_INT(pst_cloud_set_mobility(c, 3, NULL), PST_OK);
    CHECK_INT(pst_cloud_mobility_ncomp(c), 3);
    CHECK(pst_cloud_mobility(c, 2)[0] == 1 && pst_cloud_mobility(c, 3) == NULL);
    CHECK_INT(pst_cloud_set_mobility(c, 2, NULL), PST_EINVAL);
    CHECK_INT(pst_cloud_mobility_ncomp(c), 3);
    pst_cloud_mobility(c, 1)[5] = -1;
    CHECK_INT(pst_cloud_validate(c, NULL), PST_EINPUT); /* also: all particles at the origin */
    CHECK_INT(pst_cloud_set_mobility(c, 0, NULL), PST_OK);
    CHECK(pst_cloud_mobility(c, 0) == NULL);

    /* smoothing length layouts */
    CHECK_INT(pst_cloud_set_h_uniform(c, 0.5, NULL), PST_OK);
    CHECK(pst_cloud_h_max(c) == 0.5 && pst_cloud_h_array(c) == NULL);
    double *h = pst_cloud_h_per_particle(c);
    CHECK(h && h[3] == 0.5 && !pst_cloud_h_is_uniform(c));
    h[3] = 2;
    CHECK(pst_cloud_h_max(c) == 2);
    CHECK_INT(pst_cloud_set_h_uniform(c, -1, NULL), PST_EINVAL);
    CHECK_INT(pst_cloud_set_h_uniform(c, 0.25, NULL), PST_OK);
    CHECK(pst_cloud_h_is_uniform(c) && pst_cloud_h_uniform(c) == 0.25);
    pst_cloud_destroy(c);

    pst_cloud *bad_dim = (pst_cloud *)&bad_dim;
    char err[PST_ERRLEN] = "";
    CHECK_INT(pst_cloud_create(&bad_dim, 1, 5, err), PST_EINVAL);
    CHECK(bad_dim == NULL);
    CHECK(strstr(err, "dim must be 2 or 3 (got 1)") != NULL);
    if (sizeof(size_t) > 4) { /* more particles than 32-bit neighbour indices can name */
        CHECK_INT(pst_cloud_create(&bad_dim, 2, (size_t)UINT32_MAX + 1, err), PST_EINVAL);
        CHECK(bad_dim == NULL && strstr(err, "32-bit index limit") != NULL);
    }
    pst_cloud_destroy(NULL);
}

/* Fields added at once (the readers' path): a repeat of an existing field or among the new
 * names refuses them all; otherwise each is there, zero-filled, in order. */
static void test_add_fields(void)
{
    pst_cloud *c;
    char err[PST_ERRLEN];
    CHECK_INT(pst_cloud_create(&c, 2, 3, NULL), PST_OK);
    CHECK_INT(pst_cloud_add_field(c, "u", NULL, NULL), PST_OK);
    const char *again[] = {"a", "b", "u"}, *twice[] = {"p", "q", "p"}, *bad[] = {"ok", "x"};
    CHECK_INT(pst_cloud_add_fields(c, again, 3, NULL, err), PST_EINVAL);
    CHECK(strstr(err, "field 'u' already exists") != NULL);
    CHECK_INT(pst_cloud_add_fields(c, twice, 3, NULL, err), PST_EINVAL);
    CHECK(strstr(err, "field 'p' already exists") != NULL);
    CHECK_INT(pst_cloud_add_fields(c, bad, 2, NULL, err), PST_EINVAL);
    CHECK_INT(pst_cloud_nfields(c), 1);
    const char *names[] = {"a", "b"};
    double *data[2] = {NULL, NULL};
    CHECK_INT(pst_cloud_add_fields(c, names, 2, data, err), PST_OK);
    CHECK_INT(pst_cloud_nfields(c), 3);
    CHECK(strcmp(pst_cloud_field_name(c, 2), "b") == 0 && pst_cloud_field(c, 2) == data[1]);
    CHECK(data[0] && data[0][2] == 0 && pst_cloud_field_by_name(c, "a") == data[0]);
    size_t first = 9, rep = 9;
    const char *list[] = {"c", "a", "b", "a", "c"};
    CHECK_INT(pst_find_repeated_name(list, 5, &first, &rep), 1);
    CHECK(first == 1 && rep == 3); /* the earliest repeat, as a scan in order finds it */
    CHECK_INT(pst_find_repeated_name(list, 3, &first, &rep), 0);
    pst_cloud_destroy(c);
}

int main(void)
{
    test_rng();
    test_add_fields();
    test_defaults();
    test_lattice_plain();
    test_lattice_jitter();
    test_threads();
    check_boundary_layer(2);
    check_boundary_layer(3);
    check_cell_centred(2);
    check_cell_centred(3);
    check_rotation(2);
    check_rotation(3);
    test_bad_options();
    test_permute();
    test_validate();
    test_fields_and_mobility();
    return check_summary("test_cloud");
}
