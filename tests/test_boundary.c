/* A boundary given to the operator (pst_op_opts.kinds, .normals) instead of the cloud's own:
 * every scheme's operator equals, bit for bit, the one built on a cloud that carries that
 * boundary; the cloud is never written, by the operator nor by a scene run with boundary
 * groups; a bad boundary is refused with a message. */
#include "check.h"
#include "run.h"
#include "support.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A boundary unlike the cloud's: every third Dirichlet particle becomes Neumann with a tilted
 * unit normal, every fifth interior particle Dirichlet. */
static void other_boundary(const pst_cloud *c, uint8_t *kind, double *normal[3])
{
    size_t n = pst_cloud_size(c);
    int dim = pst_cloud_dim(c);
    memcpy(kind, pst_cloud_kinds_const(c), n);
    for (int d = 0; d < dim; ++d)
        memcpy(normal[d], pst_cloud_normal_const(c, d), n * sizeof(double));
    for (size_t i = 0; i < n; ++i) {
        if (kind[i] == PST_DIRICHLET && i % 3 == 0) {
            static const double tilted[2][3] = {{0.8, 0.6, 0.0}, {0.48, 0.6, 0.64}};
            kind[i] = PST_NEUMANN;
            for (int d = 0; d < dim; ++d)
                normal[d][i] = tilted[dim - 2][d];
        } else if (kind[i] == PST_INTERIOR && i % 5 == 0) {
            kind[i] = PST_DIRICHLET;
        }
    }
}

static int same_doubles(const double *a, const double *b, size_t n)
{
    return memcmp(a, b, n * sizeof(double)) == 0;
}

/* Apply, stored apply, diagonal, assembled matrix and row status of two operators, bit for
 * bit. */
static void check_same_operator(pst_op *a, pst_op *b, size_t n, const double *u)
{
    double *ya = malloc(n * sizeof *ya), *yb = malloc(n * sizeof *yb);
    CHECK_INT(pst_op_apply(a, u, ya), PST_OK);
    CHECK_INT(pst_op_apply(b, u, yb), PST_OK);
    CHECK(same_doubles(ya, yb, n));
    CHECK_INT(pst_op_diagonal(a, ya), PST_OK);
    CHECK_INT(pst_op_diagonal(b, yb), PST_OK);
    CHECK(same_doubles(ya, yb, n));
    CHECK_INT(pst_op_store(a), PST_OK);
    CHECK_INT(pst_op_store(b), PST_OK);
    CHECK_INT(pst_op_apply_stored(a, u, ya), PST_OK);
    CHECK_INT(pst_op_apply_stored(b, u, yb), PST_OK);
    CHECK(same_doubles(ya, yb, n));
    CHECK(memcmp(pst_op_status(a), pst_op_status(b), n) == 0);
    pst_csr ma, mb;
    CHECK_INT(pst_op_assemble(a, &ma), PST_OK);
    CHECK_INT(pst_op_assemble(b, &mb), PST_OK);
    CHECK(memcmp(ma.rowptr, mb.rowptr, (n + 1) * sizeof *ma.rowptr) == 0);
    if (ma.rowptr[n] == mb.rowptr[n]) {
        size_t nnz = (size_t)ma.rowptr[n];
        CHECK(memcmp(ma.col, mb.col, nnz * sizeof *ma.col) == 0);
        CHECK(same_doubles(ma.val, mb.val, nnz));
    }
    pst_csr_free(&ma);
    pst_csr_free(&mb);
    free(ya);
    free(yb);
}

static double wave(const double *x) { return sin(3 * x[0] + 2 * x[1]) + x[2] * x[2]; }

/* Every scheme, in 2D and 3D: the operator with the override on cloud a equals the operator on
 * cloud b (the same lattice) whose kinds and normals were set to the override; a unchanged. */
static void test_override_equals_cloud(int dim)
{
    double s0 = dim == 2 ? 0.1 : 0.25;
    pst_cloud *a = test_lattice(dim, 0, 1, s0, 1.3, 0.2, 7, 1);
    pst_cloud *b = test_lattice(dim, 0, 1, s0, 1.3, 0.2, 7, 1);
    size_t n = pst_cloud_size(a);
    uint8_t *kind = malloc(n), *kind_before = malloc(n);
    double *normal[3] = {NULL, NULL, NULL}, *normal_before[3] = {NULL, NULL, NULL};
    for (int d = 0; d < dim; ++d) {
        normal[d] = malloc(n * sizeof(double));
        normal_before[d] = malloc(n * sizeof(double));
        memcpy(normal_before[d], pst_cloud_normal_const(a, d), n * sizeof(double));
    }
    memcpy(kind_before, pst_cloud_kinds_const(a), n);
    other_boundary(a, kind, normal);
    memcpy(pst_cloud_kinds(b), kind, n);
    for (int d = 0; d < dim; ++d)
        memcpy(pst_cloud_normal(b, d), normal[d], n * sizeof(double));
    pst_nlist *nla = test_nlist(a, 2.0), *nlb = test_nlist(b, 2.0);
    double *u = test_field(a, wave);
    for (int k = 0; k < pst_scheme_count(); ++k) {
        pst_op_opts o;
        pst_op_defaults(&o);
        o.scheme = pst_scheme_name(k);
        pst_op *opb = NULL, *opa = NULL;
        char err[PST_ERRLEN];
        int stb = pst_op_create(&opb, b, nlb, &o, err);
        o.kinds = kind;
        for (int d = 0; d < dim; ++d)
            o.normals[d] = normal[d];
        int sta = pst_op_create(&opa, a, nla, &o, err);
        CHECK_INT(sta, stb);
        if (sta == PST_OK && stb == PST_OK)
            check_same_operator(opa, opb, n, u);
        pst_op_destroy(opa);
        pst_op_destroy(opb);
    }
    CHECK(memcmp(pst_cloud_kinds_const(a), kind_before, n) == 0);
    for (int d = 0; d < dim; ++d)
        CHECK(same_doubles(pst_cloud_normal_const(a, d), normal_before[d], n));
    free(u);
    for (int d = 0; d < dim; ++d) {
        free(normal[d]);
        free(normal_before[d]);
    }
    free(kind);
    free(kind_before);
    pst_nlist_destroy(nla);
    pst_nlist_destroy(nlb);
    pst_cloud_destroy(a);
    pst_cloud_destroy(b);
}

/* An unknown kind and a non-finite Neumann normal: PST_EINVAL naming the particle. */
static void test_bad_override(void)
{
    pst_cloud *c = test_lattice(2, 0, 1, 0.1, 1.3, 0.0, 1, 1);
    pst_nlist *nl = test_nlist(c, 2.0);
    size_t n = pst_cloud_size(c);
    uint8_t *kind = malloc(n);
    double *normal[3] = {malloc(n * sizeof(double)), malloc(n * sizeof(double)), NULL};
    other_boundary(c, kind, normal);
    pst_op_opts o;
    pst_op_defaults(&o);
    o.kinds = kind;
    o.normals[0] = normal[0];
    o.normals[1] = normal[1];
    pst_op *op = NULL;
    char err[PST_ERRLEN] = "";
    kind[4] = 7;
    CHECK_INT(pst_op_create(&op, c, nl, &o, err), PST_EINVAL);
    CHECK(op == NULL);
    CHECK(strstr(err, "particle 4 has unknown kind 7") != NULL);
    kind[4] = PST_INTERIOR;
    size_t neu = 0;
    while (neu < n && kind[neu] != PST_NEUMANN)
        ++neu;
    CHECK(neu < n);
    normal[1][neu] = NAN;
    err[0] = '\0';
    CHECK_INT(pst_op_create(&op, c, nl, &o, err), PST_EINVAL);
    CHECK(strstr(err, "non-finite normal") != NULL);
    char want[64];
    snprintf(want, sizeof want, "particle %zu ", neu);
    CHECK(strstr(err, want) != NULL);
    free(kind);
    free(normal[0]);
    free(normal[1]);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
}

static const char *const grouped_scene =
    "{ \"dim\": 2,\n"
    "  \"cloud\": { \"source\": \"lattice\", \"lo\": [0, 0], \"hi\": [1, 1], \"spacing\": 0.1,\n"
    "             \"jitter\": 0.2, \"seed\": 5, \"boundary_layer\": true, \"h_ratio\": 1.3 },\n"
    "  \"operator\": { \"scheme\": \"lv\" },\n"
    "  \"tasks\": [ { \"type\": \"solve\", \"name\": \"u\", \"rhs\": \"0\",\n"
    "      \"exact\": \"x + 2*y\", \"norms\": [\"max_abs\"],\n"
    "      \"boundary\": [ { \"where\": \"xhi\", \"type\": \"neumann\", \"value\": \"1\" },\n"
    "                      { \"where\": \"ylo\", \"type\": \"neumann\", \"value\": \"-2\" },\n"
    "                      { \"where\": \"all\", \"type\": \"dirichlet\", \"value\": \"x + 2*y\" }"
    " ] } ] }";

/* A run with boundary groups hands back the cloud with the generator's kinds and normals
 * (matched by input id), and its solve did see the groups: the Neumann sides are solved. */
static void test_run_keeps_cloud(void)
{
    pst_scene s;
    char err[1024];
    int parsed = pst_scene_parse(&s, grouped_scene, "grouped.json", NULL, 0, err, sizeof err);
    if (parsed != PST_OK)
        printf("scene: %s\n", err);
    CHECK_INT(parsed, PST_OK);
    pst_run_opts o = {.quiet = 1};
    pst_cloud *c = NULL;
    int st = pst_run_scene(&s, &o, NULL, NULL, &c, err, sizeof err);
    CHECK_INT(st, PST_OK);
    pst_cloud *fresh = test_lattice(2, 0, 1, 0.1, 1.3, 0.2, 5, 1);
    if (st == PST_OK && c) {
        size_t n = pst_cloud_size(c), kinds_differ = 0, normals_differ = 0;
        CHECK_INT(n, pst_cloud_size(fresh));
        const int64_t *ids = pst_cloud_ids_const(c);
        for (size_t i = 0; i < n && n == pst_cloud_size(fresh); ++i) {
            size_t j = (size_t)ids[i];
            kinds_differ += pst_cloud_kinds_const(c)[i] != pst_cloud_kinds_const(fresh)[j];
            for (int d = 0; d < 2; ++d)
                normals_differ += memcmp(&pst_cloud_normal_const(c, d)[i],
                                         &pst_cloud_normal_const(fresh, d)[j], sizeof(double)) != 0;
        }
        CHECK_INT(kinds_differ, 0);
        CHECK_INT(normals_differ, 0);
        size_t neumann = 0;
        for (size_t i = 0; i < n; ++i)
            neumann += pst_cloud_kinds_const(c)[i] == PST_NEUMANN;
        CHECK_INT(neumann, 0); /* the generator makes none: the groups' stayed in the solve */
        /* the groups reached the solve: u is linear, which every LV row reproduces */
        const double *u = pst_cloud_field_by_name(c, "u");
        CHECK(u != NULL);
        double worst = 0;
        for (size_t i = 0; u && i < n; ++i) {
            double ex = pst_cloud_coord_const(c, 0)[i] + 2 * pst_cloud_coord_const(c, 1)[i];
            worst = fmax(worst, fabs(u[i] - ex));
        }
        CHECK(worst < 1e-6);
    }
    pst_cloud_destroy(fresh);
    pst_cloud_destroy(c);
    pst_scene_free(&s);
}

int main(void)
{
    test_override_equals_cloud(2);
    test_override_equals_cloud(3);
    test_bad_override();
    test_run_keeps_cloud();
    return check_summary("test_boundary");
}
