/* Plots of a sweep (docs/plots.md): the series each plot shows, extracted from the sweep CSV
 * and its summary (the fits' slopes). No drawing here: src/cli/cmd_plot.c hands the series to
 * gnuplot. Every mean is over the rows with status ok, like the summary's. */
#ifndef PSTENCIL_PLOT_H
#define PSTENCIL_PLOT_H

#include "sweep.h"

#include <stddef.h>

struct cJSON;

typedef enum {
    PST_PLOT_LINES,  /* lines and points, with error bars where err is finite       */
    PST_PLOT_STACKED /* stacked bars: category c stacks series[0..].y[c]            */
} pst_plot_kind;

typedef struct {
    char *label;      /* legend entry, e.g. "qsfdi (slope 1.98 ± 0.03)"              */
    size_t n;         /* points (stacked bars: the plot's ncat)                      */
    double *x, *y;    /* x increasing (stacked bars: x = category index)             */
    double *err;      /* standard deviation of y over the repeats; NAN: none         */
} pst_plot_series;

typedef struct {
    char name[160];   /* file name without ".png": error_vs_s0, error_vs_s0_jitter-0.4 */
    char title[256];
    char xlabel[96], ylabel[96];
    pst_plot_kind kind;
    int logx, logy;
    int nseries;
    pst_plot_series *series;
    int ncat;         /* stacked bars: the categories (bars), labelled cat[c]        */
    char **cat;
} pst_plot;

typedef struct {
    int nplots;
    pst_plot *plots;
    int nskipped;
    char **skipped;   /* "time_ratio_vs_h.png: cloud.h_ratio takes one value", ...   */
    char norm[32];    /* the error norm of the error plots                           */
} pst_plot_set;

/* The error norms a plot may use, and the default order (the first with a value wins). */
extern const char *const pst_plot_norms[];
extern const int pst_plot_nnorms;
/* Every norm column --norm accepts. */
extern const char *const pst_plot_known_norms[];
extern const int pst_plot_nknown_norms;

/* Build the plots the sweep table supports:
 *   error_vs_s0          mean error (std bars) vs the slope key, per series, with the
 *                        summary fits' slopes in the legend; one per value of the keys that
 *                        vary within a scheme (suffix _KEY-VALUE);
 *   error_vs_time        mean error vs mean t_total, per series (same files);
 *   time_ratio_vs_jitter mean (t_precompute + t_task) of lpmps over qsfdi vs cloud.jitter,
 *   time_ratio_vs_h      ... vs cloud.h_ratio, one line per other key values (the spacing);
 *   phases               stacked mean t_geometry, t_moments, t_inversion, t_weights, t_task
 *                        per scheme at the finest spacing;
 *   iterations_vs_n      solve tasks: mean iterations vs mean particles.
 * `summary` (may be NULL) gives slope_key, repeat_key (defaults cloud.spacing, cloud.seed) and
 * the fits. `norm` NULL picks the first of rel_l2, qsfdi11, lv95, lv78, max_abs with a value.
 * Plots the data does not support are listed in ps->skipped with the reason.
 * PST_EINPUT (not a sweep CSV, unknown norm) or PST_ENOMEM with the reason in err. */
int pst_plot_build(const pst_csv_table *t, const struct cJSON *summary, const char *norm,
                   pst_plot_set *ps, char *err, size_t errlen);
void pst_plot_set_free(pst_plot_set *ps);

/* The plot named `name` (NULL when absent). */
const pst_plot *pst_plot_find(const pst_plot_set *ps, const char *name);

#endif
