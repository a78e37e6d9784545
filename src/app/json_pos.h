/* Positions in JSON text. cJSON keeps none, so a message that names a line and column finds
 * the key again by re-scanning the original text with a small tokenizer. */
#ifndef PSTENCIL_JSON_POS_H
#define PSTENCIL_JSON_POS_H

#include <stddef.h>

/* One step of a path from the top-level value. */
typedef struct {
    const char *key; /* object member name (compared after decoding escapes), or NULL for an
                        array element                                                        */
    int index;       /* array element index; for a member, which occurrence of a repeated
                        key (0: the first)                                                   */
} json_step;

/* 1-based line and column of byte `offset` of `text` (the column counts UTF-8 characters;
 * an offset past the terminating NUL is clamped to it). */
void json_pos_offset(const char *text, size_t offset, int *line, int *col);

/* Find the value that path[0..depth) leads to in `text` and give the line and column of its
 * member key's opening quote, or of the array element itself. Returns how many steps were
 * found: depth on success; on a partial match (a missing key, malformed text) line:col is
 * that of the deepest step found, or of the top-level value when none was (1:1 for text
 * with no value). Never reads past the terminating NUL. */
int json_pos_find(const char *text, const json_step *path, int depth, int *line, int *col);

/* Line and column of cJSON's syntax-error pointer `at` (from cJSON_ParseWithOpts'
 * return_parse_end or cJSON_GetErrorPtr) into `text`; NULL or an out-of-text pointer gives
 * the end of the text. */
void json_pos_error(const char *text, const char *at, int *line, int *col);

/* 1 when cJSON's syntax error at `at` is an array or object opened past its nesting limit
 * (CJSON_NESTING_LIMIT levels): a file to refuse as too deep, not as malformed. */
int json_pos_too_deep(const char *text, const char *at);

#endif
