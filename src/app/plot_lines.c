/* The line plots of a sweep (docs/plots.md): error against spacing or time, iterations
 * against particles. Series and files come from the grid keys that vary; each point is the
 * mean (and standard deviation) over a group of rows, as the summary's groups. */
#include "plot_ctx.h"

#include "pstencil.h"

#include <cjson/cJSON.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* 1 when the kept rows with equal cells in column `by` have equal cells in column `col`. */
static int determined(const plot_ctx *c, const unsigned char *keep, int col, int by)
{
    for (size_t r = 1; r <= c->t->nrows; ++r) {
        if (!keep[r])
            continue;
        for (size_t s = 1; s < r; ++s)
            if (keep[s] && strcmp(plot_cell(c, s, by), plot_cell(c, r, by)) == 0) {
                if (strcmp(plot_cell(c, s, col), plot_cell(c, r, col)) != 0)
                    return 0;
                break; /* rows before s agree with s already */
            }
    }
    return 1;
}

/* A file-name-safe copy of a cell: [A-Za-z0-9.-] kept, others '_'. */
static void safe_name(char *out, size_t len, const char *s)
{
    size_t i = 0;
    for (; *s && i + 1 < len; ++s)
        out[i++] = ((*s >= 'a' && *s <= 'z') || (*s >= 'A' && *s <= 'Z') ||
                    (*s >= '0' && *s <= '9') || *s == '.' || *s == '-')
                       ? *s
                       : '_';
    out[i] = '\0';
}

/* A cell typed as the summary's keys are (a number, bool, list or object when it parses as
 * one, else a string), compared with a fit's key value. */
static int cell_equals(const char *c, const cJSON *v)
{
    cJSON *p = cJSON_Parse(c);
    int eq;
    if (p && (cJSON_IsNumber(p) || cJSON_IsBool(p) || cJSON_IsArray(p) || cJSON_IsObject(p)))
        eq = cJSON_Compare(p, v, 1);
    else
        eq = cJSON_IsString(v) && strcmp(v->valuestring, c) == 0;
    cJSON_Delete(p);
    return eq;
}

/* The summary fit of the group whose first row is r (task, norm, keys): slope and stderr. */
static const cJSON *find_fit(const plot_ctx *c, size_t r, const char *norm)
{
    const cJSON *f;
    cJSON_ArrayForEach(f, c->fits)
    {
        const cJSON *task = cJSON_GetObjectItemCaseSensitive(f, "task");
        const cJSON *fn = cJSON_GetObjectItemCaseSensitive(f, "norm");
        const cJSON *key = cJSON_GetObjectItemCaseSensitive(f, "key");
        if (!cJSON_IsString(task) || !cJSON_IsString(fn) || !cJSON_IsObject(key) ||
            strcmp(task->valuestring, plot_cell(c, r, c->task)) != 0 ||
            strcmp(fn->valuestring, norm) != 0)
            continue;
        int match = 1;
        const cJSON *kv;
        cJSON_ArrayForEach(kv, key)
        {
            int q = pst_csv_table_column(c->t, kv->string, c->nkeys);
            if (q < 0 || !cell_equals(plot_cell(c, r, q), kv)) {
                match = 0;
                break;
            }
        }
        if (match)
            return f;
    }
    return NULL;
}

/* Rows grouped three ways for a line plot: by file (the keys that split), by series, by
 * point; gid[r] and first[g] as group_by gives them. */
typedef struct {
    unsigned char *split, *label, *use; /* per column: splits files, labels series, groups */
    size_t *gid[3], *first[3], n[3];
    double *xv, *yv;                    /* a point's values, scratch                        */
} line_groups;

enum { BY_FILE, BY_SERIES, BY_POINT };

static void line_groups_free(line_groups *lg)
{
    free(lg->split);
    free(lg->label);
    free(lg->use);
    for (int k = 0; k < 3; ++k) {
        free(lg->gid[k]);
        free(lg->first[k]);
    }
    free(lg->xv);
    free(lg->yv);
}

static int line_groups_alloc(line_groups *lg, size_t nc, size_t n)
{
    memset(lg, 0, sizeof *lg);
    lg->split = calloc(nc, 1);
    lg->label = calloc(nc, 1);
    lg->use = calloc(nc, 1);
    int ok = lg->split && lg->label && lg->use;
    for (int k = 0; k < 3; ++k) {
        lg->gid[k] = malloc((n + 1) * sizeof *lg->gid[k]);
        lg->first[k] = malloc((n + 1) * sizeof *lg->first[k]);
        ok = ok && lg->gid[k] && lg->first[k];
    }
    lg->xv = malloc((n + 1) * sizeof *lg->xv);
    lg->yv = malloc((n + 1) * sizeof *lg->yv);
    return ok && lg->xv && lg->yv;
}

/* Keep the rows with a number x and y (positive on a log axis): 0 when none has a y. */
static int keep_points(plot_ctx *c, const line_spec *sp, unsigned char *keep)
{
    for (size_t r = 1; r <= c->t->nrows; ++r) {
        double x, y;
        if (keep[r] && !(plot_number(c, r, sp->xcol, &x) && plot_number(c, r, sp->ycol, &y) &&
                         (!sp->logx || x > 0) && (!sp->logy || y > 0)))
            keep[r] = 0;
    }
    if (plot_distinct(c, keep, sp->ycol) > 0)
        return 1;
    plot_skip(c, "%s.png: no ok rows with a positive %s%s", sp->name, c->t->cell[sp->ycol],
         sp->logx ? " and x" : "");
    return 0;
}

/* The series keys (all but the resolution and the repeat key) that vary: the primary one (the
 * scheme, or the first that varies) names the series, the keys it determines label them, the
 * others split the plot into files. The primary key's column, or -1. */
static int classify_keys(const plot_ctx *c, const unsigned char *keep, line_groups *lg)
{
    int ser[SW_MAX_KEYS * 4], nser = 0;
    for (int q = 0; q < c->nkeys && nser < SW_MAX_KEYS * 4; ++q)
        if (q != c->spacing && q != c->repeat)
            ser[nser++] = q;
    int primary = c->scheme;
    for (int i = 0; primary < 0 && i < nser; ++i)
        if (plot_distinct(c, keep, ser[i]) > 1)
            primary = ser[i];
    for (int i = 0; i < nser; ++i) {
        int q = ser[i];
        lg->use[q] = 1;
        if (q == primary || plot_distinct(c, keep, q) < 2)
            continue;
        if (primary >= 0 && determined(c, keep, q, primary))
            lg->label[q] = 1;
        else
            lg->split[q] = 1;
    }
    return primary;
}

/* A new plot for file f: the name and title carry the splitting keys' values. */
static pst_plot *file_plot(plot_ctx *c, const line_spec *sp, const line_groups *lg, size_t r0)
{
    pst_plot *p = plot_new_plot(c);
    if (!p)
        return NULL;
    char name[160], cond[200];
    snprintf(name, sizeof name, "%s", sp->name);
    cond[0] = '\0';
    for (int q = 0; q < c->nkeys; ++q)
        if (lg->split[q]) {
            char v[64], part[160];
            safe_name(v, sizeof v, plot_cell(c, r0, q));
            snprintf(part, sizeof part, "_%s-%s", plot_short_key(c->t->cell[q]), v);
            plot_append(name, sizeof name, "", part);
            snprintf(part, sizeof part, "%s = %s", c->t->cell[q], plot_cell(c, r0, q));
            plot_append(cond, sizeof cond, ", ", part);
        }
    snprintf(p->name, sizeof p->name, "%s", name);
    if (cond[0])
        snprintf(p->title, sizeof p->title, "%s (%s)", sp->title, cond);
    else
        snprintf(p->title, sizeof p->title, "%s", sp->title);
    snprintf(p->xlabel, sizeof p->xlabel, "%s", sp->xlabel);
    snprintf(p->ylabel, sizeof p->ylabel, "%s", sp->ylabel);
    p->kind = PST_PLOT_LINES;
    p->logx = sp->logx;
    p->logy = sp->logy;
    return p;
}

/* The legend entry of the series whose first row is r0, with the fit's slope when asked. */
static void series_label(const plot_ctx *c, const line_spec *sp, const line_groups *lg, int primary,
                         int bytask, size_t r0, char *lab, size_t len)
{
    lab[0] = '\0';
    if (primary >= 0)
        plot_append(lab, len, ", ", plot_cell(c, r0, primary));
    for (int q = 0; q < c->nkeys; ++q)
        if (lg->label[q]) {
            char part[128];
            snprintf(part, sizeof part, "%s %s", plot_short_key(c->t->cell[q]),
                     plot_cell(c, r0, q));
            plot_append(lab, len, ", ", part);
        }
    if (bytask || !lab[0])
        plot_append(lab, len, ", ", plot_cell(c, r0, c->task));
    if (!sp->slopes)
        return;
    const cJSON *fit = find_fit(c, r0, c->t->cell[sp->ycol]);
    const cJSON *sl = cJSON_GetObjectItemCaseSensitive(fit, "slope");
    const cJSON *se = cJSON_GetObjectItemCaseSensitive(fit, "stderr");
    char part[96];
    if (cJSON_IsNumber(sl) && cJSON_IsNumber(se))
        snprintf(part, sizeof part, " (slope %.2f \xc2\xb1 %.2f)", sl->valuedouble,
                 se->valuedouble);
    else if (cJSON_IsNumber(sl))
        snprintf(part, sizeof part, " (slope %.2f)", sl->valuedouble);
    else
        part[0] = '\0';
    plot_append(lab, len, "", part);
}

/* The points of series s: per point group, the means of x and y (y's standard deviation). */
static void series_points(const plot_ctx *c, const line_spec *sp, line_groups *lg, size_t s,
                          pst_plot_series *se)
{
    const size_t n = c->t->nrows;
    for (size_t g = 0; g < lg->n[BY_POINT]; ++g) {
        if (lg->gid[BY_SERIES][lg->first[BY_POINT][g]] != s)
            continue;
        size_t m = 0;
        for (size_t r = lg->first[BY_POINT][g]; r <= n; ++r)
            if (lg->gid[BY_POINT][r] == g) {
                plot_number(c, r, sp->xcol, &lg->xv[m]);
                plot_number(c, r, sp->ycol, &lg->yv[m]);
                ++m;
            }
        double sx;
        pst_mean_std(lg->xv, m, &se->x[se->n], &sx);
        pst_mean_std(lg->yv, m, &se->y[se->n], &se->err[se->n]);
        ++se->n;
    }
    plot_sort_points(se);
}

/* The plot of file f: one series per series group in it. */
static void file_series(plot_ctx *c, const line_spec *sp, line_groups *lg, size_t f, int primary,
                        int bytask)
{
    size_t nsf = 0;
    for (size_t s = 0; s < lg->n[BY_SERIES]; ++s)
        nsf += lg->gid[BY_FILE][lg->first[BY_SERIES][s]] == f;
    if (nsf > MAX_SERIES) {
        plot_skip(c, "%s.png: %zu series (more than %d)", sp->name, nsf, MAX_SERIES);
        return;
    }
    pst_plot *p = file_plot(c, sp, lg, lg->first[BY_FILE][f]);
    for (size_t s = 0; p && s < lg->n[BY_SERIES] && !c->oom; ++s) {
        const size_t r0 = lg->first[BY_SERIES][s];
        if (lg->gid[BY_FILE][r0] != f)
            continue;
        char lab[256];
        series_label(c, sp, lg, primary, bytask, r0, lab, sizeof lab);
        size_t npts = 0;
        for (size_t g = 0; g < lg->n[BY_POINT]; ++g)
            npts += lg->gid[BY_SERIES][lg->first[BY_POINT][g]] == s;
        pst_plot_series *se = plot_new_series(c, p, lab, npts);
        if (!se)
            break;
        series_points(c, sp, lg, s, se);
    }
}

/* Lines of mean y against mean x, one per series (the grid keys but the resolution and the
 * repeat key, and the task when several): the points are the groups of all keys but the
 * repeat key. Keys that vary within a scheme split the plot into files. */
void plot_lines(plot_ctx *c, const line_spec *sp, unsigned char *keep)
{
    if (!keep_points(c, sp, keep))
        return;
    line_groups lg;
    if (!line_groups_alloc(&lg, (size_t)c->nc, c->t->nrows)) {
        c->oom = 1;
        line_groups_free(&lg);
        return;
    }
    const int primary = classify_keys(c, keep, &lg);
    const int bytask = plot_distinct(c, keep, c->task) > 1;
    lg.n[BY_FILE] = plot_group_by(c, keep, lg.split, lg.gid[BY_FILE], lg.first[BY_FILE]);
    lg.use[c->task] = 1;
    lg.n[BY_SERIES] = plot_group_by(c, keep, lg.use, lg.gid[BY_SERIES], lg.first[BY_SERIES]);
    if (c->spacing >= 0)
        lg.use[c->spacing] = 1;
    lg.n[BY_POINT] = plot_group_by(c, keep, lg.use, lg.gid[BY_POINT], lg.first[BY_POINT]);
    if (lg.n[BY_FILE] > MAX_FILES)
        plot_skip(c, "%s.png: %zu combinations of the keys that vary within a scheme (more "
                     "than %d)", sp->name, lg.n[BY_FILE], MAX_FILES);
    for (size_t f = 0; lg.n[BY_FILE] <= MAX_FILES && f < lg.n[BY_FILE] && !c->oom; ++f)
        file_series(c, sp, &lg, f, primary, bytask);
    line_groups_free(&lg);
}

