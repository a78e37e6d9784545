/* libFuzzer harness of the sweep file parser (pst_sweep_parse, docs/sweeps.md): any bytes as a
 * sweep file. The file is named as if it were in scenes/sweeps/ of the source tree, so that a
 * "scene" such as "../qsfdi_test_a.json" reads the project's own scene (the parser only reads;
 * nothing is written). A sweep that parses must give every combination's values. */
#include "fuzz_input.h"
#include "pstencil.h"
#include "sweep.h"

#include <stdio.h>
#include <stdlib.h>

/* Combinations checked from each end of a sweep. */
enum { NCHECK = 32 };

static void check_combo(const pst_sweep *sw, size_t k)
{
    const char *vals[SW_MAX_KEYS] = {0};
    pst_sweep_combo(sw, k, vals);
    for (int i = 0; i < sw->nkeys; ++i)
        if (!vals[i]) {
            fprintf(stderr, "combination %zu of %zu: no value for key %d\n", k, sw->ncombos, i);
            abort();
        }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char *text = fuzz_text(data, size);
    pst_sweep sw;
    char err[PST_ERRLEN * 4] = "";
    int st = pst_sweep_parse(&sw, text, PSTENCIL_SOURCE_DIR "/scenes/sweeps/fuzz.json", err,
                             sizeof err);
    free(text);
    if (st != PST_OK) {
        if (!err[0]) {
            fprintf(stderr, "status %d without a message\n", st);
            abort();
        }
        return 0;
    }
    for (size_t k = 0; k < sw.ncombos && k < NCHECK; ++k) {
        check_combo(&sw, k);
        check_combo(&sw, sw.ncombos - 1 - k);
    }
    pst_sweep_free(&sw);
    return 0;
}
