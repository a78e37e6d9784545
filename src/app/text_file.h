/* Text for the front end: whole files (scenes, sweeps) read into one string, JSON documents
 * written, and copies of strings. */
#ifndef PSTENCIL_TEXT_FILE_H
#define PSTENCIL_TEXT_FILE_H

#include <stddef.h>
#include <stdio.h>

/* The content of `path` as a NUL-terminated string (free it). On failure NULL, *status is
 * PST_EIO (cannot open, read error) or PST_ENOMEM and err (may be NULL) gets "PATH: reason".
 * *len (may be NULL) receives the byte count: a file holding a NUL byte has strlen(text) <
 * *len. */
char *pst_read_text(const char *path, size_t *len, char *err, size_t errlen, int *status);

/* The pst_write_atomic writer of a JSON document: `json` (a cJSON *) printed formatted, then a
 * newline; nothing when out of memory. */
void pst_write_json(FILE *f, const void *json);

/* A malloc'ed copy of s (free it), or NULL when out of memory: C17 has no strdup. */
char *pst_strdup(const char *s);

#endif
