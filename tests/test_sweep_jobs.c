/* Sweep runs at once (src/app/sweep_jobs.c, sweep_worker.c; docs/sweeps.md "Runs at once"):
 * a sweep with ok, unparsable and failing combinations gives, run two at a time in worker
 * processes, the CSV of the one-at-a-time sweep in every column but the times, the CPU and
 * the peak RSS; a worker that dies fails only the run it had and the rest run here; small and
 * large runs are told apart by their plans; the worker answers a combination over its socket
 * and refuses another sweep's digest; reports cross the socket with every number bit for bit. */
#define _POSIX_C_SOURCE 200809L /* socketpair */
#include "check.h"
#include "support.h"
#include "sweep.h"
#include "sweep_grid.h"
#include "sweep_jobs.h"

#include "pstencil.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

static char dir[256];

/* A sweep file NAME.json in dir over an inline 2D scene with a Laplacian task and, with
 * `gradient`, a gradient task (brookshaw has none: its runs fail). */
static int load(pst_sweep *sw, const char *name, const char *grid, int gradient)
{
    char path[512], text[4096];
    snprintf(text, sizeof text,
             "{ \"scene\": { \"dim\": 2,\n"
             "    \"cloud\": { \"source\": \"lattice\", \"spacing\": 0.1, \"jitter\": 0.2,\n"
             "               \"boundary_layer\": true, \"h_ratio\": 1.2 },\n"
             "    \"fields\": { \"u\": \"sin(6*x + 8*y)\" },\n"
             "    \"tasks\": [ { \"type\": \"laplacian\", \"field\": \"u\",\n"
             "                   \"exact\": \"-100*sin(6*x + 8*y)\" }%s ] },\n"
             "  \"grid\": %s,\n"
             "  \"output\": { \"csv\": \"%s/%s.csv\", \"summary\": \"%s/%s.summary.json\" } }\n",
             gradient ? ",\n { \"type\": \"gradient\", \"field\": \"u\",\n"
                        "   \"exact\": [\"6*cos(6*x+8*y)\", \"8*cos(6*x+8*y)\"] }"
                      : "",
             grid, dir, name, dir, name);
    snprintf(path, sizeof path, "%s/%s.json", dir, name);
    FILE *f = fopen(path, "wb");
    fputs(text, f);
    fclose(f);
    char err[2048];
    int st = pst_sweep_load(sw, path, err, sizeof err);
    if (st != PST_OK)
        printf("load %s: %s\n", name, err);
    return st;
}

static const char *grid =
    "{ \"operator.scheme\": [\"qsfdi\", \"brookshaw\", \"lpmps\"],\n"
    "  \"cloud.jitter\": [0.2, 1.5], \"cloud.spacing\": [0.1, 0.05],\n"
    "  \"cloud.seed\": { \"from\": 1, \"count\": 2 } }";

static int run(const char *name, int jobs, const char *exe, pst_sweep_stats *s)
{
    pst_sweep sw;
    if (load(&sw, name, grid, 1) != PST_OK)
        return PST_EINPUT;
    pst_sweep_opts o = {.quiet = 1, .jobs = jobs, .worker_exe = exe};
    char err[2048];
    int st = pst_sweep_run(&sw, &o, s, err, sizeof err);
    if (st != PST_OK)
        printf("run %s: %s\n", name, err);
    pst_sweep_free(&sw);
    return st;
}

static pst_csv_table read_csv(const char *name)
{
    char path[512], err[PST_ERRLEN];
    pst_csv_table t;
    snprintf(path, sizeof path, "%s/%s.csv", dir, name);
    CHECK_INT(pst_csv_read_table(&t, path, 0, err), PST_OK);
    return t;
}

/* The columns a schedule may change: times, CPU, peak RSS. */
static int schedule_column(const char *name)
{
    return strncmp(name, "t_", 2) == 0 || strcmp(name, "cpu") == 0 ||
           strcmp(name, "peak_rss_bytes") == 0;
}

/* Rows of a and b (the header too) that differ outside the schedule's columns. */
static int differing_rows(const pst_csv_table *a, const pst_csv_table *b)
{
    int bad = 0;
    for (size_t r = 0; r <= a->nrows && r <= b->nrows && a->ncols == b->ncols; ++r) {
        int differs = 0;
        for (int q = 0; q < a->ncols; ++q)
            differs |= !schedule_column(a->cell[q]) &&
                       strcmp(a->cell[r * (size_t)a->ncols + q], b->cell[r * (size_t)b->ncols + q]);
        bad += differs;
    }
    return bad;
}

static void test_same_csv(void)
{
    pst_sweep_stats one, two;
    CHECK_INT(run("one", 1, NULL, &one), PST_OK);
    CHECK_INT(run("two", 2, PSTENCIL_EXE, &two), PST_OK);
    /* 24 combinations: 12 do not parse (jitter 1.5), 4 of the others are brookshaw's */
    CHECK_INT(one.runs, 12);
    CHECK_INT(one.failed, 16);
    CHECK_INT(two.runs, one.runs);
    CHECK_INT(one.in_workers, 0);
    CHECK_INT(two.in_workers, 8); /* brookshaw's runs do not plan: they fail here */
    CHECK_INT(two.failed, one.failed);
    CHECK_INT(two.rows, one.rows);
    CHECK_INT(one.rows, 12 + 12 * 2); /* a scene that does not parse: one row */
    pst_csv_table a = read_csv("one"), b = read_csv("two");
    CHECK_INT(b.nrows, a.nrows);
    CHECK_INT(b.ncols, a.ncols);
    CHECK_INT(differing_rows(&a, &b), 0);
    /* and the times are there, from the workers' runs */
    int tcol = -1;
    for (int q = 0; q < b.ncols; ++q)
        if (strcmp(b.cell[q], "t_total") == 0)
            tcol = q;
    CHECK(tcol >= 0 && b.num[1 * (size_t)b.ncols + (size_t)tcol] > 0);
    pst_csv_table_free(&a);
    pst_csv_table_free(&b);
}

/* Workers that read one combination and exit 3: each fails the run it had, then the rest run
 * here, one after the other. */
static void test_dying_workers(void)
{
    char exe[512];
    snprintf(exe, sizeof exe, "%s/dies.sh", dir);
    FILE *f = fopen(exe, "wb");
    fputs("#!/bin/sh\nread k <&3\nexit 3\n", f);
    fclose(f);
    chmod(exe, 0755);
    pst_sweep_stats s;
    CHECK_INT(run("dies", 2, exe, &s), PST_OK);
    CHECK_INT(s.failed, 16 + 2);
    CHECK_INT(s.runs, 12);
    CHECK_INT(s.in_workers, 0);
    pst_csv_table a = read_csv("one"), d = read_csv("dies");
    const size_t nc = (size_t)d.ncols;
    int status = -1, message = -1;
    for (int q = 0; q < d.ncols; ++q) {
        status = strcmp(d.cell[q], "status") == 0 ? q : status;
        message = strcmp(d.cell[q], "message") == 0 ? q : message;
    }
    /* rows 1-4: the first two combinations (qsfdi, jitter 0.2, s0 0.1, seeds 1 and 2), two
     * tasks each */
    for (size_t r = 1; r <= 4; ++r) {
        CHECK(strcmp(d.cell[r * nc + status], "failed") == 0);
        CHECK(strstr(d.cell[r * nc + message],
                     "the sweep worker running this combination ended with exit status 3"));
    }
    CHECK_INT(differing_rows(&a, &d), 4); /* those rows only */
    pst_csv_table_free(&a);
    pst_csv_table_free(&d);
}

static void test_small_and_large(void)
{
    pst_sweep sw;
    const char *g = "{ \"dim\": [2, 3], \"cloud.spacing\": [0.1, 0.02] }";
    if (load(&sw, "sizes", g, 0) != PST_OK)
        return;
    /* 2D 0.1: 121 particles; 2D 0.02: 2601; 3D 0.1: 1331; 3D 0.02: 132651 x ~50 pairs */
    CHECK_INT(sweep_combo_is_small(&sw, 0, 2), 1);
    CHECK_INT(sweep_combo_is_small(&sw, 1, 2), 1);
    CHECK_INT(sweep_combo_is_small(&sw, 2, 2), 1);
    CHECK_INT(sweep_combo_is_small(&sw, 3, 2), 0);
    pst_sweep_free(&sw);
}

/* The worker's side in this process: combination 0 answered on the socket, another digest
 * and a bad line refused. */
static void test_worker_protocol(void)
{
    pst_sweep sw;
    if (load(&sw, "serve", grid, 1) != PST_OK)
        return;
    char digest[32], err[2048];
    snprintf(digest, sizeof digest, "%016llx", (unsigned long long)sweep_digest(&sw));
    pst_sweep_opts o = {.quiet = 1};
    int sv[2];
    CHECK_INT(socketpair(AF_UNIX, SOCK_STREAM, 0, sv), 0);
    CHECK_INT(write(sv[0], "1\n", 2), 2);
    shutdown(sv[0], SHUT_WR);
    CHECK_INT(pst_sweep_serve(&sw, digest, &o, sv[1], err, sizeof err), PST_OK);
    char line[65536];
    ssize_t n = read(sv[0], line, sizeof line - 1);
    CHECK(n > 0 && line[n - 1] == '\n');
    line[n > 0 ? n : 0] = '\0';
    cJSON *a = cJSON_Parse(line);
    CHECK(cJSON_GetNumberValue(cJSON_GetObjectItem(a, "k")) == 1);
    CHECK(cJSON_IsTrue(cJSON_GetObjectItem(a, "ran")));
    cJSON *rep = cJSON_GetObjectItem(a, "report");
    sweep_report_decode(rep);
    CHECK(cJSON_GetNumberValue(cJSON_GetObjectItem(rep, "dim")) == 2);
    CHECK_INT(cJSON_GetArraySize(cJSON_GetObjectItem(rep, "tasks")), 2);
    cJSON_Delete(a);
    close(sv[0]);
    close(sv[1]);

    CHECK_INT(pst_sweep_serve(&sw, "0123456789abcdef", &o, -1, err, sizeof err), PST_EINPUT);
    CHECK(strstr(err, "is not the sweep this worker was started for") != NULL);
    CHECK_INT(socketpair(AF_UNIX, SOCK_STREAM, 0, sv), 0);
    CHECK_INT(write(sv[0], "99\n", 3), 3);
    CHECK_INT(pst_sweep_serve(&sw, digest, &o, sv[1], err, sizeof err), PST_EINPUT);
    CHECK(strstr(err, "'99' is not a combination of") != NULL);
    close(sv[0]);
    close(sv[1]);
    pst_sweep_free(&sw);
}

/* Every number of a report crosses as text and comes back bit for bit, keys kept. */
static void test_report_numbers(void)
{
    const double v[] = {0.1, 1.0 / 3.0, 1e-310, -0.0, 3e9, NAN, INFINITY, -INFINITY};
    const int nv = (int)(sizeof v / sizeof v[0]);
    cJSON *r = cJSON_CreateObject(), *arr = cJSON_AddArrayToObject(r, "list");
    cJSON *inner = cJSON_AddObjectToObject(r, "inner");
    for (int q = 0; q < nv; ++q) {
        char key[16];
        snprintf(key, sizeof key, "v%d", q);
        cJSON_AddItemToArray(arr, cJSON_CreateNumber(v[q]));
        cJSON_AddNumberToObject(inner, key, v[q]);
    }
    cJSON_AddStringToObject(r, "name", "lap");
    sweep_report_encode(r);
    char *text = cJSON_PrintUnformatted(r);
    cJSON_Delete(r);
    r = cJSON_Parse(text);
    free(text);
    sweep_report_decode(r);
    CHECK(strcmp(cJSON_GetStringValue(cJSON_GetObjectItem(r, "name")), "lap") == 0);
    for (int q = 0; q < nv; ++q) {
        char key[16];
        snprintf(key, sizeof key, "v%d", q);
        double a = cJSON_GetNumberValue(cJSON_GetArrayItem(cJSON_GetObjectItem(r, "list"), q));
        double b = cJSON_GetNumberValue(cJSON_GetObjectItem(cJSON_GetObjectItem(r, "inner"), key));
        CHECK(isnan(v[q]) ? isnan(a) && isnan(b)
                          : memcmp(&a, &v[q], sizeof a) == 0 && memcmp(&b, &v[q], sizeof b) == 0);
    }
    cJSON_Delete(r);
}

int main(void)
{
    if (test_scratch_dir(dir, sizeof dir, "pst_sweep_jobs") != 0)
        return 1;
    test_same_csv();
    test_dying_workers();
    test_small_and_large();
    test_worker_protocol();
    test_report_numbers();
    test_remove_dir(dir);
    return check_summary("test_sweep_jobs");
}
