/* Sweeps (src/app/sweep_*.c, docs/sweeps.md): a tiny 2D sweep runs, its CSV has the header
 * and the rows it should, the summary has its groups and a qsfdi convergence slope of second
 * order, --resume reruns nothing and leaves the same bytes (and reruns exactly what is missing
 * or failed), failing combinations become failed rows, the summary recomputed from the CSV
 * equals the one written, the statistics of a hand-made table are the known ones, errors in
 * sweep files name the key and its position, and every sweep file of scenes/sweeps parses and
 * plans. */
#define _POSIX_C_SOURCE 200809L /* mkdtemp */
#include "check.h"
#include "support.h"
#include "sweep.h"

#include "pstencil.h"

#include <cjson/cJSON.h>
#include <dirent.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char dir[256];

static char *slurp(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *s = malloc((size_t)n + 1);
    size_t got = fread(s, 1, (size_t)n, f);
    fclose(f);
    s[got] = '\0';
    if (len)
        *len = got;
    return s;
}

static void spit(const char *path, const char *text)
{
    FILE *f = fopen(path, "wb");
    fputs(text, f);
    fclose(f);
}

/* A sweep over an inline scene: the direct Laplacian of sin(6x + 8y) on a lightly jittered
 * lattice; `grid` and `tasks` are spliced in. Outputs go to dir/NAME.csv, NAME.summary.json. */
static char *sweep_text(const char *name, const char *grid, const char *tasks)
{
    static char buf[4096];
    snprintf(buf, sizeof buf,
             "{\n"
             "  \"scene\": {\n"
             "    \"dim\": 2,\n"
             "    \"cloud\": { \"source\": \"lattice\", \"lo\": [0, 0], \"hi\": [1, 1],\n"
             "               \"spacing\": 0.05, \"jitter\": 0.05, \"seed\": 1,\n"
             "               \"boundary_layer\": true, \"h_ratio\": 1.2 },\n"
             "    \"operator\": { \"scheme\": \"qsfdi\" },\n"
             "    \"fields\": { \"u\": \"sin(6*x + 8*y)\" },\n"
             "    \"tasks\": %s\n"
             "  },\n"
             "  \"grid\": %s,\n"
             "  \"output\": { \"csv\": \"%s/%s.csv\", \"summary\": \"%s/%s.summary.json\" }\n"
             "}\n",
             tasks, grid, dir, name, dir, name);
    return buf;
}

static const char *lap_task =
    "[ { \"type\": \"laplacian\", \"name\": \"lap\", \"field\": \"u\",\n"
    "      \"exact\": \"-100*sin(6*x + 8*y)\", \"norms\": [\"rel_l2\", \"max_abs\"] } ]";

static int parse(pst_sweep *sw, const char *name, const char *text, char *err, size_t errlen)
{
    char path[512];
    snprintf(path, sizeof path, "%s/%s.json", dir, name);
    spit(path, text);
    return pst_sweep_parse(sw, text, path, err, errlen);
}

static const cJSON *find_fit(const cJSON *sum, const char *scheme, const char *norm)
{
    const cJSON *f;
    cJSON_ArrayForEach(f, cJSON_GetObjectItem(sum, "fits"))
    {
        const cJSON *k = cJSON_GetObjectItem(f, "key");
        if (strcmp(cJSON_GetStringValue(cJSON_GetObjectItem(k, "operator.scheme")), scheme) == 0 &&
            strcmp(cJSON_GetStringValue(cJSON_GetObjectItem(f, "norm")), norm) == 0)
            return f;
    }
    return NULL;
}

/* Read the sweep CSV DIR/NAME.csv into t. */
static void read_result(const char *name, pst_csv_table *t)
{
    char path[512], err[PST_ERRLEN];
    snprintf(path, sizeof path, "%s/%s.csv", dir, name);
    CHECK_INT(pst_csv_read_table(t, path, 0, err), PST_OK);
}

/* The summary in the file without what the CSV does not hold, against the one from the CSV. */
static void check_summary_from_csv(const char *name, const pst_sweep *sw)
{
    char path[512];
    snprintf(path, sizeof path, "%s/%s.summary.json", dir, name);
    char *text = slurp(path, NULL);
    cJSON *written = text ? cJSON_Parse(text) : NULL;
    free(text);
    CHECK(written != NULL);
    cJSON_DeleteItemFromObject(written, "machine");
    cJSON_DeleteItemFromObject(written, "compiler_flags");
    cJSON_DeleteItemFromObject(written, "sweep");
    cJSON_DeleteItemFromObject(written, "csv");
    /* the operators' parameters come from the scenes, not the CSV: one entry per distinct
     * set, each with the thresholds in force and its scheme's fallback chain */
    const cJSON *params = cJSON_GetObjectItem(written, "operator_parameters"), *p;
    CHECK(cJSON_GetArraySize(params) >= 1);
    cJSON_ArrayForEach(p, params) {
        const char *scheme = cJSON_GetStringValue(cJSON_GetObjectItem(p, "scheme"));
        const char *fb = cJSON_GetStringValue(cJSON_GetObjectItem(p, "fallback"));
        CHECK(scheme && fb && pst_scheme_fallback(scheme) &&
              strcmp(fb, pst_scheme_fallback(scheme)) == 0);
        CHECK_NEAR(cJSON_GetNumberValue(cJSON_GetObjectItem(p, "min_pair_distance")), 1e-8, 0);
        CHECK_NEAR(cJSON_GetNumberValue(cJSON_GetObjectItem(p, "cond_max")), 1e10, 0);
    }
    cJSON_DeleteItemFromObject(written, "operator_parameters");
    pst_csv_table t;
    read_result(name, &t);
    cJSON *again = pst_sweep_summary(&t, sw->slope_key, sw->repeat_key);
    CHECK(again != NULL);
    CHECK(cJSON_Compare(written, again, 1));
    cJSON_Delete(again);
    cJSON_Delete(written);
    pst_csv_table_free(&t);
}

static void test_tiny_sweep(void)
{
    const char *grid = "{ \"operator.scheme\": [\"qsfdi\", \"lpmps\"],\n"
                       "    \"cloud.spacing\": [0.1, 0.05, 0.025],\n"
                       "    \"cloud.seed\": { \"from\": 1, \"count\": 2 } }";
    pst_sweep sw;
    char err[2048];
    int st = parse(&sw, "tiny", sweep_text("tiny", grid, lap_task), err, sizeof err);
    if (st != PST_OK)
        printf("parse: %s\n", err);
    CHECK_INT(st, PST_OK);
    if (st != PST_OK)
        return;
    CHECK_INT(sw.ncombos, 12);
    CHECK_INT(sw.nkeys, 3);
    const char *vals[SW_MAX_KEYS];
    pst_sweep_combo(&sw, 0, vals); /* the last key fastest */
    CHECK(strcmp(vals[0], "\"qsfdi\"") == 0 && strcmp(vals[1], "0.1") == 0 &&
          strcmp(vals[2], "1") == 0);
    pst_sweep_combo(&sw, 1, vals);
    CHECK(strcmp(vals[1], "0.1") == 0 && strcmp(vals[2], "2") == 0);
    pst_sweep_combo(&sw, 11, vals);
    CHECK(strcmp(vals[0], "\"lpmps\"") == 0 && strcmp(vals[1], "0.025") == 0);

    cJSON *machine = cJSON_Parse("{\"machine\": {\"cores\": 2}, \"compiler_flags\": \"-O3\"}");
    pst_sweep_opts o = {.quiet = 1, .machine = machine};
    pst_sweep_stats s;
    st = pst_sweep_run(&sw, &o, &s, err, sizeof err);
    if (st != PST_OK)
        printf("run: %s\n", err);
    CHECK_INT(st, PST_OK);
    CHECK_INT(s.runs, 12);
    CHECK_INT(s.failed, 0);
    CHECK_INT(s.skipped, 0);
    CHECK_INT(s.rows, 12);

    /* the CSV: header and one row per (run, task) */
    char path[512];
    snprintf(path, sizeof path, "%s/tiny.csv", dir);
    pst_csv_table t;
    read_result("tiny", &t);
    CHECK_INT(t.nrows, 12);
    CHECK_INT(t.ncols, 3 + pst_sweep_ncolumns);
    CHECK(strcmp(t.cell[0], "operator.scheme") == 0 && strcmp(t.cell[1], "cloud.spacing") == 0 &&
          strcmp(t.cell[2], "cloud.seed") == 0 && strcmp(t.cell[3], "dim") == 0);
    CHECK(strcmp(t.cell[t.ncols - 1], "message") == 0);
    CHECK(strcmp(t.cell[t.ncols - 2], "status") == 0);
    char *bytes = slurp(path, NULL);
    const char *header = "operator.scheme,cloud.spacing,cloud.seed,dim,particles,"
                                  "neighbours_estimate,task,type,rel_l2,qsfdi11,"
                                  "qsfdi11_normalised,lv78,lv95,max_abs,max_rel,iterations,"
                                  "converged,rel_residual,t_cloud,t_neighbours,t_geometry,"
                                  "t_moments,t_inversion,t_weights,t_precompute,t_task,t_total,"
                                  "cpu,peak_rss_bytes,memory_estimate,rows_ok,rows_fallback,"
                                  "rows_ill_conditioned,rows_rank_deficient,rows_too_few,status,"
                                  "message\n";
    CHECK(bytes && strncmp(bytes, header, strlen(header)) == 0);
    /* row 1: qsfdi, s0 0.1, seed 1: 11 x 11 particles, a Laplacian task, ok, no solver cells */
    char **r1 = t.cell + t.ncols;
    CHECK(strcmp(r1[0], "qsfdi") == 0 && strcmp(r1[1], "0.1") == 0 && strcmp(r1[2], "1") == 0);
    CHECK(strcmp(r1[4], "121") == 0);
    CHECK(strcmp(r1[6], "lap") == 0 && strcmp(r1[7], "laplacian") == 0);
    CHECK(r1[8][0] != '\0' && r1[9][0] == '\0'); /* rel_l2 measured, qsfdi11 not asked for */
    CHECK(r1[15][0] == '\0');                    /* iterations: not a solve */
    CHECK(strcmp(r1[t.ncols - 2], "ok") == 0);
    pst_csv_table_free(&t);

    /* the summary: 2 schemes x 3 spacings groups, fits per scheme and norm */
    snprintf(path, sizeof path, "%s/tiny.summary.json", dir);
    char *text = slurp(path, NULL);
    cJSON *sum = text ? cJSON_Parse(text) : NULL;
    free(text);
    CHECK(sum != NULL);
    CHECK_INT(cJSON_GetArraySize(cJSON_GetObjectItem(sum, "groups")), 6);
    CHECK_INT(cJSON_GetArraySize(cJSON_GetObjectItem(sum, "fits")), 4);
    const cJSON *g0 = cJSON_GetArrayItem(cJSON_GetObjectItem(sum, "groups"), 0);
    CHECK_INT(cJSON_GetNumberValue(cJSON_GetObjectItem(g0, "count")), 2);
    CHECK(cJSON_GetObjectItem(cJSON_GetObjectItem(g0, "key"), "cloud.seed") == NULL);
    CHECK(cJSON_IsNumber(cJSON_GetObjectItem(cJSON_GetObjectItem(g0, "std"), "rel_l2")));
    CHECK(cJSON_IsNumber(cJSON_GetObjectItem(cJSON_GetObjectItem(g0, "mean"), "t_total")));
    const cJSON *fq = find_fit(sum, "qsfdi", "rel_l2"), *fl = find_fit(sum, "lpmps", "rel_l2");
    CHECK(fq && fl);
    if (fq && fl) {
        double slope = cJSON_GetNumberValue(cJSON_GetObjectItem(fq, "slope"));
        double se = cJSON_GetNumberValue(cJSON_GetObjectItem(fq, "stderr"));
        printf("qsfdi rel_l2 slope %.3f +- %.3f, lpmps %.3f\n", slope, se,
               cJSON_GetNumberValue(cJSON_GetObjectItem(fl, "slope")));
        CHECK(slope > 1.5 && slope < 2.5);
        CHECK(se >= 0 && se < 0.3);
        CHECK_INT(cJSON_GetNumberValue(cJSON_GetObjectItem(fq, "points")), 3);
    }
    CHECK(cJSON_GetObjectItem(sum, "machine") != NULL);
    cJSON_Delete(sum);
    check_summary_from_csv("tiny", &sw);

    /* --resume: nothing reruns, the same bytes */
    snprintf(path, sizeof path, "%s/tiny.csv", dir);
    o.resume = 1;
    CHECK_INT(pst_sweep_run(&sw, &o, &s, err, sizeof err), PST_OK);
    CHECK_INT(s.runs, 0);
    CHECK_INT(s.skipped, 12);
    size_t len2;
    char *bytes2 = slurp(path, &len2);
    CHECK(bytes && bytes2 && strcmp(bytes, bytes2) == 0);
    free(bytes2);
    check_summary_from_csv("tiny", &sw);

    /* --resume after losing the last 5 rows (an interrupted sweep): 5 runs */
    char *cut = bytes;
    for (int line = 0; line < 1 + 7; ++line)
        cut = strchr(cut, '\n') + 1;
    *cut = '\0';
    spit(path, bytes);
    CHECK_INT(pst_sweep_run(&sw, &o, &s, err, sizeof err), PST_OK);
    CHECK_INT(s.runs, 5);
    CHECK_INT(s.skipped, 7);
    CHECK_INT(s.rows, 12);

    /* --resume with another sweep's header: refused, the file untouched */
    spit(path, "a,b\n1,2\n");
    st = pst_sweep_run(&sw, &o, &s, err, sizeof err);
    CHECK_INT(st, PST_EINPUT);
    CHECK(strstr(err, "header") != NULL);
    bytes2 = slurp(path, NULL);
    CHECK(bytes2 && strcmp(bytes2, "a,b\n1,2\n") == 0);
    free(bytes2);
    free(bytes);
    cJSON_Delete(machine);
    pst_sweep_free(&sw);
}

/* A scheme that cannot do the task (brookshaw has no gradient) and a value out of range give
 * failed rows with their messages; the sweep goes on; --resume reruns exactly those. */
static void test_failures(void)
{
    const char *grid = "{ \"operator.scheme\": [\"qsfdi\", \"brookshaw\"],\n"
                       "    \"cloud.jitter\": [0.1, 1.5] }";
    const char *tasks =
        "[ { \"type\": \"gradient\", \"name\": \"g\", \"field\": \"u\",\n"
        "    \"exact\": [\"6*cos(6*x + 8*y)\", \"8*cos(6*x + 8*y)\"] } ]";
    pst_sweep sw;
    char err[2048];
    int st = parse(&sw, "fail", sweep_text("fail", grid, tasks), err, sizeof err);
    CHECK_INT(st, PST_OK);
    if (st != PST_OK) {
        printf("parse: %s\n", err);
        return;
    }
    size_t nbad = 0;
    CHECK_INT(pst_sweep_check(&sw, &nbad, err, sizeof err), PST_EINPUT);
    CHECK_INT(nbad, 3);
    CHECK(strstr(err, "combination 1") != NULL && strstr(err, "cloud.jitter") != NULL);
    pst_sweep_opts o = {.quiet = 1};
    pst_sweep_stats s;
    CHECK_INT(pst_sweep_run(&sw, &o, &s, err, sizeof err), PST_OK);
    CHECK_INT(s.runs, 2); /* the jitter 1.5 combinations do not parse: not run */
    CHECK_INT(s.failed, 3);
    CHECK_INT(s.rows, 4);
    pst_csv_table t;
    read_result("fail", &t);
    CHECK_INT(t.nrows, 4);
    const char *want[4] = {"ok", "failed", "failed", "failed"};
    for (size_t r = 1; r <= t.nrows && r <= 4; ++r)
        CHECK(strcmp(t.cell[r * (size_t)t.ncols + t.ncols - 2], want[r - 1]) == 0);
    if (t.nrows >= 3) {
        const char *m1 = t.cell[2 * (size_t)t.ncols + t.ncols - 1];
        const char *m2 = t.cell[3 * (size_t)t.ncols + t.ncols - 1];
        printf("failed rows: '%s' | '%s'\n", m1, m2);
        CHECK(strstr(m1, "cloud.jitter") != NULL);
        CHECK(strstr(m2, "brookshaw") != NULL || strstr(m2, "gradient") != NULL);
        /* a failed run still names its task */
        CHECK(strcmp(t.cell[3 * (size_t)t.ncols + 2 + 3], "g") == 0);
    }
    pst_csv_table_free(&t);
    check_summary_from_csv("fail", &sw);
    o.resume = 1;
    CHECK_INT(pst_sweep_run(&sw, &o, &s, err, sizeof err), PST_OK);
    CHECK_INT(s.skipped, 1);
    CHECK_INT(s.failed, 3);
    CHECK_INT(s.runs, 1);
    pst_sweep_free(&sw);
}

/* Errors name the key and its line and column in the sweep file. */
static void test_errors(void)
{
    pst_sweep sw;
    char err[2048];
    const char *bad_key = "{ \"cloud.spaing\": [0.1, 0.05] }";
    CHECK_INT(parse(&sw, "bad", sweep_text("bad", bad_key, lap_task), err, sizeof err),
              PST_EINPUT);
    printf("bad key: %s\n", err);
    CHECK(strstr(err, "bad.json:12:13: key 'grid.cloud.spaing': unknown scene key") != NULL);
    const char *empty = "{ \"cloud.spacing\": [] }";
    CHECK_INT(parse(&sw, "bad", sweep_text("bad", empty, lap_task), err, sizeof err), PST_EINPUT);
    CHECK(strstr(err, "empty list") != NULL);
    const char *scalar = "{ \"cloud.spacing\": 0.1 }";
    CHECK_INT(parse(&sw, "bad", sweep_text("bad", scalar, lap_task), err, sizeof err), PST_EINPUT);
    CHECK(strstr(err, "key 'grid.cloud.spacing'") != NULL);
    /* an error inside the inline scene has the sweep file's line and column */
    const char *bad_task = "[ { \"type\": \"laplacian\", \"feld\": \"u\" } ]";
    const char *grid = "{ \"cloud.spacing\": [0.1] }";
    CHECK_INT(parse(&sw, "bad", sweep_text("bad", grid, bad_task), err, sizeof err), PST_EINPUT);
    printf("inline scene: %s\n", err);
    CHECK(strstr(err, "bad.json:9:39: key 'tasks.0.feld': unknown key") != NULL);
    /* a list of grids must share their keys */
    const char *two = "[ { \"cloud.spacing\": [0.1] }, { \"cloud.seed\": [1] } ]";
    CHECK_INT(parse(&sw, "bad", sweep_text("bad", two, lap_task), err, sizeof err), PST_EINPUT);
    CHECK(strstr(err, "same order") != NULL);
    /* a missing scene file */
    CHECK_INT(parse(&sw, "bad", "{ \"scene\": \"none.json\", \"grid\": {\"cloud.seed\": [1]} }",
                    err, sizeof err),
              PST_EIO);
    CHECK(strstr(err, "none.json") != NULL);
    CHECK_INT(pst_sweep_load(&sw, "/nonexistent/sweep.json", err, sizeof err), PST_EIO);
    /* a list of grids: the union of their products */
    const char *union2 = "[ { \"cloud.spacing\": [0.1, 0.05], \"cloud.seed\": [1] },\n"
                         "  { \"cloud.spacing\": [0.025], \"cloud.seed\": {\"from\": 3, "
                         "\"count\": 3} } ]";
    CHECK_INT(parse(&sw, "union", sweep_text("union", union2, lap_task), err, sizeof err), PST_OK);
    CHECK_INT(sw.ncombos, 5);
    const char *vals[SW_MAX_KEYS];
    pst_sweep_combo(&sw, 4, vals);
    CHECK(strcmp(vals[0], "0.025") == 0 && strcmp(vals[1], "5") == 0);
    pst_sweep_free(&sw);
}

/* A sweep table's row: the keys, then the sweep columns with rel_l2, t_total and status set;
 * appended to buf. */
static void add_row(char *buf, size_t len, const char *scheme, const char *s0, int seed,
                    const char *rel_l2, const char *t_total, const char *status)
{
    size_t u = strlen(buf);
    u += (size_t)snprintf(buf + u, len - u, "%s,%s,%d", scheme, s0, seed);
    for (int q = 0; q < pst_sweep_ncolumns && u < len; ++q) {
        const char *name = pst_sweep_columns[q], *v = "";
        v = !strcmp(name, "task") ? "lap" : !strcmp(name, "dim") ? "2" : v;
        v = !strcmp(name, "rel_l2") ? rel_l2 : !strcmp(name, "t_total") ? t_total : v;
        v = !strcmp(name, "status") ? status : v;
        u += (size_t)snprintf(buf + u, len - u, ",%s", v);
    }
    if (u + 1 < len)
        strcat(buf, "\n");
}

static double member(const cJSON *o, const char *a, const char *b)
{
    const cJSON *v = cJSON_GetObjectItem(b ? cJSON_GetObjectItem(o, a) : o, b ? b : a);
    return cJSON_IsNumber(v) ? v->valuedouble : NAN;
}

/* The statistics of a hand-made table: means, sample standard deviations over the ok rows
 * with a number (failed rows, empty and non-finite cells left out) and the fitted slope of
 * mean rel_l2 = 2 s0^2, whose points lie on a line: slope 2, standard error 0. */
static void test_summary_statistics(void)
{
    static char text[1 << 16];
    snprintf(text, sizeof text, "operator.scheme,cloud.spacing,cloud.seed");
    for (int q = 0; q < pst_sweep_ncolumns; ++q)
        snprintf(text + strlen(text), sizeof text - strlen(text), ",%s", pst_sweep_columns[q]);
    strcat(text, "\n");
    const size_t n = sizeof text;
    add_row(text, n, "qsfdi", "0.1", 1, "0.01", "1", "ok");
    add_row(text, n, "qsfdi", "0.1", 2, "0.03", "2", "ok");
    add_row(text, n, "qsfdi", "0.1", 3, "5", "4", "failed"); /* not in the statistics */
    add_row(text, n, "qsfdi", "0.05", 1, "0.004", "", "ok"); /* no t_total */
    add_row(text, n, "qsfdi", "0.05", 2, "0.006", "inf", "ok");
    add_row(text, n, "qsfdi", "0.025", 1, "0.00125", "3", "ok");
    add_row(text, n, "qsfdi", "0.025", 2, "", "6", "ok"); /* no rel_l2 */
    add_row(text, n, "lpmps", "0.1", 1, "0.5", "1", "not-converged");
    pst_csv_table t;
    char err[PST_ERRLEN];
    CHECK_INT(pst_csv_parse_table(&t, text, "hand.csv", 0, err), PST_OK);
    cJSON *sum = pst_sweep_summary(&t, "cloud.spacing", "cloud.seed");
    pst_csv_table_free(&t);
    CHECK(sum != NULL);
    if (!sum)
        return;
    const cJSON *rows = cJSON_GetObjectItem(sum, "rows");
    CHECK(member(rows, "total", NULL) == 8 && member(rows, "ok", NULL) == 6 &&
          member(rows, "failed", NULL) == 1 && member(rows, "not-converged", NULL) == 1);
    const cJSON *groups = cJSON_GetObjectItem(sum, "groups");
    CHECK_INT(cJSON_GetArraySize(groups), 4); /* qsfdi x 3 spacings, lpmps x 1 */
    const cJSON *g0 = cJSON_GetArrayItem(groups, 0), *g1 = cJSON_GetArrayItem(groups, 1),
                *g2 = cJSON_GetArrayItem(groups, 2), *g3 = cJSON_GetArrayItem(groups, 3);
    CHECK(member(g0, "count", NULL) == 2 && member(g0, "not_ok", NULL) == 1);
    CHECK_NEAR(member(g0, "mean", "rel_l2"), 0.02, 1e-15);
    CHECK_NEAR(member(g0, "std", "rel_l2"), sqrt(2e-4), 1e-15);
    CHECK_NEAR(member(g0, "mean", "t_total"), 1.5, 0);
    CHECK_NEAR(member(g1, "mean", "rel_l2"), 0.005, 1e-15);
    CHECK_NEAR(member(g1, "std", "rel_l2"), sqrt(2e-6), 1e-15);
    CHECK(cJSON_GetObjectItem(cJSON_GetObjectItem(g1, "mean"), "t_total") == NULL);
    CHECK_NEAR(member(g2, "mean", "rel_l2"), 0.00125, 1e-18);
    CHECK(cJSON_IsNull(cJSON_GetObjectItem(cJSON_GetObjectItem(g2, "std"), "rel_l2")));
    CHECK_NEAR(member(g2, "mean", "t_total"), 4.5, 0);
    CHECK(member(g3, "count", NULL) == 0 && cJSON_GetObjectItem(g3, "mean")->child == NULL);
    const cJSON *fit = find_fit(sum, "qsfdi", "rel_l2");
    CHECK(fit != NULL && find_fit(sum, "lpmps", "rel_l2") == NULL);
    CHECK_NEAR(member(fit, "points", NULL), 3, 0);
    CHECK_NEAR(member(fit, "slope", NULL), 2, 1e-12);
    CHECK_NEAR(member(fit, "stderr", NULL), 0, 1e-12);
    CHECK_NEAR(cJSON_GetArrayItem(cJSON_GetObjectItem(fit, "mean"), 1)->valuedouble, 0.005,
               1e-15);
    cJSON_Delete(sum);
}

/* Every sweep file of scenes/sweeps parses and every combination plans. */
static void test_sweep_files(void)
{
    const char *sd = PSTENCIL_SOURCE_DIR "/scenes/sweeps";
    DIR *d = opendir(sd);
    CHECK(d != NULL);
    if (!d)
        return;
    struct dirent *e;
    int files = 0;
    while ((e = readdir(d))) {
        size_t n = strlen(e->d_name);
        if (n < 6 || strcmp(e->d_name + n - 5, ".json") != 0)
            continue;
        char path[1024], err[4096];
        snprintf(path, sizeof path, "%s/%s", sd, e->d_name);
        pst_sweep sw;
        int st = pst_sweep_load(&sw, path, err, sizeof err);
        if (st != PST_OK)
            printf("%s: %s\n", e->d_name, err);
        CHECK_INT(st, PST_OK);
        if (st != PST_OK)
            continue;
        size_t bad = 0;
        st = pst_sweep_check(&sw, &bad, err, sizeof err);
        if (st != PST_OK)
            printf("%s: %s\n", e->d_name, err);
        CHECK_INT(st, PST_OK);
        printf("%-28s %5zu runs, %zu keys\n", e->d_name, sw.ncombos, (size_t)sw.nkeys);
        pst_sweep_free(&sw);
        ++files;
    }
    closedir(d);
    CHECK(files >= 7);
}

/* Hostile sweep files (issue 16): a range object with an unknown member in a list of grids
 * (once a write past the position stack), with a did-you-mean for a misspelt member. */
static void test_hostile_grids(void)
{
    pst_sweep sw;
    char err[2048];
    const char *typo = "[ {\"cloud.seed\": {\"from\": 1, \"cout\": 2}} ]";
    CHECK_INT(parse(&sw, "bad", sweep_text("bad", typo, lap_task), err, sizeof err), PST_EINPUT);
    printf("range typo: %s\n", err);
    CHECK(strstr(err, "bad.json:12:40: key 'grid.cloud.seed.cout': unknown key (a range is "
                      "{from, count[, step]}; did you mean 'count'?)") != NULL);
    const char *extra = "[ {\"cloud.seed\": {\"from\": 1, \"count\": 2, \"x\": 1}} ]";
    CHECK_INT(parse(&sw, "bad", sweep_text("bad", extra, lap_task), err, sizeof err), PST_EINPUT);
    CHECK(strstr(err, "key 'grid.cloud.seed.x': unknown key (a range is {from, count[, step]})") !=
          NULL);
    CHECK(strstr(err, "did you mean") == NULL);
    /* the same in a single grid object */
    const char *one = "{\"cloud.seed\": {\"from\": 1, \"stpe\": 2, \"count\": 2}}";
    CHECK_INT(parse(&sw, "bad", sweep_text("bad", one, lap_task), err, sizeof err), PST_EINPUT);
    CHECK(strstr(err, "key 'grid.cloud.seed.stpe'") && strstr(err, "did you mean 'step'?"));
}

/* A grid of keys[0..n) with ranges of counts[0..n) values, in buf. */
static const char *range_grid(char *buf, size_t len, int n, const long *counts)
{
    static const char *const keys[] = {"cloud.seed", "cloud.spacing", "cloud.jitter",
                                       "cloud.h_ratio", "cloud.angle", "cloud.lo.0",
                                       "cloud.hi.0"};
    size_t used = (size_t)snprintf(buf, len, "{");
    for (int k = 0; k < n; ++k)
        used += (size_t)snprintf(buf + used, len - used, "%s\"%s\": {\"from\": 1, \"count\": %ld}",
                                 k ? ", " : "", keys[k], counts[k]);
    snprintf(buf + used, len - used, "}");
    return buf;
}

/* Combination counts: multiplied without wrapping, and capped at SW_MAX_COMBOS. */
static void test_combination_cap(void)
{
    pst_sweep sw;
    char err[2048], g1[1024], g2[2048];
    const long wrap64[] = {65536, 65536, 65536, 65536}; /* 2^64: wrapped to 0 runs */
    CHECK_INT(parse(&sw, "big", sweep_text("big", range_grid(g1, sizeof g1, 4, wrap64), lap_task),
                    err, sizeof err),
              PST_EINPUT);
    printf("2^64 combinations: %s\n", err);
    CHECK(strstr(err, "key 'grid': 1.84467440737096e+19 combinations, more than the 100000 a "
                      "sweep may have") != NULL);
    const long tera[] = {1000, 1000, 1000, 1000}; /* 10^12: --plan looped for ever */
    CHECK_INT(parse(&sw, "big", sweep_text("big", range_grid(g1, sizeof g1, 4, tera), lap_task),
                    err, sizeof err),
              PST_EINPUT);
    CHECK(strstr(err, "key 'grid': 1000000000000 combinations, more than the 100000") != NULL);
    /* seven keys whose product is 2^64 - 2, plus a one-combination grid: a sum that wrapped */
    const long seven[] = {2, 49, 73, 127, 337, 92737, 649657}, ones[] = {1, 1, 1, 1, 1, 1, 1};
    char one[1024];
    snprintf(g2, sizeof g2, "[ %s, %s ]", range_grid(g1, sizeof g1, 7, seven),
             range_grid(one, sizeof one, 7, ones));
    CHECK_INT(parse(&sw, "big", sweep_text("big", g2, lap_task), err, sizeof err), PST_EINPUT);
    CHECK(strstr(err, "e+19 combinations, more than the 100000") != NULL);
    /* the cap itself is allowed, one more is not */
    const long cap[] = {SW_MAX_COMBOS}, over[] = {SW_MAX_COMBOS + 1};
    CHECK_INT(parse(&sw, "big", sweep_text("big", range_grid(g1, sizeof g1, 1, cap), lap_task),
                    err, sizeof err),
              PST_OK);
    CHECK_INT(sw.ncombos, SW_MAX_COMBOS);
    pst_sweep_free(&sw);
    CHECK_INT(parse(&sw, "big", sweep_text("big", range_grid(g1, sizeof g1, 1, over), lap_task),
                    err, sizeof err),
              PST_EINPUT);
    CHECK(strstr(err, "100001 combinations") != NULL);
}

/* A repeated key in any object of the sweep file is refused at its second occurrence (it
 * leaked and silently won before). `from` in the text of sweep_text(grid) becomes `to`. */
static void expect_duplicate(const char *grid, const char *from, const char *to,
                             const char *key)
{
    pst_sweep sw;
    char err[2048], text[8192], want[256];
    const char *base = sweep_text("dup", grid, lap_task), *at = strstr(base, from);
    CHECK(at != NULL);
    if (!at)
        return;
    snprintf(text, sizeof text, "%.*s%s%s", (int)(at - base), base, to, at + strlen(from));
    CHECK_INT(parse(&sw, "dup", text, err, sizeof err), PST_EINPUT);
    snprintf(want, sizeof want, "key '%s': duplicate key (an earlier", key);
    if (!strstr(err, want))
        printf("duplicate %s: %s\n", key, err);
    CHECK(strstr(err, want) != NULL);
}

static void test_duplicate_keys(void)
{
    const char *grid = "{ \"cloud.spacing\": [0.1], \"cloud.seed\": {\"from\": 1, \"count\": 2} }";
    expect_duplicate(grid, "\"output\": { \"csv\":", "\"output\": { \"csv\": \"a.csv\", \"csv\":",
                     "output.csv");
    expect_duplicate(grid, "\"output\":", "\"grid\": {\"cloud.seed\": [2]}, \"output\":", "grid");
    expect_duplicate(grid, "\"cloud.seed\": {", "\"cloud.spacing\": [1], \"cloud.seed\": {",
                     "grid.cloud.spacing");
    expect_duplicate(grid, "\"count\": 2", "\"count\": 2, \"from\": 3", "grid.cloud.seed.from");
    expect_duplicate(grid, "\"output\":",
                     "\"overrides\": {\"cloud.jitter\": 0.1, \"cloud.jitter\": 0.2}, \"output\":",
                     "overrides.cloud.jitter");
    /* the position is the second occurrence's */
    pst_sweep sw;
    char err[2048];
    const char *two = "{\"scene\": \"s.json\",\n \"grid\": {\"cloud.seed\": [1]},\n \"title\": \"a\",\n"
                      " \"title\": \"b\"}";
    CHECK_INT(parse(&sw, "dup", two, err, sizeof err), PST_EINPUT);
    CHECK(strstr(err, "dup.json:4:2: key 'title': duplicate key") != NULL);
}

/* Nesting past cJSON's limit is said to be that; control bytes in a key are escaped. */
static void test_deep_and_control(void)
{
    pst_sweep sw;
    char err[2048], text[4096];
    size_t n = (size_t)snprintf(text, sizeof text, "{\"grid\": ");
    for (int k = 0; k < 1200; ++k)
        text[n++] = '[';
    text[n] = '\0';
    CHECK_INT(parse(&sw, "deep", text, err, sizeof err), PST_EINPUT);
    CHECK(strstr(err, "deep.json:1:1009: JSON nested deeper than 1000 levels") != NULL);
    CHECK_INT(parse(&sw, "ctl", "{\"scene\": \"s.json\", \"gr\\u0007d\": {}}", err, sizeof err),
              PST_EINPUT);
    CHECK(strstr(err, "ctl.json:1:21: key 'gr\\x07d': unknown key") != NULL);
}

int main(void)
{
    if (test_scratch_dir(dir, sizeof dir, "pst_sweep") != 0)
        return 1;
    test_tiny_sweep();
    test_failures();
    test_errors();
    test_summary_statistics();
    test_sweep_files();
    test_hostile_grids();
    test_combination_cap();
    test_duplicate_keys();
    test_deep_and_control();
    test_remove_dir(dir);
    return check_summary("test_sweep");
}
