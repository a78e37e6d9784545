/* Scenes: the built-in and the documented example scenes with their values, defaults, every
 * task type, overrides (list index, map entry, created keys), input paths, every class of
 * error with its exact key and line:column, JSON syntax errors, edge cases (empty text,
 * top-level list, deep nesting, huge numbers, NaN-like strings, duplicate keys), the position
 * finder on its own, a mutation fuzz that must parse or fail with a line:column, and
 * docs/scenes.md against the generated markdown.
 *
 * `test_scene --write-docs FILE` writes the markdown (to regenerate docs/scenes.md). */
#define _POSIX_C_SOURCE 200809L /* mkdtemp */
#include "check.h"
#include "json_pos.h"
#include "scene.h"

#include <omp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char err[PST_ERRLEN];

/* Parse text as "t.json" with overrides; a failed check prints the error. */
static int parse(pst_scene *s, const char *text, const char *const *ov, int nov)
{
    int rc = pst_scene_parse(s, text, "t.json", ov, nov, err, sizeof err);
    if (rc != PST_OK)
        fprintf(stderr, "  (parse failed: %s)\n", err);
    return rc;
}

/* The text must fail with exactly `want` as the message. */
static void expect_error_ov(int line, const char *text, const char *const *ov, int nov,
                            const char *want)
{
    pst_scene s;
    int rc = pst_scene_parse(&s, text, "t.json", ov, nov, err, sizeof err);
    ++check_count;
    if (rc != PST_EINPUT || strcmp(err, want) != 0) {
        ++check_failures;
        fprintf(stderr, "%s:%d: expected error\n  want: %s\n  got (rc %d): %s\n", __FILE__,
                line, want, rc, rc == PST_OK ? "(parsed)" : err);
    }
    /* a failed parse leaves an empty scene: freeing it again is harmless */
    pst_scene_free(&s);
}
#define EXPECT_ERROR(text, want) expect_error_ov(__LINE__, text, NULL, 0, want)
#define EXPECT_ERROR_OV(text, ov, want)                                                       \
    expect_error_ov(__LINE__, text, ov, (int)(sizeof ov / sizeof ov[0]), want)

static void test_default(void)
{
    pst_scene s;
    CHECK_INT(pst_scene_default(&s, NULL, 0, err, sizeof err), PST_OK);
    CHECK(strcmp(s.path, "(built-in)") == 0);
    CHECK(strcmp(s.dir, ".") == 0);
    CHECK(strncmp(s.title, "default scene: QSFDI", 20) == 0);
    CHECK_INT(s.dim, 3);
    CHECK_INT(s.cloud.source, SC_CLOUD_LATTICE);
    CHECK(s.cloud.file == NULL);
    for (int d = 0; d < 3; ++d) {
        CHECK(s.cloud.lo[d] == 0.0);
        CHECK(s.cloud.hi[d] == 1.0);
    }
    CHECK(s.cloud.spacing == 0.01);
    CHECK(s.cloud.jitter == 0.5);
    CHECK_INT(s.cloud.seed, 1);
    CHECK_INT(s.cloud.boundary_layer, 1);
    CHECK(s.cloud.angle == 0.0);
    CHECK(s.cloud.h_ratio == 1.2);
    CHECK_INT(s.cloud.h_ratio_set, 1);
    CHECK_INT(s.mobility.type, SC_MOB_NONE);
    CHECK_INT(s.mobility.ncomp, 0);
    CHECK(strcmp(s.op.scheme, "qsfdi") == 0);
    CHECK_INT(s.op.kernel, -1);
    CHECK_INT(s.op.gradient, PST_GRAD_G1);
    CHECK(s.op.cond_max == 1e10);
    CHECK(s.op.rank_tol == 1e-13);
    CHECK_INT(s.nfields, 1);
    CHECK(strcmp(s.fields[0].name, "u") == 0);
    CHECK(strcmp(s.fields[0].expr, "sin(2*x + 3*y + 4*z)") == 0);
    CHECK_INT(s.ntasks, 2);
    CHECK_INT(s.tasks[0].type, SC_TASK_LAPLACIAN);
    CHECK(strcmp(s.tasks[0].name, "laplacian") == 0);
    CHECK(strcmp(s.tasks[0].field, "u") == 0);
    CHECK_INT(s.tasks[0].nexact, 1);
    CHECK(strcmp(s.tasks[0].exact[0], "-29*sin(2*x + 3*y + 4*z)") == 0);
    CHECK_INT(s.tasks[0].nnorms, 2);
    CHECK_INT(s.tasks[0].norms[0], SC_NORM_REL_L2);
    CHECK_INT(s.tasks[0].norms[1], SC_NORM_MAX_ABS);
    CHECK_INT(s.tasks[0].region, SC_REGION_INTERIOR);
    CHECK_INT(s.tasks[1].type, SC_TASK_GRADIENT);
    CHECK(strcmp(s.tasks[1].name, "gradient") == 0);
    CHECK_INT(s.tasks[1].nexact, 3);
    CHECK(strcmp(s.tasks[1].exact[2], "4*cos(2*x + 3*y + 4*z)") == 0);
    CHECK(s.out.csv == NULL && s.out.vtu == NULL && s.out.report == NULL);
    CHECK_INT(s.out.nfields, 0);
    CHECK(s.memory_fraction == 0.8);
    pst_scene_free(&s);
    CHECK(s.path == NULL && s.ntasks == 0);
}

/* "{}" is a whole scene: every default from the table. */
static void test_minimal(void)
{
    pst_scene s;
    CHECK_INT(parse(&s, "{}", NULL, 0), PST_OK);
    CHECK_INT(s.dim, 2);
    CHECK(strcmp(s.title, "t.json") == 0);
    CHECK_INT(s.cloud.source, SC_CLOUD_LATTICE);
    CHECK(s.cloud.lo[0] == 0 && s.cloud.lo[1] == 0 && s.cloud.hi[0] == 1 && s.cloud.hi[1] == 1);
    CHECK(s.cloud.lo[2] == 0 && s.cloud.hi[2] == 0);
    CHECK(s.cloud.spacing == 0.05);
    CHECK(s.cloud.jitter == 0);
    CHECK_INT(s.cloud.seed, 1);
    CHECK_INT(s.cloud.boundary_layer, 1);
    CHECK(s.cloud.h_ratio == 1.2);
    CHECK_INT(s.cloud.h_ratio_set, 0);
    CHECK_INT(s.mobility.type, SC_MOB_NONE);
    CHECK(strcmp(s.op.scheme, "qsfdi") == 0);
    CHECK_INT(s.op.kernel, -1);
    CHECK_INT(s.op.variant, 0);
    CHECK_INT(s.nfields, 0);
    CHECK_INT(s.ntasks, 0);
    CHECK(s.memory_fraction == 0.8);
    pst_scene_free(&s);
}

/* The documented example: a task of every type and every section. */
static void test_example(void)
{
    pst_scene s;
    CHECK_INT(parse(&s, pst_scene_example(), NULL, 0), PST_OK);
    CHECK_INT(s.dim, 2);
    CHECK(s.cloud.spacing == 0.02 && s.cloud.jitter == 0.3 && s.cloud.seed == 7);
    CHECK_INT(s.mobility.type, SC_MOB_EXPR);
    CHECK_INT(s.mobility.ncomp, 2);
    CHECK(strcmp(s.mobility.expr[1], "1 + y") == 0);
    CHECK_INT(s.op.kernel, PST_KERNEL_QUINTIC);
    CHECK_INT(s.nfields, 2);
    CHECK_INT(s.ntasks, 7);
    static const char *const names[] = {"laplacian",   "flux", "gradient", "hessian",
                                        "interpolate", "p",    "heat"};
    for (int i = 0; i < 7 && i < s.ntasks; ++i) {
        CHECK(strcmp(s.tasks[i].name, names[i]) == 0);
        CHECK_INT(s.tasks[i].type, i);
    }
    if (s.ntasks == 7) {
        sc_task *t = s.tasks;
        CHECK_INT(t[0].nnorms, 2); /* the default pair */
        CHECK_INT(t[1].nnorms, 3);
        CHECK_INT(t[1].norms[1], SC_NORM_LV78);
        CHECK_INT(t[2].region, SC_REGION_BOX);
        CHECK(t[2].region_lo[0] == 0.1 && t[2].region_hi[1] == 0.9);
        CHECK_INT(t[2].nexact, 2);
        CHECK_INT(t[3].nexact, 3);
        CHECK_INT(t[3].region, SC_REGION_ALL);
        CHECK(t[4].points_file == NULL);
        CHECK(t[4].points_spacing == 0.1 && t[4].points_hi[0] == 0.95);
        CHECK(t[4].field && strcmp(t[4].field, "u") == 0);
        CHECK(t[5].field == NULL);
        CHECK(strcmp(t[5].rhs, "4 + 4*x + 4*y") == 0);
        CHECK_INT(t[5].ngroups, 2);
        CHECK_INT(t[5].groups[0].where, SC_SIDE_XLO);
        CHECK_INT(t[5].groups[0].neumann, 1);
        CHECK_INT(t[5].groups[1].where, SC_SIDE_ALL);
        CHECK_INT(t[5].groups[1].neumann, 0);
        CHECK(strcmp(t[5].groups[1].value, "x^2 + y^2") == 0);
        CHECK_INT(t[5].solver, PST_SOLVER_GMRES);
        CHECK_INT(t[5].precond, PST_PREC_JACOBI);
        CHECK_INT(t[5].amg_source, PST_AMG_AUTO);
        CHECK_INT(t[5].restart, 50);
        CHECK_INT(t[5].max_iter, 2000);
        CHECK(t[5].rtol == 1e-10);
        CHECK_INT(t[5].stored, 1);
        CHECK_INT(t[5].norms[1], SC_NORM_MAX_REL);
    }
    CHECK(strcmp(s.out.csv, "poisson.csv") == 0 && strcmp(s.out.report, "poisson.json") == 0);
    CHECK_INT(s.out.nfields, 5);
    CHECK(s.memory_fraction == 0.5);
    pst_scene_free(&s);
}

static void test_tasks(void)
{
    pst_scene s;
    /* default names skip the ones taken, whatever their order */
    const char *three = "{\"fields\": {\"u\": \"x\"}, \"tasks\": ["
                        "{\"type\": \"laplacian\", \"field\": \"u\"},"
                        "{\"type\": \"laplacian\", \"field\": \"u\"},"
                        "{\"type\": \"laplacian\", \"field\": \"u\", \"name\": \"laplacian_2\"},"
                        "{\"type\": \"solve\", \"rhs\": \"0\", \"exact\": \"x\"}]}";
    CHECK_INT(parse(&s, three, NULL, 0), PST_OK);
    CHECK(strcmp(s.tasks[0].name, "laplacian") == 0);
    CHECK(strcmp(s.tasks[1].name, "laplacian_3") == 0);
    CHECK(strcmp(s.tasks[2].name, "laplacian_2") == 0);
    CHECK(strcmp(s.tasks[3].name, "solve") == 0);
    CHECK_INT(s.tasks[0].nnorms, 0); /* no exact, no norms */
    CHECK_INT(s.tasks[3].solver, PST_SOLVER_AUTO);
    CHECK_INT(s.tasks[3].precond, SC_PRECOND_AUTO);
    CHECK(s.tasks[3].amg_radius == -1 && s.tasks[3].amg_aggressive == 0);
    CHECK_INT(s.tasks[3].amg_source, PST_AMG_AUTO);
    CHECK_INT(s.tasks[3].amg_coarsen, PST_AMG_HMIS);
    CHECK_INT(s.tasks[3].amg_interp, PST_AMG_EXT_I);
    CHECK_INT(s.tasks[3].amg_pmax, 4);
    CHECK_INT(s.tasks[3].stored, -1);
    CHECK_INT(s.tasks[3].restart, 50);
    CHECK_INT(s.tasks[3].max_iter, 5000);
    CHECK(s.tasks[3].rtol == 1e-10);
    CHECK_INT(s.tasks[3].ngroups, 0);
    pst_scene_free(&s);

    /* hypre's settings reach the task */
    CHECK_INT(parse(&s, "{\"tasks\": [{\"type\": \"solve\", \"rhs\": \"0\", \"exact\": "
                        "\"x\", \"amg_source\": \"own\", \"amg_coarsen\": \"falgout\", "
                        "\"amg_interp\": \"classical\", \"amg_pmax\": 0}]}",
                    NULL, 0),
              PST_OK);
    CHECK_INT(s.tasks[0].amg_source, PST_AMG_OWN);
    CHECK_INT(s.tasks[0].amg_coarsen, PST_AMG_FALGOUT);
    CHECK_INT(s.tasks[0].amg_interp, PST_AMG_CLASSICAL);
    CHECK_INT(s.tasks[0].amg_pmax, 0);
    pst_scene_free(&s);

    /* 3D Hessian: six entries; constant and SPE10 mobility; a file cloud */
    const char *hess = "{\"dim\": 3, \"cloud\": {\"source\": \"file\", \"file\": \"c.csv\", "
                       "\"h_ratio\": 2}, \"mobility\": {\"type\": \"spe10\", \"file\": "
                       "\"/data/permx.geos\", \"layer\": 84, \"j0\": 100}, "
                       "\"fields\": {\"u\": \"x*y*z\"}, \"tasks\": [{\"type\": \"hessian\", "
                       "\"field\": \"u\", \"exact\": [\"0\",\"0\",\"0\",\"z\",\"y\",\"x\"]},"
                       "{\"type\": \"interpolate\", \"field\": \"u\", \"points\": {\"file\": "
                       "\"p.csv\"}}]}";
    CHECK_INT(pst_scene_parse(&s, hess, "runs/a/s.json", NULL, 0, err, sizeof err), PST_OK);
    CHECK_INT(s.cloud.source, SC_CLOUD_FILE);
    CHECK(s.cloud.file && strcmp(s.cloud.file, "runs/a/c.csv") == 0);
    CHECK(strcmp(s.dir, "runs/a") == 0);
    CHECK_INT(s.cloud.h_ratio_set, 1);
    CHECK_INT(s.mobility.type, SC_MOB_SPE10);
    CHECK(s.mobility.file && strcmp(s.mobility.file, "/data/permx.geos") == 0);
    CHECK_INT(s.mobility.layer, 84);
    CHECK_INT(s.mobility.i0, 0);
    CHECK_INT(s.mobility.j0, 100);
    CHECK_INT(s.tasks[0].nexact, 6);
    CHECK(strcmp(s.tasks[0].exact[5], "x") == 0);
    CHECK(s.tasks[1].points_file && strcmp(s.tasks[1].points_file, "runs/a/p.csv") == 0);
    pst_scene_free(&s);

    CHECK_INT(parse(&s, "{\"mobility\": {\"type\": \"constant\", \"value\": 2.5}}", NULL, 0),
              PST_OK);
    CHECK_INT(s.mobility.type, SC_MOB_CONSTANT);
    CHECK(s.mobility.value == 2.5);
    CHECK_INT(s.mobility.ncomp, 1);
    pst_scene_free(&s);
    CHECK_INT(parse(&s, "{\"mobility\": {\"type\": \"expression\", \"expression\": \"1+x\"}, "
                        "\"operator\": {\"kernel\": \"wendland_c4\", \"gradient\": \"G3\"}, "
                        "\"cloud\": {\"source\": \"cell_centred\"}}",
                    NULL, 0),
              PST_OK);
    CHECK_INT(s.mobility.ncomp, 1);
    CHECK_INT(s.op.kernel, PST_KERNEL_WENDLAND_C4);
    CHECK_INT(s.op.gradient, PST_GRAD_G3);
    CHECK_INT(s.cloud.source, SC_CLOUD_CELL_CENTRED);
    pst_scene_free(&s);
    /* the older scene name of the same kernel */
    CHECK_INT(parse(&s, "{\"operator\": {\"kernel\": \"wendland2\"}}", NULL, 0), PST_OK);
    CHECK_INT(s.op.kernel, PST_KERNEL_WENDLAND_C2);
    pst_scene_free(&s);
}

/* Diffuse tasks: every key read, the defaults, and the checks between keys the table cannot
 * make (what the method, the velocity and pvd decide). */
static void test_steps(void)
{
    pst_scene s;
    const char *moving =
        "{\"tasks\": [{\"type\": \"diffuse\", \"name\": \"heat\", \"initial\": \"sin(x)\", "
        "\"exact\": \"t*x\", \"source\": \"t\", \"boundary_value\": \"0\", \"t_end\": 0.5, "
        "\"method\": \"explicit\", \"velocity\": [\"y\", \"-x\"], \"skin\": 0.4, "
        "\"pvd\": \"a.pvd\", \"output_every\": 3, \"steps_csv\": \"a.csv\"}]}";
    CHECK_INT(parse(&s, moving, NULL, 0), PST_OK);
    const sc_task *t = s.tasks;
    CHECK_INT(t->type, SC_TASK_DIFFUSE);
    CHECK_INT(t->method, SC_METHOD_EXPLICIT);
    CHECK(t->t_end == 0.5 && t->dt == 0 && t->safety == 0.9 && t->skin == 0.4);
    CHECK_INT(t->nvelocity, 2);
    CHECK(strcmp(t->velocity[1], "-x") == 0 && strcmp(t->initial, "sin(x)") == 0);
    CHECK(strcmp(t->source, "t") == 0 && strcmp(t->boundary_value, "0") == 0);
    CHECK(strcmp(t->pvd, "a.pvd") == 0 && strcmp(t->steps_csv, "a.csv") == 0);
    CHECK_INT(t->output_every, 3);
    CHECK_INT(t->max_steps, 100000);
    CHECK_INT(t->nnorms, 2); /* exact gives the default pair */
    /* expressions of a diffuse task read t; those of other tasks do not */
    CHECK_INT(pst_scene_compile_exprs(&s, err, sizeof err), PST_OK);
    pst_scene_free(&s);
    CHECK_INT(parse(&s, "{\"tasks\": [{\"type\": \"diffuse\", \"initial\": \"x\", "
                        "\"t_end\": 2, \"dt\": 0.1}]}", NULL, 0), PST_OK);
    CHECK_INT(s.tasks[0].method, SC_METHOD_IMPLICIT);
    CHECK(s.tasks[0].dt == 0.1 && s.tasks[0].rtol == 1e-10 && s.tasks[0].nvelocity == 0);
    CHECK(strcmp(s.tasks[0].name, "diffuse") == 0 && s.tasks[0].pvd == NULL);
    pst_scene_free(&s);
    CHECK_INT(parse(&s, "{\"tasks\": [{\"type\": \"solve\", \"rhs\": \"t\", \"exact\": \"x\"}]}",
                    NULL, 0), PST_OK);
    CHECK_INT(pst_scene_compile_exprs(&s, err, sizeof err), PST_EINPUT);
    CHECK(strstr(err, "t.json: tasks[0].rhs: ") == err);
    pst_scene_free(&s);

#define DIFFUSE "{\"tasks\": [{\"type\": \"diffuse\", \"initial\": \"x\", \"t_end\": 1, "
    EXPECT_ERROR(DIFFUSE "\"method\": \"crank_nicolson\"}]}",
                 "t.json:1:12: key 'tasks.0.dt': missing: the implicit methods need a step (the "
                 "automatic one is the explicit method's stability limit)");
    EXPECT_ERROR(DIFFUSE "\"dt\": 0.1, \"safety\": 0.5}]}",
                 "t.json:1:71: key 'tasks.0.safety': applies only to method explicit");
    EXPECT_ERROR(DIFFUSE "\"method\": \"explicit\", \"dt\": 0.1, \"safety\": 0.5}]}",
                 "t.json:1:93: key 'tasks.0.safety': applies only without dt (the step is dt)");
    EXPECT_ERROR(DIFFUSE "\"method\": \"explicit\", \"rtol\": 1e-6}]}",
                 "t.json:1:82: key 'tasks.0.rtol': applies only to the implicit methods");
    EXPECT_ERROR(DIFFUSE "\"dt\": 0.1, \"skin\": 0.5}]}",
                 "t.json:1:71: key 'tasks.0.skin': applies only with velocity");
    EXPECT_ERROR(DIFFUSE "\"dt\": 0.1, \"output_every\": 5}]}",
                 "t.json:1:71: key 'tasks.0.output_every': applies only with pvd");
    EXPECT_ERROR(DIFFUSE "\"dt\": 0.1, \"pvd\": \"a.vtu\"}]}",
                 "t.json:1:71: key 'tasks.0.pvd': 'a.vtu': expected a .pvd file name");
    EXPECT_ERROR(DIFFUSE "\"dt\": 0.1, \"pvd\": \"a.pvd\", \"steps_csv\": \"a.pvd\"}]}",
                 "t.json:1:87: key 'tasks.0.steps_csv': the same file as pvd");
    EXPECT_ERROR(DIFFUSE "\"dt\": 0.1, \"velocity\": \"x\"}]}",
                 "t.json:1:71: key 'tasks.0.velocity': needs a list of 2 expressions (one per "
                 "axis), got 1");
    EXPECT_ERROR(DIFFUSE "\"dt\": 0.1, \"max_steps\": 0}]}",
                 "t.json:1:71: key 'tasks.0.max_steps': must be in [1, 1000000], got 0");
    EXPECT_ERROR("{\"tasks\": [{\"type\": \"diffuse\", \"initial\": \"x\", \"dt\": 1}]}",
                 "t.json:1:12: key 'tasks.0.t_end': missing required key (for tasks of type "
                 "diffuse)");
    EXPECT_ERROR("{\"tasks\": [{\"type\": \"solve\", \"rhs\": \"0\", \"exact\": \"x\", "
                 "\"initial\": \"x\"}]}",
                 "t.json:1:56: key 'tasks.0.initial': applies only to tasks of type diffuse");
    EXPECT_ERROR("{\"fields\": {\"u\": \"x\"}, \"tasks\": [{\"type\": \"laplacian\", "
                 "\"field\": \"u\"},\n{\"type\": \"diffuse\", \"initial\": \"x\", \"t_end\": 1, "
                 "\"dt\": 0.1, \"velocity\": [\"y\", \"x\"]}]}",
                 "t.json:2:60: key 'tasks.1.velocity': moves the particles, so the task must be "
                 "the scene's only one (there are 2)");
#undef DIFFUSE
}

static void test_overrides(void)
{
    pst_scene s;
    const char *ov[] = {"cloud.jitter=0.3",
                        "tasks.0.norms=[\"max_rel\"]",
                        "tasks.1.region=all",
                        "fields.v=x*y",
                        "cloud.lo=[0.5,0,0]",
                        "title=hello world",
                        "tasks.2.type=hessian",
                        "tasks.2.field=v",
                        "tasks.0.norms.1=lv95",
                        "outputs.csv=out/a.csv",
                        "cloud.seed=12"};
    CHECK_INT(pst_scene_default(&s, ov, (int)(sizeof ov / sizeof ov[0]), err, sizeof err),
              PST_OK);
    CHECK(s.cloud.jitter == 0.3);
    CHECK(s.cloud.lo[0] == 0.5);
    CHECK_INT(s.cloud.seed, 12);
    CHECK(strcmp(s.title, "hello world") == 0);
    CHECK_INT(s.nfields, 2);
    CHECK(strcmp(s.fields[1].name, "v") == 0 && strcmp(s.fields[1].expr, "x*y") == 0);
    CHECK_INT(s.tasks[0].nnorms, 2);
    CHECK_INT(s.tasks[0].norms[0], SC_NORM_MAX_REL);
    CHECK_INT(s.tasks[0].norms[1], SC_NORM_LV95);
    CHECK_INT(s.tasks[1].region, SC_REGION_ALL);
    CHECK_INT(s.ntasks, 3);
    CHECK_INT(s.tasks[2].type, SC_TASK_HESSIAN);
    CHECK(strcmp(s.tasks[2].name, "hessian") == 0);
    CHECK(strcmp(s.out.csv, "out/a.csv") == 0); /* outputs are not resolved */
    pst_scene_free(&s);

    /* the dimension can change, and the vectors with it */
    const char *ov2[] = {"dim=2", "cloud.lo=[0,0]", "cloud.hi=[2,1]",
                         "tasks.1.exact=[\"a\",\"b\"]", "fields.u=sin(x)"};
    CHECK_INT(pst_scene_default(&s, ov2, 5, err, sizeof err), PST_OK);
    CHECK_INT(s.dim, 2);
    CHECK(s.cloud.hi[0] == 2 && s.cloud.hi[2] == 0);
    CHECK(strcmp(s.fields[0].expr, "sin(x)") == 0);
    pst_scene_free(&s);

    const char *dflt = "{}";
    const char *o1[] = {"cloud.jiter=0.3"};
    EXPECT_ERROR_OV(dflt, o1,
                    "override 'cloud.jiter=0.3': unknown key 'cloud.jiter' (did you mean "
                    "'cloud.jitter'?)");
    const char *o2[] = {"cloud.jitter=abc"};
    EXPECT_ERROR_OV(dflt, o2,
                    "override 'cloud.jitter=abc': key 'cloud.jitter': expected a number, got "
                    "a string");
    const char *o3[] = {"tasks.1.rtol=1e-8"};
    EXPECT_ERROR_OV(dflt, o3,
                    "override 'tasks.1.rtol=1e-8': key 'tasks.1': index 1 is past the end of "
                    "the list (0 items)");
    const char *o4[] = {"tasks.0.rtol=1e-8"};
    EXPECT_ERROR_OV(dflt, o4,
                    "override 'tasks.0.rtol=1e-8': key 'tasks.0.type': missing required key");
    const char *o5[] = {"tasks.x=1"};
    EXPECT_ERROR_OV(dflt, o5, "override 'tasks.x=1': key 'tasks.x': 'x' is not a list index");
    const char *o6[] = {"novalue"};
    EXPECT_ERROR_OV(dflt, o6, "override 'novalue': expected KEY=VALUE");
    const char *o7[] = {"dim.x=1"};
    EXPECT_ERROR_OV(dflt, o7, "override 'dim.x=1': unknown key 'dim.x'");
    const char *o8[] = {"cloud=3"};
    EXPECT_ERROR_OV(dflt, o8, "override 'cloud=3': key 'cloud': expected an object, got a number");
    const char *o9[] = {"dim=4"};
    EXPECT_ERROR_OV(dflt, o9, "override 'dim=4': key 'dim': must be one of 2, 3, got 4");
    /* an error in the file is still reported at its position when overrides are given */
    const char *o10[] = {"cloud.jitter=0.1"};
    EXPECT_ERROR_OV("{\"cloud\": {\"spacing\": -1}}", o10,
                    "t.json:1:12: key 'cloud.spacing': must be > 0, got -1");
}

static void test_errors(void)
{
    EXPECT_ERROR("{\n  \"cloud\": {\n    \"jiter\": 0.3\n  }\n}",
                 "t.json:3:5: key 'cloud.jiter': unknown key (did you mean 'cloud.jitter'?)");
    EXPECT_ERROR("{\"titel\": \"x\"}",
                 "t.json:1:2: key 'titel': unknown key (did you mean 'title'?)");
    EXPECT_ERROR("{\"zzz\": 1}", "t.json:1:2: key 'zzz': unknown key");
    EXPECT_ERROR("{\"cloud\": {\"spacing\": \"big\"}}",
                 "t.json:1:12: key 'cloud.spacing': expected a number, got a string");
    EXPECT_ERROR("{\"cloud\": {\"boundary_layer\": 1}}",
                 "t.json:1:12: key 'cloud.boundary_layer': expected true or false, got a number");
    EXPECT_ERROR("{\"cloud\": []}", "t.json:1:2: key 'cloud': expected an object, got a list");
    EXPECT_ERROR("{\"dim\": 2.5}", "t.json:1:2: key 'dim': expected an integer, got 2.5");
    EXPECT_ERROR("{\"cloud\": {\"jitter\": 1.5}}",
                 "t.json:1:12: key 'cloud.jitter': must be in [0, 1), got 1.5");
    EXPECT_ERROR("{\"limits\": {\"memory_fraction\": 0}}",
                 "t.json:1:13: key 'limits.memory_fraction': must be in (0, 1], got 0");
    EXPECT_ERROR("{\"cloud\": {\"seed\": -1}}",
                 "t.json:1:12: key 'cloud.seed': must be >= 0, got -1");
    EXPECT_ERROR("{\"tasks\": [{\"type\": \"solve\", \"rhs\": \"0\", \"exact\": \"x\", "
                 "\"amg_pmax\": 101}]}",
                 "t.json:1:56: key 'tasks.0.amg_pmax': must be in [0, 100], got 101");
    EXPECT_ERROR("{\"tasks\": [{\"type\": \"solve\", \"rhs\": \"1\", \"exact\": \"0\",\n"
                 "  \"rtol\": 1.5}]}",
                 "t.json:2:3: key 'tasks.0.rtol': must be in (0, 1), got 1.5");
    EXPECT_ERROR("{\"dim\": 3, \"cloud\": {\"lo\": [0, 0]}}",
                 "t.json:1:22: key 'cloud.lo': expected 3 numbers (dim = 3), got 2");
    EXPECT_ERROR("{\"cloud\": {\"hi\": [1, \"2\"]}}",
                 "t.json:1:22: key 'cloud.hi.1': expected a number, got a string");
    EXPECT_ERROR("{\"cloud\": {\"source\": \"latice\"}}",
                 "t.json:1:12: key 'cloud.source': unknown value 'latice' (one of lattice, "
                 "cell_centred, file; did you mean 'lattice'?)");
    /* the registered schemes are listed, whichever they are */
    char want[PST_ERRLEN];
    size_t n = (size_t)snprintf(want, sizeof want, "t.json:1:15: key 'operator.scheme': "
                                                   "unknown scheme 'qsfd' (one of ");
    for (int i = 0; i < pst_scheme_count(); ++i)
        n += (size_t)snprintf(want + n, sizeof want - n, "%s%s", i ? ", " : "",
                              pst_scheme_name(i));
    snprintf(want + n, sizeof want - n, "; did you mean 'qsfdi'?)");
    EXPECT_ERROR("{\"operator\": {\"scheme\": \"qsfd\"}}", want);
    /* missing required keys: at the object that lacks them */
    EXPECT_ERROR("{\"tasks\": [\n  {\"field\": \"u\"}]}",
                 "t.json:2:3: key 'tasks.0.type': missing required key");
    EXPECT_ERROR("{\"tasks\": [{\"type\": \"solve\", \"exact\": \"0\"}]}",
                 "t.json:1:12: key 'tasks.0.rhs': missing required key (for tasks of type "
                 "solve)");
    EXPECT_ERROR("{\"cloud\": {\"source\": \"file\"}}",
                 "t.json:1:2: key 'cloud.file': missing required key (when 'cloud.source' is "
                 "file)");
    EXPECT_ERROR("{\"tasks\": [{\"type\": \"solve\", \"rhs\": \"0\", \"boundary\": [{}]}]}",
                 "t.json:1:55: key 'tasks.0.boundary.0.value': missing required key");
    /* keys that do not apply */
    EXPECT_ERROR("{\"fields\": {\"u\": \"x\"},\n \"tasks\": [{\"type\": \"laplacian\", "
                 "\"field\": \"u\", \"rtol\": 1e-8}]}",
                 "t.json:2:48: key 'tasks.0.rtol': applies only to tasks of type solve, "
                 "diffuse");
    EXPECT_ERROR("{\"tasks\": [{\"type\": \"solve\", \"rhs\": \"0\", \"field\": \"u\"}]}",
                 "t.json:1:42: key 'tasks.0.field': applies only to tasks of type laplacian, "
                 "divergence, gradient, hessian, interpolate");
    EXPECT_ERROR("{\"cloud\": {\"source\": \"cell_centred\", \"boundary_layer\": false}}",
                 "t.json:1:38: key 'cloud.boundary_layer': applies only when 'cloud.source' is "
                 "lattice");
    EXPECT_ERROR("{\"mobility\": {\"value\": 2}}",
                 "t.json:1:15: key 'mobility.value': applies only when 'mobility.type' is "
                 "constant");
    /* names */
    EXPECT_ERROR("{\"fields\": {\"v\": \"x\"}, \"tasks\": [{\"type\": \"gradient\", "
                 "\"field\": \"vv\"}]}",
                 "t.json:1:55: key 'tasks.0.field': field 'vv' is not declared in 'fields' "
                 "(did you mean 'v'?)");
    EXPECT_ERROR("{\"fields\": {\"u\": \"x\"}, \"tasks\": [{\"type\": \"laplacian\", "
                 "\"field\": \"u\", \"name\": \"a\"},\n{\"type\": \"gradient\", \"field\": \"u\", "
                 "\"name\": \"a\"}]}",
                 "t.json:2:36: key 'tasks.1.name': duplicate task name 'a' (also tasks.0.name)");
    EXPECT_ERROR("{\"fields\": {\"u\": \"x\"}, \"tasks\": [{\"type\": \"laplacian\", "
                 "\"field\": \"u\", \"name\": \"u\"}]}",
                 "t.json:1:70: key 'tasks.0.name': 'u' is already the name of a field");
    EXPECT_ERROR("{\"fields\": {\"2u\": \"x\"}}",
                 "t.json:1:13: key 'fields.2u': a field name must be a C identifier (letters, "
                 "digits and _, not starting with a digit, at most 63 characters)");
    EXPECT_ERROR("{\"fields\": {\"kind\": \"x\"}}",
                 "t.json:1:13: key 'fields.kind': 'kind' is a column of the CSV format, not a "
                 "field name");
    EXPECT_ERROR("{\"fields\": {\"u\": \" \"}}",
                 "t.json:1:13: key 'fields.u': the expression is empty");
    EXPECT_ERROR("{\"outputs\": {\"fields\": [\"u\"]}}",
                 "t.json:1:25: key 'outputs.fields.0': name 'u' is not a field or a task name");
    /* counts */
    EXPECT_ERROR("{\"fields\": {\"u\": \"x\"}, \"tasks\": [{\"type\": \"gradient\", "
                 "\"field\": \"u\", \"exact\": [\"1\", \"2\", \"3\"]}]}",
                 "t.json:1:69: key 'tasks.0.exact': a gradient task in 2D needs a list of 2 "
                 "expressions, got 3");
    EXPECT_ERROR("{\"fields\": {\"u\": \"x\"}, \"tasks\": [{\"type\": \"hessian\", "
                 "\"field\": \"u\", \"exact\": \"1\"}]}",
                 "t.json:1:68: key 'tasks.0.exact': a hessian task in 2D needs a list of 3 "
                 "expressions, got a single expression, not 1");
    EXPECT_ERROR("{\"fields\": {\"u\": \"x\"}, \"tasks\": [{\"type\": \"laplacian\", "
                 "\"field\": \"u\", \"norms\": [\"rel_l2\"]}]}",
                 "t.json:1:70: key 'tasks.0.norms': error norms need an exact solution "
                 "('exact')");
    EXPECT_ERROR("{\"mobility\": {\"type\": \"expression\", \"expression\": [\"1\", \"2\", "
                 "\"3\"]}}",
                 "t.json:1:37: key 'mobility.expression': expected one expression or a list of "
                 "2 (one per axis), got 3");
    EXPECT_ERROR("{\"tasks\": [{\"type\": \"solve\", \"rhs\": \"0\"}]}",
                 "t.json:1:12: key 'tasks.0': a solve without 'boundary' needs 'exact' (its "
                 "Dirichlet values)");
    EXPECT_ERROR("{\"cloud\": {\"spacing\": 0.3}}",
                 "t.json:1:12: key 'cloud.spacing': the box length along x (1) is not a whole "
                 "number of spacings (ratio 3.33333333333333)");
    EXPECT_ERROR("{\"cloud\": {\"lo\": [0, 2]}}",
                 "t.json:1:2: key 'cloud.hi': must exceed lo along y (lo 2, hi 1)");
    EXPECT_ERROR("{\"tasks\": [{\"type\": \"solve\", \"rhs\": \"0\", \"boundary\": "
                 "[{\"where\": \"zlo\", \"value\": \"0\"}]}]}",
                 "t.json:1:56: key 'tasks.0.boundary.0.where': there is no z side in 2D");
    EXPECT_ERROR("{\"fields\": {\"u\": \"x\"}, \"tasks\": [{\"type\": \"interpolate\", "
                 "\"field\": \"u\", \"points\": {\"lo\": [0, 0], \"spacing\": 0.1}}]}",
                 "t.json:1:72: key 'tasks.0.points.hi': missing (a point lattice needs lo, hi "
                 "and spacing)");

    /* too many tasks and fields: at the first one too many */
    char big[8192];
    n = (size_t)snprintf(big, sizeof big, "{\"fields\": {\"u\": \"x\"}, \"tasks\": [");
    for (int i = 0; i <= SC_MAX_TASKS; ++i)
        n += (size_t)snprintf(big + n, sizeof big - n, "%s\n{\"type\": \"laplacian\", "
                              "\"field\": \"u\"}", i ? "," : "");
    snprintf(big + n, sizeof big - n, "]}");
    EXPECT_ERROR(big, "t.json:34:1: key 'tasks.32': too many items in 'tasks' (at most 32)");
    n = (size_t)snprintf(big, sizeof big, "{\"fields\": {");
    for (int i = 0; i <= SC_MAX_FIELDS; ++i)
        n += (size_t)snprintf(big + n, sizeof big - n, "%s\n\"f%d\": \"x\"", i ? "," : "", i);
    snprintf(big + n, sizeof big - n, "}}");
    EXPECT_ERROR(big, "t.json:34:1: key 'fields.f32': too many entries in 'fields' (at most "
                      "32)");
}

static void test_edges(void)
{
    EXPECT_ERROR("", "t.json:1:1: empty file (expected a JSON object)");
    EXPECT_ERROR(" \n\t", "t.json:2:2: empty file (expected a JSON object)");
    EXPECT_ERROR("[1, 2]", "t.json:1:1: a scene must be a JSON object, got a list");
    EXPECT_ERROR("  \"x\"", "t.json:1:3: a scene must be a JSON object, got a string");
    /* syntax errors: where cJSON stopped */
    EXPECT_ERROR("{\n  \"dim\": 2,\n  \"cloud\": {\"spacing\": 0.1,}\n}",
                 "t.json:3:28: JSON syntax error near '}'");
    EXPECT_ERROR("{\"dim\": 2", "t.json:1:10: JSON syntax error: unexpected end of the text");
    EXPECT_ERROR("{\"dim\": 2} x", "t.json:1:12: JSON syntax error near 'x'");
    EXPECT_ERROR("{\"cloud\": {\"spacing\": NaN}}", "t.json:1:23: JSON syntax error near 'NaN}}'");
    EXPECT_ERROR("{\"cloud\": {\"spacing\": \"NaN\"}}",
                 "t.json:1:12: key 'cloud.spacing': expected a number, got a string");
    EXPECT_ERROR("{\"cloud\": {\"spacing\": 1e999}}",
                 "t.json:1:12: key 'cloud.spacing': number out of range (not a finite double)");
    EXPECT_ERROR("{\"cloud\": {\"seed\": 1e300}}",
                 "t.json:1:12: key 'cloud.seed': expected an integer, got 1e+300");
    EXPECT_ERROR("{\"dim\": 2, \"dim\": 3}",
                 "t.json:1:12: key 'dim': duplicate key (an earlier 'dim' is in the same object)");
    EXPECT_ERROR("{\"cloud\": {\"jitter\": 0.1},\n \"cloud\": {}}",
                 "t.json:2:2: key 'cloud': duplicate key (an earlier 'cloud' is in the same "
                 "object)");
    /* an escaped key is found where it is written */
    EXPECT_ERROR("{\"cl\\u006fud\": {\"j\\u00e9\": 1}}",
                 "t.json:1:17: key 'cloud.j\xc3\xa9': unknown key");
    /* a key with table syntax in it is not a way in */
    EXPECT_ERROR("{\"cloud.spacing\": 1}", "t.json:1:2: key 'cloud.spacing': unknown key");
    /* junk nested below an unknown key is not looked at; nesting past cJSON's limit is said
     * to be that, naming the limit, at the first bracket past it */
    EXPECT_ERROR("{\"cloud\": {\"x\": {\"a\": [[[{\"b\": {}}]]]}}}",
                 "t.json:1:12: key 'cloud.x': unknown key");
    size_t deep = 5000;
    char *text = malloc(2 * deep + 1);
    memset(text, '[', deep);
    memset(text + deep, ']', deep);
    text[2 * deep] = '\0';
    pst_scene s;
    CHECK_INT(pst_scene_parse(&s, text, "t.json", NULL, 0, err, sizeof err), PST_EINPUT);
    CHECK(strcmp(err, "t.json:1:1001: JSON nested deeper than 1000 levels") == 0);
    free(text);
    text = malloc(6 * deep + 1); /* {"a":{"a":... : objects count too, strings do not */
    size_t n = (size_t)sprintf(text, "{\"[[\":");
    for (size_t k = 1; k < 1100; ++k)
        n += (size_t)sprintf(text + n, "{\"a\":");
    n += (size_t)sprintf(text + n, "1");
    for (size_t k = 0; k < 1100; ++k)
        text[n++] = '}';
    text[n] = '\0';
    CHECK_INT(pst_scene_parse(&s, text, "t.json", NULL, 0, err, sizeof err), PST_EINPUT);
    CHECK(strcmp(err, "t.json:1:5002: JSON nested deeper than 1000 levels") == 0);
    free(text);
    /* control bytes of the input are escaped in the message */
    EXPECT_ERROR("{\"a\\u0001b\\u001b[2J\": 1}", "t.json:1:2: key 'a\\x01b\\x1b[2J': unknown key");
    /* bad arguments */
    CHECK_INT(pst_scene_parse(&s, NULL, "t.json", NULL, 0, err, sizeof err), PST_EINVAL);
    CHECK_INT(pst_scene_parse(&s, "{}", "t.json", NULL, 1, NULL, 0), PST_EINVAL);
}

static void test_positions(void)
{
    int line, col;
    json_pos_offset("ab\ncd", 4, &line, &col);
    CHECK(line == 2 && col == 2);
    json_pos_offset("\xc3\xa9\xc3\xa9x", 4, &line, &col); /* two 2-byte characters */
    CHECK(line == 1 && col == 3);
    json_pos_offset("ab", 99, &line, &col); /* clamped at the NUL */
    CHECK(line == 1 && col == 3);
    const char *t = "{\"a\": [1, {\"b\": 2, \"b\": [3, 4]}],\n \"c\\\"d\": {}, \"e\": \"]}\"}";
    json_step p1[] = {{"a", 0}, {NULL, 1}, {"b", 1}, {NULL, 1}};
    CHECK_INT(json_pos_find(t, p1, 4, &line, &col), 4);
    CHECK(line == 1 && col == 29);
    json_step p2[] = {{"c\"d", 0}};
    CHECK_INT(json_pos_find(t, p2, 1, &line, &col), 1);
    CHECK(line == 2 && col == 2);
    json_step p3[] = {{"e", 0}};
    CHECK_INT(json_pos_find(t, p3, 1, &line, &col), 1);
    CHECK(line == 2 && col == 14);
    json_step p4[] = {{"a", 0}, {NULL, 1}, {"zz", 0}};
    CHECK_INT(json_pos_find(t, p4, 3, &line, &col), 2); /* the deepest found: a[1] */
    CHECK(line == 1 && col == 11);
    json_step p5[] = {{"a", 0}, {NULL, 7}};
    CHECK_INT(json_pos_find(t, p5, 2, &line, &col), 1);
    CHECK(line == 1 && col == 2);
    /* malformed or truncated text never faults */
    const char *bad[] = {"", "{", "{\"a", "{\"a\"", "{\"a\":", "{\"a\": [", "{\"a\": \"\\",
                         "{\"a\": \"\\u12", "[", "\"x", "{\"a\" 1}", "{\"a\": [1 2]}"};
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; ++k) {
        json_step p[] = {{"a", 0}, {NULL, 1}};
        int found = json_pos_find(bad[k], p, 2, &line, &col);
        CHECK(found >= 0 && found <= 2 && line == 1 && col >= 1);
    }
    json_pos_error("ab\ncd", NULL, &line, &col);
    CHECK(line == 2 && col == 3);
}

/* pst_scene_load: files, relative paths, unreadable and NUL-carrying files. */
static void test_load(void)
{
    char dir[] = "/tmp/test_scene_XXXXXX";
    if (!mkdtemp(dir)) {
        CHECK(0);
        return;
    }
    char path[256], bad[256];
    snprintf(path, sizeof path, "%s/s.json", dir);
    snprintf(bad, sizeof bad, "%s/nul.json", dir);
    FILE *f = fopen(path, "w");
    fputs("{\"cloud\": {\"source\": \"file\", \"file\": \"c.csv\"}}\n", f);
    fclose(f);
    f = fopen(bad, "wb");
    fwrite("{\n \"a\0\": 1}", 1, 11, f);
    fclose(f);
    pst_scene s;
    CHECK_INT(pst_scene_load(&s, path, NULL, 0, err, sizeof err), PST_OK);
    char want[300];
    snprintf(want, sizeof want, "%s/c.csv", dir);
    CHECK(s.cloud.file && strcmp(s.cloud.file, want) == 0);
    pst_scene_free(&s);
    char missing[256];
    snprintf(missing, sizeof missing, "%s/none.json", dir);
    CHECK_INT(pst_scene_load(&s, missing, NULL, 0, err, sizeof err), PST_EIO);
    CHECK(strstr(err, "none.json: cannot open") != NULL);
    CHECK_INT(pst_scene_load(&s, bad, NULL, 0, err, sizeof err), PST_EINPUT);
    snprintf(want, sizeof want, "%s:2:4: a NUL byte in the file", bad);
    CHECK(strcmp(err, want) == 0);
    remove(path);
    remove(bad);
    rmdir(dir);
}

static uint64_t rng_state = 12345;
static uint64_t rnd64(void) /* splitmix64 */
{
    uint64_t z = (rng_state += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}
static size_t rndi(size_t n) { return (size_t)(rnd64() % n); }

/* Mutations of the example scene (every section, every task type) must parse or fail with
 * "t.json:L:C: ": byte flips, deletions, truncations, insertions, copied bytes. */
static void test_fuzz(void)
{
    const char *base = pst_scene_example();
    pst_scene s;
    static const char alphabet[] = "{}[]:,\"\\0123456789.eE+-truefalsnul xyz\n\t";
    size_t cap = strlen(base) + 64;
    char *text = malloc(cap);
    int parsed = 0, failed = 0, bad = 0;
    for (int iter = 0; iter < 4000; ++iter) {
        snprintf(text, cap, "%s", base);
        int mutations = 1 + (int)rndi(4);
        for (int m = 0; m < mutations; ++m) {
            size_t len = strlen(text);
            size_t at = rndi(len + 1);
            switch (rndi(5)) {
            case 0: /* flip a byte to a structural or random one (never NUL) */
                if (at < len)
                    text[at] = rndi(2) ? alphabet[rndi(sizeof alphabet - 1)]
                                       : (char)(1 + rndi(255));
                break;
            case 1: /* delete a run */
                if (at < len) {
                    size_t k = 1 + rndi(8);
                    if (k > len - at)
                        k = len - at;
                    memmove(text + at, text + at + k, len - at - k + 1);
                }
                break;
            case 2: /* truncate */
                text[at] = '\0';
                break;
            case 3: /* insert a character */
                if (len + 2 < cap) {
                    memmove(text + at + 1, text + at, len - at + 1);
                    text[at] = alphabet[rndi(sizeof alphabet - 1)];
                }
                break;
            default: /* copy a byte from elsewhere: quotes and brackets move */
                if (at < len && len > 0)
                    text[at] = text[rndi(len)];
                break;
            }
        }
        int rc = pst_scene_parse(&s, text, "t.json", NULL, 0, err, sizeof err);
        int line = 0, col = 0;
        if (rc == PST_OK) {
            ++parsed;
            pst_scene_free(&s);
        } else if (rc == PST_EINPUT && sscanf(err, "t.json:%d:%d: ", &line, &col) == 2 &&
                   line >= 1 && col >= 1) {
            ++failed;
        } else {
            ++bad;
            if (bad <= 5)
                fprintf(stderr, "fuzz %d: rc %d, message without a position: %s\n", iter, rc,
                        err);
        }
    }
    free(text);
    CHECK_INT(bad, 0);
    CHECK(parsed > 100 && failed > 1000); /* both outcomes are exercised */
    printf("fuzz: %d parsed, %d failed cleanly\n", parsed, failed);
}

/* The markdown from the table, in a malloc'd string. */
static char *markdown(size_t *len)
{
    FILE *f = tmpfile();
    if (!f)
        return NULL;
    pst_scene_print_help(f, 1);
    long n = ftell(f);
    rewind(f);
    char *text = malloc((size_t)n + 1);
    if (text && fread(text, 1, (size_t)n, f) == (size_t)n) {
        text[n] = '\0';
        *len = (size_t)n;
    } else {
        free(text);
        text = NULL;
    }
    fclose(f);
    return text;
}

static void test_docs(void)
{
    size_t len = 0;
    char *want = markdown(&len);
    CHECK(want != NULL);
    FILE *f = fopen(PSTENCIL_SOURCE_DIR "/docs/scenes.md", "rb");
    char *have = malloc(len + 2);
    size_t got = f && have ? fread(have, 1, len + 1, f) : 0;
    if (f)
        fclose(f);
    int same = want && have && got == len && memcmp(want, have, len) == 0;
    CHECK(same);
    if (!same)
        fprintf(stderr, "docs/scenes.md differs from the table: regenerate it with "
                        "`test_scene --write-docs docs/scenes.md` (or `pstencil help scene "
                        "--markdown`)\n");
    /* the text help names every key */
    FILE *t = tmpfile();
    pst_scene_print_help(t, 0);
    long tn = ftell(t);
    rewind(t);
    char *text = malloc((size_t)tn + 1);
    size_t tg = fread(text, 1, (size_t)tn, t);
    text[tg] = '\0';
    fclose(t);
    for (int i = 0; i < sc_nparams; ++i)
        CHECK(strstr(text, sc_params[i].key) != NULL);
    free(text);
    free(want);
    free(have);
}

/* cloud.periodic (every axis, a list, the default), a file cloud's cloud.box, and their
 * refusals: wrong shapes, a rotated periodic lattice, a box on a generated cloud, a periodic
 * file cloud without one, a box without a periodic axis, a boundary side of a periodic axis. */
static void test_periodic(void)
{
    pst_scene s;
    CHECK_INT(parse(&s, "{\"cloud\": {\"periodic\": [true, false]}}", NULL, 0), PST_OK);
    CHECK(s.cloud.periodic[0] == 1 && s.cloud.periodic[1] == 0 && s.cloud.periodic[2] == 0);
    CHECK_INT(pst_scene_periodic_axes(&s), 1);
    pst_scene_free(&s);
    CHECK_INT(parse(&s, "{\"dim\": 3, \"cloud\": {\"periodic\": true}}", NULL, 0), PST_OK);
    CHECK(s.cloud.periodic[0] && s.cloud.periodic[1] && s.cloud.periodic[2]);
    pst_scene_free(&s);
    CHECK_INT(parse(&s, "{\"cloud\": {\"periodic\": true}}", NULL, 0), PST_OK);
    CHECK(s.cloud.periodic[0] && s.cloud.periodic[1] && !s.cloud.periodic[2]); /* 2D */
    pst_scene_free(&s);
    CHECK_INT(parse(&s, "{}", NULL, 0), PST_OK);
    CHECK_INT(pst_scene_periodic_axes(&s), 0);
    pst_scene_free(&s);
    /* a file cloud with its box, given by overrides too */
    const char *ov[] = {"cloud.periodic=[false,true]", "cloud.box.lo=[0,-1]", "cloud.box.hi=[2,1]"};
    CHECK_INT(parse(&s, "{\"cloud\": {\"source\": \"file\", \"file\": \"c.csv\"}}", ov, 3),
              PST_OK);
    CHECK(!s.cloud.periodic[0] && s.cloud.periodic[1]);
    CHECK(s.cloud.box_lo[0] == 0 && s.cloud.box_lo[1] == -1 && s.cloud.box_hi[0] == 2 &&
          s.cloud.box_hi[1] == 1);
    pst_scene_free(&s);
    /* fully periodic, a generated cloud has no boundary: a solve needs no exact values */
    CHECK_INT(parse(&s, "{\"cloud\": {\"periodic\": true}, \"tasks\": [{\"type\": "
                        "\"solve\", \"rhs\": \"sin(2*pi*x)\"}]}", NULL, 0), PST_OK);
    pst_scene_free(&s);
    EXPECT_ERROR("{\"cloud\": {\"periodic\": [true, false]}, \"tasks\": [{\"type\": "
                 "\"solve\", \"rhs\": \"0\"}]}",
                 "t.json:1:50: key 'tasks.0': a solve without 'boundary' needs 'exact' (its "
                 "Dirichlet values)");

    EXPECT_ERROR("{\"cloud\": {\"periodic\": [true]}}",
                 "t.json:1:12: key 'cloud.periodic': expected 2 booleans (dim = 2), got 1");
    EXPECT_ERROR("{\"cloud\": {\"periodic\": [true, 1]}}",
                 "t.json:1:31: key 'cloud.periodic.1': expected true or false, got a number");
    EXPECT_ERROR("{\"cloud\": {\"periodic\": \"xy\"}}",
                 "t.json:1:12: key 'cloud.periodic': expected true, false or a list of 2 "
                 "booleans (one per axis), got a string");
    EXPECT_ERROR("{\"cloud\": {\"periodic\": true, \"angle\": 30}}",
                 "t.json:1:30: key 'cloud.angle': a periodic lattice cannot be rotated "
                 "(cloud.periodic): its axes are the box's");
    EXPECT_ERROR("{\"cloud\": {\"periodic\": true, \"box\": {\"lo\": [0, 0], \"hi\": [1, 1]}}}",
                 "t.json:1:30: key 'cloud.box': applies only when 'cloud.source' is file");
    EXPECT_ERROR("{\"cloud\": {\"source\": \"file\", \"file\": \"c.csv\", \"periodic\": true}}",
                 "t.json:1:2: key 'cloud.box': missing: a file cloud with periodic axes "
                 "(cloud.periodic) needs its periodic box {lo, hi}");
    EXPECT_ERROR("{\"cloud\": {\"source\": \"file\", \"file\": \"c.csv\",\n"
                 "  \"box\": {\"lo\": [0, 0], \"hi\": [1, 1]}}}",
                 "t.json:2:3: key 'cloud.box': no axis is periodic (cloud.periodic): the box "
                 "applies only to periodic axes");
    EXPECT_ERROR("{\"cloud\": {\"source\": \"file\", \"file\": \"c.csv\", \"periodic\": true,\n"
                 "  \"box\": {\"lo\": [0, 0], \"hi\": [1, 0]}}}",
                 "t.json:2:25: key 'cloud.box.hi': must exceed lo along y (lo 0, hi 0)");
    EXPECT_ERROR("{\"cloud\": {\"source\": \"file\", \"file\": \"c.csv\", \"periodic\": true,\n"
                 "  \"box\": {\"lo\": [0, 0]}}}",
                 "t.json:2:3: key 'cloud.box.hi': missing required key");
    EXPECT_ERROR("{\"cloud\": {\"source\": \"file\", \"file\": \"c.csv\", \"periodic\": true,\n"
                 "  \"box\": {\"lo\": [0, 0], \"hi\": [1, 1, 1]}}}",
                 "t.json:2:25: key 'cloud.box.hi': expected 2 numbers (dim = 2), got 3");
    EXPECT_ERROR("{\"cloud\": {\"periodic\": [false, true]},\n"
                 " \"tasks\": [{\"type\": \"solve\", \"rhs\": \"0\", \"boundary\": [\n"
                 "   {\"where\": \"xlo\", \"value\": \"0\"}, {\"where\": \"yhi\", \"value\": "
                 "\"0\"}]}]}",
                 "t.json:3:37: key 'tasks.0.boundary.1.where': the y axis is periodic "
                 "(cloud.periodic): it has no sides");
}

/* Two outputs on one file would overwrite each other: refused, both keys named, the paths
 * compared after normalisation ("./x" is "x", "/tmp/../tmp/x" is "/tmp/x"). */
static void test_output_paths(void)
{
    EXPECT_ERROR("{\"outputs\": {\"csv\": \"out.vtu\", \"vtu\": \"out.vtu\"}}",
                 "t.json:1:32: key 'outputs.vtu': outputs.csv and outputs.vtu are the same file "
                 "'out.vtu': one would overwrite the other");
    EXPECT_ERROR("{\"outputs\": {\"vtu\": \"x.vtp\", \"report\": \".//./x.vtp\"}}",
                 "t.json:1:30: key 'outputs.report': outputs.vtu and outputs.report are the same "
                 "file './/./x.vtp': one would overwrite the other");
    /* outputs.vtu names its dataset by the extension */
    EXPECT_ERROR("{\"outputs\": {\"vtu\": \"x.vtk\"}}",
                 "t.json:1:14: key 'outputs.vtu': 'x.vtk': expected a .vtu (UnstructuredGrid) or "
                 ".vtp (PolyData) file name");
    const char *ov[] = {"outputs.report=/tmp/../tmp/r.json"};
    EXPECT_ERROR_OV("{\"outputs\": {\"csv\": \"/tmp/r.json\"}}", ov,
                    "override 'outputs.report=/tmp/../tmp/r.json': key 'outputs.report': "
                    "outputs.csv and outputs.report are the same file '/tmp/../tmp/r.json': one "
                    "would overwrite the other");
    pst_scene s;
    CHECK_INT(parse(&s, "{\"outputs\": {\"csv\": \"a.csv\", \"vtu\": \"a.vtu\", "
                        "\"report\": \"sub/a.csv\"}}", NULL, 0), PST_OK);
    pst_scene_free(&s);
}

int main(int argc, char **argv)
{
    if (argc == 3 && strcmp(argv[1], "--write-docs") == 0) {
        FILE *f = fopen(argv[2], "wb");
        if (!f)
            return 1;
        pst_scene_print_help(f, 1);
        return fclose(f) == 0 ? 0 : 1;
    }
    double t0 = omp_get_wtime();
    test_default();
    test_minimal();
    test_example();
    test_tasks();
    test_steps();
    test_overrides();
    test_errors();
    test_edges();
    test_positions();
    test_load();
    test_fuzz();
    test_docs();
    test_output_paths();
    test_periodic();
    printf("test_scene: %.2f s\n", omp_get_wtime() - t0);
    return check_summary("test_scene");
}
