/* SPE10 reader and grid-to-cloud mobility: the real data files of data/spe10 (their
 * README statistics, the index layout checked against an independent read), the mapping onto
 * a cell-centred cloud, and the error paths on corrupted copies. */
#define _POSIX_C_SOURCE 200809L /* access */

#include "check.h"
#include "support.h"
#include "pstencil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#ifndef PSTENCIL_DATA_DIR
#error "PSTENCIL_DATA_DIR must name the repository's data/ directory (tests/CMakeLists.txt)"
#endif

#define GEOS_DIR PSTENCIL_DATA_DIR "/spe10/geos_layers84_85"
#define GEOS_X GEOS_DIR "/permx.geos"
#define TARBERT PSTENCIL_DATA_DIR "/spe10/rtsphem_tarbert_layer/perm.txt"
#define LAYER 13200

static char tmpdir[64];

/* Every number of a file, read with fscanf independently of the library. */
static double *slurp(const char *path, size_t *n)
{
    FILE *f = fopen(path, "r");
    size_t cap = 1024, k = 0;
    double *v = malloc(cap * sizeof *v), x;
    while (f && v && fscanf(f, "%lf", &x) == 1) {
        if (k == cap) {
            double *w = realloc(v, (cap *= 2) * sizeof *v);
            if (!w)
                break;
            v = w;
        }
        v[k++] = x;
    }
    if (f)
        fclose(f);
    *n = k;
    return v;
}

static void minmax(const double *v, size_t n, double *lo, double *hi)
{
    *lo = INFINITY;
    *hi = -INFINITY;
    for (size_t k = 0; k < n; ++k) {
        *lo = fmin(*lo, v[k]);
        *hi = fmax(*hi, v[k]);
    }
}

/* Count Kz/Kx ratios equal to 0.3 and to 1e-4; `other` counts the rest. The data are rounded
 * to a few digits (Kx = 1000.9 has Kz = 0.10008), which moves a ratio by up to 1e-4
 * relative: 1e-3 still separates the two classes by far. */
static void ratios(const pst_perm_grid *g, size_t *r03, size_t *r14, size_t *other)
{
    size_t n = (size_t)g->nx * (size_t)g->ny;
    for (size_t k = 0; k < n; ++k) {
        double r = g->k[2][k] / g->k[0][k];
        if (fabs(r / 0.3 - 1) < 1e-3)
            ++*r03;
        else if (fabs(r / 1e-4 - 1) < 1e-3)
            ++*r14;
        else
            ++*other;
    }
}

static size_t count_equal(const double *v, size_t n, double x)
{
    size_t c = 0;
    for (size_t k = 0; k < n; ++k)
        c += v[k] == x;
    return c;
}

/* README statistics of the three layers. */
static void test_statistics(void)
{
    char err[PST_ERRLEN] = "";
    pst_perm_grid g84, g85, gt;
    CHECK_INT(pst_spe10_read(&g84, GEOS_X, 84, 0, 0, 60, 220, err), PST_OK);
    CHECK_INT(pst_spe10_read(&g85, GEOS_X, 85, 0, 0, 60, 220, err), PST_OK);
    CHECK_INT(pst_spe10_read(&gt, TARBERT, 0, 0, 0, 60, 220, err), PST_OK);
    if (!g84.k[0] || !g85.k[0] || !gt.k[0]) {
        fprintf(stderr, "test_spe10: reading the SPE10 layers failed: %s\n", err);
        goto done;
    }
    CHECK_INT(g85.nx, 60);
    CHECK_INT(g85.ny, 220);
    CHECK_INT(g85.nz, 1);
    CHECK_INT((size_t)g85.nx * g85.ny * g85.nz, 13200);
    CHECK(g85.dx == 6.096 && g85.dy == 3.048 && g85.dz == 0.6096);
    double lo, hi;
    minmax(g85.k[0], LAYER, &lo, &hi);
    CHECK(lo == 0.000665);
    CHECK(hi == 20000);
    CHECK(hi / lo > 3e7); /* the contrast docs/spe10.md quotes */
    minmax(g84.k[0], LAYER, &lo, &hi);
    CHECK(lo == 0.002272);
    CHECK(hi == 20000);
    minmax(g85.k[2], LAYER, &lo, &hi);
    CHECK(lo == 6.65e-08);
    CHECK(hi == 6000);
    CHECK_INT(count_equal(g84.k[0], LAYER, 20000) + count_equal(g85.k[0], LAYER, 20000), 107);
    CHECK(memcmp(g84.k[0], g84.k[1], LAYER * sizeof(double)) == 0);
    CHECK(memcmp(g85.k[0], g85.k[1], LAYER * sizeof(double)) == 0);
    size_t r03 = 0, r14 = 0, other = 0;
    ratios(&g84, &r03, &r14, &other);
    ratios(&g85, &r03, &r14, &other);
    CHECK_INT(r03, 6106);
    CHECK_INT(r14, 20294);
    CHECK_INT(other, 0);

    minmax(gt.k[0], LAYER, &lo, &hi);
    CHECK(lo == 0.003033);
    CHECK(hi == 4647.5);
    minmax(gt.k[2], LAYER, &lo, &hi);
    CHECK(lo == 3.636e-07);
    CHECK(hi == 1394.25);
    CHECK(memcmp(gt.k[0], gt.k[1], LAYER * sizeof(double)) == 0);
    r03 = r14 = other = 0;
    ratios(&gt, &r03, &r14, &other);
    CHECK_INT(r03, 6481);
    CHECK_INT(r14, 6719);
    CHECK_INT(other, 0);
done:
    pst_perm_grid_free(&g84);
    pst_perm_grid_free(&g85);
    pst_perm_grid_free(&gt);
}

/* A sub-block holds exactly the lines i + 60*j (+ 13200*block) of the files. */
static void test_subblock(void)
{
    enum { I0 = 7, J0 = 13, NI = 20, NJ = 30 };
    char err[PST_ERRLEN] = "";
    size_t nx, nz, nt;
    double *rx = slurp(GEOS_X, &nx), *rz = slurp(GEOS_DIR "/permz.geos", &nz);
    double *rt = slurp(TARBERT, &nt);
    CHECK_INT(nx, 2 * LAYER);
    CHECK_INT(nz, 2 * LAYER);
    CHECK_INT(nt, 3 * LAYER);
    for (int layer = 84; layer <= 85 && nx == 2 * LAYER && nz == 2 * LAYER; ++layer) {
        pst_perm_grid g;
        int st = pst_spe10_read(&g, GEOS_X, layer, I0, J0, NI, NJ, err);
        CHECK_INT(st, PST_OK);
        if (st != PST_OK)
            continue;
        CHECK(g.nx == NI && g.ny == NJ && g.nz == 1);
        int bad = 0;
        for (int j = 0; j < NJ; ++j)
            for (int i = 0; i < NI; ++i) {
                size_t line = (size_t)(I0 + i) + 60 * (size_t)(J0 + j) + LAYER * (layer - 84);
                size_t cell = (size_t)i + NI * (size_t)j;
                bad += g.k[0][cell] != rx[line] || g.k[1][cell] != rx[line] ||
                       g.k[2][cell] != rz[line];
            }
        CHECK_INT(bad, 0);
        pst_perm_grid_free(&g);
        CHECK(g.k[0] == NULL && g.nx == 0);
    }
    pst_perm_grid g;
    if (nt == 3 * LAYER && pst_spe10_read(&g, TARBERT, 0, I0, J0, NI, NJ, err) == PST_OK) {
        int bad = 0;
        for (int c = 0; c < 3; ++c)
            for (int j = 0; j < NJ; ++j)
                for (int i = 0; i < NI; ++i)
                    bad += g.k[c][i + NI * j] !=
                           rt[(size_t)(I0 + i) + 60 * (size_t)(J0 + j) + (size_t)LAYER * c];
        CHECK_INT(bad, 0);
        pst_perm_grid_free(&g);
    } else {
        CHECK(0);
    }
    /* The far corner of the layer: the last line of each block. */
    if (pst_spe10_read(&g, GEOS_X, 85, 59, 219, 1, 1, err) == PST_OK) {
        CHECK(g.k[0][0] == rx[2 * LAYER - 1]);
        CHECK(g.k[2][0] == rz[2 * LAYER - 1]);
        pst_perm_grid_free(&g);
    } else {
        CHECK(0);
    }
    free(rx);
    free(rz);
    free(rt);
}

static long clampi(long v, long n) { return v < 0 ? 0 : v >= n ? n - 1 : v; }

/* LV §5.3 set-up: the 60x60 block of layer 85 on a cell-centred unit-square cloud. */
/* The 60x60 block of layer 85 into g and a cell-centred cloud of the unit square on it, one
 * particle per cell, h = h_ratio s0, with the diagonal mobility (Kx, Ky) of the cell under each
 * particle. NULL after a failed check (g is then empty). */
static pst_cloud *block85_cloud(pst_perm_grid *g, double h_ratio)
{
    char err[PST_ERRLEN] = "";
    if (pst_spe10_read(g, GEOS_X, 85, 0, 0, 60, 60, err) != PST_OK) {
        fprintf(stderr, "test_spe10: %s\n", err);
        CHECK(0);
        return NULL;
    }
    pst_lattice_opts o;
    pst_lattice_defaults(&o);
    o.dim = 2;
    o.lo[0] = o.lo[1] = 0;
    o.hi[0] = o.hi[1] = 1;
    o.s0 = 1.0 / 60;
    o.h_ratio = h_ratio;
    pst_cloud *c = NULL;
    CHECK_INT(pst_cloud_cell_centred(&c, &o, err), PST_OK);
    const double scale[3] = {1 / (60 * g->dx), 1 / (60 * g->dy), 1};
    if (c)
        CHECK_INT(pst_cloud_mobility_from_grid(c, g, NULL, scale, 1, err), PST_OK);
    else
        pst_perm_grid_free(g);
    return c;
}

static void test_cloud_mapping(void)
{
    char err[PST_ERRLEN] = "";
    pst_perm_grid g;
    pst_cloud *c = block85_cloud(&g, 1.2);
    if (!c)
        return;
    const double scale[3] = {1 / (60 * g.dx), 1 / (60 * g.dy), 1};
    double lo, hi;
    minmax(g.k[0], 3600, &lo, &hi); /* the block's contrast, docs/spe10.md */
    CHECK(lo == 0.004519);
    CHECK(hi == 20000);
    CHECK_INT(pst_cloud_mobility_ncomp(c), 2);
    size_t n = pst_cloud_size(c), interior = 0;
    const double *x = pst_cloud_coord_const(c, 0), *y = pst_cloud_coord_const(c, 1);
    const uint8_t *kind = pst_cloud_kinds_const(c);
    const double *mx = pst_cloud_mobility(c, 0), *my = pst_cloud_mobility(c, 1);
    int bad_interior = 0, bad_face = 0;
    for (size_t p = 0; p < n; ++p) {
        /* Cell centres sit at (i + 1/2)/60; face particles at 0 or 1 take the edge cell. */
        long i = clampi(lround(x[p] * 60 - 0.5), 60), j = clampi(lround(y[p] * 60 - 0.5), 60);
        int ok = mx[p] == g.k[0][i + 60 * j] && my[p] == g.k[1][i + 60 * j];
        if (kind[p] == PST_INTERIOR) {
            ++interior;
            bad_interior += !ok;
        } else {
            bad_face += !ok;
        }
    }
    CHECK_INT(interior, 3600);
    CHECK_INT(n, 3600 + 4 * 60);
    CHECK_INT(bad_interior, 0);
    CHECK_INT(bad_face, 0);
    CHECK_INT(pst_cloud_validate(c, NULL), PST_OK); /* every mobility > 0 */

    /* Scalar: Kx only. A zero scale is refused and leaves the mobility as it was. */
    CHECK_INT(pst_cloud_mobility_from_grid(c, &g, NULL, scale, 0, err), PST_OK);
    CHECK_INT(pst_cloud_mobility_ncomp(c), 1);
    const double zero[3] = {0, 1, 1};
    CHECK_INT(pst_cloud_mobility_from_grid(c, &g, NULL, zero, 1, err), PST_EINVAL);
    CHECK_INT(pst_cloud_mobility_ncomp(c), 1);
    double m_first = pst_cloud_mobility(c, 0)[0];
    pst_cloud_coord(c, 1)[0] = NAN;
    CHECK_INT(pst_cloud_mobility_from_grid(c, &g, NULL, scale, 1, err), PST_EINPUT);
    CHECK(strstr(err, "particle 0") != NULL);
    CHECK_INT(pst_cloud_mobility_ncomp(c), 1);
    CHECK(pst_cloud_mobility(c, 0)[0] == m_first);
    pst_cloud_destroy(c);
    pst_perm_grid_free(&g);
}

/* A hand-made 2x3x2 grid on a 3D cloud: the k[c][i + nx*(j + ny*l)] layout, origin, clamping
 * of particles on the outer faces and outside. */
static void test_grid_3d(void)
{
    char err[PST_ERRLEN] = "";
    double kx[12], ky[12], kz[12];
    for (int q = 0; q < 12; ++q) {
        kx[q] = 1 + q;
        ky[q] = 100 + q;
        kz[q] = 1000 + q;
    }
    pst_perm_grid g = {2, 3, 2, 0.5, 1.0, 2.0, {kx, ky, kz}};
    const double origin[3] = {-1, 0, 10};
    /* Particle, expected cell (i, j, l). */
    const double pos[][3] = {{-0.75, 0.5, 11},   /* (0,0,0)                         */
                             {-0.25, 2.5, 13},   /* (1,2,1)                         */
                             {-0.5, 1.0, 12},    /* interior faces: upper cell (1,1,1) */
                             {0.0, 3.0, 14},     /* upper outer faces: (1,2,1)      */
                             {-1.0, 0.0, 10},    /* lower outer faces: (0,0,0)      */
                             {-9.0, 7.0, 11.5}}; /* outside: clamped to (0,2,0)     */
    const int cell[][3] = {{0, 0, 0}, {1, 2, 1}, {1, 1, 1}, {1, 2, 1}, {0, 0, 0}, {0, 2, 0}};
    enum { NP = 6 };
    pst_cloud *c = NULL;
    CHECK_INT(pst_cloud_create(&c, 3, NP, NULL), PST_OK);
    if (!c)
        return;
    for (int p = 0; p < NP; ++p)
        for (int a = 0; a < 3; ++a)
            pst_cloud_coord(c, a)[p] = pos[p][a];
    CHECK_INT(pst_cloud_mobility_from_grid(c, &g, origin, NULL, 1, err), PST_OK);
    CHECK_INT(pst_cloud_mobility_ncomp(c), 3);
    for (int p = 0; p < NP; ++p) {
        int q = cell[p][0] + 2 * (cell[p][1] + 3 * cell[p][2]);
        CHECK(pst_cloud_mobility(c, 0)[p] == kx[q]);
        CHECK(pst_cloud_mobility(c, 1)[p] == ky[q]);
        CHECK(pst_cloud_mobility(c, 2)[p] == kz[q]);
    }
    /* A scale of 2 along x doubles the cell width: x = 0.5 from origin -1 is cell 0. */
    const double scale[3] = {2, 1, 1};
    pst_cloud_coord(c, 0)[0] = -0.5;
    CHECK_INT(pst_cloud_mobility_from_grid(c, &g, origin, scale, 0, err), PST_OK);
    CHECK(pst_cloud_mobility(c, 0)[0] == kx[0]);
    /* The diagonal tensor of a 3D cloud needs Kz. */
    g.k[2] = NULL;
    CHECK_INT(pst_cloud_mobility_from_grid(c, &g, origin, NULL, 1, err), PST_EINVAL);
    CHECK(strstr(err, "Kz") != NULL);
    pst_cloud_destroy(c);
}

/* Copy `src` to `dst` keeping the first `keep` lines (0: all) and replacing line `line`
 * (1-based; 0: none) by `text`. Then append `extra` if not NULL. */
static int corrupt_copy(const char *src, const char *dst, size_t keep, size_t line,
                        const char *text, const char *extra)
{
    FILE *in = fopen(src, "r"), *out = fopen(dst, "w");
    int ok = in && out;
    char buf[512];
    for (size_t k = 1; ok && fgets(buf, sizeof buf, in); ++k) {
        if (keep && k > keep)
            break;
        fputs(k == line ? text : buf, out);
    }
    if (ok && extra)
        fputs(extra, out);
    if (in)
        fclose(in);
    if (out && fclose(out) != 0)
        ok = 0;
    return ok;
}

/* Read the GEOS copy in tmpdir; expect `status` and `needle` in the message. */
static void expect_geos(int status, const char *needle)
{
    char err[PST_ERRLEN] = "", px[256];
    snprintf(px, sizeof px, "%s", test_path_in(tmpdir, "permx.geos"));
    pst_perm_grid g;
    int st = pst_spe10_read(&g, px, 85, 0, 0, 60, 60, err);
    CHECK_INT(st, status);
    if (status != PST_OK)
        CHECK(g.k[0] == NULL && g.k[1] == NULL && g.k[2] == NULL);
    if (!strstr(err, needle)) {
        fprintf(stderr, "test_spe10: expected '%s' in: %s\n", needle, err);
        CHECK(0);
    }
    pst_perm_grid_free(&g);
}

static void test_errors(void)
{
    char err[PST_ERRLEN] = "";
    pst_perm_grid g;
    /* Arguments. */
    CHECK_INT(pst_spe10_read(&g, GEOS_X, 83, 0, 0, 60, 60, err), PST_EINVAL);
    CHECK(strstr(err, "layer 83") != NULL);
    CHECK_INT(pst_spe10_read(&g, TARBERT, 85, 0, 0, 60, 60, err), PST_EINVAL);
    CHECK_INT(pst_spe10_read(&g, GEOS_DIR "/poro.geos", 85, 0, 0, 60, 60, err), PST_EINVAL);
    CHECK_INT(pst_spe10_read(&g, GEOS_X, 85, 0, 0, 61, 60, err), PST_EINVAL);
    CHECK(strstr(err, "not inside") != NULL);
    CHECK_INT(pst_spe10_read(&g, GEOS_X, 85, 0, 161, 60, 60, err), PST_EINVAL);
    CHECK_INT(pst_spe10_read(&g, GEOS_X, 85, -1, 0, 10, 10, err), PST_EINVAL);
    CHECK_INT(pst_spe10_read(&g, GEOS_X, 85, 0, 0, 0, 10, err), PST_EINVAL);
    CHECK_INT(pst_spe10_read(&g, TARBERT, 0, 59, 219, 2, 1, err), PST_EINVAL);
    CHECK(g.k[0] == NULL);
    CHECK_INT(pst_spe10_read(&g, PSTENCIL_DATA_DIR "/no/such/dir/permx.geos", 84, 0, 0, 1, 1,
                             err),
              PST_EIO);
    CHECK(strstr(err, "no/such/dir/permx.geos: cannot open") != NULL);

    /* Corrupted copies: each case rewrites one file and restores it afterwards. */
    if (test_scratch_dir(tmpdir, sizeof tmpdir, "pst_spe10") != 0) {
        CHECK(0);
        return;
    }
    char px[256], py[256], pz[256], pt[256];
    snprintf(px, sizeof px, "%s", test_path_in(tmpdir, "permx.geos"));
    snprintf(py, sizeof py, "%s", test_path_in(tmpdir, "permy.geos"));
    snprintf(pz, sizeof pz, "%s", test_path_in(tmpdir, "permz.geos"));
    snprintf(pt, sizeof pt, "%s", test_path_in(tmpdir, "perm.txt"));
    CHECK(corrupt_copy(GEOS_X, px, 0, 0, NULL, NULL));
    expect_geos(PST_EIO, "permy.geos: cannot open"); /* permy missing */
    CHECK(corrupt_copy(GEOS_DIR "/permy.geos", py, 0, 0, NULL, NULL));
    CHECK(corrupt_copy(GEOS_DIR "/permz.geos", pz, 0, 0, NULL, NULL));
    expect_geos(PST_OK, "");

    CHECK(corrupt_copy(GEOS_DIR "/permy.geos", py, 0, 20000, "nan\n", NULL));
    expect_geos(PST_EINPUT, "permy.geos:20000: permeability 'nan' is not finite");
    CHECK(corrupt_copy(GEOS_DIR "/permy.geos", py, 0, 0, NULL, NULL));
    CHECK(corrupt_copy(GEOS_DIR "/permz.geos", pz, 0, 5, "-0.25\n", NULL));
    expect_geos(PST_EINPUT, "permz.geos:5: permeability -0.25 must be > 0");
    CHECK(corrupt_copy(GEOS_DIR "/permz.geos", pz, 0, 0, NULL, NULL));
    /* Layer 84 is outside the requested layer 85 block but is still checked. */
    CHECK(corrupt_copy(GEOS_X, px, 0, 100, "0\n", NULL));
    expect_geos(PST_EINPUT, "permx.geos:100: permeability 0 must be > 0");
    CHECK(corrupt_copy(GEOS_X, px, 0, 26400, "1.5e\n", NULL));
    expect_geos(PST_EINPUT, "permx.geos:26400: cannot parse '1.5e'");
    CHECK(corrupt_copy(GEOS_X, px, 0, 7, "inf\n", NULL));
    expect_geos(PST_EINPUT, "permx.geos:7: permeability 'inf' is not finite");
    CHECK(corrupt_copy(GEOS_X, px, 20000, 0, NULL, NULL));
    expect_geos(PST_EINPUT, "permx.geos:20000: too few values: expected 26400, found 20000");
    CHECK(corrupt_copy(GEOS_X, px, 0, 0, NULL, "1.0\n"));
    expect_geos(PST_EINPUT, "permx.geos:26401: too many values");

    CHECK(corrupt_copy(TARBERT, pt, 0, 3000, "1 2 3 -1.5 5 6\n", NULL));
    CHECK_INT(pst_spe10_read(&g, pt, 0, 0, 0, 60, 60, err), PST_EINPUT);
    CHECK(strstr(err, "perm.txt:3000: permeability -1.5 must be > 0") != NULL);
    CHECK(corrupt_copy(TARBERT, pt, 0, 6600, "1 2 3 4 5 NaN\n", NULL));
    CHECK_INT(pst_spe10_read(&g, pt, 0, 0, 0, 60, 60, err), PST_EINPUT);
    CHECK(strstr(err, "perm.txt:6600: permeability 'NaN' is not finite") != NULL);
    CHECK(corrupt_copy(TARBERT, pt, 0, 2, "1 2 3 4 5\n", NULL)); /* one value short */
    CHECK_INT(pst_spe10_read(&g, pt, 0, 0, 0, 60, 60, err), PST_EINPUT);
    CHECK(strstr(err, "perm.txt:6600: too few values: expected 39600, found 39599") != NULL);
    CHECK(g.k[0] == NULL);

    test_remove_dir(tmpdir);
    CHECK(access(tmpdir, F_OK) != 0);
}

/* The Lukyanov–Vuik operators on real heterogeneous data (LV §5.3 set-up): layer 85, 60x60,
 * one particle per cell, diagonal tensor mobility (Kx, Ky), f = 1.2012. Every scheme must
 * build with every row classified, give finite output, and report its status counts. */
static void test_operators(void)
{
    char err[PST_ERRLEN] = "";
    pst_perm_grid g;
    pst_cloud *c = block85_cloud(&g, 1.2012);
    if (!c)
        return;
    pst_nlist *nl = NULL;
    CHECK_INT(pst_nlist_build(&nl, c, pst_kernel_support(PST_KERNEL_CUBIC), err), PST_OK);
    size_t n = pst_cloud_size(c);
    double *u = malloc(n * sizeof *u), *y = malloc(n * sizeof *y);
    for (size_t i = 0; i < n; ++i)
        u[i] = pst_cloud_coord_const(c, 1)[i]; /* the pressure drop direction */
    /* the schemes with a heterogeneous (diagonal tensor) form */
    static const char *const hetero[] = {"brookshaw", "cb", "schwaiger", "lv"};
    for (int s = 0; s < 4; ++s) {
        pst_op_opts oo;
        pst_op_defaults(&oo);
        oo.scheme = hetero[s];
        pst_op *op = NULL;
        CHECK_INT(pst_op_create(&op, c, nl, &oo, err), PST_OK);
        if (!op)
            continue;
        size_t counts[PST_ROW_NSTATUS], total = 0;
        pst_op_status_counts(op, counts);
        for (int k = 0; k < PST_ROW_NSTATUS; ++k)
            total += counts[k];
        CHECK_INT(total, n);
        pst_op_apply(op, u, y);
        int finite = 1;
        for (size_t i = 0; i < n; ++i)
            finite = finite && isfinite(y[i]);
        CHECK(finite);
        pst_op_audit a;
        CHECK_INT(pst_op_audit_rows(op, &a), PST_OK);
        printf("SPE10 layer 85 60x60 %-9s: ok %zu, fallback %zu, ill-conditioned %zu, "
               "rank-deficient %zu, too few %zu; rows with positive off-diagonals %zu\n",
               oo.scheme, counts[0], counts[1], counts[2], counts[3], counts[4],
               a.rows_positive_offdiag);
        pst_op_destroy(op);
    }
    free(u);
    free(y);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
    pst_perm_grid_free(&g);
}

int main(void)
{
    struct stat sb;
    if (stat(PSTENCIL_DATA_DIR "/spe10", &sb) != 0 || !S_ISDIR(sb.st_mode)) {
        /* A missing data directory must fail loudly: the checks below are the point. */
        fprintf(stderr,
                "test_spe10: FAIL: the SPE10 data directory %s/spe10 does not exist "
                "(it is part of the repository: data/spe10)\n",
                PSTENCIL_DATA_DIR);
        CHECK(0);
        return check_summary("test_spe10");
    }
    test_statistics();
    test_subblock();
    test_cloud_mapping();
    test_grid_3d();
    test_errors();
    test_operators();
    return check_summary("test_spe10");
}
