/* `pstencil plot RESULTS.csv [--summary S.json] [--out DIR] [--norm NAME] [--size WxH]`: PNG
 * plots of a sweep (docs/plots.md). src/plot.c extracts the series; this file writes them as
 * inline data blocks into a gnuplot (Debian gnuplot-nox) driven through a pipe, then renames
 * the PNGs from their temporary names, all of them or none. */
#define _POSIX_C_SOURCE 200809L /* popen, pclose, getpid, access, mkdir */
#include "cli.h"
#include "gnuplot.h"
#include "plot.h"
#include "text_file.h"

#include <cjson/cJSON.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static void plot_help(void)
{
    printf("usage: pstencil plot RESULTS.csv [--summary SUMMARY.json] [--out DIR] [--norm NAME]\n"
           "                    [--size WxH]\n\n"
           "Draw PNG plots of a sweep's CSV with gnuplot: error against s0 (log-log, the fitted\n"
           "slopes in the legend), error against time, the LP-MPS / QSFDI time ratio against\n"
           "the jitter and h/s0, stacked phase times per scheme, solver iterations against the\n"
           "particle count. Only the plots the data supports are drawn; each skipped one is\n"
           "listed with the reason. docs/plots.md describes them.\n\n"
           "  --summary F  the sweep's summary JSON, for the slopes (default: RESULTS'\n"
           "               <stem>.summary.json when present, else computed from the CSV)\n"
           "  --out DIR    output folder, created when missing (default: <stem>_plots)\n"
           "  --norm NAME  error norm: rel_l2, qsfdi11, qsfdi11_normalised, lv78, lv95,\n"
           "               max_abs, max_rel (default: the first of rel_l2, qsfdi11, lv95,\n"
           "               lv78, max_abs with a value)\n"
           "  --size WxH   image size in pixels (default 800x500)\n\n"
           "exit codes: 0 ok, 1 usage, 2 unreadable CSV or summary, no gnuplot, or gnuplot\n"
           "failed (then no PNG is written)\n");
}

/* 1 when an executable `name` is on PATH. */
static int on_path(const char *name)
{
    const char *path = getenv("PATH");
    if (!path || !*path)
        return 0;
    while (*path) {
        const char *end = strchr(path, ':');
        size_t len = end ? (size_t)(end - path) : strlen(path);
        char buf[4096];
        if (len == 0)
            snprintf(buf, sizeof buf, "./%s", name);
        else
            snprintf(buf, sizeof buf, "%.*s/%s", (int)len, path, name);
        if (access(buf, X_OK) == 0)
            return 1;
        if (!end)
            break;
        path = end + 1;
    }
    return 0;
}

/* A shell single-quoted word. */
static void shell_quote(char *out, size_t len, const char *s)
{
    size_t i = 0;
    if (len < 3)
        return;
    out[i++] = '\'';
    for (; *s && i + 5 < len; ++s) {
        if (*s == '\'') {
            memcpy(out + i, "'\\''", 4);
            i += 4;
        } else {
            out[i++] = *s;
        }
    }
    out[i++] = '\'';
    out[i] = '\0';
}

static int nonempty_series(const pst_plot *p)
{
    int k = 0;
    for (int s = 0; s < p->nseries; ++s)
        k += p->series[s].n > 0;
    return k;
}

/* Tics of a log axis over [lo, hi]: gnuplot's decades when the range spans 3 or more, else
 * 1-2-5 (or 1..9) times the powers of ten, or the x values themselves when there are few. */
static void log_tics(FILE *g, char axis, double lo, double hi, const double *vals, int nvals)
{
    fprintf(g, "set logscale %c\n", axis);
    if (!(lo > 0) || !(hi >= lo))
        return;
    double dec = log10(hi / lo);
    if (nvals > 0 && nvals <= 8 && dec < 3) {
        fprintf(g, "set %ctics (", axis);
        for (int i = 0; i < nvals; ++i)
            fprintf(g, "%s%.17g", i ? ", " : "", vals[i]);
        fprintf(g, ")\nset format %c '%%g'\n", axis);
        return;
    }
    if (dec >= 3) {
        fprintf(g, "set format %c '%s'\n", axis, axis == 'y' ? "10^{%L}" : "%g");
        return;
    }
    static const double m125[3] = {1, 2, 5}, m19[9] = {1, 2, 3, 4, 5, 6, 7, 8, 9};
    const double *m = dec < 0.7 ? m19 : m125;
    int nm = dec < 0.7 ? 9 : 3, k = 0;
    fprintf(g, "set %ctics (", axis);
    for (int e = (int)floor(log10(lo)) - 1; e <= (int)ceil(log10(hi)) + 1; ++e)
        for (int i = 0; i < nm; ++i) {
            double v = m[i] * pow(10, e);
            if (v >= lo / 1.25 && v <= hi * 1.25)
                fprintf(g, "%s%.6g", k++ ? ", " : "", v);
        }
    fprintf(g, ")\nset format %c '%%g'\n", axis);
}

static void script_lines(FILE *g, const pst_plot *p)
{
    fprintf(g, "set grid\nset key below center samplen 2 height 1\n");
    double xlo = INFINITY, xhi = -INFINITY, ylo = INFINITY, yhi = -INFINITY, xs[9];
    int nx = 0;
    for (int s = 0; s < p->nseries; ++s)
        for (size_t i = 0; i < p->series[s].n; ++i) {
            const pst_plot_series *se = &p->series[s];
            double e = isfinite(se->err[i]) ? se->err[i] : 0;
            xlo = fmin(xlo, se->x[i]);
            xhi = fmax(xhi, se->x[i]);
            ylo = fmin(ylo, se->y[i] - e > se->y[i] / 100 ? se->y[i] - e : se->y[i] / 100);
            yhi = fmax(yhi, se->y[i] + e);
            int seen = 0;
            for (int j = 0; j < nx && j < 9; ++j)
                seen |= xs[j] == se->x[i];
            if (!seen && nx < 9)
                xs[nx] = se->x[i];
            nx += !seen;
        }
    if (p->logx)
        log_tics(g, 'x', xlo, xhi, xs, nx <= 8 ? nx : 0);
    if (p->logy)
        log_tics(g, 'y', ylo, yhi, NULL, 0);
    /* the data's range plus a margin, not whole decades */
    fprintf(g, "set autoscale fix\nset offsets graph 0.05, graph 0.05, graph 0.08, graph 0.05\n");
    for (int s = 0; s < p->nseries; ++s) {
        const pst_plot_series *se = &p->series[s];
        if (!se->n)
            continue;
        fprintf(g, "$d%d << EOD\n", s);
        for (size_t i = 0; i < se->n; ++i) {
            double e = isfinite(se->err[i]) ? se->err[i] : 0;
            double lo = se->y[i] - e, hi = se->y[i] + e;
            if (p->logy && lo < se->y[i] / 100) /* a bar below zero, cut on a log axis */
                lo = se->y[i] / 100;
            fprintf(g, "%.17g %.17g %.17g %.17g\n", se->x[i], se->y[i], lo, hi);
        }
        fprintf(g, "EOD\n");
    }
    fprintf(g, "plot ");
    int first = 1;
    for (int s = 0; s < p->nseries; ++s) {
        const pst_plot_series *se = &p->series[s];
        if (!se->n)
            continue;
        int bars = 0;
        for (size_t i = 0; i < se->n; ++i)
            bars |= isfinite(se->err[i]) && se->err[i] > 0;
        fprintf(g, "%s$d%d using 1:2%s with %s lw 2 pt %d ps 1.2 title ", first ? "" : ", ", s,
                bars ? ":3:4" : "", bars ? "yerrorlines" : "linespoints", 4 + 2 * (s % 5) + 1);
        pst_gnuplot_quoted(g, se->label);
        fprintf(g, " noenhanced");
        first = 0;
    }
    fprintf(g, "\n");
}

static void script_stacked(FILE *g, const pst_plot *p)
{
    fprintf(g, "set style data histograms\nset style histogram rowstacked\n"
               "set style fill solid 0.85 border -1\nset boxwidth 0.7\nset grid ytics\n"
               "set key below center samplen 1\nset yrange [0:*]\n");
    if (p->ncat > 6)
        fprintf(g, "set xtics rotate by -35\n");
    fprintf(g, "set xtics nomirror noenhanced\n");
    fprintf(g, "$d << EOD\n");
    for (int c = 0; c < p->ncat; ++c) {
        fputc('"', g);
        for (const char *s = p->cat[c]; *s; ++s)
            fputc(*s == '"' ? '\'' : *s, g);
        fputc('"', g);
        for (int s = 0; s < p->nseries; ++s)
            fprintf(g, " %.17g", p->series[s].y[c]);
        fputc('\n', g);
    }
    fprintf(g, "EOD\nplot ");
    for (int s = 0; s < p->nseries; ++s) {
        fprintf(g, "%s$d using %d%s title ", s ? ", " : "", s + 2, s ? "" : ":xtic(1)");
        pst_gnuplot_quoted(g, p->series[s].label);
        fprintf(g, " noenhanced");
    }
    fprintf(g, "\n");
}

typedef struct {
    const char *csv, *summary, *out, *norm, *size;
    int width, height;
    char stem[4096]; /* the CSV's path without ".csv" */
} plot_args;

static int usage(const char *fmt, const char *arg)
{
    fprintf(stderr, "pstencil plot: ");
    fprintf(stderr, fmt, arg);
    fprintf(stderr, "\nTry 'pstencil plot --help'.\n");
    return CLI_USAGE;
}

/* The command line into a: CLI_OK, CLI_USAGE, or -1 after --help. */
static int parse_args(int argc, char **argv, plot_args *a)
{
    *a = (plot_args){.size = "800x500"};
    for (int i = 0; i < argc; ++i) {
        const char *v;
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            plot_help();
            return -1;
        } else if (cli_option(argc, argv, &i, "--summary", &v)) {
            a->summary = v;
        } else if (cli_option(argc, argv, &i, "--out", &v)) {
            a->out = v;
        } else if (cli_option(argc, argv, &i, "--norm", &v)) {
            a->norm = v;
        } else if (cli_option(argc, argv, &i, "--size", &v)) {
            a->size = v;
        } else if (argv[i][0] == '-' || a->csv) {
            return usage("unexpected argument '%s'", argv[i]);
        } else {
            a->csv = argv[i];
            continue;
        }
        if (!v || !*v)
            return usage("%s needs a value", argv[i]);
    }
    if (!a->csv)
        return usage("no sweep CSV%s", "");
    int known = !a->norm;
    for (int i = 0; i < pst_plot_nknown_norms && !known; ++i)
        known = strcmp(a->norm, pst_plot_known_norms[i]) == 0;
    if (!known) {
        fprintf(stderr, "pstencil plot: unknown norm '%s' (known: rel_l2, qsfdi11, "
                        "qsfdi11_normalised, lv78, lv95, max_abs, max_rel)\n", a->norm);
        return CLI_USAGE;
    }
    char tail;
    if (sscanf(a->size, "%dx%d%c", &a->width, &a->height, &tail) != 2 || a->width < 100 ||
        a->height < 100 || a->width > 10000 || a->height > 10000) {
        fprintf(stderr, "pstencil plot: --size needs WxH, 100 to 10000 pixels each (got '%s')\n",
                a->size);
        return CLI_USAGE;
    }
    snprintf(a->stem, sizeof a->stem, "%s", a->csv);
    size_t sl = strlen(a->stem);
    if (sl > 4 && strcmp(a->stem + sl - 4, ".csv") == 0)
        a->stem[sl - 4] = '\0';
    return CLI_OK;
}

/* The summary: --summary, else <stem>.summary.json when readable, else computed from t. */
static int load_summary(const plot_args *a, const pst_csv_table *t, cJSON **out, char *err,
                        size_t errlen)
{
    char defsum[4200];
    snprintf(defsum, sizeof defsum, "%s.summary.json", a->stem);
    const char *from = a->summary;
    if (!from && access(defsum, R_OK) == 0)
        from = defsum;
    if (!from) {
        *out = pst_sweep_summary(t, "cloud.spacing", "cloud.seed");
        if (!*out)
            snprintf(err, errlen, "%s: not a sweep CSV", a->csv);
        return *out ? PST_OK : PST_EINPUT;
    }
    int rst = PST_OK;
    char *text = pst_read_text(from, NULL, err, errlen, &rst);
    *out = text ? cJSON_Parse(text) : NULL;
    free(text);
    if (*out && cJSON_IsObject(*out))
        return PST_OK;
    cJSON_Delete(*out);
    *out = NULL;
    if (text)
        snprintf(err, errlen, "%s: not a JSON object", from);
    return PST_EINPUT;
}

/* The plot set of the CSV and its summary. */
static int build_plots(const plot_args *a, pst_plot_set *ps, char *err, size_t errlen)
{
    pst_csv_table t;
    int st = pst_csv_read_table(&t, a->csv, 0, err);
    if (st != PST_OK)
        return st;
    cJSON *summary = NULL;
    st = load_summary(a, &t, &summary, err, errlen);
    if (st == PST_OK) {
        char msg[PST_ERRLEN + 512];
        st = pst_plot_build(&t, summary, a->norm, ps, msg, sizeof msg);
        if (st != PST_OK)
            snprintf(err, errlen, "%s: %s", a->csv, msg);
    }
    cJSON_Delete(summary);
    pst_csv_table_free(&t);
    return st;
}

/* The output folder, created when missing. */
static int make_dir(const char *dir, char *err, size_t errlen)
{
    struct stat sb;
    if (mkdir(dir, 0777) == 0 || (errno == EEXIST && stat(dir, &sb) == 0 && S_ISDIR(sb.st_mode)))
        return PST_OK;
    snprintf(err, errlen, "%s: cannot create the folder: %s", dir, strerror(errno));
    return PST_EIO;
}

/* The gnuplot script of every plot with points, each into its temporary name tmp[i]. */
static void write_script(FILE *g, const pst_plot_set *ps, const plot_args *a, const char *dir,
                         char (*tmp)[4400])
{
    fprintf(g, "set encoding utf8\n"
               "if (strstrt(GPVAL_TERMINALS, 'pngcairo') > 0) {\n"
               "  set terminal pngcairo enhanced size %d,%d font ',10'\n"
               "} else {\n"
               "  set terminal png enhanced size %d,%d\n"
               "}\n",
            a->width, a->height, a->width, a->height);
    for (int i = 0; i < ps->nplots; ++i) {
        const pst_plot *p = &ps->plots[i];
        if (!nonempty_series(p))
            continue;
        snprintf(tmp[i], sizeof tmp[i], "%s/.%s.%ld.png.tmp", dir, p->name, (long)getpid());
        /* enhanced text for the tic labels (10^{-3}), none in strings from the data */
        fprintf(g, "reset\nset output ");
        pst_gnuplot_quoted(g, tmp[i]);
        fprintf(g, "\nset title ");
        pst_gnuplot_quoted(g, p->title);
        fprintf(g, " noenhanced\nset xlabel ");
        pst_gnuplot_quoted(g, p->xlabel);
        fprintf(g, " noenhanced\nset ylabel ");
        pst_gnuplot_quoted(g, p->ylabel);
        fprintf(g, " noenhanced\n");
        if (p->kind == PST_PLOT_STACKED)
            script_stacked(g, p);
        else
            script_lines(g, p);
        fprintf(g, "unset output\n");
    }
    fprintf(g, "exit\n");
}

/* After gnuplot: every PNG renamed to its final name, or (gnuplot failed) none, its log on
 * stderr. */
static int publish(const pst_plot_set *ps, const char *dir, int status, const char *log,
                   char (*tmp)[4400])
{
    int ok = status == 0, rc = CLI_OK;
    for (int i = 0; ok && i < ps->nplots; ++i)
        ok = !tmp[i][0] || pst_file_is_png(tmp[i]);
    if (!ok) {
        fprintf(stderr, "pstencil: plot: gnuplot failed (no PNG written)\n");
        int rst;
        char *text = pst_read_text(log, NULL, NULL, 0, &rst);
        if (text)
            fputs(text, stderr);
        free(text);
        rc = CLI_BAD_INPUT;
    }
    for (int i = 0; i < ps->nplots && rc == CLI_OK; ++i) {
        if (!tmp[i][0])
            continue;
        char final[4400], err[9000];
        snprintf(final, sizeof final, "%s/%s.png", dir, ps->plots[i].name);
        if (rename(tmp[i], final) != 0) {
            snprintf(err, sizeof err, "cannot rename %s to %s: %s", tmp[i], final,
                     strerror(errno));
            rc = cli_fail(PST_EIO, "plot", err);
            break;
        }
        tmp[i][0] = '\0';
        printf("wrote %s\n", final);
    }
    for (int i = 0; i < ps->nplots; ++i)
        if (tmp[i][0])
            remove(tmp[i]);
    remove(log);
    return rc;
}

/* The plots with points through one gnuplot, all PNGs or none; *started once gnuplot runs
 * (or nothing needs it). */
static int draw(const pst_plot_set *ps, const plot_args *a, const char *dir, int *started)
{
    int ndraw = 0;
    for (int i = 0; i < ps->nplots; ++i)
        ndraw += nonempty_series(&ps->plots[i]) > 0;
    char (*tmp)[4400] = calloc((size_t)ps->nplots + 1, sizeof *tmp);
    char log[4400], qlog[9000], cmd[9100];
    snprintf(log, sizeof log, "%s/.gnuplot.%ld.log", dir, (long)getpid());
    shell_quote(qlog, sizeof qlog, log);
    snprintf(cmd, sizeof cmd, "exec gnuplot 2> %s", qlog);
    FILE *g = tmp && ndraw ? popen(cmd, "w") : NULL;
    if (!tmp || (ndraw && !g)) {
        free(tmp);
        return cli_fail(tmp ? PST_EIO : PST_ENOMEM, "plot", tmp ? "cannot start gnuplot" : "");
    }
    int rc = CLI_OK;
    *started = 1;
    if (g) {
        write_script(g, ps, a, dir, tmp);
        rc = publish(ps, dir, pclose(g), log, tmp);
    }
    free(tmp);
    return rc;
}

static void list_skipped(const pst_plot_set *ps, int rc)
{
    for (int i = 0; i < ps->nplots; ++i)
        if (!nonempty_series(&ps->plots[i]))
            printf("skipped %s.png: no points\n", ps->plots[i].name);
    for (int i = 0; i < ps->nskipped; ++i)
        printf("skipped %s\n", ps->skipped[i]);
    if (rc == CLI_OK)
        printf("error norm: %s\n", ps->norm[0] ? ps->norm : "(none)");
}

int cli_plot(const cli_ctx *ctx, int argc, char **argv)
{
    plot_args a;
    int rc = parse_args(argc, argv, &a);
    if (rc != CLI_OK)
        return rc < 0 ? CLI_OK : rc;
    char err[PST_ERRLEN + 12000];
    pst_plot_set ps;
    int st = build_plots(&a, &ps, err, sizeof err);
    if (st != PST_OK)
        return cli_fail(st, "plot", err);
    if (!on_path("gnuplot")) {
        pst_plot_set_free(&ps);
        fprintf(stderr, "pstencil: plot: gnuplot not found: install gnuplot-nox "
                        "(scripts/install-deps.sh)\n");
        return CLI_BAD_INPUT;
    }
    char dir[4200];
    if (a.out)
        snprintf(dir, sizeof dir, "%s", a.out);
    else
        snprintf(dir, sizeof dir, "%s_plots", a.stem);
    int started = 0;
    st = make_dir(dir, err, sizeof err);
    rc = st == PST_OK ? draw(&ps, &a, dir, &started) : cli_fail(st, "plot", err);
    if (!ctx->quiet && started)
        list_skipped(&ps, rc);
    pst_plot_set_free(&ps);
    return rc;
}
