/* Running a sweep (docs/sweeps.md): every combination not kept by --resume, the CSV rewritten
 * all or nothing after each run (an interrupted sweep loses at most the run in progress), and
 * the summary at the end, computed from the CSV's rows. */
#include "sweep.h"
#include "sweep_csv.h"
#include "sweep_grid.h"
#include "sweep_jobs.h"

#include "pstencil.h"
#include "progress.h"
#include "report.h"
#include "run.h"
#include "scene.h"
#include "text_file.h"

#include <cjson/cJSON.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* The distinct operator parameters over the sweep's combinations (report_parameters), from
 * the scenes themselves, so that resumed runs count too. A combination whose scene does not
 * parse has none. */
static cJSON *sweep_parameters(const pst_sweep *sw)
{
    cJSON *list = cJSON_CreateArray();
    for (size_t k = 0; list && k < sw->ncombos; ++k) {
        pst_scene s;
        char msg[PST_ERRLEN * 2];
        if (sweep_combo_scene(sw, k, &s, msg, sizeof msg) != PST_OK)
            continue;
        pst_op_opts oo;
        pst_scene_op_opts(&s, &oo);
        cJSON *p = report_parameters(&oo), *q;
        pst_scene_free(&s);
        int seen = 0;
        cJSON_ArrayForEach(q, list)
            seen |= cJSON_Compare(p, q, 1);
        if (seen)
            cJSON_Delete(p);
        else
            cJSON_AddItemToArray(list, p);
    }
    return list;
}

static int write_summary(const pst_sweep *sw, const sweep_rows *j, const cJSON *machine,
                         char *err, size_t errlen)
{
    pst_csv_table t;
    char msg[PST_ERRLEN];
    cJSON *s = sweep_rows_table(j, &t, msg) == PST_OK
                   ? pst_sweep_summary(&t, sw->slope_key, sw->repeat_key)
                   : NULL;
    pst_csv_table_free(&t);
    if (!s) {
        snprintf(err, errlen, "out of memory for the summary");
        return PST_ENOMEM;
    }
    /* what the CSV does not hold: where it came from, the operators' parameters, the machine */
    cJSON_AddStringToObject(s, "sweep", sw->path);
    cJSON_AddItemToObject(s, "operator_parameters", sweep_parameters(sw));
    cJSON_AddStringToObject(s, "csv", sw->csv);
    const cJSON *m;
    cJSON_ArrayForEach(m, machine)
        cJSON_AddItemToObject(s, m->string, cJSON_Duplicate(m, 1));
    int st = pst_write_atomic(sw->summary, pst_write_json, s, msg);
    cJSON_Delete(s);
    if (st != PST_OK)
        snprintf(err, errlen, "output.summary: %s", msg);
    return st;
}

/* The key cells of every combination, ncombos * nkeys (free with free_cells). */
static char **combo_cells(const pst_sweep *sw)
{
    const size_t nk = (size_t)sw->nkeys;
    char **ck = calloc(sw->ncombos * nk + 1, sizeof *ck);
    for (size_t k = 0; ck && k < sw->ncombos; ++k) {
        const char *vals[SW_MAX_KEYS];
        pst_sweep_combo(sw, k, vals);
        for (size_t q = 0; q < nk; ++q)
            if (!(ck[k * nk + q] = sweep_key_cell(vals[q]))) {
                for (size_t i = 0; i < k * nk + q; ++i)
                    free(ck[i]);
                free(ck);
                return NULL;
            }
    }
    return ck;
}

/* The combination whose key cells are the row's, searched from `hint` on; ncombos if none. */
static size_t match_combo(const pst_sweep *sw, char *const *ck, char *const *row, size_t hint)
{
    const size_t nk = (size_t)sw->nkeys;
    for (size_t s = 0; s < sw->ncombos; ++s) {
        size_t c = (hint + s) % sw->ncombos;
        int eq = 1;
        for (size_t q = 0; eq && q < nk; ++q)
            eq = strcmp(ck[c * nk + q], row[q]) == 0;
        if (eq)
            return c;
    }
    return sw->ncombos;
}

/* The rows of table t into their combinations' rowsets: done[k] for each combination that has
 * rows and none failed, the others cleared. */
static int take_rows(const pst_sweep *sw, sweep_rows *j, pst_csv_table *t, char *const *ck,
                     char *done, pst_sweep_stats *stats)
{
    const int nk = sw->nkeys, nc = j->ncols;
    char *bad = calloc(sw->ncombos + 1, 1);
    if (!bad)
        return PST_ENOMEM;
    size_t hint = 0;
    for (size_t r = 1; r <= t->nrows; ++r) {
        char **row = t->cell + r * (size_t)nc;
        size_t k = match_combo(sw, ck, row, hint);
        if (k == sw->ncombos) {
            stats->dropped++;
            continue;
        }
        hint = k;
        char **dst = sweep_new_row(&j->runs[k], nc);
        if (!dst) {
            free(bad);
            return PST_ENOMEM;
        }
        memcpy(dst, row, (size_t)nc * sizeof *dst); /* the cells move to the rowset */
        for (int q = 0; q < nc; ++q)
            row[q] = NULL;
        const char *status = dst[nk + C_STATUS];
        bad[k] |= strcmp(status, "ok") != 0 && strcmp(status, "not-converged") != 0;
    }
    for (size_t k = 0; k < sw->ncombos; ++k) {
        if (j->runs[k].nrows > 0 && !bad[k])
            done[k] = 1;
        else
            sweep_rowset_clear(&j->runs[k], nc);
    }
    free(bad);
    return PST_OK;
}

/* The table's header: the grid keys, then the sweep columns. */
static int same_header(const pst_sweep *sw, const pst_csv_table *t, int nc)
{
    int same = t->ncols == nc;
    for (int q = 0; same && q < nc; ++q)
        same = strcmp(t->cell[q], q < sw->nkeys ? sw->keys[q]
                                                : pst_sweep_columns[q - sw->nkeys]) == 0;
    return same;
}

/* --resume: take the rows of an existing CSV whose combination has no failed row. */
static int resume_rows(const pst_sweep *sw, sweep_rows *j, char *done, pst_sweep_stats *stats,
                       char *err, size_t errlen)
{
    FILE *f = fopen(sw->csv, "rb");
    if (!f)
        return PST_OK; /* nothing to resume: a fresh sweep */
    fclose(f);
    pst_csv_table t;
    char msg[PST_ERRLEN];
    int st = pst_csv_read_table(&t, sw->csv, 0, msg);
    if (st != PST_OK) {
        snprintf(err, errlen, "--resume: %s", msg);
        return st;
    }
    if (!same_header(sw, &t, j->ncols)) {
        snprintf(err, errlen, "--resume: %s: the header differs from this sweep's (grid keys "
                              "then the sweep columns); move the file away or fix the sweep",
                 sw->csv);
        pst_csv_table_free(&t);
        return PST_EINPUT;
    }
    char **ck = combo_cells(sw);
    st = ck ? take_rows(sw, j, &t, ck, done, stats) : PST_ENOMEM;
    for (size_t i = 0; ck && i < sw->ncombos * (size_t)sw->nkeys; ++i)
        free(ck[i]);
    free(ck);
    pst_csv_table_free(&t);
    if (st == PST_ENOMEM)
        snprintf(err, errlen, "--resume: out of memory");
    return st;
}

int sweep_run_one(const pst_sweep *sw, const pst_sweep_opts *o, size_t k, int *ran,
                  cJSON **report, char *msg, size_t len)
{
    pst_scene s;
    *ran = 0;
    *report = NULL;
    int st = sweep_combo_scene(sw, k, &s, msg, len);
    if (st != PST_OK)
        return st;
    pst_run_opts ro = {.quiet = 1, .report = report, .start_mpi = o->start_mpi,
                       .start_petsc = o->start_petsc};
    st = pst_run_scene(&s, &ro, NULL, NULL, NULL, msg, len);
    *ran = 1;
    pst_scene_free(&s);
    return st;
}

int sweep_record(sweep_rows *j, size_t k, int ran, const cJSON *report, int status,
                 const char *msg, pst_sweep_stats *stats)
{
    stats->runs += ran;
    if (report) {
        stats->not_converged += status == PST_ENUMERIC;
        return sweep_add_rows(j, k, report, NULL, NULL);
    }
    stats->failed++;
    pst_scene s; /* for the names of the failed tasks, when the scene parses */
    char unused[PST_ERRLEN];
    int parsed = sweep_combo_scene(j->sw, k, &s, unused, sizeof unused) == PST_OK;
    int st = sweep_add_rows(j, k, NULL, parsed ? &s : NULL, msg);
    if (parsed)
        pst_scene_free(&s);
    return st;
}

int sweep_run_combo(const pst_sweep *sw, const pst_sweep_opts *o, sweep_rows *j, size_t k,
                     pst_sweep_stats *stats)
{
    cJSON *rep;
    char msg[PST_ERRLEN * 2];
    int ran, rs = sweep_run_one(sw, o, k, &ran, &rep, msg, sizeof msg);
    if (rs == PST_ENOMEM && !ran)
        return rs;
    int st = sweep_record(j, k, ran, rep, rs, msg, stats);
    cJSON_Delete(rep);
    return st;
}

int sweep_write_rows(const pst_sweep *sw, const sweep_rows *j, char *err, size_t errlen)
{
    char msg[PST_ERRLEN];
    int st = pst_write_atomic(sw->csv, sweep_write_csv, j, msg);
    if (st != PST_OK)
        snprintf(err, errlen, "output.csv: %s", msg);
    return st;
}

/* Every combination not done, one after the other here or several at once (sweep_jobs.c),
 * the CSV after each. */
static int run_all(const pst_sweep *sw, const pst_sweep_opts *o, sweep_rows *j,
                   const char *done, pst_sweep_stats *stats, char *err, size_t errlen)
{
    if (o->jobs > 1 && o->worker_exe)
        return sweep_run_jobs(sw, o, j, done, stats, err, errlen);
    cli_progress pg;
    progress_begin(&pg, !o->quiet, "sweep", NULL);
    size_t todo = 0, made = 0;
    for (size_t k = 0; k < sw->ncombos; ++k)
        todo += !done[k];
    int st = PST_OK;
    for (size_t k = 0; st == PST_OK && k < sw->ncombos; ++k) {
        if (done[k]) {
            stats->skipped++;
            continue;
        }
        char label[512], detail[160];
        sweep_combo_label(sw, k, label, sizeof label);
        snprintf(detail, sizeof detail, "run %zu/%zu: %.100s", made + 1, todo, label);
        progress_update(&pg, todo ? (double)made / (double)todo : 1, detail);
        st = sweep_run_combo(sw, o, j, k, stats);
        ++made;
        if (st != PST_OK)
            snprintf(err, errlen, "out of memory for the rows");
        else
            st = sweep_write_rows(sw, j, err, errlen);
    }
    progress_update(&pg, 1, ""); /* the last line of a log says all are done */
    progress_end(&pg);
    return st;
}

/* The .pvd of the runs' VTUs: run k as timestep k, for every run whose VTU is there (a failed
 * run wrote none; a resumed one keeps the file of its earlier sweep). */
static int write_pvd(const pst_sweep *sw, char *err, size_t errlen)
{
    pst_pvd_dataset *d = calloc(sw->ncombos + 1, sizeof *d);
    char (*names)[1024] = calloc(sw->ncombos + 1, sizeof *names);
    int st = d && names ? PST_OK : PST_ENOMEM;
    size_t n = 0;
    for (size_t k = 0; st == PST_OK && k < sw->ncombos; ++k) {
        char path[1024];
        const char *base;
        sweep_run_vtu(sw, k, path, sizeof path, &base);
        if (access(path, F_OK) != 0)
            continue;
        snprintf(names[n], sizeof names[n], "%s", base);
        d[n] = (pst_pvd_dataset){(double)k, 0, names[n]};
        ++n;
    }
    char msg[PST_ERRLEN];
    if (st == PST_OK && (st = pst_write_pvd(sw->pvd, d, n, msg)) != PST_OK)
        snprintf(err, errlen, "output.pvd: %s", msg);
    else if (st == PST_ENOMEM)
        snprintf(err, errlen, "out of memory for the .pvd");
    free(d);
    free(names);
    return st;
}

int pst_sweep_run(const pst_sweep *sw, const pst_sweep_opts *o, pst_sweep_stats *stats,
                  char *err, size_t errlen)
{
    pst_sweep_stats local;
    if (!stats)
        stats = &local;
    memset(stats, 0, sizeof *stats);
    err[0] = '\0';
    sweep_rows j = {.sw = sw, .ncols = sw->nkeys + pst_sweep_ncolumns, .ncombos = sw->ncombos};
    j.runs = calloc(sw->ncombos + 1, sizeof *j.runs);
    char *done = calloc(sw->ncombos + 1, 1);
    int st = j.runs && done ? PST_OK : PST_ENOMEM;
    if (st == PST_ENOMEM)
        snprintf(err, errlen, "out of memory");
    if (st == PST_OK && o->resume)
        st = resume_rows(sw, &j, done, stats, err, errlen);
    if (st == PST_OK)
        st = run_all(sw, o, &j, done, stats, err, errlen);
    if (st == PST_OK) /* also when nothing ran (everything resumed) */
        st = sweep_write_rows(sw, &j, err, errlen);
    if (st == PST_OK)
        st = write_summary(sw, &j, o->machine, err, errlen);
    if (st == PST_OK && sw->pvd)
        st = write_pvd(sw, err, errlen);
    for (size_t k = 0; j.runs && k < sw->ncombos; ++k) {
        stats->rows += j.runs[k].nrows;
        sweep_rowset_clear(&j.runs[k], j.ncols);
    }
    free(j.runs);
    free(done);
    return st;
}
