/* A JSON tokenizer that only walks: it skips values without building them and compares member
 * names after decoding their escapes the way cJSON does, so that a path into cJSON's tree
 * leads to the same place in the text. Malformed text stops the walk (a partial match), it
 * never faults: every read checks for the terminating NUL first. */
#include "json_pos.h"

#include <cjson/cJSON.h>

#include <string.h>

void json_pos_offset(const char *text, size_t offset, int *line, int *col)
{
    int l = 1, c = 1;
    for (size_t i = 0; i < offset && text[i]; ++i) {
        unsigned char ch = (unsigned char)text[i];
        if (ch == '\n') {
            ++l;
            c = 1;
        } else if ((ch & 0xC0) != 0x80) { /* continuation bytes belong to the previous char */
            ++c;
        }
    }
    *line = l;
    *col = c;
}

void json_pos_error(const char *text, const char *at, int *line, int *col)
{
    size_t len = strlen(text);
    size_t off = len;
    if (at && at >= text && at <= text + len)
        off = (size_t)(at - text);
    json_pos_offset(text, off, line, col);
}

int json_pos_too_deep(const char *text, const char *at)
{
    size_t len = strlen(text);
    if (!at || at < text || at >= text + len || (*at != '[' && *at != '{'))
        return 0;
    int depth = 0, in_string = 0;
    for (const char *p = text; p < at; ++p) {
        if (in_string) {
            if (*p == '\\' && p + 1 < at)
                ++p;
            else if (*p == '"')
                in_string = 0;
        } else if (*p == '"') {
            in_string = 1;
        } else if (*p == '[' || *p == '{') {
            ++depth;
        } else if (*p == ']' || *p == '}') {
            --depth;
        }
    }
    return !in_string && depth >= CJSON_NESTING_LIMIT;
}

/* cJSON's whitespace: every byte up to and including the space. */
static const char *skip_ws(const char *p)
{
    while (*p && (unsigned char)*p <= 32)
        ++p;
    return p;
}

/* Skip a string whose opening quote is at p; returns the byte after the closing quote, or
 * NULL when the text ends first. */
static const char *skip_string(const char *p)
{
    for (++p; *p; ++p) {
        if (*p == '\\') {
            if (!p[1])
                return NULL;
            ++p;
        } else if (*p == '"') {
            return p + 1;
        }
    }
    return NULL;
}

/* Skip one value (scalar or nested) starting at p, without recursion. NULL on malformed or
 * truncated text. */
static const char *skip_value(const char *p)
{
    if (*p == '"')
        return skip_string(p);
    if (*p != '{' && *p != '[') {
        const char *q = p;
        while (*q && (unsigned char)*q > 32 && !strchr(",:]}[{\"", *q))
            ++q;
        return q == p ? NULL : q;
    }
    long depth = 0;
    for (; *p; ++p) {
        if (*p == '"') {
            p = skip_string(p);
            if (!p)
                return NULL;
            --p;
        } else if (*p == '{' || *p == '[') {
            ++depth;
        } else if (*p == '}' || *p == ']') {
            if (--depth == 0)
                return p + 1;
        }
    }
    return NULL;
}

static int hex4(const char *p, unsigned *out)
{
    unsigned v = 0;
    for (int i = 0; i < 4; ++i) {
        char c = p[i];
        unsigned d;
        if (c >= '0' && c <= '9')
            d = (unsigned)(c - '0');
        else if (c >= 'a' && c <= 'f')
            d = (unsigned)(c - 'a' + 10);
        else if (c >= 'A' && c <= 'F')
            d = (unsigned)(c - 'A' + 10);
        else
            return -1; /* also stops at the NUL */
        v = v * 16 + d;
    }
    *out = v;
    return 0;
}

/* Decode one character of a string body at *pp into buf (UTF-8, up to 4 bytes) and advance.
 * Returns the byte count, 0 at the closing quote, -1 on a malformed escape or the end. */
static int decode_char(const char **pp, unsigned char buf[4])
{
    const char *p = *pp;
    if (!*p)
        return -1;
    if (*p == '"')
        return 0;
    if (*p != '\\') {
        buf[0] = (unsigned char)*p;
        *pp = p + 1;
        return 1;
    }
    const char *simple = "\"\\/bfnrt", *value = "\"\\/\b\f\n\r\t";
    const char *s = p[1] ? strchr(simple, p[1]) : NULL;
    if (s) {
        buf[0] = (unsigned char)value[s - simple];
        *pp = p + 2;
        return 1;
    }
    unsigned cp;
    if (p[1] != 'u' || hex4(p + 2, &cp) != 0)
        return -1;
    p += 6;
    if (cp >= 0xD800 && cp <= 0xDBFF) { /* a surrogate pair, as cJSON combines it */
        unsigned lo;
        if (p[0] != '\\' || p[1] != 'u' || hex4(p + 2, &lo) != 0 || lo < 0xDC00 || lo > 0xDFFF)
            return -1;
        cp = 0x10000 + ((cp - 0xD800) << 10) + (lo - 0xDC00);
        p += 6;
    }
    *pp = p;
    if (cp < 0x80) {
        buf[0] = (unsigned char)cp;
        return 1;
    }
    if (cp < 0x800) {
        buf[0] = (unsigned char)(0xC0 | (cp >> 6));
        buf[1] = (unsigned char)(0x80 | (cp & 0x3F));
        return 2;
    }
    if (cp < 0x10000) {
        buf[0] = (unsigned char)(0xE0 | (cp >> 12));
        buf[1] = (unsigned char)(0x80 | ((cp >> 6) & 0x3F));
        buf[2] = (unsigned char)(0x80 | (cp & 0x3F));
        return 3;
    }
    buf[0] = (unsigned char)(0xF0 | (cp >> 18));
    buf[1] = (unsigned char)(0x80 | ((cp >> 12) & 0x3F));
    buf[2] = (unsigned char)(0x80 | ((cp >> 6) & 0x3F));
    buf[3] = (unsigned char)(0x80 | (cp & 0x3F));
    return 4;
}

/* Compare the string at p (opening quote) with `key` after decoding. Returns 1 or 0 and sets
 * *end past the closing quote; *end = NULL on malformed text. */
static int string_equals(const char *p, const char *key, const char **end)
{
    const char *q = p + 1;
    size_t k = 0, klen = strlen(key);
    int equal = 1;
    for (;;) {
        unsigned char buf[4];
        int n = decode_char(&q, buf);
        if (n < 0) {
            *end = skip_string(p);
            return 0;
        }
        if (n == 0)
            break;
        if (equal && (k + (size_t)n > klen || memcmp(key + k, buf, (size_t)n) != 0))
            equal = 0;
        k += (size_t)n;
    }
    *end = q + 1;
    return equal && k == klen;
}

/* Within the container at p ('{' or '['), find the target of one step; returns a pointer to
 * the member's key (objects) or the element (arrays), NULL when absent or malformed. */
static const char *find_step(const char *p, const json_step *s)
{
    int object = *p == '{';
    if (!object && *p != '[') /* a scalar, or the end of the text */
        return NULL;
    if ((s->key != NULL) != object)
        return NULL;
    p = skip_ws(p + 1);
    if (*p == (object ? '}' : ']'))
        return NULL;
    int skip = s->index; /* occurrences of the key still to pass over */
    for (int count = 0;; ++count) {
        const char *item = p;
        if (object) {
            if (*p != '"')
                return NULL;
            const char *after;
            int eq = string_equals(p, s->key, &after);
            if (!after)
                return NULL;
            if (eq && skip-- == 0)
                return item;
            p = skip_ws(after);
            if (*p != ':')
                return NULL;
            p = skip_ws(p + 1);
        } else if (count == s->index) {
            return item;
        }
        p = skip_value(p);
        if (!p)
            return NULL;
        p = skip_ws(p);
        if (*p != ',')
            return NULL;
        p = skip_ws(p + 1);
    }
}

/* The value of the member whose key starts at p. */
static const char *member_value(const char *p)
{
    p = skip_string(p);
    if (!p)
        return NULL;
    p = skip_ws(p);
    return *p == ':' ? skip_ws(p + 1) : NULL;
}

int json_pos_find(const char *text, const json_step *path, int depth, int *line, int *col)
{
    const char *p = text;
    if (strncmp(p, "\xEF\xBB\xBF", 3) == 0) /* cJSON skips a UTF-8 byte-order mark */
        p += 3;
    p = skip_ws(p);
    const char *at = *p ? p : text;
    int found = 0;
    for (; found < depth; ++found) {
        const char *item = find_step(p, &path[found]);
        if (!item)
            break;
        at = item;
        p = path[found].key ? member_value(item) : item;
        if (!p)
            break;
    }
    if (found < depth && p == NULL)
        ++found; /* the key itself was found, its value is malformed */
    json_pos_offset(text, (size_t)(at - text), line, col);
    return found;
}
