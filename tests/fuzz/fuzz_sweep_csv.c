/* libFuzzer harness of what `pstencil plot` reads (docs/plots.md): any bytes as a sweep's
 * results CSV, parsed into a table (pst_csv_parse_table), summarised as `plot` does without a
 * summary file (pst_sweep_summary), and turned into plots (pst_plot_build). Every step must
 * succeed or fail cleanly. */
#include "fuzz_input.h"
#include "fuzz_plot_check.h"
#include "plot.h"
#include "pstencil.h"
#include "sweep.h"

#include <cjson/cJSON.h>
#include <stdio.h>
#include <stdlib.h>

/* The plots of table t with its summary; the summary must print (it is written as JSON). */
static void plot(const pst_csv_table *t, cJSON *summary)
{
    char *json = cJSON_PrintUnformatted(summary);
    if (!json) {
        fprintf(stderr, "a summary that does not print\n");
        abort();
    }
    free(json);
    fuzz_check_plots(t, summary, NULL);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char *text = fuzz_text(data, size);
    pst_csv_table t;
    char err[PST_ERRLEN] = "";
    int st = pst_csv_parse_table(&t, text, "fuzz.csv", 0, err);
    free(text);
    if (st != PST_OK) {
        if (!err[0]) {
            fprintf(stderr, "pst_csv_parse_table: status %d without a message\n", st);
            abort();
        }
        return 0;
    }
    cJSON *summary = pst_sweep_summary(&t, "cloud.spacing", "cloud.seed");
    if (summary)
        plot(&t, summary);
    cJSON_Delete(summary);
    pst_csv_table_free(&t);
    return 0;
}
