/* pstencil analyse's parts (src/analyse*.c, docs/stability.md):
 *   - von Neumann growth factors (LV eq. 83) of lv on a regular lattice at f = h/dx = 0.5005,
 *     where lv is the 5-point Laplacian: lambda = 1 - 4 tau (sin^2(kx dx/2) + sin^2(ky dx/2))
 *     for every unknown row and k; max |lambda| = 1 at tau = 0.25 (the checkerboard gives
 *     exactly -1) and 1.08 at tau = 0.26, where only the checkerboard grows;
 *   - the discrete maximum principle: brookshaw (an M-matrix) on a jittered cloud has no
 *     violation for step data; lv and qsfdi reproduce g = x; a singular block is a finding;
 *     a cloud without Dirichlet particles is "not applicable";
 *   - qsfdi on a hard cloud (K = 0.8, h = 0.75 s0): growth factors well above 1, positive
 *     off-diagonals in most rows, and still exact for linear data;
 *   - the scene path (pst_analyse_scene_all) and analysis.json agree with the parts. */
#include "analyse.h"
#include "check.h"
#include "support.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define DX 0.2

/* The slit-flow lattice of test_slit_flow.c on [0,2]^2: 11 x 11, the outer layer Dirichlet,
 * h = 0.5005 dx (four axis neighbours: the 5-point stencil with lv). */
static pst_op *five_point(pst_cloud **c, pst_nlist **nl)
{
    *c = test_lattice(2, 0, 2, DX, 0.5005, 0, 1, 1);
    *nl = test_nlist(*c, pst_kernel_support(pst_scheme_default_kernel("lv")));
    return test_op(*c, *nl, "lv", PST_GRAD_G1, 0);
}

static void test_five_point(void)
{
    pst_cloud *c;
    pst_nlist *nl;
    pst_op *op = five_point(&c, &nl);
    CHECK_NEAR(pst_mean_nearest_distance(c, nl), DX, 1e-12);
    char err[PST_ERRLEN];
    pst_vonneumann vn;
    CHECK_INT(pst_vonneumann_compute(c, nl, op, DX, 0.25, 4, &vn, err, sizeof err), PST_OK);
    CHECK_INT(vn.rows, 81);
    CHECK_INT(vn.nk, 24);
    double worst = 0;
    for (size_t q = 0; q < vn.nk; ++q) {
        double sx = sin(vn.k[3 * q] * DX / 2), sy = sin(vn.k[3 * q + 1] * DX / 2);
        double want = 1 - 4 * 0.25 * (sx * sx + sy * sy);
        for (size_t r = 0; r < vn.rows; ++r) {
            worst = fmax(worst, fabs(vn.re[q * vn.rows + r] - want));
            worst = fmax(worst, fabs(vn.im[q * vn.rows + r]));
        }
    }
    printf("5-point lattice, tau 0.25: max |lambda - (1 - 4 tau (sx^2 + sy^2))| = %.3g, "
           "max |lambda| = %.17g\n", worst, vn.max_abs);
    CHECK(worst <= 1e-12);
    CHECK_NEAR(vn.max_abs, 1.0, 1e-12);
    CHECK_INT(vn.over, 0);
    CHECK_INT(vn.particles_over, 0);
    /* the rows next to the Dirichlet layer: the 9 x 9 interior's perimeter */
    CHECK_INT(vn.adjacent_rows, 32);
    pst_vonneumann_free(&vn);

    CHECK_INT(pst_vonneumann_compute(c, nl, op, DX, 0.26, 4, &vn, err, sizeof err), PST_OK);
    printf("5-point lattice, tau 0.26: max |lambda| = %.17g, %zu growing pairs\n", vn.max_abs,
           vn.over);
    CHECK_NEAR(vn.max_abs, 1.08, 1e-12);
    CHECK(vn.max_abs > 1);
    /* only the checkerboard k = (pi/dx)(1, 1) grows: one pair per row */
    CHECK_INT(vn.over, 81);
    CHECK_INT(vn.particles_over, 81);
    CHECK_INT(vn.particles_over_adjacent, 32);
    CHECK_NEAR(vn.over_fraction, 1.0 / 24, 1e-15);
    pst_vonneumann_free(&vn);

    /* bad arguments are errors, not NaN */
    CHECK_INT(pst_vonneumann_compute(c, nl, op, DX, 0, 4, &vn, err, sizeof err), PST_EINVAL);
    CHECK_INT(pst_vonneumann_compute(c, nl, op, DX, 0.25, 0, &vn, err, sizeof err), PST_EINVAL);
    CHECK_INT(pst_vonneumann_compute(c, nl, op, NAN, 0.25, 4, &vn, err, sizeof err), PST_EINVAL);
    pst_vonneumann_free(&vn);

    /* the 5-point stencil is an M-matrix, exact for linear data */
    pst_csr a = {0};
    CHECK_INT(pst_op_assemble(op, &a), PST_OK);
    pst_dmp d;
    CHECK_INT(pst_dmp_check(c, &a, &d, err, sizeof err), PST_OK);
    CHECK_INT(d.applicable, 1);
    CHECK_INT(d.singular, 0);
    CHECK_INT(d.step.violations, 0);
    CHECK(d.linear.max_err < 1e-12);
    pst_csr_free(&a);
    pst_op_destroy(op);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
}

/* The maximum principle of `scheme` on a lattice of [0,1]^2 with s0 = 0.05 (441 particles,
 * 361 unknowns), h = h_ratio s0, jitter K; audit and von Neumann at tau 0.25 on request. */
static pst_dmp dmp_of(const char *scheme, double h_ratio, double K, uint64_t seed,
                      pst_op_audit *audit, pst_vonneumann *vn)
{
    pst_cloud *c = test_lattice(2, 0, 1, 0.05, h_ratio, K, seed, 1);
    pst_nlist *nl = test_nlist(c, pst_kernel_support(pst_scheme_default_kernel(scheme)));
    pst_op *op = test_op(c, nl, scheme, PST_GRAD_G1, 0);
    pst_csr a = {0};
    pst_dmp d;
    char err[PST_ERRLEN];
    CHECK_INT(pst_op_assemble(op, &a), PST_OK);
    CHECK_INT(pst_dmp_check(c, &a, &d, err, sizeof err), PST_OK);
    CHECK_INT(d.unknowns, 361);
    if (audit)
        CHECK_INT(pst_op_audit_rows(op, audit), PST_OK);
    if (vn)
        CHECK_INT(pst_vonneumann_compute(c, nl, op, 0.05, 0.25, 4, vn, err, sizeof err),
                  PST_OK);
    pst_csr_free(&a);
    pst_op_destroy(op);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
    return d;
}

static void test_maximum_principle(void)
{
    pst_op_audit au;
    pst_dmp d = dmp_of("brookshaw", 1.2, 0.35, 7, &au, NULL);
    printf("brookshaw K 0.35: audit %zu rows with positive off-diagonals; step: %zu outside "
           "[%g, %g], overshoot %g\n", au.rows_positive_offdiag, d.step.violations, d.step.gmin,
           d.step.gmax, d.step.overshoot);
    CHECK_INT(au.rows_positive_offdiag, 0);
    CHECK_INT(d.singular, 0);
    CHECK_NEAR(d.step.gmin, 0, 0);
    CHECK_NEAR(d.step.gmax, 1, 0);
    CHECK_INT(d.step.violations, 0);
    CHECK_NEAR(d.step.overshoot, 0, 0);
    CHECK_INT(d.linear.violations, 0);

    const char *exact[] = {"lv", "qsfdi"};
    for (int s = 0; s < 2; ++s) {
        d = dmp_of(exact[s], 1.2, 0.35, 7, NULL, NULL);
        printf("%s K 0.35: max |u - x| = %.3g\n", exact[s], d.linear.max_err);
        CHECK_INT(d.singular, 0);
        CHECK(d.linear.max_err >= 0 && d.linear.max_err < 1e-10);
        CHECK_NEAR(d.linear.gmin, 0, 0.05);
        CHECK_NEAR(d.linear.gmax, 1, 0.05);
    }
}

/* qsfdi on a hard cloud, K = 0.8 and h = 0.75 s0, five seeds. Measured (s0 = 0.05):
 * max |lambda| 4.7-12.5, 9-13 % of the (row, k) pairs above 1, 309-317 of 361 rows with
 * positive off-diagonals; the step data leave [0, 1] at 2-3 unknowns on some seeds and none
 * on others, so only "some seed violates" is asserted; g = x is still exact. */
static void test_qsfdi_hard(void)
{
    size_t violations = 0, seeds_violating = 0;
    for (uint64_t seed = 1; seed <= 5; ++seed) {
        pst_op_audit au;
        pst_vonneumann vn;
        pst_dmp d = dmp_of("qsfdi", 0.75, 0.8, seed, &au, &vn);
        printf("qsfdi K 0.8 h 0.75 seed %d: max |lambda| %.4g, fraction > 1 %.4f, %zu rows "
               "with positive off-diagonals, step %zu outside (overshoot %.3g), max |u - x| "
               "%.3g\n", (int)seed, vn.max_abs, vn.over_fraction, au.rows_positive_offdiag,
               d.step.violations, d.step.overshoot, d.linear.max_err);
        CHECK(vn.max_abs > 2);
        CHECK(vn.over_fraction > 0.03);
        CHECK(au.rows_positive_offdiag > 200);
        CHECK_INT(d.singular, 0);
        CHECK(d.linear.max_err < 1e-10);
        violations += d.step.violations;
        seeds_violating += d.step.violations > 0;
        pst_vonneumann_free(&vn);
    }
    CHECK(seeds_violating >= 1 && violations > 0);
}

/* A singular unknowns' block (an isolated interior particle: a zero row in brookshaw) is a
 * finding; a cloud without Dirichlet particles is not applicable. */
static void test_degenerate(void)
{
    /* 5 x 5 lattice of spacing 0.1, outer layer Dirichlet, plus one far interior particle */
    pst_cloud *c;
    CHECK_INT(pst_cloud_create(&c, 2, 26, NULL), PST_OK);
    double *x = pst_cloud_coord(c, 0), *y = pst_cloud_coord(c, 1);
    uint8_t *kind = pst_cloud_kinds(c);
    for (size_t i = 0; i < 25; ++i) {
        x[i] = 0.1 * (double)(i % 5);
        y[i] = 0.1 * (double)(i / 5);
        kind[i] = (i % 5 == 0 || i % 5 == 4 || i / 5 == 0 || i / 5 == 4) ? PST_DIRICHLET
                                                                           : PST_INTERIOR;
    }
    x[25] = y[25] = 5;
    CHECK_INT(pst_cloud_set_h_uniform(c, 0.12, NULL), PST_OK);
    pst_nlist *nl = test_nlist(c, 2);
    pst_op *op = test_op(c, nl, "brookshaw", PST_GRAD_G1, 0);
    pst_csr a = {0};
    pst_dmp d;
    char err[PST_ERRLEN];
    CHECK_INT(pst_op_assemble(op, &a), PST_OK);
    CHECK_INT(pst_dmp_check(c, &a, &d, err, sizeof err), PST_OK);
    printf("isolated particle: applicable %d, singular %d: %s\n", d.applicable, d.singular,
           d.why);
    CHECK_INT(d.applicable, 1);
    CHECK_INT(d.singular, 1);
    CHECK(strstr(d.why, "singular") != NULL);
    pst_csr_free(&a);
    pst_op_destroy(op);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);

    c = test_lattice(2, 0, 1, 0.1, 1.2, 0, 1, 0);
    nl = test_nlist(c, 2);
    op = test_op(c, nl, "brookshaw", PST_GRAD_G1, 0);
    CHECK_INT(pst_op_assemble(op, &a), PST_OK);
    CHECK_INT(pst_dmp_check(c, &a, &d, err, sizeof err), PST_OK);
    CHECK_INT(d.applicable, 0);
    CHECK_INT(d.dirichlet, 0);
    pst_csr_free(&a);
    pst_op_destroy(op);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
}

/* The scene path: one operator, every part, and analysis.json holding the same numbers. */
static void test_scene(void)
{
    static const char *text =
        "{ \"dim\": 2,\n"
        "  \"cloud\": { \"source\": \"lattice\", \"lo\": [0, 0], \"hi\": [1, 1], \"spacing\": 0.05,\n"
        "             \"jitter\": 0.35, \"seed\": 7, \"boundary_layer\": true, \"h_ratio\": 1.2 },\n"
        "  \"operator\": { \"scheme\": \"lv\" },\n"
        "  \"fields\": { \"u\": \"x\" },\n"
        "  \"tasks\": [ { \"type\": \"laplacian\", \"field\": \"u\" } ] }";
    pst_scene s;
    char err[1024];
    if (pst_scene_parse(&s, text, "analyse.json", NULL, 0, err, sizeof err) != PST_OK) {
        printf("scene: %s\n", err);
        exit(1);
    }
    pst_analyse_opts o;
    pst_analyse_defaults(&o);
    CHECK_NEAR(o.tau, 0.25, 0);
    CHECK_INT(o.waves, 4);
    o.waves = 3;
    pst_analysis an;
    int st = pst_analyse_scene_all(&s, &o, 1, PST_ANALYSE_MAX_UNKNOWNS, &an, err, sizeof err);
    if (st != PST_OK)
        printf("analyse: %s\n", err);
    CHECK_INT(st, PST_OK);
    CHECK_INT(an.spectrum.n, 361);
    CHECK_INT(an.spectrum.wrong_sign, 0);
    CHECK_INT(an.vn.nk, 15);
    CHECK_INT(an.s0_from_spacing, 1);
    CHECK_NEAR(an.vn.s0, 0.05, 0);
    CHECK_INT(an.audit.rows, 361);
    CHECK_INT(an.diag_rows, 361);
    CHECK_INT(an.nonpositive_diag, 0);
    CHECK_INT(an.dmp.applicable, 1);
    CHECK(an.dmp.linear.max_err < 1e-10);
    CHECK(strcmp(an.opts.scheme, "lv") == 0);
    /* the per-particle fields add up to the summary */
    size_t n = pst_cloud_size(an.cloud), rows_pos = 0, mixed = 0, growing = 0;
    double vmax = 0;
    const double *fp = pst_cloud_field_by_name(an.cloud, "audit_positive_offdiag"),
                 *fm = pst_cloud_field_by_name(an.cloud, "audit_lemma3_mixed"),
                 *fv = pst_cloud_field_by_name(an.cloud, "vn_max_abs");
    CHECK(fp && fm && fv && an.status);
    for (size_t i = 0; fp && fm && fv && i < n; ++i) {
        rows_pos += fp[i] == 1;
        mixed += fm[i] == 1;
        growing += fv[i] > 1 + PST_VN_TOL;
        vmax = fmax(vmax, fv[i]);
    }
    CHECK_INT(rows_pos, an.audit.rows_positive_offdiag);
    CHECK_INT(mixed, (size_t)an.audit.lemma3_sign_mixed);
    CHECK_INT(growing, an.vn.particles_over);
    CHECK_NEAR(vmax, an.vn.max_abs, 0);

    char dir[64], path[128];
    if (test_scratch_dir(dir, sizeof dir, "test_analyse") == 0) {
        snprintf(path, sizeof path, "%s/analysis.vtu", dir);
        CHECK_INT(pst_analysis_write_vtu(&an, path, err, sizeof err), PST_OK);
        pst_cloud *back = NULL;
        CHECK_INT(pst_cloud_read_vtu(&back, path, err), PST_OK);
        CHECK(back && pst_cloud_field_by_name(back, "vn_max_abs") != NULL);
        pst_cloud_destroy(back);
        snprintf(path, sizeof path, "%s/analysis.json", dir);
        CHECK_INT(pst_analysis_write_json(&an, s.path, path, err, sizeof err), PST_OK);
        FILE *f = fopen(path, "rb");
        char buf[8192] = {0};
        size_t got = f ? fread(buf, 1, sizeof buf - 1, f) : 0;
        if (f)
            fclose(f);
        /* cJSON writes a NaN or an infinity as null */
        CHECK(got > 0 && strstr(buf, "null") == NULL);
        cJSON *j = cJSON_Parse(buf);
        CHECK(j != NULL);
        cJSON *v = cJSON_GetObjectItem(j, "von_neumann");
        CHECK_NEAR(cJSON_GetNumberValue(cJSON_GetObjectItem(v, "max_abs")), an.vn.max_abs, 0);
        CHECK_NEAR(cJSON_GetNumberValue(cJSON_GetObjectItem(v, "waves")), 3, 0);
        cJSON *mp = cJSON_GetObjectItem(j, "maximum_principle");
        CHECK(cJSON_IsTrue(cJSON_GetObjectItem(mp, "applicable")));
        CHECK_NEAR(cJSON_GetNumberValue(
                       cJSON_GetObjectItem(cJSON_GetObjectItem(mp, "step"), "violations")),
                   (double)an.dmp.step.violations, 0);
        cJSON_Delete(j);
        test_remove_dir(dir);
    }
    pst_analysis_free(&an);

    o.tau = -1;
    CHECK_INT(pst_analyse_scene_all(&s, &o, 1, PST_ANALYSE_MAX_UNKNOWNS, &an, err, sizeof err),
              PST_EINVAL);
    pst_analysis_free(&an);
    pst_scene_free(&s);
}

int main(void)
{
    test_five_point();
    test_maximum_principle();
    test_qsfdi_hard();
    test_degenerate();
    test_scene();
    return check_summary("test_analyse");
}
