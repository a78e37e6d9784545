/* libFuzzer harness of the summary JSON that `pstencil plot --summary` reads (docs/plots.md):
 * any bytes as the summary, parsed as the command parses it (cJSON, an object or a refusal),
 * then read by pst_plot_build (slope_key, repeat_key, the fits' slopes) beside the sweep table
 * it was written with, docs/reports/data/qsfdi_vs_lpmps_2d.csv of the source tree (read once
 * per process). The build must succeed with plots that can be found by name, or fail with a
 * message. */
#include "fuzz_input.h"
#include "fuzz_plot_check.h"
#include "plot.h"
#include "pstencil.h"
#include "sweep.h"
#include "text_file.h"

#include <cjson/cJSON.h>
#include <stdio.h>
#include <stdlib.h>

static pst_csv_table table;
static int have_table;

static void free_table(void) { pst_csv_table_free(&table); }

/* The sweep table, once. */
static void load_table(void)
{
    const char *path = PSTENCIL_SOURCE_DIR "/docs/reports/data/qsfdi_vs_lpmps_2d.csv";
    char err[PST_ERRLEN] = "";
    int rst = PST_OK;
    char *text = pst_read_text(path, NULL, err, sizeof err, &rst);
    if (!text || pst_csv_parse_table(&table, text, path, 0, err) != PST_OK) {
        fprintf(stderr, "fuzz_summary: %s\n", err);
        abort();
    }
    free(text);
    have_table = 1;
    atexit(free_table);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (!have_table)
        load_table();
    char *text = fuzz_text(data, size);
    cJSON *summary = cJSON_Parse(text);
    free(text);
    if (!cJSON_IsObject(summary)) { /* `plot` refuses it: "not a JSON object" */
        cJSON_Delete(summary);
        return 0;
    }
    fuzz_check_plots(&table, summary, NULL);
    fuzz_check_plots(&table, summary, "rel_l2");
    cJSON_Delete(summary);
    return 0;
}
