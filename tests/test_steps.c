/* Diffuse tasks (docs/time-stepping.md): sin(pi x) sin(pi y) with u = 0 held at the boundary
 * decays as exp(-2 pi^2 t). Forward Euler's error falls with h; backward Euler's halves with dt
 * and Crank-Nicolson's is far smaller; the Gershgorin rho bounds the spectral radius that
 * power iterations find; a scene dt above 2/rho is refused and one below it is stable; 1 and 2
 * threads give the same bits, moving particles included; particles moved by a zero velocity
 * give the static run's bits; a constant field stays constant under any motion; the .pvd lists
 * the VTUs written and the table has one row per step; counts over the caps are refused. */
#include "check.h"
#include "run.h"
#include "support.h"

#include <cjson/cJSON.h>

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static char dir[256];
static char err[PST_ERRLEN];

/* A 2D lattice on the unit square with a Dirichlet layer; the task is given as JSON. */
static int parse(pst_scene *s, double spacing, double jitter, const char *task)
{
    char text[4096];
    snprintf(text, sizeof text,
             "{\"dim\": 2, \"cloud\": {\"spacing\": %g, \"jitter\": %g, \"seed\": 3, "
             "\"h_ratio\": 1.5}, \"tasks\": [%s]}",
             spacing, jitter, task);
    int st = pst_scene_parse(s, text, "steps.json", NULL, 0, err, sizeof err);
    if (st != PST_OK)
        fprintf(stderr, "parse: %s\n", err);
    return st;
}

/* Run the scene; the report (cJSON_Delete it) and the cloud (may be NULL) on success. */
static int run(const pst_scene *s, cJSON **report, pst_cloud **c, pst_run_counters *cnt)
{
    pst_run_opts o = {.quiet = 1, .report = report};
    return pst_run_scene(s, &o, NULL, cnt, c, err, sizeof err);
}

/* tasks[0]'s "steps" number or norm `name` of a report. */
static double steps_value(const cJSON *rep, const char *name)
{
    const cJSON *t = cJSON_GetArrayItem(cJSON_GetObjectItem(rep, "tasks"), 0);
    const cJSON *v = cJSON_GetObjectItem(cJSON_GetObjectItem(t, "steps"), name);
    return v ? v->valuedouble : NAN;
}

static double norm_value(const cJSON *rep, const char *name)
{
    const cJSON *t = cJSON_GetArrayItem(cJSON_GetObjectItem(rep, "tasks"), 0);
    const cJSON *v = cJSON_GetObjectItem(cJSON_GetObjectItem(t, "norms"), name);
    return v ? v->valuedouble : NAN;
}

#define SINES "\"initial\": \"sin(pi*x)*sin(pi*y)\", " \
              "\"exact\": \"exp(-2*pi^2*t)*sin(pi*x)*sin(pi*y)\""

/* The relative l2 error at t_end of one run, its rho and dt (NAN when the run fails). */
static double heat_error(double spacing, const char *method, const char *dt, double *rho,
                         double *dt_used)
{
    char task[512];
    snprintf(task, sizeof task,
             "{\"type\": \"diffuse\", \"name\": \"u\", \"method\": \"%s\", %s, \"t_end\": 0.1%s%s}",
             method, SINES, dt ? ", \"dt\": " : "", dt ? dt : "");
    pst_scene s;
    cJSON *rep = NULL;
    double e = NAN;
    if (parse(&s, spacing, 0.0, task) == PST_OK && run(&s, &rep, NULL, NULL) == PST_OK) {
        e = norm_value(rep, "rel_l2");
        if (rho)
            *rho = steps_value(rep, "rho");
        if (dt_used)
            *dt_used = steps_value(rep, "dt");
    } else {
        fprintf(stderr, "heat_error: %s\n", err);
    }
    cJSON_Delete(rep);
    pst_scene_free(&s);
    return e;
}

static void test_convergence(void)
{
    double rho, dt;
    double e1 = heat_error(0.1, "explicit", NULL, NULL, NULL);
    double e2 = heat_error(0.05, "explicit", NULL, &rho, &dt);
    printf("explicit: rel_l2 %.3e (h 0.1), %.3e (h 0.05); rho %.4g, dt %.4g\n", e1, e2, rho, dt);
    CHECK(e2 < 0.02);          /* a wrong sign grows as exp(+2 pi^2 t): error ~ 50 */
    CHECK(e2 < 0.5 * e1);      /* second order in h: about a quarter */
    CHECK(dt <= 0.9 * 2 / rho * (1 + 1e-12) && dt > 0.8 * 2 / rho);
    double b1 = heat_error(0.05, "implicit", "0.02", NULL, NULL);
    double b2 = heat_error(0.05, "implicit", "0.01", NULL, NULL);
    double c1 = heat_error(0.05, "crank_nicolson", "0.02", NULL, NULL);
    printf("backward Euler: %.3e (dt 0.02), %.3e (dt 0.01); Crank-Nicolson %.3e (dt 0.02)\n",
           b1, b2, c1);
    CHECK(b1 > 0.2 && b1 < 0.5); /* the amplification 1/(1 + lambda dt): 36 % after 5 steps */
    CHECK(b2 < 0.6 * b1);        /* first order in dt */
    CHECK(c1 < 0.1 * b1);        /* second order */
}

/* The largest |lambda| of L on the interior rows and columns, by power iterations: below the
 * Gershgorin bound the runner uses. */
static double power_radius(double spacing)
{
    pst_scene s;
    pst_cloud *c = NULL;
    pst_nlist *nl = NULL;
    pst_op *op = NULL;
    double lambda = NAN;
    if (parse(&s, spacing, 0.3, "{\"type\": \"diffuse\", " SINES ", \"t_end\": 1, "
                                "\"dt\": 0.1}") != PST_OK ||
        pst_run_build_operator(&s, 1, 0, &c, &nl, &op, err, sizeof err) != PST_OK) {
        fprintf(stderr, "power_radius: %s\n", err);
        pst_scene_free(&s);
        return NAN;
    }
    size_t n = pst_cloud_size(c);
    const uint8_t *kind = pst_cloud_kinds_const(c);
    double *x = malloc(n * sizeof *x), *y = malloc(n * sizeof *y);
    test_rng_seed(7);
    for (size_t i = 0; i < n; ++i)
        x[i] = kind[i] == PST_INTERIOR ? test_rnd() - 0.5 : 0.0;
    for (int it = 0; it < 400; ++it) {
        pst_op_apply(op, x, y);
        double norm = 0, dot = 0;
        for (size_t i = 0; i < n; ++i) {
            y[i] = kind[i] == PST_INTERIOR ? y[i] : 0.0;
            norm += y[i] * y[i];
            dot += x[i] * x[i];
        }
        lambda = sqrt(norm / dot);
        for (size_t i = 0; i < n; ++i)
            x[i] = y[i] / sqrt(norm);
    }
    free(x);
    free(y);
    pst_op_destroy(op);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
    pst_scene_free(&s);
    return lambda;
}

static void test_limit(void)
{
    /* the bound holds on a jittered cloud, and is not loose by more than a few times */
    pst_scene s;
    cJSON *rep = NULL;
    CHECK_INT(parse(&s, 0.05, 0.3, "{\"type\": \"diffuse\", \"method\": \"explicit\", " SINES
                                   ", \"t_end\": 0.01}"), PST_OK);
    CHECK_INT(run(&s, &rep, NULL, NULL), PST_OK);
    double rho = steps_value(rep, "rho"), limit = steps_value(rep, "dt_limit");
    double power = power_radius(0.05);
    printf("jittered: rho %.5g (Gershgorin), %.5g (power iterations)\n", rho, power);
    CHECK(power <= rho && rho < 4 * power);
    CHECK_NEAR(limit, 2 / rho, 1e-12 * limit);
    cJSON_Delete(rep);
    pst_scene_free(&s);

    /* 1 % above the limit is refused with the numbers, 1 % below is stable */
    char task[512];
    snprintf(task, sizeof task, "{\"type\": \"diffuse\", \"method\": \"explicit\", " SINES
             ", \"t_end\": 0.01, \"dt\": %.17g}", 1.01 * limit);
    CHECK_INT(parse(&s, 0.05, 0.3, task), PST_OK);
    CHECK_INT(run(&s, &rep, NULL, NULL), PST_EINPUT);
    CHECK(strstr(err, "exceeds the forward-Euler step limit 2/rho") != NULL);
    pst_scene_free(&s);
    snprintf(task, sizeof task, "{\"type\": \"diffuse\", \"method\": \"explicit\", " SINES
             ", \"t_end\": 0.01, \"dt\": %.17g}", 0.99 * limit);
    CHECK_INT(parse(&s, 0.05, 0.3, task), PST_OK);
    CHECK_INT(run(&s, &rep, NULL, NULL), PST_OK);
    CHECK(norm_value(rep, "rel_l2") < 0.05);
    CHECK(steps_value(rep, "dt") <= 0.99 * limit);
    cJSON_Delete(rep);
    pst_scene_free(&s);
}

/* The task's field `name` in input order. */
static double *field(pst_cloud *c, const char *name)
{
    double *out = malloc(pst_cloud_size(c) * sizeof *out);
    pst_cloud_to_input_order(c, pst_cloud_field_by_name(c, name), out);
    return out;
}

/* The field u and the counters of a run on `threads` threads. */
static double *run_field(const char *task, int threads, double jitter, pst_run_counters *cnt)
{
    pst_scene s;
    pst_cloud *c = NULL;
    double *u = NULL;
    int was = omp_get_max_threads();
    omp_set_num_threads(threads);
    if (parse(&s, 0.05, jitter, task) == PST_OK && run(&s, NULL, &c, cnt) == PST_OK)
        u = field(c, "u");
    else
        fprintf(stderr, "run_field: %s\n", err);
    omp_set_num_threads(was);
    pst_cloud_destroy(c);
    pst_scene_free(&s);
    return u;
}

/* 1 and 2 threads agree bit for bit, static and moving; a zero velocity gives the static
 * run's bits through the update and refresh path; a constant stays constant while moving. */
static void test_threads_and_moving(void)
{
    const char *tasks[] = {
        "{\"type\": \"diffuse\", \"name\": \"u\", \"method\": \"implicit\", " SINES
        ", \"t_end\": 0.02, \"dt\": 0.005, \"source\": \"x*t\"}",
        "{\"type\": \"diffuse\", \"name\": \"u\", \"method\": \"explicit\", " SINES
        ", \"t_end\": 0.005, \"velocity\": [\"-sin(pi*x)*cos(pi*y)\", \"cos(pi*x)*sin(pi*y)\"]}",
        "{\"type\": \"diffuse\", \"name\": \"u\", \"method\": \"crank_nicolson\", " SINES
        ", \"t_end\": 0.02, \"dt\": 0.005, \"velocity\": [\"y - 0.5\", \"0.5 - x\"], "
        "\"skin\": 0.2}"};
    size_t n = 21 * 21;
    for (int k = 0; k < 3; ++k) {
        pst_run_counters c1, c2;
        double *u1 = run_field(tasks[k], 1, 0.3, &c1), *u2 = run_field(tasks[k], 2, 0.3, &c2);
        CHECK(u1 && u2 && memcmp(u1, u2, n * sizeof *u1) == 0);
        CHECK_INT(c1.steps, c2.steps);
        CHECK_INT(c1.refreshes, k == 0 ? 0 : c1.steps);
        free(u1);
        free(u2);
    }
    pst_run_counters a, b;
    double *still = run_field("{\"type\": \"diffuse\", \"name\": \"u\", \"method\": \"implicit\", "
                              SINES ", \"t_end\": 0.02, \"dt\": 0.005}", 2, 0.3, &a);
    double *zero = run_field("{\"type\": \"diffuse\", \"name\": \"u\", \"method\": \"implicit\", "
                             SINES ", \"t_end\": 0.02, \"dt\": 0.005, "
                             "\"velocity\": [\"0\", \"0*x\"]}", 2, 0.3, &b);
    double diff = 0;
    for (size_t i = 0; still && zero && i < n; ++i)
        diff = fmax(diff, fabs(still[i] - zero[i]));
    printf("zero velocity against none: max |difference| %.3g\n", diff);
    CHECK(still && zero && diff < 1e-14); /* the cells of the sort differ, so the sums' order */
    CHECK_INT(a.refreshes, 0);
    CHECK_INT(b.refreshes, 4);
    free(still);
    free(zero);
    /* a rotation moves every interior particle; u = 1 has L u = 0 on any cloud */
    double *one = run_field("{\"type\": \"diffuse\", \"name\": \"u\", \"method\": \"implicit\", "
                            "\"initial\": \"1\", \"boundary_value\": \"1\", \"t_end\": 0.1, "
                            "\"dt\": 0.01, \"velocity\": [\"y - 0.5\", \"0.5 - x\"]}",
                            2, 0.3, &a);
    double most = 0;
    for (size_t i = 0; one && i < n; ++i)
        most = fmax(most, fabs(one[i] - 1));
    CHECK(one && most < 1e-8);
    CHECK_INT(a.refreshes, 10);
    free(one);
}

/* A moving implicit run on weights stored in float (refreshed in float every step): the same
 * bits at 1 and 2 threads, within the weights' rounding of the double store's answer and not
 * equal to it; the report says which store. */
static void test_float_weights(void)
{
    const char *fmt = "{\"type\": \"diffuse\", \"name\": \"u\", \"method\": \"crank_nicolson\", "
                      SINES ", \"t_end\": 0.02, \"dt\": 0.005, \"velocity\": [\"y - 0.5\", "
                      "\"0.5 - x\"], \"operator\": \"%s\"}";
    char dbl[512], flt[512];
    snprintf(dbl, sizeof dbl, fmt, "stored");
    snprintf(flt, sizeof flt, fmt, "stored_float");
    size_t n = 21 * 21;
    pst_run_counters a, b, c;
    double *ud = run_field(dbl, 2, 0.3, &a), *u1 = run_field(flt, 1, 0.3, &b),
           *u2 = run_field(flt, 2, 0.3, &c);
    CHECK(ud && u1 && u2 && memcmp(u1, u2, n * sizeof *u1) == 0);
    CHECK_INT(b.stored_weights, 1);
    CHECK_INT(b.refreshes, 4);
    double diff = 0;
    for (size_t i = 0; ud && u1 && i < n; ++i)
        diff = fmax(diff, fabs(ud[i] - u1[i]));
    printf("moving, weights in float against double: max |difference| %.3g\n", diff);
    CHECK(diff > 0 && diff < 1e-6);
    free(ud);
    free(u1);
    free(u2);
    pst_scene s;
    cJSON *rep = NULL;
    const char *use = NULL;
    if (parse(&s, 0.05, 0.3, flt) == PST_OK && run(&s, &rep, NULL, NULL) == PST_OK) {
        const cJSON *t = cJSON_GetArrayItem(cJSON_GetObjectItem(rep, "tasks"), 0);
        const cJSON *sj = cJSON_GetObjectItem(t, "steps");
        use = cJSON_GetStringValue(cJSON_GetObjectItem(sj, "operator"));
    }
    CHECK(use && strcmp(use, "stored_float") == 0);
    cJSON_Delete(rep);
    pst_scene_free(&s);
}

/* Lines of a file that contain `what`. */
static int count_lines(const char *path, const char *what)
{
    FILE *f = fopen(path, "r");
    char line[4096];
    int k = 0;
    while (f && fgets(line, sizeof line, f))
        k += strstr(line, what) != NULL;
    if (f)
        fclose(f);
    return f ? k : -1;
}

static void test_outputs(void)
{
    char task[2048], pvd[300], csv[300];
    snprintf(pvd, sizeof pvd, "%s", test_path_in(dir, "heat.pvd"));
    snprintf(csv, sizeof csv, "%s", test_path_in(dir, "heat_steps.csv"));
    /* 23 steps, output_every 5: steps 0, 5, 10, 15, 20 and the last */
    snprintf(task, sizeof task,
             "{\"type\": \"diffuse\", \"name\": \"u\", \"method\": \"implicit\", " SINES
             ", \"t_end\": 0.023, \"dt\": 0.001, \"pvd\": \"%s\", \"output_every\": 5, "
             "\"steps_csv\": \"%s\"}", pvd, csv);
    pst_scene s;
    cJSON *rep = NULL;
    pst_run_counters cnt;
    CHECK_INT(parse(&s, 0.1, 0.0, task), PST_OK);
    CHECK_INT(run(&s, &rep, NULL, &cnt), PST_OK);
    CHECK_INT(count_lines(pvd, "<DataSet"), 6);
    CHECK_INT(count_lines(pvd, "file=\"heat_000023.vtu\""), 1);
    CHECK_INT(count_lines(pvd, "timestep=\"0\" part=\"0\" file=\"heat_000000.vtu\""), 1);
    const int steps[] = {0, 5, 10, 15, 20, 23};
    for (int q = 0; q < 6; ++q) {
        char name[64];
        snprintf(name, sizeof name, "heat_%06d.vtu", steps[q]);
        CHECK(count_lines(test_path_in(dir, name), "<VTKFile") == 1);
    }
    CHECK(count_lines(test_path_in(dir, "heat_000001.vtu"), "<VTKFile") == -1);
    CHECK_INT(count_lines(csv, ","), 24); /* the header and one row per step */
    CHECK_INT(count_lines(csv, "step,t,dt,neighbour_seconds,rebuilt,"), 1);
    CHECK_INT(count_lines(csv, "23,0.02"), 1); /* the last step ends at t_end */
    CHECK_INT(cnt.steps, 23);
    CHECK_INT(cnt.files, 8); /* six VTUs, the .pvd, the table */
    CHECK_INT(test_count_temporaries(dir), 0);
    CHECK_INT(steps_value(rep, "series_files"), 6);
    cJSON_Delete(rep);
    pst_scene_free(&s);
}

/* Refusals at run time, before the first step. */
static void test_refusals(void)
{
    const struct {
        const char *task, *want;
    } cases[] = {
        {"{\"type\": \"diffuse\", \"initial\": \"x\", \"t_end\": 1, \"dt\": 0.1}",
         "Dirichlet particles need a value: give tasks[0].boundary_value or tasks[0].exact"},
        {"{\"type\": \"diffuse\", " SINES ", \"t_end\": 1, \"dt\": 1e-6}",
         "1000000 steps of dt 1e-06 to t_end 1, more than tasks[0].max_steps (100000)"},
        {"{\"type\": \"diffuse\", " SINES ", \"t_end\": 1, \"dt\": 1e-5, \"pvd\": \"x.pvd\", "
         "\"output_every\": 1}",
         "100001 files in the time series, more than 10000: raise tasks[0].output_every"},
        {"{\"type\": \"diffuse\", " SINES ", \"t_end\": 1, \"dt\": 0.1, \"precond\": \"amg\"}",
         "AMG needs the engine operator's rows"},
        {"{\"type\": \"diffuse\", " SINES ", \"t_end\": 1, \"dt\": 0.1, \"solver\": \"cg\"}",
         "CG needs a symmetric operator"},
        {"{\"type\": \"diffuse\", " SINES ", \"t_end\": 1, \"dt\": 0.1, \"source\": \"log(x)\"}",
         "tasks[0].source: 'log(x)' is not finite at particle"},
    };
    for (size_t q = 0; q < sizeof cases / sizeof cases[0]; ++q) {
        pst_scene s;
        CHECK_INT(parse(&s, 0.1, 0.0, cases[q].task), PST_OK);
        int st = run(&s, NULL, NULL, NULL);
        CHECK(st == PST_EINPUT && strstr(err, cases[q].want));
        if (st != PST_EINPUT || !strstr(err, cases[q].want))
            fprintf(stderr, "  case %zu: %s\n", q, err);
        pst_scene_free(&s);
    }
    CHECK(count_lines("x.pvd", "<") == -1); /* nothing written */
}

int main(void)
{
    if (test_scratch_dir(dir, sizeof dir, "pst_steps") != 0)
        return 1;
    test_convergence();
    test_limit();
    test_threads_and_moving();
    test_float_weights();
    test_outputs();
    test_refusals();
    test_remove_dir(dir);
    return check_summary("test_steps");
}
