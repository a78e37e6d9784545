/* The sweep CSV (docs/sweeps.md): one row per (run, task), the grid keys' cells then
 * pst_sweep_columns, numbers at full precision (%.17g) and missing values as empty cells. */
#include "sweep_csv.h"

#include "pstencil.h"
#include "text_file.h"

#include <cjson/cJSON.h>
#include <stdlib.h>
#include <string.h>

const char *const pst_sweep_columns[] = {
    "dim", "particles", "neighbours_estimate", "task", "type", "rel_l2", "qsfdi11",
    "qsfdi11_normalised", "lv78", "lv95", "max_abs", "max_rel", "iterations", "converged",
    "rel_residual", "t_cloud", "t_neighbours", "t_geometry", "t_moments", "t_inversion",
    "t_weights", "t_precompute", "t_task", "t_total", "cpu", "peak_rss_bytes", "memory_estimate",
    "rows_ok", "rows_fallback", "rows_ill_conditioned", "rows_rank_deficient", "rows_too_few",
    "status", "message"};
const int pst_sweep_ncolumns = (int)(sizeof pst_sweep_columns / sizeof pst_sweep_columns[0]);

const char *const sweep_norm_columns[7] = {"rel_l2", "qsfdi11", "qsfdi11_normalised", "lv78",
                                           "lv95",   "max_abs", "max_rel"};

static void put_cell(FILE *f, const char *s)
{
    if (!strpbrk(s, ",\"\r\n")) {
        fputs(s, f);
        return;
    }
    fputc('"', f);
    for (; *s; ++s) {
        if (*s == '"')
            fputc('"', f);
        fputc(*s, f);
    }
    fputc('"', f);
}

char *sweep_key_cell(const char *json)
{
    cJSON *v = cJSON_Parse(json);
    char *out = v && cJSON_IsString(v) ? pst_strdup(v->valuestring) : pst_strdup(json);
    cJSON_Delete(v);
    return out;
}

static char *num_cell(double v)
{
    char buf[40];
    snprintf(buf, sizeof buf, "%.17g", v);
    return pst_strdup(buf);
}

char **sweep_new_row(sweep_rowset *rs, int ncols)
{
    if (rs->nrows == rs->cap) {
        size_t cap = rs->cap ? 2 * rs->cap : 4;
        char **g = realloc(rs->cells, cap * (size_t)ncols * sizeof *g);
        if (!g)
            return NULL;
        rs->cells = g;
        rs->cap = cap;
    }
    char **row = rs->cells + rs->nrows * (size_t)ncols;
    memset(row, 0, (size_t)ncols * sizeof *row);
    rs->nrows++;
    return row;
}

void sweep_rowset_clear(sweep_rowset *rs, int ncols)
{
    for (size_t i = 0; i < rs->nrows * (size_t)ncols; ++i)
        free(rs->cells[i]);
    free(rs->cells);
    memset(rs, 0, sizeof *rs);
}

static const cJSON *get(const cJSON *o, const char *k)
{
    return cJSON_GetObjectItemCaseSensitive(o, k);
}

static char *num_of(const cJSON *v)
{
    return cJSON_IsNumber(v) ? num_cell(v->valuedouble) : NULL;
}

/* The cells of a failed row: the task's name and type when the scene parsed. */
static void failed_cells(char **c, const pst_scene *s, int t, const char *message)
{
    static const char *const types[] = {"laplacian", "divergence", "gradient",
                                        "hessian",   "interpolate", "solve", "diffuse"};
    if (s && t < s->ntasks) {
        c[C_DIM] = num_cell(s->dim);
        c[C_TASK] = pst_strdup(s->tasks[t].name);
        c[C_TYPE] = pst_strdup(types[s->tasks[t].type]);
    }
    c[C_STATUS] = pst_strdup("failed");
    c[C_MESSAGE] = pst_strdup(message ? message : "");
}

/* Phase times and row counts summed over the run's operators (none: empty cells). */
static void operator_cells(char **c, const cJSON *report)
{
    const cJSON *op;
    double ph[5] = {0}, rows[5] = {0};
    int nops = 0;
    cJSON_ArrayForEach(op, get(report, "operators"))
    {
        ++nops;
        for (int q = 0; q < 5; ++q) {
            ph[q] += cJSON_GetNumberValue(get(get(op, "phases"), pst_phase_name(q)));
            const cJSON *rv = get(get(op, "row_status"), pst_row_status_name(q));
            rows[q] += cJSON_IsNumber(rv) ? rv->valuedouble : 0;
        }
    }
    for (int q = 0; q < 5 && nops; ++q) {
        c[C_T_GEOM + q] = num_cell(ph[q]);
        c[C_ROWS0 + q] = num_cell(rows[q]);
    }
}

/* The cells of task t of a run's report. */
static void report_cells(char **c, const cJSON *report, int t)
{
    const cJSON *tj = cJSON_GetArrayItem(get(report, "tasks"), t), *plan = get(report, "plan"),
                *tim = get(report, "timers"), *sv = get(tj, "solver");
    c[C_DIM] = num_of(get(report, "dim"));
    c[C_PARTICLES] = num_of(get(plan, "particles"));
    c[C_NEIGH] = num_of(get(plan, "neighbours_estimate"));
    c[C_TASK] = pst_strdup(tj ? cJSON_GetStringValue(get(tj, "name")) : "");
    c[C_TYPE] = pst_strdup(tj ? cJSON_GetStringValue(get(tj, "type")) : "");
    for (int q = 0; q < 7; ++q)
        c[C_NORM0 + q] = num_of(get(get(tj, "norms"), sweep_norm_columns[q]));
    int notconv = 0;
    if (sv) {
        c[C_ITER] = num_of(get(sv, "iterations"));
        c[C_CONV] = pst_strdup(cJSON_IsTrue(get(sv, "converged")) ? "1" : "0");
        c[C_RESID] = num_of(get(sv, "relative_residual"));
        notconv = !cJSON_IsTrue(get(sv, "converged"));
    }
    c[C_T_CLOUD] = num_of(get(tim, "cloud"));
    c[C_T_NEIGH] = num_of(get(tim, "neighbours"));
    operator_cells(c, report);
    c[C_T_TASK] = num_of(get(tj, "seconds"));
    c[C_T_TOTAL] = num_of(get(tim, "total"));
    c[C_CPU] = num_of(get(tim, "cpu"));
    c[C_RSS] = num_of(get(report, "peak_rss_bytes"));
    c[C_MEM] = num_of(get(get(plan, "memory_estimate_bytes"), "total"));
    c[C_STATUS] = pst_strdup(notconv ? "not-converged" : "ok");
    const char *why = notconv ? cJSON_GetStringValue(get(sv, "message")) : NULL;
    c[C_MESSAGE] = pst_strdup(why ? why : "");
}

int sweep_add_rows(sweep_rows *j, size_t k, const cJSON *report, const pst_scene *s,
                   const char *message)
{
    const pst_sweep *sw = j->sw;
    const char *vals[SW_MAX_KEYS];
    pst_sweep_combo(sw, k, vals);
    int ntasks = report ? cJSON_GetArraySize(get(report, "tasks")) : (s ? s->ntasks : 0);
    if (ntasks == 0)
        ntasks = 1;
    for (int t = 0; t < ntasks; ++t) {
        char **row = sweep_new_row(&j->runs[k], j->ncols);
        if (!row)
            return PST_ENOMEM;
        for (int q = 0; q < sw->nkeys; ++q)
            row[q] = sweep_key_cell(vals[q]);
        if (report)
            report_cells(row + sw->nkeys, report, t);
        else
            failed_cells(row + sw->nkeys, s, t, message);
        for (int q = 0; q < j->ncols; ++q) /* missing cells (and failed copies) become "" */
            if (!row[q] && !(row[q] = pst_strdup("")))
                return PST_ENOMEM;
    }
    return PST_OK;
}

static void put_row(FILE *f, char *const *row, int ncols)
{
    for (int q = 0; q < ncols; ++q) {
        put_cell(f, row[q]);
        fputc(q + 1 < ncols ? ',' : '\n', f);
    }
}

void sweep_write_csv(FILE *f, const void *rows)
{
    const sweep_rows *j = rows;
    for (int q = 0; q < j->sw->nkeys; ++q) {
        put_cell(f, j->sw->keys[q]);
        fputc(',', f);
    }
    put_row(f, (char *const *)pst_sweep_columns, pst_sweep_ncolumns);
    for (size_t k = 0; k < j->ncombos; ++k)
        for (size_t r = 0; r < j->runs[k].nrows; ++r)
            put_row(f, j->runs[k].cells + r * (size_t)j->ncols, j->ncols);
}

int sweep_rows_table(const sweep_rows *j, pst_csv_table *t, char *err)
{
    memset(t, 0, sizeof *t);
    const char *head[4 * SW_MAX_KEYS + 64];
    for (int q = 0; q < j->ncols; ++q)
        head[q] = q < j->sw->nkeys ? j->sw->keys[q] : pst_sweep_columns[q - j->sw->nkeys];
    int st = pst_csv_table_add(t, j->ncols, head, err);
    for (size_t k = 0; st == PST_OK && k < j->ncombos; ++k)
        for (size_t i = 0; st == PST_OK && i < j->runs[k].nrows; ++i)
            st = pst_csv_table_add(t, j->ncols,
                                   (const char *const *)j->runs[k].cells + i * (size_t)j->ncols,
                                   err);
    if (st != PST_OK)
        pst_csv_table_free(t);
    return st;
}
