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

/* A boundary description: kinds and normals in cloud order. */
typedef struct {
    size_t n;
    int dim;
    uint8_t *kind;
    double *normal[3];
} boundary;

/* A copy of the cloud's own boundary. */
static boundary boundary_of(const pst_cloud *c)
{
    boundary b = {pst_cloud_size(c), pst_cloud_dim(c), malloc(pst_cloud_size(c)), {NULL}};
    memcpy(b.kind, pst_cloud_kinds_const(c), b.n);
    for (int d = 0; d < b.dim; ++d) {
        b.normal[d] = malloc(b.n * sizeof(double));
        memcpy(b.normal[d], pst_cloud_normal_const(c, d), b.n * sizeof(double));
    }
    return b;
}

static void boundary_free(boundary *b)
{
    free(b->kind);
    for (int d = 0; d < 3; ++d)
        free(b->normal[d]);
}

/* The cloud's kinds and normals are those of b, bit for bit. */
static int boundary_is(const pst_cloud *c, const boundary *b)
{
    int same = memcmp(pst_cloud_kinds_const(c), b->kind, b->n) == 0;
    for (int d = 0; d < b->dim; ++d)
        same = same && memcmp(pst_cloud_normal_const(c, d), b->normal[d],
                              b->n * sizeof(double)) == 0;
    return same;
}

/* Change b to a boundary unlike the cloud's: every third Dirichlet particle becomes Neumann
 * with a tilted unit normal, every fifth interior particle Dirichlet. */
static void tilt(boundary *b)
{
    static const double tilted[2][3] = {{0.8, 0.6, 0.0}, {0.48, 0.6, 0.64}};
    for (size_t i = 0; i < b->n; ++i) {
        if (b->kind[i] == PST_DIRICHLET && i % 3 == 0) {
            b->kind[i] = PST_NEUMANN;
            for (int d = 0; d < b->dim; ++d)
                b->normal[d][i] = tilted[b->dim - 2][d];
        } else if (b->kind[i] == PST_INTERIOR && i % 5 == 0) {
            b->kind[i] = PST_DIRICHLET;
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

/* A lattice and its neighbour list. */
typedef struct {
    pst_cloud *c;
    pst_nlist *nl;
} fixture;

static fixture lattice(int dim, double s0, double jitter, uint64_t seed)
{
    fixture f = {test_lattice(dim, 0, 1, s0, 1.3, jitter, seed, 1), NULL};
    f.nl = test_nlist(f.c, 2.0);
    return f;
}

static void fixture_free(fixture *f)
{
    pst_nlist_destroy(f->nl);
    pst_cloud_destroy(f->c);
}

static double wave(const double *x) { return sin(3 * x[0] + 2 * x[1]) + x[2] * x[2]; }

/* Every scheme, in 2D and 3D: the operator with the override on cloud a equals the operator on
 * cloud b (the same lattice) whose kinds and normals were set to the override; a unchanged. */
static void test_override_equals_cloud(int dim)
{
    double s0 = dim == 2 ? 0.1 : 0.25;
    fixture a = lattice(dim, s0, 0.2, 7), b = lattice(dim, s0, 0.2, 7);
    size_t n = pst_cloud_size(a.c);
    boundary before = boundary_of(a.c), over = boundary_of(a.c);
    tilt(&over);
    memcpy(pst_cloud_kinds(b.c), over.kind, n);
    for (int d = 0; d < dim; ++d)
        memcpy(pst_cloud_normal(b.c, d), over.normal[d], n * sizeof(double));
    double *u = test_field(a.c, wave);
    for (int k = 0; k < pst_scheme_count(); ++k) {
        pst_op_opts o;
        pst_op_defaults(&o);
        o.scheme = pst_scheme_name(k);
        pst_op *opb = NULL, *opa = NULL;
        char err[PST_ERRLEN];
        int stb = pst_op_create(&opb, b.c, b.nl, &o, err);
        o.kinds = over.kind;
        for (int d = 0; d < dim; ++d)
            o.normals[d] = over.normal[d];
        int sta = pst_op_create(&opa, a.c, a.nl, &o, err);
        CHECK_INT(sta, stb);
        if (sta == PST_OK && stb == PST_OK)
            check_same_operator(opa, opb, n, u);
        pst_op_destroy(opa);
        pst_op_destroy(opb);
    }
    CHECK(boundary_is(a.c, &before));
    CHECK(!boundary_is(a.c, &over)); /* the override did differ from the cloud */
    free(u);
    boundary_free(&before);
    boundary_free(&over);
    fixture_free(&a);
    fixture_free(&b);
}

/* An unknown kind and a non-finite Neumann normal: PST_EINVAL naming the particle. */
static void test_bad_override(void)
{
    fixture f = lattice(2, 0.1, 0.0, 1);
    size_t n = pst_cloud_size(f.c);
    boundary over = boundary_of(f.c);
    tilt(&over);
    pst_op_opts o;
    pst_op_defaults(&o);
    o.kinds = over.kind;
    o.normals[0] = over.normal[0];
    o.normals[1] = over.normal[1];
    pst_op *op = NULL;
    char err[PST_ERRLEN] = "";
    over.kind[4] = 7;
    CHECK_INT(pst_op_create(&op, f.c, f.nl, &o, err), PST_EINVAL);
    CHECK(op == NULL);
    CHECK(strstr(err, "particle 4 has unknown kind 7") != NULL);
    over.kind[4] = PST_INTERIOR;
    size_t neu = 0;
    while (neu < n && over.kind[neu] != PST_NEUMANN)
        ++neu;
    CHECK(neu < n);
    over.normal[1][neu] = NAN;
    err[0] = '\0';
    CHECK_INT(pst_op_create(&op, f.c, f.nl, &o, err), PST_EINVAL);
    CHECK(strstr(err, "non-finite normal") != NULL);
    char want[64];
    snprintf(want, sizeof want, "particle %zu ", neu);
    CHECK(strstr(err, want) != NULL);
    boundary_free(&over);
    fixture_free(&f);
}

static const char *const grouped_scene =
    "{ \"dim\": 2,\n"
    "  \"cloud\": { \"source\": \"lattice\", \"lo\": [0, 0], \"hi\": [1, 1], \"spacing\": 0.1,\n"
    "             \"jitter\": 0.2, \"seed\": 5, \"boundary_layer\": true, \"h_ratio\": 1.3 },\n"
    "  \"operator\": { \"scheme\": \"lv\" },\n"
    "  \"tasks\": [ { \"type\": \"solve\", \"name\": \"u\", \"rhs\": \"0\",\n"
    "      \"exact\": \"x + 2*y\", \"norms\": [\"max_abs\"],\n"
    "      \"boundary\": [ { \"where\": \"xhi\", \"type\": \"neumann\", \"normals\": \"face\",\n"
    "                        \"value\": \"1\" },\n"
    "                      { \"where\": \"ylo\", \"type\": \"neumann\", \"normals\": \"face\",\n"
    "                        \"value\": \"-2\" },\n"
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
    test_mpi_init(); /* the solves' default preconditioner is AMG, which needs MPI */
    test_override_equals_cloud(2);
    test_override_equals_cloud(3);
    test_bad_override();
    test_run_keeps_cloud();
    return check_summary("test_boundary");
}
