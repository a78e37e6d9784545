/* What the plot files share (src/app/plot.c, plot_lines.c): the table being plotted, the
 * plot set being built, and the row helpers. Private to the plot files. Rows are r = 1..nrows
 * of the table (row 0 is the header). */
#ifndef PSTENCIL_PLOT_CTX_H
#define PSTENCIL_PLOT_CTX_H

#include "plot.h"

#include <cjson/cJSON.h>

enum { MAX_SERIES = 64, MAX_FILES = 32, MAX_BARS = 48 };

typedef struct {
    const pst_csv_table *t;
    int nkeys, nc;
    int scheme, spacing, repeat, jitter, hratio;        /* key columns, -1 when absent */
    int task, type, status, particles, iter, tpre, ttask, ttotal, normcol;
    int phase[5];
    const char *slope_key;
    const cJSON *fits;
    pst_plot_set *ps;
    int oom;
} plot_ctx;

typedef struct {
    const char *name, *title, *xlabel, *ylabel;
    int logx, logy;
    int xcol, ycol;
    int slopes; /* legend slopes from the summary fits (ycol is c->normcol) */
} line_spec;

const char *plot_cell(const plot_ctx *c, size_t r, int col);
/* 1 and *v when the cell of row r, column col is a number (the table's typed cells). */
int plot_number(const plot_ctx *c, size_t r, int col, double *v);
/* The part of a dotted key after its last dot: cloud.h_ratio -> h_ratio. */
const char *plot_short_key(const char *k);
/* Record a plot that is not drawn, with the reason (c->oom when out of memory). */
void plot_skip(plot_ctx *c, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* A new plot, or a new series of n points, zeroed; NULL (c->oom) when out of memory. */
pst_plot *plot_new_plot(plot_ctx *c);
pst_plot_series *plot_new_series(plot_ctx *c, pst_plot *p, const char *label, size_t n);
/* Group the kept rows (keep[r]) by the cells of the columns with use[col]: gid[r] (SIZE_MAX
 * for rows not kept) and each group's first row, in order of appearance; the group count. */
size_t plot_group_by(const plot_ctx *c, const unsigned char *keep, const unsigned char *use,
                     size_t *gid, size_t *first);
/* Distinct cells of column col among the kept rows: 0, 1 or 2 meaning "several". */
int plot_distinct(const plot_ctx *c, const unsigned char *keep, int col);
/* Append to buf (size len) "sep" then text, when buf is not empty, else text. */
void plot_append(char *buf, size_t len, const char *sep, const char *text);
/* Sort a series' points by x. */
void plot_sort_points(pst_plot_series *s);

/* Lines of mean y against mean x (plot_lines.c), over the rows with keep[r] (changed). */
void plot_lines(plot_ctx *c, const line_spec *sp, unsigned char *keep);

#endif
