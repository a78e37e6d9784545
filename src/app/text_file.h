/* Text for the front end: whole files (scenes, sweeps, CSV results) read into one string, and
 * copies of strings. */
#ifndef PSTENCIL_TEXT_FILE_H
#define PSTENCIL_TEXT_FILE_H

#include <stddef.h>

/* The content of `path` as a NUL-terminated string (free it). On failure NULL, *status is
 * PST_EIO (cannot open, read error) or PST_ENOMEM and err (may be NULL) gets "PATH: reason". *len (may be
 * NULL) receives the byte count: a file holding a NUL byte has strlen(text) < *len. */
char *pst_read_text(const char *path, size_t *len, char *err, size_t errlen, int *status);

/* A malloc'ed copy of s (free it), or NULL when out of memory: C17 has no strdup. */
char *pst_strdup(const char *s);

#endif
