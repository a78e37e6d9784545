/* What the plot harnesses check of every plot set they build (fuzz_plot_check.c). */
#ifndef PSTENCIL_FUZZ_PLOT_CHECK_H
#define PSTENCIL_FUZZ_PLOT_CHECK_H

#include "plot.h"

/* pst_plot_build of table t with `summary` (may be NULL) and `norm` (may be NULL): on success
 * every plot built must be found by its name; on failure err must hold a message. Aborts
 * otherwise, so libFuzzer records the input. */
void fuzz_check_plots(const pst_csv_table *t, const struct cJSON *summary, const char *norm);

#endif
