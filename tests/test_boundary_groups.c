/* Boundary groups on a curved, file-given geometry (docs/boundaries.md): a ball whose surface
 * particles carry their own outward normals. A Neumann group keeps those normals (the solve
 * of a quadratic is exact), face normals make it wrong, estimated ones land in between; each
 * group's count and normal sources are reported; regions select by half-space, ball, box and
 * expression, also cloud-interior particles of a CSV without kinds; the solve's kinds and
 * normals reach the outputs; the normal estimate is measured on the sphere. */
#include "check.h"
#include "run.h"
#include "support.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { BALL_LATTICE = 21 }; /* interior lattice points per axis over [-1, 1] */
static const double pi = 3.14159265358979323846;

/* The ball of radius 1: a jittered lattice inside r < 1 - s/2 and a Fibonacci sphere of
 * surface particles with their outward normals (kind neumann), written as CSV. Returns the
 * count of surface particles with z <= 0 in *lower. */
static int write_ball(const char *path, size_t *lower, size_t *surface)
{
    FILE *f = fopen(path, "w");
    if (!f)
        return -1;
    double s = 2.0 / (BALL_LATTICE - 1);
    fprintf(f, "x,y,z,V,h,kind,nx,ny,nz\n");
    test_rng_seed(17);
    for (int i = 0; i < BALL_LATTICE; ++i)
        for (int j = 0; j < BALL_LATTICE; ++j)
            for (int k = 0; k < BALL_LATTICE; ++k) {
                double x[3] = {-1 + i * s, -1 + j * s, -1 + k * s};
                for (int d = 0; d < 3; ++d)
                    x[d] += 0.2 * s * (2 * test_rnd() - 1);
                if (sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]) < 1 - 0.5 * s)
                    fprintf(f, "%.17g,%.17g,%.17g,%.17g,%.17g,interior,0,0,0\n", x[0], x[1],
                            x[2], s * s * s, 1.3 * s);
            }
    size_t m = (size_t)(4 * pi / (s * s));
    *lower = 0;
    *surface = m;
    for (size_t q = 0; q < m; ++q) {
        double z = 1 - (2.0 * (double)q + 1) / (double)m, rho = sqrt(1 - z * z);
        double phi = (double)q * pi * (3 - sqrt(5.0));
        double x = rho * cos(phi), y = rho * sin(phi);
        *lower += z <= 0;
        fprintf(f, "%.17g,%.17g,%.17g,%.17g,%.17g,neumann,%.17g,%.17g,%.17g\n", x, y, z,
                s * s * s, 1.3 * s, x, y, z);
    }
    return fclose(f) == 0 ? 0 : -1;
}

static const char *const ball_scene =
    "{ \"dim\": 3, \"cloud\": { \"source\": \"file\", \"file\": \"ball.csv\" },\n"
    "  \"operator\": { \"scheme\": \"qsfdi\" },\n"
    "  \"tasks\": [ { \"type\": \"solve\", \"name\": \"u\", \"rhs\": \"6\",\n"
    "      \"exact\": \"x^2 + y^2 + z^2\", \"rtol\": 1e-10, %s\n"
    "      \"boundary\": [\n"
    "        { \"type\": \"dirichlet\", \"value\": \"x^2 + y^2 + z^2\",\n"
    "          \"region\": { \"point\": [0, 0, 0], \"normal\": [0, 0, -1] } },\n"
    "        { \"type\": \"neumann\", \"kind\": \"neumann\", \"normals\": \"%s\",\n"
    "          \"value\": \"2*sqrt(x^2 + y^2 + z^2)\" } ] } ] }";

typedef struct {
    double rel_l2;
    double particles[2], file, face, estimated, degenerate;
    int has_kind, has_normal;
} ball_result;

/* Run the ball scene with the Neumann group's normals from `normals` (and the solver keys
 * `solver`); a solve that does not converge still reports its error. */
static ball_result run_ball(const char *dir, const char *normals, const char *solver)
{
    ball_result res = {NAN, {0, 0}, 0, 0, 0, 0, 0, 0};
    char text[2048], err[1024];
    snprintf(text, sizeof text, ball_scene, solver, normals);
    pst_scene s;
    int st = pst_scene_parse(&s, text, test_path_in(dir, "scene.json"), NULL, 0, err, sizeof err);
    if (st != PST_OK)
        printf("scene: %s\n", err);
    CHECK_INT(st, PST_OK);
    cJSON *rep = NULL;
    pst_run_opts o = {.quiet = 1, .report = &rep};
    pst_cloud *c = NULL;
    st = st == PST_OK ? pst_run_scene(&s, &o, NULL, NULL, &c, err, sizeof err) : st;
    if (st != PST_OK)
        printf("run (normals %s): %s\n", normals, err);
    CHECK(st == PST_OK || (st == PST_ENUMERIC && strcmp(normals, "face") == 0));
    if (c) {
        res.has_kind = pst_cloud_field_by_name(c, "u_kind") != NULL;
        res.has_normal = pst_cloud_field_by_name(c, "u_normal_z") != NULL;
    }
    CHECK(rep != NULL);
    const cJSON *t = cJSON_GetArrayItem(cJSON_GetObjectItem(rep, "tasks"), 0);
    res.rel_l2 = cJSON_GetNumberValue(
        cJSON_GetObjectItem(cJSON_GetObjectItem(t, "norms"), "rel_l2"));
    const cJSON *groups = cJSON_GetObjectItem(t, "boundary_groups");
    CHECK_INT(cJSON_GetArraySize(groups), 2);
    for (int g = 0; g < 2; ++g)
        res.particles[g] = cJSON_GetNumberValue(
            cJSON_GetObjectItem(cJSON_GetArrayItem(groups, g), "particles"));
    const cJSON *nm = cJSON_GetObjectItem(cJSON_GetArrayItem(groups, 1), "normals");
    res.file = cJSON_GetNumberValue(cJSON_GetObjectItem(nm, "file"));
    res.face = cJSON_GetNumberValue(cJSON_GetObjectItem(nm, "face"));
    res.estimated = cJSON_GetNumberValue(cJSON_GetObjectItem(nm, "estimated"));
    res.degenerate = cJSON_GetNumberValue(cJSON_GetObjectItem(nm, "degenerate"));
    cJSON_Delete(rep);
    pst_cloud_destroy(c);
    pst_scene_free(&s);
    return res;
}

static void test_ball(const char *dir)
{
    size_t lower = 0, surface = 0;
    CHECK_INT(write_ball(test_path_in(dir, "ball.csv"), &lower, &surface), 0);
    ball_result file = run_ball(dir, "file", "");
    /* face normals on a sphere make rows BoomerAMG refuses: Jacobi, and a short budget */
    ball_result face = run_ball(dir, "face", "\"precond\": \"jacobi\", \"max_iter\": 300,");
    ball_result est = run_ball(dir, "estimate", "");
    printf("ball: rel_l2 with the file's normals %.3e, face normals %.3e, estimated %.3e\n",
           file.rel_l2, face.rel_l2, est.rel_l2);
    /* the half-space took the lower hemisphere; the Neumann group the rest of the surface */
    CHECK_INT((size_t)file.particles[0], lower);
    CHECK_INT((size_t)file.particles[1], surface - lower);
    CHECK_INT((size_t)file.file, surface - lower);
    CHECK_INT((size_t)face.face, surface - lower);
    CHECK_INT((size_t)est.estimated, surface - lower);
    CHECK_INT((size_t)est.degenerate, 0);
    CHECK(file.rel_l2 < 1e-8);          /* quadratic, exact normals: exact                   */
    CHECK(face.rel_l2 > 1e-2);          /* axis normals on a sphere: the flux is wrong       */
    CHECK(est.rel_l2 < face.rel_l2 / 3); /* the estimate is much closer to the true normal    */
    CHECK(file.has_kind && file.has_normal);
}

/* The normal estimate on the ball's surface: mean and largest angle to the radial normal. */
static void test_estimate_on_sphere(const char *dir)
{
    pst_cloud *c = NULL;
    char err[PST_ERRLEN];
    CHECK_INT(pst_cloud_read_csv(&c, test_path_in(dir, "ball.csv"), err), PST_OK);
    if (!c)
        return;
    pst_nlist *nl = test_nlist(c, pst_kernel_support(PST_KERNEL_QUINTIC));
    size_t n = pst_cloud_size(c), degenerate = 99, m = 0;
    double *nrm[3];
    for (int d = 0; d < 3; ++d)
        nrm[d] = calloc(n, sizeof(double));
    CHECK_INT(pst_normals_estimate(c, nl, PST_KERNEL_QUINTIC, NULL, nrm, &degenerate, err),
              PST_OK);
    CHECK_INT(degenerate, 0);
    double sum = 0, worst = 0;
    for (size_t i = 0; i < n; ++i) {
        if (pst_cloud_kinds_const(c)[i] == PST_INTERIOR)
            continue;
        double dot = 0;
        for (int d = 0; d < 3; ++d)
            dot += nrm[d][i] * pst_cloud_normal_const(c, d)[i];
        double angle = acos(fmin(1, dot)) * 180 / pi;
        sum += angle;
        worst = fmax(worst, angle);
        ++m;
    }
    printf("normal estimate on the sphere: mean angle %.2f deg, largest %.2f deg over %zu\n",
           sum / (double)m, worst, m);
    CHECK(sum / (double)m < 5);
    CHECK(worst < 20);
    /* a half list is refused, with a message */
    pst_nlist *half = NULL;
    CHECK_INT(pst_nlist_halve(&half, nl, err), PST_OK);
    CHECK_INT(pst_normals_estimate(c, half, PST_KERNEL_QUINTIC, NULL, nrm, NULL, err), PST_EINVAL);
    CHECK(strstr(err, "half") != NULL);
    pst_nlist_destroy(half);
    for (int d = 0; d < 3; ++d)
        free(nrm[d]);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
}

/* A CSV without kinds (every particle interior): groups with kind "any" and regions make the
 * boundary. The box's rim by expression, a ball and a box: the solve of a quadratic is exact,
 * the claimed particles are left out of the error region, and kind "boundary" claims none. */
static void test_kindless_csv(const char *dir)
{
    FILE *f = fopen(test_path_in(dir, "square.csv"), "w");
    CHECK(f != NULL);
    if (!f)
        return;
    fprintf(f, "x,y,V,h\n");
    int m = 21, rim = 0;
    for (int i = 0; i < m; ++i)
        for (int j = 0; j < m; ++j) {
            fprintf(f, "%.17g,%.17g,0.0025,0.065\n", i * 0.05, j * 0.05);
            rim += i == 0 || j == 0 || i == m - 1 || j == m - 1;
        }
    fclose(f);
    const char *text =
        "{ \"dim\": 2, \"cloud\": { \"source\": \"file\", \"file\": \"square.csv\" },\n"
        "  \"operator\": { \"scheme\": \"qsfdi\" },\n"
        "  \"tasks\": [ { \"type\": \"solve\", \"name\": \"u\", \"rhs\": \"4\",\n"
        "      \"exact\": \"x^2 + y^2\", \"rtol\": 1e-10,\n"
        "      \"boundary\": [\n"
        "        { \"kind\": \"boundary\", \"value\": \"0\" },\n"
        "        { \"kind\": \"any\", \"value\": \"x^2 + y^2\",\n"
        "          \"region\": { \"center\": [0, 0], \"radius\": 0.01 } },\n"
        "        { \"kind\": \"any\", \"value\": \"x^2 + y^2\",\n"
        "          \"region\": { \"lo\": [0.99, -1], \"hi\": [2, 2] } },\n"
        "        { \"kind\": \"any\", \"value\": \"x^2 + y^2\",\n"
        "          \"region\": { \"expr\": \"0.01 - x*(1 - x)*y*(1 - y)\" } } ] } ] }";
    pst_scene s;
    char err[1024];
    int st = pst_scene_parse(&s, text, test_path_in(dir, "sq.json"), NULL, 0, err, sizeof err);
    if (st != PST_OK)
        printf("scene: %s\n", err);
    CHECK_INT(st, PST_OK);
    pst_run_opts o = {.quiet = 1};
    pst_cloud *c = NULL;
    st = st == PST_OK ? pst_run_scene(&s, &o, NULL, NULL, &c, err, sizeof err) : st;
    if (st != PST_OK)
        printf("run: %s\n", err);
    CHECK_INT(st, PST_OK);
    const double *u = c ? pst_cloud_field_by_name(c, "u") : NULL;
    const double *kind = c ? pst_cloud_field_by_name(c, "u_kind") : NULL;
    CHECK(u && kind);
    size_t n = c ? pst_cloud_size(c) : 0, dirichlet = 0;
    double worst = 0;
    for (size_t i = 0; u && kind && i < n; ++i) {
        double x = pst_cloud_coord_const(c, 0)[i], y = pst_cloud_coord_const(c, 1)[i];
        worst = fmax(worst, fabs(u[i] - (x * x + y * y)));
        dirichlet += kind[i] == PST_DIRICHLET;
        CHECK_INT(pst_cloud_kinds_const(c)[i], PST_INTERIOR); /* the cloud keeps its kinds */
    }
    CHECK(worst < 1e-8);
    CHECK((int)dirichlet >= rim);
    pst_cloud_destroy(c);
    pst_scene_free(&s);
}

/* Scene errors of the new keys, each with its message. */
static void test_group_errors(void)
{
    static const struct {
        const char *group, *message;
    } cases[] = {
        {"{ \"value\": \"0\", \"region\": { \"lo\": [0, 0], \"radius\": 1 } }", "give one region"},
        {"{ \"value\": \"0\", \"region\": { \"center\": [0, 0] } }", "needs both center"},
        {"{ \"value\": \"0\", \"region\": { \"point\": [0, 0], \"normal\": [0, 0] } }",
         "must not be zero"},
        {"{ \"value\": \"0\", \"normals\": \"face\" }", "only a neumann group has normals"},
        {"{ \"value\": \"0\", \"kind\": \"outer\" }", "kind"},
        {"{ \"value\": \"0\", \"region\": { \"expr\": \"x +\" } }", "region.expr"},
        {"{ \"value\": \"0\", \"region\": { \"lo\": [0, 0], \"hi\": [1, 0] } }", "must exceed"},
    };
    for (size_t q = 0; q < sizeof cases / sizeof cases[0]; ++q) {
        char text[1024], err[1024];
        snprintf(text, sizeof text,
                 "{ \"dim\": 2, \"cloud\": { \"source\": \"lattice\", \"spacing\": 0.1 },\n"
                 "  \"tasks\": [ { \"type\": \"solve\", \"rhs\": \"0\", \"exact\": \"0\",\n"
                 "      \"boundary\": [ %s ] } ] }",
                 cases[q].group);
        pst_scene s;
        int st = pst_scene_parse(&s, text, "bad.json", NULL, 0, err, sizeof err);
        if (st == PST_OK) { /* expressions are compiled when the run is planned */
            st = pst_scene_compile_exprs(&s, err, sizeof err);
            pst_scene_free(&s);
        }
        CHECK(st != PST_OK);
        if (!strstr(err, cases[q].message))
            printf("case %zu: '%s' lacks '%s'\n", q, err, cases[q].message);
        CHECK(strstr(err, cases[q].message) != NULL);
    }
}

int main(void)
{
    test_mpi_init(); /* the solves' default preconditioner is AMG, which needs MPI */
    char dir[256];
    if (test_scratch_dir(dir, sizeof dir, "pst_groups") != 0)
        return 1;
    test_ball(dir);
    test_estimate_on_sphere(dir);
    test_kindless_csv(dir);
    test_group_errors();
    test_remove_dir(dir);
    return check_summary("test_boundary_groups");
}
