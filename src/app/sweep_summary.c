/* The summary of a sweep CSV (docs/sweeps.md): row counts by status, per group the means and
 * standard deviations over the ok rows, and the convergence fits. A function of the table
 * alone, so that it can be recomputed from the file. The statistics read the table's typed
 * cells (pst_csv_table.num, NAN when missing); groups are told apart by their key cells. */
#include "sweep.h"
#include "sweep_csv.h"

#include "pstencil.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static const char *const stat_cols[] = {"rel_l2", "qsfdi11", "qsfdi11_normalised", "lv78",
                                        "lv95", "max_abs", "max_rel", "t_cloud",
                                        "t_neighbours", "t_geometry", "t_moments", "t_inversion",
                                        "t_weights", "t_precompute", "t_task", "t_total", "cpu",
                                        "peak_rss_bytes", "iterations"};
enum { NSTAT = sizeof stat_cols / sizeof stat_cols[0], MAX_POINTS = 512 };

/* The table as the summary reads it: rows r = 1..nrows, their status ok or not, the groups. */
typedef struct {
    const pst_csv_table *t;
    int nkeys, task, slope, repeat;
    int stat_col[NSTAT];       /* the columns of stat_cols                      */
    unsigned char *ok;         /* ok[r]: status "ok"                            */
    int skip[SW_MAX_KEYS * 4]; /* key columns left out of the grouping          */
    size_t *gid, *first;       /* gid[r - 1]: row r's group; first[g]: its first row */
    size_t ngroups;
    double *vals;              /* scratch, nrows + 1                            */
} view;

static const char *cell(const view *v, size_t r, int col)
{
    return v->t->cell[r * (size_t)v->t->ncols + (size_t)col];
}

static double num(const view *v, size_t r, int col)
{
    return v->t->num[r * (size_t)v->t->ncols + (size_t)col];
}

void pst_mean_std(const double *v, size_t n, double *mean, double *sd)
{
    double s = 0;
    for (size_t i = 0; i < n; ++i)
        s += v[i];
    *mean = s / (double)n;
    double q = 0;
    for (size_t i = 0; i < n; ++i)
        q += (v[i] - *mean) * (v[i] - *mean);
    *sd = n > 1 ? sqrt(q / (double)(n - 1)) : NAN;
}

/* A CSV cell as a typed JSON value: a number, bool or list when it reads as one, else a
 * string. */
static cJSON *typed(const char *c)
{
    cJSON *v = cJSON_Parse(c);
    if (v && (cJSON_IsNumber(v) || cJSON_IsBool(v) || cJSON_IsArray(v) || cJSON_IsObject(v)))
        return v;
    cJSON_Delete(v);
    return cJSON_CreateString(c);
}

static void add_number_or_null(cJSON *o, const char *name, double x)
{
    if (isfinite(x))
        cJSON_AddNumberToObject(o, name, x);
    else
        cJSON_AddNullToObject(o, name);
}

/* Group the rows by the key cells except the skipped ones, and the task, in order of
 * appearance. */
static void group_rows(view *v)
{
    size_t ng = 0;
    for (size_t r = 1; r <= v->t->nrows; ++r) {
        size_t g = 0;
        for (; g < ng; ++g) {
            int same = strcmp(cell(v, v->first[g], v->task), cell(v, r, v->task)) == 0;
            for (int q = 0; same && q < v->nkeys; ++q)
                same = v->skip[q] || strcmp(cell(v, v->first[g], q), cell(v, r, q)) == 0;
            if (same)
                break;
        }
        if (g == ng)
            v->first[ng++] = r;
        v->gid[r - 1] = g;
    }
    v->ngroups = ng;
}

/* A group's "key" object (the keys it is grouped by) and "task". */
static cJSON *group_object(const view *v, size_t g)
{
    cJSON *gj = cJSON_CreateObject(), *k = cJSON_CreateObject();
    for (int q = 0; q < v->nkeys; ++q)
        if (!v->skip[q])
            cJSON_AddItemToObject(k, v->t->cell[q], typed(cell(v, v->first[g], q)));
    cJSON_AddItemToObject(gj, "key", k);
    cJSON_AddStringToObject(gj, "task", cell(v, v->first[g], v->task));
    return gj;
}

static void add_row_counts(cJSON *sum, const view *v)
{
    long n_ok = 0, n_nc = 0, n_failed = 0;
    for (size_t r = 1; r <= v->t->nrows; ++r) {
        const char *s = cell(v, r, v->nkeys + C_STATUS);
        n_ok += strcmp(s, "ok") == 0;
        n_nc += strcmp(s, "not-converged") == 0;
        n_failed += strcmp(s, "failed") == 0;
    }
    cJSON *rows = cJSON_AddObjectToObject(sum, "rows");
    cJSON_AddNumberToObject(rows, "total", (double)v->t->nrows);
    cJSON_AddNumberToObject(rows, "ok", (double)n_ok);
    cJSON_AddNumberToObject(rows, "not-converged", (double)n_nc);
    cJSON_AddNumberToObject(rows, "failed", (double)n_failed);
}

/* groups: all keys but repeat_key, per task; statistics over the rows with status ok */
static void add_groups(cJSON *sum, view *v)
{
    for (int q = 0; q < v->nkeys; ++q)
        v->skip[q] = q == v->repeat;
    group_rows(v);
    cJSON *groups = cJSON_AddArrayToObject(sum, "groups");
    for (size_t g = 0; g < v->ngroups; ++g) {
        cJSON *gj = group_object(v, g);
        cJSON_AddItemToArray(groups, gj);
        long count = 0, total = 0;
        for (size_t r = 1; r <= v->t->nrows; ++r)
            if (v->gid[r - 1] == g) {
                ++total;
                count += v->ok[r];
            }
        cJSON_AddNumberToObject(gj, "count", (double)count);
        cJSON_AddNumberToObject(gj, "not_ok", (double)(total - count));
        cJSON *mean = cJSON_AddObjectToObject(gj, "mean"), *sd = cJSON_AddObjectToObject(gj, "std");
        for (int q = 0; q < NSTAT; ++q) {
            const int col = v->stat_col[q];
            size_t m = 0;
            for (size_t r = 1; r <= v->t->nrows; ++r)
                if (v->gid[r - 1] == g && v->ok[r] && !isnan(num(v, r, col)))
                    v->vals[m++] = num(v, r, col);
            if (m == 0)
                continue;
            double mu, s;
            pst_mean_std(v->vals, m, &mu, &s);
            add_number_or_null(mean, stat_cols[q], mu);
            if (q + 1 < NSTAT) /* iterations: the mean only */
                add_number_or_null(sd, stat_cols[q], s);
        }
    }
}

/* Least-squares slope of ys against xs and its standard error (NAN when undetermined). */
static void line_fit(const double *xs, const double *ys, int np, double *slope, double *se)
{
    *slope = *se = NAN;
    if (np < 2)
        return;
    double mx = 0, my = 0;
    for (int i = 0; i < np; ++i) {
        mx += xs[i];
        my += ys[i];
    }
    mx /= np;
    my /= np;
    double sxx = 0, sxy = 0;
    for (int i = 0; i < np; ++i) {
        sxx += (xs[i] - mx) * (xs[i] - mx);
        sxy += (xs[i] - mx) * (ys[i] - my);
    }
    if (!(sxx > 0))
        return;
    *slope = sxy / sxx;
    if (np < 3)
        return;
    double ssr = 0;
    for (int i = 0; i < np; ++i) {
        double e = ys[i] - my - *slope * (xs[i] - mx);
        ssr += e * e;
    }
    *se = sqrt(ssr / (np - 2) / sxx);
}

/* The resolutions of group g, in order of appearance: distinct cells of the slope key that
 * are positive numbers. */
static size_t resolutions(const view *v, size_t g, const char **rescell, double *res)
{
    size_t nres = 0;
    for (size_t r = 1; r <= v->t->nrows; ++r) {
        if (v->gid[r - 1] != g)
            continue;
        const char *c = cell(v, r, v->slope);
        size_t q = 0;
        while (q < nres && strcmp(rescell[q], c) != 0)
            ++q;
        if (q == nres && num(v, r, v->slope) > 0) {
            res[nres] = num(v, r, v->slope);
            rescell[nres++] = c;
        }
    }
    return nres;
}

/* The fit of norm column col over group g: the mean over the repeats at each resolution,
 * then log(mean) against log(resolution). NULL when no resolution has a positive mean. */
static cJSON *fit_norm(const view *v, size_t g, int nq, const char *const *rescell,
                       const double *res, size_t nres)
{
    const int col = v->nkeys + C_NORM0 + nq;
    double xs[MAX_POINTS], ys[MAX_POINTS], rx[MAX_POINTS], ry[MAX_POINTS];
    int np = 0;
    for (size_t q = 0; q < nres && np < MAX_POINTS; ++q) {
        double s = 0;
        long m = 0;
        for (size_t r = 1; r <= v->t->nrows; ++r)
            if (v->gid[r - 1] == g && strcmp(cell(v, r, v->slope), rescell[q]) == 0 &&
                v->ok[r] && !isnan(num(v, r, col))) {
                s += num(v, r, col);
                ++m;
            }
        if (m > 0 && s > 0) {
            rx[np] = res[q];
            ry[np] = s / (double)m;
            xs[np] = log(rx[np]);
            ys[np] = log(ry[np]);
            ++np;
        }
    }
    if (np == 0)
        return NULL;
    cJSON *fj = group_object(v, g);
    cJSON_AddStringToObject(fj, "norm", sweep_norm_columns[nq]);
    cJSON_AddNumberToObject(fj, "points", np);
    double slope, se;
    line_fit(xs, ys, np, &slope, &se);
    add_number_or_null(fj, "slope", slope);
    add_number_or_null(fj, "stderr", se);
    cJSON *xa = cJSON_AddArrayToObject(fj, "resolution"), *ya = cJSON_AddArrayToObject(fj, "mean");
    for (int i = 0; i < np; ++i) {
        cJSON_AddItemToArray(xa, cJSON_CreateNumber(rx[i]));
        cJSON_AddItemToArray(ya, cJSON_CreateNumber(ry[i]));
    }
    return fj;
}

/* fits: all keys but slope_key and repeat_key, per task and norm */
static void add_fits(cJSON *sum, view *v)
{
    cJSON *fits = cJSON_AddArrayToObject(sum, "fits");
    if (v->slope < 0 || v->slope >= v->nkeys)
        return;
    for (int q = 0; q < v->nkeys; ++q)
        v->skip[q] = q == v->repeat || q == v->slope;
    group_rows(v);
    double *res = malloc((v->t->nrows + 1) * sizeof *res);
    const char **rescell = malloc((v->t->nrows + 1) * sizeof *rescell);
    for (size_t g = 0; res && rescell && g < v->ngroups; ++g) {
        size_t nres = resolutions(v, g, rescell, res);
        for (int nq = 0; nq < 7; ++nq) {
            cJSON *fj = fit_norm(v, g, nq, rescell, res, nres);
            if (fj)
                cJSON_AddItemToArray(fits, fj);
        }
    }
    free(res);
    free(rescell);
}

/* The grid keys' count when the header is a sweep's: the keys, then pst_sweep_columns. */
static int sweep_keys(const pst_csv_table *t)
{
    const int nkeys = pst_csv_table_column(t, "dim", t->ncols);
    if (nkeys < 0 || nkeys > 4 * SW_MAX_KEYS || t->ncols != nkeys + pst_sweep_ncolumns)
        return -1;
    for (int q = 0; q < pst_sweep_ncolumns; ++q)
        if (strcmp(t->cell[nkeys + q], pst_sweep_columns[q]) != 0)
            return -1;
    return nkeys;
}

cJSON *pst_sweep_summary(const pst_csv_table *t, const char *slope_key, const char *repeat_key)
{
    view v = {.t = t, .nkeys = sweep_keys(t)};
    if (v.nkeys < 0)
        return NULL;
    v.task = v.nkeys + C_TASK;
    v.slope = pst_csv_table_column(t, slope_key, t->ncols);
    v.repeat = pst_csv_table_column(t, repeat_key, t->ncols);
    for (int q = 0; q < NSTAT; ++q)
        v.stat_col[q] = pst_csv_table_column(t, stat_cols[q], t->ncols);
    const size_t n = t->nrows;
    v.ok = malloc(n + 1);
    v.gid = malloc((n + 1) * sizeof *v.gid);
    v.first = malloc((n + 1) * sizeof *v.first);
    v.vals = malloc((n + 1) * sizeof *v.vals);
    cJSON *sum = v.ok && v.gid && v.first && v.vals ? cJSON_CreateObject() : NULL;
    if (sum) {
        for (size_t r = 1; r <= n; ++r)
            v.ok[r] = strcmp(cell(&v, r, v.nkeys + C_STATUS), "ok") == 0;
        cJSON *keys = cJSON_AddArrayToObject(sum, "keys");
        for (int q = 0; q < v.nkeys; ++q)
            cJSON_AddItemToArray(keys, cJSON_CreateString(t->cell[q]));
        cJSON_AddStringToObject(sum, "slope_key", slope_key);
        cJSON_AddStringToObject(sum, "repeat_key", repeat_key);
        add_row_counts(sum, &v);
        add_groups(sum, &v);
        add_fits(sum, &v);
    }
    free(v.ok);
    free(v.gid);
    free(v.first);
    free(v.vals);
    return sum;
}
