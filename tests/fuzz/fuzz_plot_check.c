/* The plot harnesses' check of a built plot set. */
#include "fuzz_plot_check.h"

#include "pstencil.h"

#include <stdio.h>
#include <stdlib.h>

void fuzz_check_plots(const pst_csv_table *t, const struct cJSON *summary, const char *norm)
{
    pst_plot_set ps;
    char err[PST_ERRLEN + 512] = "";
    int st = pst_plot_build(t, summary, norm, &ps, err, sizeof err);
    if (st == PST_OK) {
        for (int i = 0; i < ps.nplots; ++i)
            if (!pst_plot_find(&ps, ps.plots[i].name))
                abort();
        pst_plot_set_free(&ps);
    } else if (!err[0]) {
        fprintf(stderr, "pst_plot_build: status %d without a message\n", st);
        abort();
    }
}
