/* The planner and the scene runner: a run computes what its scene asks for and nothing more
 * (the counters), the answers do not change when unneeded work is skipped, the plan's
 * decisions (stored weights, solver, mobility factor, derivatives-only operator), a run that
 * cannot fit is refused before allocating, bad expressions are clear errors, periodic
 * clouds fix the mean of a solve without Dirichlet particles, and a plan over several ranks is
 * one rank's. */
#include "check.h"
#include "plan.h"
#include "run.h"
#include "support.h"

#include <cjson/cJSON.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const char *const base_scene =
    "{ \"dim\": 2,\n"
    "  \"cloud\": { \"source\": \"lattice\", \"lo\": [0, 0], \"hi\": [1, 1], \"spacing\": 0.05,\n"
    "             \"jitter\": 0.3, \"seed\": 3, \"boundary_layer\": true, \"h_ratio\": 1.2 },\n"
    "  \"operator\": { \"scheme\": \"qsfdi\" },\n"
    "  \"fields\": { \"u\": \"sin(6*x + 8*y)\" },\n"
    "  \"tasks\": [] }";

/* Parse the base scene with overrides; exits the test on a parse failure. */
static pst_scene scene(const char *const *ov, int nov)
{
    pst_scene s;
    char err[1024];
    int st = pst_scene_parse(&s, base_scene, "test.json", ov, nov, err, sizeof err);
    if (st != PST_OK) {
        printf("scene: %s\n", err);
        exit(1);
    }
    return s;
}

static pst_cloud *run(const pst_scene *s, pst_run_counters *cnt, pst_plan *plan, int expect)
{
    pst_run_opts o = {.quiet = 1};
    pst_cloud *c = NULL;
    char err[1024];
    int st = pst_run_scene(s, &o, plan, cnt, &c, err, sizeof err);
    if (st != expect)
        printf("run: status %d (%s)\n", st, err);
    CHECK_INT(st, expect);
    return c;
}

/* Field `name` of c in input order (the runner sorts the cloud). */
static double *field(pst_cloud *c, const char *name)
{
    const double *f = pst_cloud_field_by_name(c, name);
    CHECK(f != NULL);
    if (!f)
        exit(1);
    double *out = malloc(pst_cloud_size(c) * sizeof *out);
    pst_cloud_to_input_order(c, f, out);
    return out;
}

static double max_diff(const double *a, const double *b, size_t n)
{
    double d = 0;
    for (size_t i = 0; i < n; ++i)
        d = fmax(d, fabs(a[i] - b[i]));
    return d;
}

/* A gradient-only scene builds no Laplacian rows (qsfdi's derivatives do not need them), does
 * no apply, no Hessian, no solve; adding a Laplacian task changes nothing in the gradient. */
static void test_only_what_is_asked(void)
{
    const char *grad_only[] = {"tasks=[{\"type\":\"gradient\",\"field\":\"u\","
                               "\"exact\":[\"6*cos(6*x+8*y)\",\"8*cos(6*x+8*y)\"]}]"};
    pst_scene s = scene(grad_only, 1);
    pst_run_counters k;
    pst_plan p;
    pst_cloud *c1 = run(&s, &k, &p, PST_OK);
    CHECK_INT(p.base_operator, 1);
    CHECK_INT(p.base_laplacian, 0);
    CHECK_INT(k.laplacian_precomputes, 0);
    CHECK_INT(k.derivative_operators, 1);
    CHECK_INT(k.gradients, 1);
    CHECK_INT(k.applies + k.hessians + k.interpolations + k.solves + k.stored_weights, 0);
    CHECK_INT(k.mobility_arrays, 0);
    CHECK_INT(k.fields, 1);
    CHECK_INT(k.norms, 2); /* the default norms: rel_l2, max_abs */
    pst_scene_free(&s);

    const char *both[] = {"tasks=[{\"type\":\"gradient\",\"field\":\"u\"},"
                          "{\"type\":\"laplacian\",\"field\":\"u\"}]"};
    s = scene(both, 1);
    pst_cloud *c2 = run(&s, &k, &p, PST_OK);
    CHECK_INT(p.base_laplacian, 1);
    CHECK_INT(k.laplacian_precomputes, 1);
    CHECK_INT(k.derivative_operators, 0);
    CHECK_INT(k.applies, 1);
    CHECK_INT(k.norms, 0); /* no exact solution given: no norms */
    size_t n = pst_cloud_size(c1);
    for (int a = 0; a < 2; ++a) {
        const char *name = a ? "gradient_y" : "gradient_x";
        double *g1 = field(c1, name), *g2 = field(c2, name);
        double d = max_diff(g1, g2, n);
        printf("gradient %s: skipped rows vs full operator differ by %.1e\n", name, d);
        CHECK(d == 0); /* same code on the same data: bit for bit */
        free(g1);
        free(g2);
    }
    pst_cloud_destroy(c1);
    pst_cloud_destroy(c2);
    pst_scene_free(&s);
}

/* A constant mobility is a factor: no per-particle array, and the result is c times the
 * Laplacian (to rounding). A mobility expression fills an array. */
static void test_mobility_factor(void)
{
    const char *lap[] = {"tasks=[{\"type\":\"laplacian\",\"field\":\"u\"}]",
                         "operator.scheme=lv"};
    const char *div[] = {"tasks=[{\"type\":\"divergence\",\"field\":\"u\"}]",
                         "operator.scheme=lv", "mobility.type=constant", "mobility.value=2.5"};
    const char *expr[] = {"tasks=[{\"type\":\"divergence\",\"field\":\"u\"}]",
                          "operator.scheme=lv", "mobility.type=expression",
                          "mobility.expression=2.5 + 0*x"};
    const struct {
        const char *const *ov;
        int nov, arrays;
        const char *field;
    } runs[3] = {{lap, 2, 0, "laplacian"}, {div, 4, 0, "divergence"}, {expr, 4, 1, "divergence"}};
    pst_cloud *c[3];
    double *l[3];
    for (int r = 0; r < 3; ++r) {
        pst_scene s = scene(runs[r].ov, runs[r].nov);
        pst_run_counters k;
        pst_plan p;
        c[r] = run(&s, &k, &p, PST_OK);
        CHECK_INT(k.mobility_arrays, runs[r].arrays);
        CHECK(p.mobility_factor == (r == 1 ? 2.5 : 1.0));
        pst_scene_free(&s);
        l[r] = field(c[r], runs[r].field);
    }
    size_t n = pst_cloud_size(c[0]);
    double scale = 0;
    for (size_t i = 0; i < n; ++i) {
        l[0][i] *= 2.5;
        scale = fmax(scale, fabs(l[0][i]));
    }
    double d12 = max_diff(l[0], l[1], n) / scale, d13 = max_diff(l[0], l[2], n) / scale;
    printf("constant mobility: factor vs 2.5 L %.1e, per-particle array vs 2.5 L %.1e\n", d12,
           d13);
    CHECK(d12 <= 1e-15);
    CHECK(d13 <= 1e-13);
    for (int r = 0; r < 3; ++r) {
        free(l[r]);
        pst_cloud_destroy(c[r]);
    }
}

/* Solves: the plan stores the weights (many applies), picks CG for cb and GMRES for qsfdi,
 * and the solution matches the exact one to the scheme's accuracy. */
static void test_solve_plan(void)
{
    const char *solve[] = {
        "tasks=[{\"type\":\"solve\",\"rhs\":\"-100*sin(6*x+8*y)\",\"exact\":\"sin(6*x+8*y)\","
        "\"rtol\":1e-10}]"};
    pst_scene s = scene(solve, 1);
    pst_run_counters k;
    pst_plan p;
    pst_cloud *c = run(&s, &k, &p, PST_OK);
    CHECK_INT(p.task_stored[0], 1);
    CHECK_INT(p.task_solver[0], PST_SOLVER_GMRES);
    CHECK_INT(p.task_precond[0], pst_have_amg() ? PST_PREC_AMG : PST_PREC_JACOBI); /* auto */
    CHECK_INT(k.solves, 1);
    CHECK_INT(k.stored_weights, 1);
    CHECK_INT(k.applies, 0);
    double *u_double = field(c, "solve");
    size_t n = pst_cloud_size(c);
    pst_cloud_destroy(c);
    pst_scene_free(&s);

    /* Asked for in float: stored so, counted, reported; the answer moves by the weights'
     * rounding (2^-24 relative: about 1e-8 of u here), not by nothing and not by the
     * scheme's error (about 1e-3 at this spacing). */
    const char *flt[] = {solve[0], "tasks.0.operator=stored_float"};
    s = scene(flt, 2);
    cJSON *rep = NULL;
    pst_run_opts ro = {.quiet = 1, .report = &rep};
    char err[1024];
    CHECK_INT(pst_run_scene(&s, &ro, &p, &k, &c, err, sizeof err), PST_OK);
    CHECK_INT(p.task_stored[0], SC_OPERATOR_STORED_FLOAT);
    CHECK_INT(k.stored_weights, 1);
    const cJSON *sv = cJSON_GetObjectItem(
        cJSON_GetArrayItem(cJSON_GetObjectItem(rep, "tasks"), 0), "solver");
    const char *use = cJSON_GetStringValue(cJSON_GetObjectItem(sv, "operator"));
    CHECK(use && strcmp(use, "stored_float") == 0);
    double *u_float = field(c, "solve"), moved = max_diff(u_double, u_float, n);
    printf("solve on the float weights: max |u_float - u_double| = %.2e\n", moved);
    CHECK(moved > 0 && moved < 1e-6);
    cJSON_Delete(rep);
    pst_cloud_destroy(c);
    pst_scene_free(&s);

    /* Two solves on the one base operator, double then float: the second stores again in
     * float, and each gets its own store's answer (to well below the ~2e-8 between the two
     * stores' answers, whatever the preconditioner's rounding). */
    const char *two[] = {
        "tasks=[{\"type\":\"solve\",\"name\":\"d\",\"rhs\":\"-100*sin(6*x+8*y)\","
        "\"exact\":\"sin(6*x+8*y)\",\"rtol\":1e-10,\"operator\":\"stored\"},"
        "{\"type\":\"solve\",\"name\":\"f\",\"rhs\":\"-100*sin(6*x+8*y)\","
        "\"exact\":\"sin(6*x+8*y)\",\"rtol\":1e-10,\"operator\":\"stored_float\"}]"};
    s = scene(two, 1);
    c = run(&s, &k, &p, PST_OK);
    CHECK_INT(k.stored_weights, 2);
    double *ud = field(c, "d"), *uf = field(c, "f");
    CHECK(max_diff(ud, u_double, n) < 2e-9 && max_diff(uf, u_float, n) < 2e-9);
    CHECK(max_diff(ud, uf, n) > 5e-9);
    free(ud);
    free(uf);
    free(u_double);
    free(u_float);
    pst_cloud_destroy(c);
    pst_scene_free(&s);

    const char *jac[] = {solve[0], "tasks.0.precond=jacobi"};
    s = scene(jac, 2);
    c = run(&s, &k, &p, PST_OK);
    CHECK_INT(p.task_precond[0], PST_PREC_JACOBI); /* asked for: kept */
    pst_cloud_destroy(c);
    pst_scene_free(&s);

    const char *cb[] = {solve[0], "operator.scheme=cb", "tasks.0.operator=matrix_free"};
    s = scene(cb, 3);
    c = run(&s, &k, &p, PST_OK);
    CHECK_INT(p.task_solver[0], PST_SOLVER_CG);
    CHECK_INT(p.task_stored[0], 0);
    CHECK_INT(p.task_precond[0], pst_have_amg() ? PST_PREC_AMG : PST_PREC_JACOBI);
    CHECK_INT(k.stored_weights, 0);
    pst_cloud_destroy(c);
    pst_scene_free(&s);

    /* A Neumann group makes cb non-symmetrisable: the plan switches to GMRES. */
    const char *neu[] = {"tasks=[{\"type\":\"solve\",\"rhs\":\"0\",\"exact\":\"1 + x\","
                         "\"boundary\":[{\"where\":\"xhi\",\"type\":\"neumann\",\"normals\":\"face\","
                         "\"value\":\"1\"},"
                         "{\"where\":\"all\",\"type\":\"dirichlet\",\"value\":\"1 + x\"}]}]",
                         "operator.scheme=lv"};
    s = scene(neu, 2);
    c = run(&s, &k, &p, PST_OK);
    CHECK_INT(p.task_solver[0], PST_SOLVER_GMRES);
    double *u = field(c, "solve");
    n = pst_cloud_size(c);
    double *xi = malloc(n * sizeof *xi), worst = 0;
    pst_cloud_to_input_order(c, pst_cloud_coord_const(c, 0), xi);
    for (size_t i = 0; i < n; ++i)
        worst = fmax(worst, fabs(u[i] - (1 + xi[i])));
    printf("lv, linear solution with a Neumann side: max error %.1e\n", worst);
    CHECK(worst <= 1e-8); /* lv is exact for linear fields, Neumann rows included */
    free(u);
    free(xi);
    pst_cloud_destroy(c);
    pst_scene_free(&s);
}

/* Task 0's report object of a run of s, which must succeed (NULL otherwise); *rep is the whole
 * report, for cJSON_Delete. */
static const cJSON *run_report(const pst_scene *s, cJSON **rep, pst_cloud **c)
{
    pst_run_opts o = {.quiet = 1, .report = rep};
    char err[1024];
    int st = pst_run_scene(s, &o, NULL, NULL, c, err, sizeof err);
    if (st != PST_OK)
        printf("run: status %d (%s)\n", st, err);
    CHECK_INT(st, PST_OK);
    return st == PST_OK ? cJSON_GetArrayItem(cJSON_GetObjectItem(*rep, "tasks"), 0) : NULL;
}

static double number(const cJSON *o, const char *a, const char *b)
{
    const cJSON *v = cJSON_GetObjectItem(o, a);
    if (b)
        v = cJSON_GetObjectItem(v, b);
    return cJSON_IsNumber(v) ? v->valuedouble : NAN;
}

/* Periodic clouds (cloud.periodic): the plan counts the particles the generators make; a solve
 * without Dirichlet particles fixes the mean of u by itself (GMRES, also where auto would take
 * CG), reports lambda and compares with the exact solution moved to u's mean; cg is refused
 * there; a partly periodic box keeps its Dirichlet sides and solves as before. */
static void test_periodic(void)
{
    static const struct {
        const char *source, *periodic;
        size_t n;
    } sizes[] = {{"lattice", "[true, false]", 20 * 21},
                 {"lattice", "true", 20 * 20},
                 {"cell_centred", "[false, true]", 400 + 2 * 20},
                 {"cell_centred", "true", 400}};
    for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; ++k) {
        char text[256], why[1024];
        snprintf(text, sizeof text, "{\"cloud\": {\"source\": \"%s\", \"spacing\": 0.05, "
                 "\"periodic\": %s}}", sizes[k].source, sizes[k].periodic);
        pst_scene s;
        CHECK_INT(pst_scene_parse(&s, text, "test.json", NULL, 0, why, sizeof why), PST_OK);
        pst_run_counters cnt;
        pst_plan p;
        pst_cloud *c = run(&s, &cnt, &p, PST_OK);
        CHECK(pst_plan_particles(&s) == sizes[k].n);
        CHECK(c && pst_cloud_size(c) == sizes[k].n);
        CHECK_INT(c ? pst_cloud_periodic(c, NULL, NULL, NULL) : -1, 1 + (int)(k % 2));
        pst_cloud_destroy(c);
        pst_scene_free(&s);
    }

    const char *solve[] = {
        "cloud.periodic=true",
        "tasks=[{\"type\":\"solve\",\"rhs\":\"-8*pi^2*sin(2*pi*x)*cos(2*pi*y)\","
        "\"exact\":\"3 + sin(2*pi*x)*cos(2*pi*y)\",\"precond\":\"jacobi\"}]"};
    pst_scene s = scene(solve, 2);
    cJSON *rep = NULL;
    pst_cloud *c = NULL;
    const cJSON *t = run_report(&s, &rep, &c);
    const cJSON *sv = cJSON_GetObjectItem(t, "solver");
    CHECK(cJSON_IsTrue(cJSON_GetObjectItem(sv, "fix_mean")));
    CHECK(strcmp(cJSON_GetStringValue(cJSON_GetObjectItem(sv, "method")), "gmres") == 0);
    double lambda = number(sv, "mean_shift", NULL), shift = number(t, "exact_shift", NULL);
    double rel = number(t, "norms", "rel_l2");
    printf("periodic Poisson in a scene: lambda %.3g, exact shift %.6g, rel_l2 %.3g\n", lambda,
           shift, rel);
    CHECK(fabs(lambda) < 0.5);        /* compatible up to the truncation error */
    CHECK(fabs(shift + 3) < 1e-2);    /* u has mean 0, the exact solution 3 */
    CHECK(rel < 0.05);                /* against the unshifted exact it would be about 1 */
    if (c) { /* u's V-weighted mean is 0, and NAME_error is u - the shifted exact */
        size_t n = pst_cloud_size(c);
        const double *u = pst_cloud_field_by_name(c, "solve");
        const double *e = pst_cloud_field_by_name(c, "solve_error");
        const double *V = pst_cloud_volume_const(c);
        double mu = 0, me = 0, vol = 0;
        for (size_t i = 0; i < n; ++i) {
            mu += V[i] * u[i];
            me += V[i] * e[i];
            vol += V[i];
        }
        CHECK(fabs(mu / vol) < 1e-10);
        CHECK(fabs(me / vol) < 1e-12);
    }
    cJSON_Delete(rep);
    pst_cloud_destroy(c);
    pst_scene_free(&s);

    /* cb's auto solver is CG; a fully periodic box takes GMRES, and cg is refused */
    const char *cb[] = {solve[0], solve[1], "operator.scheme=cb"};
    s = scene(cb, 3);
    pst_run_counters cnt;
    pst_plan p;
    c = run(&s, &cnt, &p, PST_OK);
    CHECK_INT(p.task_solver[0], PST_SOLVER_GMRES);
    pst_cloud_destroy(c);
    pst_scene_free(&s);
    const char *cg[] = {solve[0], solve[1], "operator.scheme=cb", "tasks.0.solver=cg"};
    s = scene(cg, 4);
    char err[1024];
    pst_run_opts o = {.quiet = 1};
    CHECK_INT(pst_run_scene(&s, &o, NULL, NULL, NULL, err, sizeof err), PST_EINPUT);
    CHECK(strstr(err, "the mean of u is fixed, which CG cannot do") != NULL);
    pst_scene_free(&s);

    /* periodic along x only: the y sides stay Dirichlet, nothing is shifted */
    const char *part[] = {
        "cloud.periodic=[true,false]",
        "tasks=[{\"type\":\"solve\",\"rhs\":\"-4*pi^2*sin(2*pi*x)*(1 + y)\","
        "\"exact\":\"sin(2*pi*x)*(1 + y)\",\"precond\":\"jacobi\"}]"};
    s = scene(part, 2);
    c = NULL;
    t = run_report(&s, &rep, &c);
    sv = cJSON_GetObjectItem(t, "solver");
    CHECK(cJSON_IsFalse(cJSON_GetObjectItem(sv, "fix_mean")));
    CHECK(!cJSON_GetObjectItem(sv, "mean_shift") && !cJSON_GetObjectItem(t, "exact_shift"));
    CHECK(number(t, "norms", "rel_l2") < 0.05);
    cJSON_Delete(rep);
    pst_cloud_destroy(c);
    pst_scene_free(&s);
}

/* Refusals: a plan that does not fit is refused before the cloud exists; a scheme without a
 * Hessian, CG on qsfdi, a Laplacian task with a mobility, a bad expression. */
static void test_refusals(void)
{
    pst_run_opts o = {.quiet = 1};
    char err[1024];
    pst_cloud *c = NULL;
    const char *huge[] = {"tasks=[{\"type\":\"laplacian\",\"field\":\"u\"}]",
                          "cloud.spacing=0.00002"};
    pst_scene s = scene(huge, 2);
    CHECK_INT(pst_run_scene(&s, &o, NULL, NULL, &c, err, sizeof err), PST_ENOMEM);
    CHECK(strstr(err, "GB") && strstr(err, "available"));
    CHECK(c == NULL);
    printf("refused: %s\n", err);
    pst_scene_free(&s);

    const struct {
        const char *ov[3];
        int n, status;
        const char *words;
    } bad[] = {
        {{"tasks=[{\"type\":\"hessian\",\"field\":\"u\"}]", "operator.scheme=lv"}, 2,
         PST_EINPUT, "has no Hessian"},
        {{"tasks=[{\"type\":\"solve\",\"rhs\":\"1\",\"exact\":\"0\",\"solver\":\"cg\"}]"}, 1,
         PST_EINPUT, "CG needs"},
        {{"tasks=[{\"type\":\"laplacian\",\"field\":\"u\"}]", "mobility.type=constant",
          "mobility.value=2"}, 3, PST_EINPUT, "use type 'divergence'"},
        {{"tasks=[{\"type\":\"divergence\",\"field\":\"u\"}]", "mobility.type=expression",
          "mobility.expression=1+x"}, 3, PST_EINPUT, "plain Laplacian only"},
        {{"tasks=[{\"type\":\"laplacian\",\"field\":\"u\",\"exact\":\"sinn(x)\"}]"}, 1,
         PST_EINPUT, "unknown function 'sinn'"},
        {{"fields.v=log(x - 2)", "tasks=[{\"type\":\"laplacian\",\"field\":\"v\"}]"}, 2,
         PST_EINPUT, "not finite"},
        {{"tasks=[{\"type\":\"laplacian\",\"field\":\"u\",\"exact\":\"0\","
          "\"norms\":[\"lv95\"]}]"}, 1, PST_ENUMERIC, "relative to the exact value"},
    };
    for (size_t q = 0; q < sizeof bad / sizeof bad[0]; ++q) {
        s = scene(bad[q].ov, bad[q].n);
        int st = pst_run_scene(&s, &o, NULL, NULL, &c, err, sizeof err);
        printf("refused (%d): %s\n", st, err);
        CHECK_INT(st, bad[q].status);
        CHECK(strstr(err, bad[q].words) != NULL);
        CHECK(c == NULL);
        pst_scene_free(&s);
    }
}

/* The degeneracy thresholds and the fallback chain are named parameters: a scene sets them,
 * the report carries them, bad values are refused, and min_pair_distance decides whether a
 * near-duplicate pair contributes. */
static void test_parameters(void)
{
    const char *ov[] = {"operator.min_pair_distance=1e-6", "operator.cond_max=1e8",
                        "tasks=[{\"type\":\"laplacian\",\"field\":\"u\"}]"};
    pst_scene s = scene(ov, 3);
    cJSON *rep = NULL;
    pst_run_opts o = {.quiet = 1, .report = &rep};
    char err[1024];
    pst_cloud *c = NULL;
    CHECK_INT(pst_run_scene(&s, &o, NULL, NULL, &c, err, sizeof err), PST_OK);
    const cJSON *p = cJSON_GetObjectItem(
        cJSON_GetArrayItem(cJSON_GetObjectItem(rep, "operators"), 0), "parameters");
    CHECK_NEAR(cJSON_GetNumberValue(cJSON_GetObjectItem(p, "min_pair_distance")), 1e-6, 0);
    CHECK_NEAR(cJSON_GetNumberValue(cJSON_GetObjectItem(p, "cond_max")), 1e8, 0);
    CHECK_NEAR(cJSON_GetNumberValue(cJSON_GetObjectItem(p, "rank_tol")), 1e-13, 0);
    const char *fb = cJSON_GetStringValue(cJSON_GetObjectItem(p, "fallback"));
    CHECK(fb && strcmp(fb, pst_scheme_fallback("qsfdi")) == 0);
    CHECK(strcmp(cJSON_GetStringValue(cJSON_GetObjectItem(p, "regularisation")), "none") == 0);
    cJSON_Delete(rep);
    pst_cloud_destroy(c);
    pst_scene_free(&s);

    const char *bad[] = {"operator.min_pair_distance=0.7"};
    pst_scene t;
    CHECK_INT(pst_scene_parse(&t, base_scene, "test.json", bad, 1, err, sizeof err), PST_EINPUT);
    CHECK(strstr(err, "operator.min_pair_distance") != NULL);

    /* every scheme: a pair at 1e-7 h contributes with the default 1e-8 and not with 1e-6 */
    for (int k = 0; k < pst_scheme_count(); ++k) {
        const char *name = pst_scheme_name(k);
        CHECK(pst_scheme_fallback(name) != NULL && strlen(pst_scheme_fallback(name)) > 10);
        pst_cloud *cl = test_lattice(2, 0, 1, 0.1, 1.2, 0.2, 5, 0);
        double *x = pst_cloud_coord(cl, 0), *y = pst_cloud_coord(cl, 1);
        size_t i = 60, j = 61; /* interior neighbours; j moved next to i */
        x[j] = x[i] + 1.2e-8;
        y[j] = y[i];
        pst_nlist *nl = test_nlist(cl, pst_kernel_support(pst_scheme_default_kernel(name)));
        double entry[2];
        for (int e = 0; e < 2; ++e) {
            pst_op_opts oo;
            pst_op_defaults(&oo);
            oo.scheme = name;
            oo.min_pair_distance = e ? 1e-6 : 1e-8;
            pst_op *op;
            CHECK_INT(pst_op_create(&op, cl, nl, &oo, err), PST_OK);
            pst_csr a;
            CHECK_INT(pst_op_assemble(op, &a), PST_OK);
            entry[e] = test_csr_entry(&a, i, j);
            pst_csr_free(&a);
            pst_op_destroy(op);
        }
        /* the mixed schemes also couple i and j through common neighbours (a two-ring
         * pattern): there the direct pair's share changes the entry */
        int two_ring = strncmp(name, "mixed", 5) == 0;
        int ok = entry[0] != 0 && isfinite(entry[0]) &&
                 (two_ring ? entry[1] != entry[0] && isfinite(entry[1]) : entry[1] == 0);
        if (!ok)
            printf("%s: w_ij %g with min_pair_distance 1e-8, %g with 1e-6\n", name, entry[0],
                   entry[1]);
        CHECK(ok);
        pst_nlist_destroy(nl);
        pst_cloud_destroy(cl);
    }
    pst_op_opts oo;
    pst_op_defaults(&oo);
    oo.min_pair_distance = 0;
    pst_cloud *cl = test_lattice(2, 0, 1, 0.1, 1.2, 0, 5, 0);
    pst_nlist *nl = test_nlist(cl, 3);
    pst_op *op = NULL;
    CHECK_INT(pst_op_create(&op, cl, nl, &oo, err), PST_EINVAL);
    CHECK(strstr(err, "min_pair_distance") != NULL);

    /* on_degenerate: an isolated particle (particle 0 moved away) has too few neighbours; it
     * falls back by default and stops the operator when refused, named */
    pst_nlist_destroy(nl);
    pst_cloud_destroy(cl);
    cl = test_lattice(2, 0, 1, 0.1, 1.2, 0, 5, 0);
    pst_cloud_coord(cl, 0)[0] = -5;
    nl = test_nlist(cl, 3);
    pst_op_defaults(&oo);
    oo.scheme = "qsfdi";
    CHECK_INT(pst_op_create(&op, cl, nl, &oo, err), PST_OK);
    size_t counts[PST_ROW_NSTATUS];
    pst_op_status_counts(op, counts);
    size_t degenerate = counts[PST_ROW_RANK_DEFICIENT] + counts[PST_ROW_TOO_FEW];
    CHECK_INT(degenerate, 1);
    pst_op_destroy(op);
    oo.on_degenerate = PST_DEGENERATE_REFUSE;
    op = NULL;
    CHECK_INT(pst_op_create(&op, cl, nl, &oo, err), PST_ENUMERIC);
    CHECK(op == NULL);
    char want[64];
    snprintf(want, sizeof want, "qsfdi: %zu degenerate rows", degenerate);
    CHECK(strstr(err, want) != NULL && strstr(err, "the first is particle 0 at (-5, 0, 0)"));
    printf("refused: %s\n", err);
    oo.on_degenerate = 2;
    CHECK_INT(pst_op_create(&op, cl, nl, &oo, err), PST_EINVAL);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(cl);
}

/* The 3D unit cube at spacing 0.1 with no fields, one task (a "tasks=[...]" override) and a
 * scheme (an "operator.scheme=..." override): the memory tests plan it for 10^6 particles. */
static pst_scene cube_solve(const char *task, const char *scheme)
{
    const char *ov[] = {"dim=3", "cloud.lo=[0,0,0]", "cloud.hi=[1,1,1]", "cloud.spacing=0.1",
                        task, "fields={}", scheme};
    return scene(ov, 7);
}

/* The AMG matrix the plan counts is the one the solve builds: with amg_source auto, lsmps's own
 * matrix (the whole list: more bytes than its Brookshaw proxy at 1.6 h, and never cut to fit)
 * and qsfdi's proxy (the same bytes as amg_source brookshaw). */
static void test_amg_matrix_memory(void)
{
    const char *const schemes[] = {"operator.scheme=lsmps", "operator.scheme=qsfdi"};
    const char *const sources[] = {"\"auto\"", "\"brookshaw\""};
    double bytes[2][2];
    for (int k = 0; k < 2; ++k)
        for (int a = 0; a < 2; ++a) {
            char task[256];
            snprintf(task, sizeof task,
                     "tasks=[{\"type\":\"solve\",\"rhs\":\"0\",\"exact\":\"x\","
                     "\"precond\":\"amg\",\"amg_source\":%s}]",
                     sources[a]);
            pst_scene s = cube_solve(task, schemes[k]);
            pst_plan p;
            char err[1024];
            CHECK_INT(pst_plan_make(&p, &s, 1000000, NULL, err, sizeof err), PST_OK);
            bytes[k][a] = p.bytes_solver;
            pst_scene_free(&s);
        }
    printf("AMG solver bytes per particle at 10^6: lsmps auto %.0f, brookshaw %.0f; qsfdi auto "
           "%.0f, brookshaw %.0f\n", bytes[0][0] / 1e6, bytes[0][1] / 1e6, bytes[1][0] / 1e6,
           bytes[1][1] / 1e6);
    CHECK(bytes[0][0] > 2 * bytes[0][1]);
    CHECK(bytes[1][0] == bytes[1][1]);
}

/* Where lsmps's own AMG matrix (amg_source auto) does not fit, the plan takes the Brookshaw
 * proxy at the automatic radius first, and says so. */
static void test_amg_source_to_fit(void)
{
    pst_scene s = cube_solve("tasks=[{\"type\":\"solve\",\"rhs\":\"0\",\"exact\":\"x\","
                             "\"precond\":\"amg\",\"operator\":\"matrix_free\"}]",
                             "operator.scheme=lsmps");
    pst_plan p;
    char err[1024];
    size_t n = 1000000;
    CHECK_INT(pst_plan_make(&p, &s, n, NULL, err, sizeof err), PST_OK);
    CHECK_INT(p.task_amg_source[0], PST_AMG_AUTO);
    double own = p.bytes_total, solver = p.bytes_solver;
    s.memory_fraction = 0.8 * own / p.bytes_available;
    CHECK_INT(pst_plan_make(&p, &s, n, NULL, err, sizeof err), PST_OK);
    CHECK_INT(p.task_amg_source[0], PST_AMG_BROOKSHAW);
    CHECK(p.task_amg_radius[0] == -1 && p.task_restart[0] == 50);
    CHECK(p.bytes_total <= s.memory_fraction * p.bytes_available && p.bytes_solver < solver);
    char text[4096] = "";
    FILE *f = tmpfile();
    CHECK(f != NULL);
    if (f) {
        pst_plan_print(f, &p, &s);
        rewind(f);
        text[fread(text, 1, sizeof text - 1, f)] = '\0';
        fclose(f);
    }
    CHECK(strstr(text, "on the Brookshaw proxy (to fit)") != NULL);
    printf("lsmps at 10^6 in 80%% of the plan: AMG on the proxy, %.0f bytes per particle\n",
           p.bytes_total / (double)n);
    pst_scene_free(&s);
}

/* A matrix-free solve keeps the whole list where it fits (its apply is the faster one); short of
 * memory it runs on a half list (the whole list freed after the precompute) and gives the
 * stored solve's answer; stored weights, a gradient task, a scheme without a half-list apply or
 * AMG on the scheme's own matrix keep the whole list. The estimate covers both phases. */
static void test_half_list(void)
{
    const char *base[] = {
        ("tasks=[{\"type\":\"solve\",\"name\":\"sol\",\"rhs\":\"-100*sin(6*x+8*y)\","
         "\"exact\":\"sin(6*x+8*y)\",\"rtol\":1e-11}]"),
        "tasks.0.operator=matrix_free", "tasks.0.precond=jacobi"};
    const char *schemes[3] = {"operator.scheme=qsfdi", "operator.scheme=lv",
                              "operator.scheme=lsmps"};
    for (int k = 0; k < 3; ++k) {
        const char *ov[4] = {base[0], schemes[k], base[1], base[2]};
        pst_scene s = scene(ov, 4);
        pst_run_counters cnt;
        pst_plan p;
        char err[1024];
        CHECK_INT(pst_plan_make(&p, &s, pst_plan_particles(&s), NULL, err, sizeof err),
                  PST_OK);
        CHECK_INT(p.half_list, 0); /* it fits: the whole list */
        /* a budget the whole list misses by a quarter of the list: the half list fits it */
        s.memory_fraction = (p.bytes_total - 0.25 * p.bytes_neighbours) / p.bytes_available;
        pst_cloud *half = run(&s, &cnt, &p, PST_OK);
        CHECK(p.half_list == 1 && cnt.half_lists == 1 && cnt.stored_weights == 0);
        CHECK(p.bytes_total <= s.memory_fraction * p.bytes_available);
        /* each pair once: about half the whole list (its offsets are not halved) */
        CHECK(p.bytes_half_list > 0.5 * p.bytes_neighbours &&
              p.bytes_half_list < 0.6 * p.bytes_neighbours);
        CHECK(p.bytes_total >= p.bytes_cloud + p.bytes_neighbours + p.bytes_half_list +
                                   p.bytes_operators);
        pst_scene_free(&s);
        ov[2] = "tasks.0.operator=stored";
        s = scene(ov, 4);
        pst_cloud *whole = run(&s, &cnt, &p, PST_OK);
        CHECK(p.half_list == 0 && cnt.half_lists == 0 && p.bytes_half_list == 0);
        double *uh = field(half, "sol"), *uw = field(whole, "sol"), d = 0;
        for (size_t i = 0; i < pst_cloud_size(half); ++i)
            d = fmax(d, fabs(uh[i] - uw[i]));
        CHECK(d < 1e-8);
        free(uh);
        free(uw);
        pst_cloud_destroy(half);
        pst_cloud_destroy(whole);
        pst_scene_free(&s);
    }
    const char *with_gradient =
        "tasks=[{\"type\":\"solve\",\"rhs\":\"0\",\"exact\":\"x\"},"
        "{\"type\":\"gradient\",\"field\":\"u\"}]";
    const char *keep[3][2] = {{base[0], "operator.scheme=cspm"},
                              {with_gradient, "tasks.1.name=g"},
                              {base[0], "tasks.0.amg_source=own"}};
    for (int k = 0; k < 3; ++k) {
        const char *ov[4] = {keep[k][0], keep[k][1], base[1],
                             k == 2 ? "tasks.0.precond=amg" : base[2]};
        pst_scene s = scene(ov, 4);
        pst_plan p;
        char err[1024];
        CHECK_INT(pst_plan_make(&p, &s, 10000, NULL, err, sizeof err), PST_OK);
        CHECK_INT(p.half_list, 0);
        pst_scene_free(&s);
    }
}

/* The base operator keeps what its gradient and Hessian tasks need, on the schemes that keep
 * (qsfdi, the WLS schemes and the CSPM family; lv keeps nothing). */
static void test_keeps(void)
{
    const char *tasks = "tasks=[{\"type\":\"laplacian\",\"field\":\"u\"},"
                        "{\"type\":\"gradient\",\"field\":\"u\"},"
                        "{\"type\":\"hessian\",\"field\":\"u\"}]";
    const char *cases[5][2] = {{"operator.scheme=qsfdi", "3"}, {"operator.scheme=icspm", "3"},
                               {"operator.scheme=lsmps", "3"}, {"operator.scheme=cspm", "1"},
                               {"operator.scheme=lv", "0"}};
    for (int k = 0; k < 5; ++k) {
        /* cspm and lv have no Hessian: their third task is a second gradient */
        const char *ov[3] = {tasks, cases[k][0], "tasks.2.type=gradient"};
        pst_scene s = scene(ov, k >= 3 ? 3 : 2);
        pst_plan p;
        pst_run_counters cnt;
        pst_cloud *c = run(&s, &cnt, &p, PST_OK);
        printf("keeps: %s, keep %d\n", cases[k][0], p.base_keep);
        CHECK_INT(p.base_keep, atoi(cases[k][1]));
        pst_cloud_destroy(c);
        pst_scene_free(&s);
    }
}

/* Where memory is short the plan of a matrix-free AMG solve first takes the half list, then
 * the tight proxy radius (1.3 h), then shortens the GMRES restart (not below 20), and each
 * plan fits its budget; the operator's estimate is the scheme's own per-particle bytes. The
 * budget is set through limits.memory_fraction as a fraction of the memory the first plan
 * saw. */
static void test_fit_memory(void)
{
    /* lpmps: its automatic AMG radius is 1.6 h (qsfdi's is the tight 1.3 h already) */
    pst_scene s = cube_solve("tasks=[{\"type\":\"solve\",\"rhs\":\"0\",\"exact\":\"x\","
                             "\"operator\":\"matrix_free\"}]",
                             "operator.scheme=lpmps");
    pst_plan p;
    char err[1024];
    size_t n = 1000000;
    CHECK_INT(pst_plan_make(&p, &s, n, NULL, err, sizeof err), PST_OK);
    CHECK(p.task_amg_radius[0] == -1 && p.task_restart[0] == 50); /* room enough: as asked */
    /* the data, the status byte and the matrix-free apply's packed rows (32 bytes) */
    CHECK_INT(pst_scheme_apply_bytes("lpmps"), 32);
    CHECK_INT(pst_scheme_apply_bytes("cspm"), 32);
    CHECK_INT(pst_scheme_apply_bytes("mixed1"), 0);
    CHECK_INT(pst_scheme_apply_bytes("nosuch"), 0);
    CHECK(fabs(p.bytes_operators - (double)n * (1 + pst_scheme_data_bytes("lpmps", 3) + 32)) < 1);
    double loose = p.bytes_total, avail = p.bytes_available;
    const double cut[3] = {0.9, 0.7, 0.6};
    for (int k = 0; k < 3; ++k) {
        s.memory_fraction = cut[k] * loose / avail;
        CHECK_INT(pst_plan_make(&p, &s, n, NULL, err, sizeof err), PST_OK);
        /* first the half list, then the tight radius, then a shorter restart */
        CHECK_INT(p.half_list, 1);
        /* the half-list lane rows read the packed rows too */
        CHECK(fabs(p.bytes_operators - (double)n * (1 + pst_scheme_data_bytes("lpmps", 3) + 32)) <
              1);
        CHECK(p.task_amg_radius[0] == (k == 0 ? -1 : 1.3));
        CHECK(k < 2 ? p.task_restart[0] == 50 : p.task_restart[0] >= 20 && p.task_restart[0] < 50);
        CHECK(p.bytes_total <= s.memory_fraction * p.bytes_available);
        printf("budget %.2f of the plan: half list %d, AMG radius %g h, GMRES(%d), %.0f bytes per "
               "particle\n",
               cut[k], p.half_list, p.task_amg_radius[0], p.task_restart[0],
               p.bytes_total / (double)n);
    }
    s.memory_fraction = 0.5 * loose / avail; /* no shortening reaches it */
    CHECK_INT(pst_plan_make(&p, &s, n, NULL, err, sizeof err), PST_ENOMEM);
    pst_scene_free(&s);
}

/* Over several ranks the plan is one rank's: a part of n / ranks owned particles and an upper
 * estimate of the ghosts of the largest part (checked against the parts pst_part_create cuts
 * at 2, 8 and 64 ranks, with one ring of ghosts (qsfdi, lv), two (cspm) and three (mixed0): at
 * least them, at most 3 times them for one ring and 3.5 for more; the estimate's factor was
 * fitted on one ring at 2 to 64 ranks), every solve in PETSc, matrix-free on the whole list, the
 * part counted beside the whole cloud that every rank builds, and a budget that the node's
 * ranks share. */
static void test_ranks(void)
{
    const char *const schemes[4] = {"operator.scheme=qsfdi", "operator.scheme=lv",
                                    "operator.scheme=cspm", "operator.scheme=mixed0"};
    for (int k = 0; k < 4; ++k) {
        const char *ov[] = {"dim=3", "cloud.lo=[0,0,0]", "cloud.hi=[1,1,1]", "cloud.spacing=0.025",
                            "tasks=[{\"type\":\"solve\",\"rhs\":\"0\",\"exact\":\"x\"}]",
                            "fields={}", schemes[k]};
        pst_scene s = scene(ov, 7);
        pst_cloud *c = NULL;
        pst_nlist *nl = NULL;
        pst_op *op = NULL;
        char err[1024];
        CHECK_INT(pst_run_build_operator(&s, 1, 0, &c, &nl, &op, err, sizeof err), PST_OK);
        size_t n = pst_cloud_size(c);
        const double *normal[3] = {NULL, NULL, NULL};
        pst_plan one, p;
        CHECK_INT(pst_plan_make(&one, &s, n, NULL, err, sizeof err), PST_OK);
        CHECK(one.ranks == 1 && one.task_petsc[0] == 0 && one.task_stored[0] == 1);
        for (int R = 2; R <= 64; R *= R < 8 ? 4 : 8) { /* 2, 8 and 64 ranks */
            size_t owned = 0, ghosts = 0;
            for (int r = 0; r < R; ++r) {
                pst_part *part = NULL;
                CHECK_INT(pst_part_create(&part, c, pst_cloud_kinds_const(c), normal, R, r,
                                          pst_nlist_support(nl), pst_scheme_halo(s.op.scheme),
                                          err),
                          PST_OK);
                pst_part_info pi;
                pst_part_layout(part, &pi);
                owned = pi.hi - pi.lo > owned ? pi.hi - pi.lo : owned;
                ghosts = pi.nghost > ghosts ? pi.nghost : ghosts;
                pst_part_destroy(part);
            }
            pst_plan_where w = {.ranks = R, .node_ranks = 1};
            CHECK_INT(pst_plan_make(&p, &s, n, &w, err, sizeof err), PST_OK);
            CHECK(p.ranks == R && p.node_ranks == 1);
            CHECK(p.part_owned == owned);
            /* on 64 parts of this small cloud the two-ring halo reaches past the cloud's faces
             * that the box model takes for borders with other parts: up to 3.24 x there */
            CHECK(p.part_ghosts >= ghosts &&
                  p.part_ghosts <= (pst_scheme_halo(s.op.scheme) == 1 ? 3.0 : 3.5) * ghosts);
            CHECK(p.task_petsc[0] == 1 && p.task_stored[0] == 0 && p.half_list == 0);
            /* the part's list, unless the estimate is the whole cloud (thick halos on 2 ranks) */
            CHECK(p.bytes_cloud > one.bytes_cloud && (p.bytes_neighbours < one.bytes_neighbours ||
                                                      p.part_owned + p.part_ghosts == n));
            printf("%s, %zu particles over %d ranks: owned %zu, ghosts %zu, estimated %zu "
                   "(%.2f)\n",
                   schemes[k] + 16, n, R, owned, ghosts, p.part_ghosts,
                   (double)p.part_ghosts / (double)ghosts);
        }
        /* four ranks on this node share its memory: a budget one rank's plan fits alone, four
         * such plans do not */
        pst_plan_where alone = {.ranks = 4, .node_ranks = 1}, shared = {.ranks = 4, .node_ranks = 4};
        CHECK_INT(pst_plan_make(&p, &s, n, &alone, err, sizeof err), PST_OK);
        s.memory_fraction = 1.2 * p.bytes_total / p.bytes_available;
        CHECK_INT(pst_plan_make(&p, &s, n, &alone, err, sizeof err), PST_OK);
        CHECK_INT(pst_plan_make(&p, &s, n, &shared, err, sizeof err), PST_ENOMEM);
        CHECK(strstr(err, "per rank") && strstr(err, "this rank's share, 1/4,"));
        pst_op_destroy(op);
        pst_nlist_destroy(nl);
        pst_cloud_destroy(c);
        pst_scene_free(&s);
    }
    /* one process with every solve in PETSc (pstencil run --petsc): matrix-free, whole list */
    const char *ov[] = {"tasks=[{\"type\":\"solve\",\"rhs\":\"0\",\"exact\":\"x\"}]"};
    pst_scene s = scene(ov, 1);
    pst_plan_where petsc = {.petsc = 1};
    pst_plan p;
    char err[1024];
    CHECK_INT(pst_plan_make(&p, &s, 1000, &petsc, err, sizeof err), PST_OK);
    CHECK(p.ranks == 1 && p.task_petsc[0] == 1 && p.task_stored[0] == 0 && p.half_list == 0);
    pst_scene_free(&s);
}

int main(void)
{
    test_mpi_init(); /* the solves' default preconditioner is AMG, which needs MPI */
    test_only_what_is_asked();
    test_mobility_factor();
    test_solve_plan();
    test_refusals();
    test_parameters();
    test_keeps();
    test_fit_memory();
    test_half_list();
    test_amg_matrix_memory();
    test_amg_source_to_fit();
    test_periodic();
    test_ranks();
    return check_summary("test_plan");
}
