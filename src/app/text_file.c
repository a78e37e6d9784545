#include "text_file.h"

#include "pstencil.h"

#include <cjson/cJSON.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

char *pst_read_text(const char *path, size_t *len_out, char *err, size_t errlen, int *status)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        if (err && errlen)
            snprintf(err, errlen, "%s: cannot open: %s", path, strerror(errno));
        *status = PST_EIO;
        return NULL;
    }
    size_t cap = 4096, len = 0;
    char *text = malloc(cap);
    for (size_t got = 1; text && got > 0;) {
        if (len + 1 == cap) {
            char *grown = realloc(text, cap *= 2);
            if (!grown) {
                free(text);
                text = NULL;
                break;
            }
            text = grown;
        }
        got = fread(text + len, 1, cap - 1 - len, f);
        len += got;
    }
    int bad = ferror(f), e = errno; /* a directory opens, then fails to read: EISDIR */
    fclose(f);
    if (!text || bad) {
        free(text);
        if (err && errlen)
            snprintf(err, errlen, "%s: %s%s", path, bad ? "read error: " : "out of memory",
                     bad ? strerror(e) : "");
        *status = bad ? PST_EIO : PST_ENOMEM;
        return NULL;
    }
    text[len] = '\0';
    if (len_out)
        *len_out = len;
    return text;
}

char *pst_strdup(const char *s)
{
    size_t n = strlen(s) + 1;
    char *d = malloc(n);
    if (d)
        memcpy(d, s, n);
    return d;
}

void pst_write_json(FILE *f, const void *json)
{
    char *text = cJSON_Print(json);
    if (text) {
        fputs(text, f);
        fputc('\n', f);
    }
    free(text);
}
