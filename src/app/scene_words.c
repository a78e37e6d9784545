/* Words of a scene's messages: the values an enum allows, and the nearest known word to a
 * misspelt one ("did you mean"), by edit distance. */
#include "scene_walk.h"

#include "pstencil.h"

#include <stdio.h>
#include <string.h>

/* Levenshtein distance, capped: strings longer than 63 bytes are "far" from everything. */
static int edit_distance(const char *a, const char *b)
{
    size_t la = strlen(a), lb = strlen(b);
    if (la > 63 || lb > 63)
        return 1000;
    int row[64];
    for (size_t j = 0; j <= lb; ++j)
        row[j] = (int)j;
    for (size_t i = 1; i <= la; ++i) {
        int diag = row[0];
        row[0] = (int)i;
        for (size_t j = 1; j <= lb; ++j) {
            int up = row[j];
            int best = diag + (a[i - 1] != b[j - 1]);
            if (up + 1 < best)
                best = up + 1;
            if (row[j - 1] + 1 < best)
                best = row[j - 1] + 1;
            row[j] = best;
            diag = up;
        }
    }
    return row[lb];
}

/* Keep `cand` in *best when it is closer to `word` than the best so far and close enough to
 * be a likely typo. */
void scene_consider(const char *word, const char *cand, const char **best, int *bestd)
{
    int d = edit_distance(word, cand);
    int len = (int)strlen(word);
    if (d <= 2 && d < len && d < *bestd) {
        *best = cand;
        *bestd = d;
    }
}

const char *sc_suggest_word(const char *word, const char *const *words, int n)
{
    const char *best = NULL;
    int bestd = 1000;
    for (int k = 0; k < n; ++k)
        scene_consider(word, words[k], &best, &bestd);
    return best;
}

/* Index of `word` in the '|'-separated list `values`, or -1. */
int scene_value_index(const char *values, const char *word)
{
    size_t wl = strlen(word);
    int k = 0;
    for (const char *p = values;; ++k) {
        const char *bar = strchr(p, '|');
        size_t n = bar ? (size_t)(bar - p) : strlen(p);
        if (n == wl && strncmp(p, word, n) == 0)
            return k;
        if (!bar)
            return -1;
        p = bar + 1;
    }
}

/* "a|b|c" as "a, b, c". */
const char *scene_listed(const char *values, char *buf, size_t len)
{
    size_t used = 0;
    buf[0] = '\0';
    for (const char *q = values; *q && used + 1 < len;) {
        size_t n = strcspn(q, "|");
        int w = snprintf(buf + used, len - used, "%s%.*s", used ? ", " : "", (int)n, q);
        if (w < 0)
            break;
        used += (size_t)w;
        q += n + (q[n] == '|');
    }
    return buf;
}
