/* libFuzzer harness of the scene parser with its overrides (pst_scene_parse, docs/scenes.md):
 * the input is a scene's JSON text, then optionally a NUL byte and "key=value" overrides, one a
 * line (what `pstencil run SCENE key=value ...` hands the parser). Every input must parse or
 * fail with a message. */
#include "fuzz_input.h"
#include "pstencil.h"
#include "scene.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { MAX_OVERRIDES = 16 };

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char *text = fuzz_text(data, size);
    size_t len = strlen(text);
    char *rest = len < size ? fuzz_text(data + len + 1, size - len - 1) : NULL;
    char *piece[MAX_OVERRIDES];
    const char *overrides[MAX_OVERRIDES];
    int nov = rest ? fuzz_split(rest, '\n', piece, MAX_OVERRIDES) : 0;
    for (int i = 0; i < nov; ++i)
        overrides[i] = piece[i];
    pst_scene s;
    char err[PST_ERRLEN * 2] = "";
    int st = pst_scene_parse(&s, text, "fuzz/scene.json", overrides, nov, err, sizeof err);
    if (st == PST_OK)
        pst_scene_free(&s);
    else if (!err[0]) {
        fprintf(stderr, "status %d without a message\n", st);
        abort();
    }
    free(rest);
    free(text);
    return 0;
}
