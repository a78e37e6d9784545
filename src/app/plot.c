/* Plots of a sweep (docs/plots.md): the series of each plot from the sweep CSV's cells. Rows
 * are grouped by their grid-key cells like the summary's groups (src/sweep.c), so a point's
 * mean and standard deviation are the summary's `mean` and `std` of its group. */
#include "plot.h"
#include "plot_ctx.h"

#include "pstencil.h"
#include "text_file.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *const pst_plot_norms[] = {"rel_l2", "qsfdi11", "lv95", "lv78", "max_abs"};
const int pst_plot_nnorms = (int)(sizeof pst_plot_norms / sizeof pst_plot_norms[0]);

const char *const pst_plot_known_norms[] = {"rel_l2", "qsfdi11", "qsfdi11_normalised",
                                            "lv78",   "lv95",    "max_abs", "max_rel"};
const int pst_plot_nknown_norms =
    (int)(sizeof pst_plot_known_norms / sizeof pst_plot_known_norms[0]);

const char *plot_cell(const plot_ctx *c, size_t r, int col)
{
    return c->t->cell[r * (size_t)c->nc + (size_t)col];
}

/* 1 and *v when the cell of row r, column col is a number (the table's typed cells). */
int plot_number(const plot_ctx *c, size_t r, int col, double *v)
{
    double x = c->t->num[r * (size_t)c->nc + (size_t)col];
    if (isnan(x))
        return 0;
    *v = x;
    return 1;
}


/* the part of a dotted key after its last dot: cloud.h_ratio -> h_ratio */
const char *plot_short_key(const char *k)
{
    const char *d = strrchr(k, '.');
    return d ? d + 1 : k;
}

void plot_skip(plot_ctx *c, const char *fmt, ...)
{
    char buf[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    char **s = realloc(c->ps->skipped, (size_t)(c->ps->nskipped + 1) * sizeof *s);
    char *d = pst_strdup(buf);
    if (!s || !d) {
        free(d);
        if (s)
            c->ps->skipped = s;
        c->oom = 1;
        return;
    }
    c->ps->skipped = s;
    s[c->ps->nskipped++] = d;
}

pst_plot *plot_new_plot(plot_ctx *c)
{
    pst_plot *p = realloc(c->ps->plots, (size_t)(c->ps->nplots + 1) * sizeof *p);
    if (!p) {
        c->oom = 1;
        return NULL;
    }
    c->ps->plots = p;
    p += c->ps->nplots++;
    memset(p, 0, sizeof *p);
    return p;
}

pst_plot_series *plot_new_series(plot_ctx *c, pst_plot *p, const char *label, size_t n)
{
    pst_plot_series *s = realloc(p->series, (size_t)(p->nseries + 1) * sizeof *s);
    if (!s) {
        c->oom = 1;
        return NULL;
    }
    p->series = s;
    s += p->nseries++;
    memset(s, 0, sizeof *s);
    s->label = pst_strdup(label);
    s->x = calloc(n + 1, sizeof *s->x);
    s->y = calloc(n + 1, sizeof *s->y);
    s->err = calloc(n + 1, sizeof *s->err);
    if (!s->label || !s->x || !s->y || !s->err) {
        c->oom = 1;
        return NULL;
    }
    return s;
}

/* Group the kept rows (keep[r], r = 1..nrows) by the cells of the columns with use[col]:
 * gid[r] (SIZE_MAX for rows not kept) and each group's first row, in order of appearance. */
size_t plot_group_by(const plot_ctx *c, const unsigned char *keep, const unsigned char *use,
                       size_t *gid, size_t *first)
{
    size_t ng = 0;
    for (size_t r = 1; r <= c->t->nrows; ++r) {
        gid[r] = SIZE_MAX;
        if (!keep[r])
            continue;
        size_t g = 0;
        for (; g < ng; ++g) {
            int same = 1;
            for (int q = 0; same && q < c->nc; ++q)
                same = !use[q] || strcmp(plot_cell(c, first[g], q), plot_cell(c, r, q)) == 0;
            if (same)
                break;
        }
        if (g == ng)
            first[ng++] = r;
        gid[r] = g;
    }
    return ng;
}

/* Distinct cells of column col among the kept rows (up to 2: 0, 1 or 2 meaning "several"). */
int plot_distinct(const plot_ctx *c, const unsigned char *keep, int col)
{
    const char *v = NULL;
    for (size_t r = 1; r <= c->t->nrows; ++r) {
        if (!keep[r])
            continue;
        if (!v)
            v = plot_cell(c, r, col);
        else if (strcmp(v, plot_cell(c, r, col)) != 0)
            return 2;
    }
    return v ? 1 : 0;
}

/* Append to buf (size len) "sep" then text, when buf is not empty, else text. */
void plot_append(char *buf, size_t len, const char *sep, const char *text)
{
    size_t u = strlen(buf);
    if (u + 1 >= len)
        return;
    snprintf(buf + u, len - u, "%s%s", u ? sep : "", text);
}

void plot_sort_points(pst_plot_series *s)
{
    for (size_t i = 1; i < s->n; ++i)
        for (size_t j = i; j > 0 && s->x[j - 1] > s->x[j]; --j) {
            double t = s->x[j];
            s->x[j] = s->x[j - 1];
            s->x[j - 1] = t;
            t = s->y[j];
            s->y[j] = s->y[j - 1];
            s->y[j - 1] = t;
            t = s->err[j];
            s->err[j] = s->err[j - 1];
            s->err[j - 1] = t;
        }
}

/* rows with status ok */
static void keep_ok(const plot_ctx *c, unsigned char *keep)
{
    keep[0] = 0;
    for (size_t r = 1; r <= c->t->nrows; ++r)
        keep[r] = strcmp(plot_cell(c, r, c->status), "ok") == 0;
}

/* The mean (t_precompute + t_task) of each group. */
static void time_means(const plot_ctx *c, const size_t *gid, const size_t *first, size_t ng,
                       double *mean)
{
    for (size_t g = 0; g < ng; ++g) {
        double s = 0;
        size_t m = 0;
        for (size_t r = first[g]; r <= c->t->nrows; ++r)
            if (gid[r] == g) {
                double a = 0, b = 0;
                plot_number(c, r, c->tpre, &a);
                plot_number(c, r, c->ttask, &b);
                s += a + b;
                ++m;
            }
        mean[g] = s / (double)m;
    }
}

/* The point of qsfdi group g: x its key value, y the mean time of the lpmps group with the
 * same cells but the scheme (and the repeat key) over g's. None when there is no such group
 * or g's mean is not positive. */
static void ratio_point(const plot_ctx *c, const size_t *first, const double *mean, size_t ng,
                        size_t g, int xcol, pst_plot_series *se)
{
    const size_t rq = first[g];
    for (size_t h = 0; h < ng; ++h) {
        const size_t rl = first[h];
        if (strcmp(plot_cell(c, rl, c->scheme), "lpmps") != 0 ||
            strcmp(plot_cell(c, rl, c->task), plot_cell(c, rq, c->task)) != 0)
            continue;
        int same = 1;
        for (int q = 0; same && q < c->nkeys; ++q)
            same = q == c->scheme || q == c->repeat ||
                   strcmp(plot_cell(c, rl, q), plot_cell(c, rq, q)) == 0;
        if (!same || !(mean[g] > 0))
            continue;
        plot_number(c, rq, xcol, &se->x[se->n]);
        se->y[se->n] = mean[h] / mean[g];
        se->err[se->n] = NAN;
        ++se->n;
        return;
    }
}

/* The LP-MPS / QSFDI ratio of mean (t_precompute + t_task) against key column xcol. */
static void ratio_plot(plot_ctx *c, unsigned char *keep, int xcol, const char *xname,
                       const char *name, const char *xlabel)
{
    const size_t n = c->t->nrows;
    if (c->scheme < 0) {
        plot_skip(c, "%s.png: operator.scheme is not a grid key", name);
        return;
    }
    int has_q = 0, has_l = 0;
    for (size_t r = 1; r <= n; ++r) {
        double a, b;
        const char *s = plot_cell(c, r, c->scheme);
        int q = strcmp(s, "qsfdi") == 0, l = strcmp(s, "lpmps") == 0;
        if (keep[r] && (q || l) && plot_number(c, r, c->tpre, &a) &&
            plot_number(c, r, c->ttask, &b)) {
            has_q |= q;
            has_l |= l;
        } else {
            keep[r] = 0;
        }
    }
    if (!has_q || !has_l) {
        plot_skip(c, "%s.png: needs ok rows of both qsfdi and lpmps", name);
        return;
    }
    if (xcol < 0) {
        plot_skip(c, "%s.png: %s is not a grid key", name, xname);
        return;
    }
    if (plot_distinct(c, keep, xcol) < 2) {
        plot_skip(c, "%s.png: %s takes one value", name, xname);
        return;
    }
    unsigned char *use = calloc((size_t)c->nc, 1);
    size_t *gid = malloc((n + 1) * sizeof *gid), *first = malloc((n + 1) * sizeof *first);
    size_t *sid = malloc((n + 1) * sizeof *sid), *sfirst = malloc((n + 1) * sizeof *sfirst);
    double *mean = malloc((n + 1) * sizeof *mean);
    if (!use || !gid || !first || !sid || !sfirst || !mean) {
        c->oom = 1;
        goto done;
    }
    for (int q = 0; q < c->nkeys; ++q)
        use[q] = q != c->repeat;
    use[c->task] = 1;
    size_t ng = plot_group_by(c, keep, use, gid, first);
    time_means(c, gid, first, ng, mean);
    /* series: the qsfdi groups by all keys but the scheme, x and the repeat key */
    use[c->scheme] = 0;
    use[xcol] = 0;
    unsigned char *qkeep = keep; /* reuse: only the qsfdi rows now */
    for (size_t r = 1; r <= n; ++r)
        qkeep[r] = keep[r] && strcmp(plot_cell(c, r, c->scheme), "qsfdi") == 0;
    size_t ns = plot_group_by(c, qkeep, use, sid, sfirst);
    int bytask = plot_distinct(c, qkeep, c->task) > 1;
    pst_plot *p = plot_new_plot(c);
    if (!p)
        goto done;
    snprintf(p->name, sizeof p->name, "%s", name);
    snprintf(p->title, sizeof p->title, "LP-MPS / QSFDI time (precompute + task)");
    snprintf(p->xlabel, sizeof p->xlabel, "%s", xlabel);
    snprintf(p->ylabel, sizeof p->ylabel, "time(lpmps) / time(qsfdi)");
    p->kind = PST_PLOT_LINES;
    for (size_t s = 0; s < ns && !c->oom; ++s) {
        const size_t r0 = sfirst[s];
        char lab[256] = "";
        for (int q = 0; q < c->nkeys; ++q)
            if (use[q] && (plot_distinct(c, qkeep, q) > 1 || q == c->spacing)) {
                char part[128];
                snprintf(part, sizeof part, "%s %s", plot_short_key(c->t->cell[q]),
                         plot_cell(c, r0, q));
                plot_append(lab, sizeof lab, ", ", part);
            }
        if (bytask || !lab[0])
            plot_append(lab, sizeof lab, ", ", plot_cell(c, r0, c->task));
        size_t npts = 0;
        for (size_t g = 0; g < ng; ++g)
            npts += sid[first[g]] == s;
        pst_plot_series *se = plot_new_series(c, p, lab, npts);
        if (!se)
            break;
        for (size_t g = 0; g < ng; ++g)
            if (sid[first[g]] == s)
                ratio_point(c, first, mean, ng, g, xcol, se);
        plot_sort_points(se);
    }
done:
    free(use);
    free(gid);
    free(first);
    free(sid);
    free(sfirst);
    free(mean);
}

static const char *const phase_cols[5] = {"t_geometry", "t_moments", "t_inversion",
                                          "t_weights", "t_task"};
static const char *const phase_labels[5] = {"geometry", "moments", "inversions", "weights",
                                            "task (apply or solve)"};

/* Stacked bars of the mean phase times per scheme (per series) at the finest resolution. */
static void phases_plot(plot_ctx *c, unsigned char *keep)
{
    const size_t n = c->t->nrows;
    double fine = INFINITY;
    for (size_t r = 1; r <= n; ++r) {
        double v;
        if (keep[r] && !plot_number(c, r, c->ttask, &v))
            keep[r] = 0;
        if (keep[r] && c->spacing >= 0 && plot_number(c, r, c->spacing, &v) && v < fine)
            fine = v;
    }
    if (plot_distinct(c, keep, c->ttask) == 0) {
        plot_skip(c, "phases.png: no ok rows with a t_task");
        return;
    }
    const char *fine_cell = NULL;
    if (c->spacing >= 0)
        for (size_t r = 1; r <= n; ++r) {
            double v;
            if (keep[r] && !(plot_number(c, r, c->spacing, &v) && v == fine))
                keep[r] = 0;
            else if (keep[r] && !fine_cell)
                fine_cell = plot_cell(c, r, c->spacing);
        }
    unsigned char *use = calloc((size_t)c->nc, 1);
    size_t *gid = malloc((n + 1) * sizeof *gid), *first = malloc((n + 1) * sizeof *first);
    double *v = malloc((n + 1) * sizeof *v);
    if (!use || !gid || !first || !v) {
        c->oom = 1;
        goto done;
    }
    for (int q = 0; q < c->nkeys; ++q)
        use[q] = q != c->repeat && q != c->spacing;
    use[c->task] = 1;
    size_t ng = plot_group_by(c, keep, use, gid, first);
    if (ng > MAX_BARS) {
        plot_skip(c, "phases.png: %zu bars (more than %d)", ng, MAX_BARS);
        goto done;
    }
    int bytask = plot_distinct(c, keep, c->task) > 1;
    pst_plot *p = plot_new_plot(c);
    if (!p)
        goto done;
    snprintf(p->name, sizeof p->name, "phases");
    if (fine_cell)
        snprintf(p->title, sizeof p->title, "mean time per phase, %s = %s",
                 c->t->cell[c->spacing], fine_cell);
    else
        snprintf(p->title, sizeof p->title, "mean time per phase");
    snprintf(p->ylabel, sizeof p->ylabel, "seconds");
    p->kind = PST_PLOT_STACKED;
    p->ncat = (int)ng;
    p->cat = calloc(ng + 1, sizeof *p->cat);
    if (!p->cat) {
        c->oom = 1;
        goto done;
    }
    for (size_t g = 0; g < ng; ++g) {
        char lab[256] = "";
        for (int q = 0; q < c->nkeys; ++q)
            if (use[q] && plot_distinct(c, keep, q) > 1)
                plot_append(lab, sizeof lab, " ", plot_cell(c, first[g], q));
        if (bytask || !lab[0])
            plot_append(lab, sizeof lab, " ", plot_cell(c, first[g], c->task));
        if (!(p->cat[g] = pst_strdup(lab)))
            c->oom = 1;
    }
    for (int k = 0; k < 5 && !c->oom; ++k) {
        pst_plot_series *se = plot_new_series(c, p, phase_labels[k], ng);
        if (!se)
            break;
        for (size_t g = 0; g < ng; ++g) {
            size_t m = 0;
            for (size_t r = first[g]; r <= n; ++r)
                if (gid[r] == g && plot_number(c, r, c->phase[k], &v[m]))
                    ++m;
            se->x[g] = (double)g;
            if (m)
                pst_mean_std(v, m, &se->y[g], &se->err[g]);
            else {
                se->y[g] = 0;
                se->err[g] = NAN;
            }
        }
        se->n = ng;
    }
done:
    free(use);
    free(gid);
    free(first);
    free(v);
}

int pst_plot_build(const pst_csv_table *t, const cJSON *summary, const char *norm,
                   pst_plot_set *ps, char *err, size_t errlen)
{
    memset(ps, 0, sizeof *ps);
    plot_ctx c = {.t = t, .nc = t->ncols, .ps = ps};
    c.nkeys = pst_csv_table_column(t, "dim", t->ncols);
    if (c.nkeys < 0 || t->ncols != c.nkeys + pst_sweep_ncolumns) {
        snprintf(err, errlen, "not a sweep CSV (no 'dim' column, or not %d columns after the "
                              "grid keys)", pst_sweep_ncolumns);
        return PST_EINPUT;
    }
    for (int q = 0; q < pst_sweep_ncolumns; ++q)
        if (strcmp(t->cell[c.nkeys + q], pst_sweep_columns[q]) != 0) {
            snprintf(err, errlen, "not a sweep CSV: column %d is '%s', expected '%s'",
                     c.nkeys + q + 1, t->cell[c.nkeys + q], pst_sweep_columns[q]);
            return PST_EINPUT;
        }
    const cJSON *sk = cJSON_GetObjectItemCaseSensitive(summary, "slope_key");
    const cJSON *rk = cJSON_GetObjectItemCaseSensitive(summary, "repeat_key");
    c.slope_key = cJSON_IsString(sk) ? sk->valuestring : "cloud.spacing";
    const char *repeat_key = cJSON_IsString(rk) ? rk->valuestring : "cloud.seed";
    c.fits = cJSON_GetObjectItemCaseSensitive(summary, "fits");
    c.scheme = pst_csv_table_column(t, "operator.scheme", c.nkeys);
    c.spacing = pst_csv_table_column(t, c.slope_key, c.nkeys);
    c.repeat = pst_csv_table_column(t, repeat_key, c.nkeys);
    c.jitter = pst_csv_table_column(t, "cloud.jitter", c.nkeys);
    c.hratio = pst_csv_table_column(t, "cloud.h_ratio", c.nkeys);
    c.task = pst_csv_table_column(t, "task", t->ncols);
    c.type = pst_csv_table_column(t, "type", t->ncols);
    c.status = pst_csv_table_column(t, "status", t->ncols);
    c.particles = pst_csv_table_column(t, "particles", t->ncols);
    c.iter = pst_csv_table_column(t, "iterations", t->ncols);
    c.tpre = pst_csv_table_column(t, "t_precompute", t->ncols);
    c.ttask = pst_csv_table_column(t, "t_task", t->ncols);
    c.ttotal = pst_csv_table_column(t, "t_total", t->ncols);
    for (int k = 0; k < 5; ++k)
        c.phase[k] = pst_csv_table_column(t, phase_cols[k], t->ncols);

    const size_t n = t->nrows;
    unsigned char *keep = malloc(n + 1);
    if (!keep) {
        snprintf(err, errlen, "out of memory");
        return PST_ENOMEM;
    }
    /* the norm: --norm, or the first of the default order with a value in an ok row */
    c.normcol = -1;
    if (norm) {
        for (int i = 0; i < pst_plot_nknown_norms; ++i)
            if (strcmp(norm, pst_plot_known_norms[i]) == 0)
                c.normcol = pst_csv_table_column(t, norm, t->ncols);
        if (c.normcol < 0) {
            free(keep);
            snprintf(err, errlen, "unknown norm '%s' (known: rel_l2, qsfdi11, "
                                  "qsfdi11_normalised, lv78, lv95, max_abs, max_rel)", norm);
            return PST_EINPUT;
        }
    } else {
        keep_ok(&c, keep);
        for (int i = 0; i < pst_plot_nnorms && c.normcol < 0; ++i) {
            int q = pst_csv_table_column(t, pst_plot_norms[i], t->ncols);
            for (size_t r = 1; r <= n && c.normcol < 0; ++r) {
                double v;
                if (keep[r] && plot_number(&c, r, q, &v))
                    c.normcol = q;
            }
        }
    }
    snprintf(ps->norm, sizeof ps->norm, "%s", c.normcol >= 0 ? t->cell[c.normcol] : "");

    char ylabel[96], xlabel[96];
    snprintf(ylabel, sizeof ylabel, "error (%s)", ps->norm);
    if (c.normcol >= 0 && c.spacing >= 0) {
        keep_ok(&c, keep);
        snprintf(xlabel, sizeof xlabel, "%s", strcmp(c.slope_key, "cloud.spacing") == 0
                                                  ? "particle spacing s0"
                                                  : c.slope_key);
        line_spec sp = {"error_vs_s0", "mean error against spacing", xlabel, ylabel, 1, 1,
                        c.spacing, c.normcol, 1};
        plot_lines(&c, &sp, keep);
    } else if (c.normcol < 0) {
        plot_skip(&c, "error_vs_s0.png: no error norm measured");
    } else {
        plot_skip(&c, "error_vs_s0.png: %s is not a grid key", c.slope_key);
    }
    if (c.normcol >= 0) {
        keep_ok(&c, keep);
        line_spec sp = {"error_vs_time", "mean error against mean wall-clock time of the run",
                        "t_total (s)", ylabel, 1, 1, c.ttotal, c.normcol, 0};
        plot_lines(&c, &sp, keep);
    } else {
        plot_skip(&c, "error_vs_time.png: no error norm measured");
    }
    keep_ok(&c, keep);
    ratio_plot(&c, keep, c.jitter, "cloud.jitter", "time_ratio_vs_jitter", "jitter K");
    keep_ok(&c, keep);
    ratio_plot(&c, keep, c.hratio, "cloud.h_ratio", "time_ratio_vs_h", "h / s0");
    keep_ok(&c, keep);
    phases_plot(&c, keep);
    keep_ok(&c, keep);
    int solves = 0;
    for (size_t r = 1; r <= n; ++r) {
        keep[r] = keep[r] && strcmp(plot_cell(&c, r, c.type), "solve") == 0;
        solves |= keep[r];
    }
    if (solves) {
        line_spec sp = {"iterations_vs_n", "mean solver iterations against particles",
                        "particles", "iterations", 1, 0, c.particles, c.iter, 0};
        plot_lines(&c, &sp, keep);
    } else {
        plot_skip(&c, "iterations_vs_n.png: no ok rows of a solve task");
    }
    free(keep);
    if (c.oom) {
        pst_plot_set_free(ps);
        snprintf(err, errlen, "out of memory");
        return PST_ENOMEM;
    }
    return PST_OK;
}

void pst_plot_set_free(pst_plot_set *ps)
{
    for (int i = 0; i < ps->nplots; ++i) {
        pst_plot *p = &ps->plots[i];
        for (int s = 0; s < p->nseries; ++s) {
            free(p->series[s].label);
            free(p->series[s].x);
            free(p->series[s].y);
            free(p->series[s].err);
        }
        free(p->series);
        for (int k = 0; p->cat && k < p->ncat; ++k)
            free(p->cat[k]);
        free(p->cat);
    }
    free(ps->plots);
    for (int i = 0; i < ps->nskipped; ++i)
        free(ps->skipped[i]);
    free(ps->skipped);
    memset(ps, 0, sizeof *ps);
}

const pst_plot *pst_plot_find(const pst_plot_set *ps, const char *name)
{
    for (int i = 0; i < ps->nplots; ++i)
        if (strcmp(ps->plots[i].name, name) == 0)
            return &ps->plots[i];
    return NULL;
}
