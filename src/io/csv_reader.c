/* The CSV tokenizer (docs/io.md): physical lines are read in bounded chunks and joined while a
 * quoted cell is open, then one record is split into NUL-terminated cells. Every count the
 * input controls (record bytes, cells) is capped before it is allocated. */
#define _POSIX_C_SOURCE 200809L /* fmemopen */

#include "check.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

struct pst_csv_reader {
    FILE *f;
    char *path;
    int flags;
    char *raw;            /* the record's raw text, its lines' ends included */
    size_t rawlen, rawcap;
    char *text;           /* the cells, unquoted, each NUL-terminated        */
    size_t textcap;
    size_t *cell;         /* offsets of the cells into text                  */
    size_t ncells, cellcap;
    size_t line, nlines;  /* the record's first line; lines read so far      */
    char *head;           /* the header's cells, NUL-separated               */
    size_t *head_off, ncols;
};

enum { CHUNK = 1 << 16 };

static int check_length(const pst_csv_reader *r, char *err)
{
    PST_CHECK(r->rawlen > (size_t)PST_CSV_MAX_RECORD, PST_EINPUT, err,
              "%s:%zu:1: a record longer than %d bytes", r->path, r->line, PST_CSV_MAX_RECORD);
    return PST_OK;
}

/* Room for another chunk of a line in raw, refused past the cap before it is allocated. */
static int grow_raw(pst_csv_reader *r, char *err)
{
    PST_TRY(check_length(r, err));
    if (r->rawcap - r->rawlen > CHUNK)
        return PST_OK;
    size_t cap = r->rawcap ? 2 * r->rawcap : 2 * CHUNK;
    char *g = realloc(r->raw, cap);
    PST_CHECK_ALLOC(g, err, "%s:%zu:1: out of memory for a record", r->path, r->line);
    r->raw = g;
    r->rawcap = cap;
    return PST_OK;
}

/* Append one physical line (its '\n' included when there is one) to raw: *got 0 at the end. */
static int read_line(pst_csv_reader *r, int *got, char *err)
{
    size_t start = r->rawlen;
    for (;;) {
        PST_TRY(grow_raw(r, err));
        char *at = r->raw + r->rawlen;
        size_t room = r->rawcap - r->rawlen, len;
        if (!fgets(at, (int)room, r->f))
            break;
        len = strlen(at);
        /* fgets stops at a line end, a full buffer or the end: anything else is a NUL byte */
        PST_CHECK(len + 1 < room && (len == 0 || at[len - 1] != '\n') && !feof(r->f),
                  PST_EINPUT, err, "%s:%zu: a NUL byte in the line", r->path, r->nlines + 1);
        r->rawlen += len;
        if (r->rawlen > start && r->raw[r->rawlen - 1] == '\n')
            break;
    }
    PST_CHECK(ferror(r->f), PST_EIO, err, "%s:%zu: read error: %s", r->path, r->nlines + 1,
              strerror(errno));
    PST_TRY(check_length(r, err));
    *got = r->rawlen > start;
    if (*got && ++r->nlines == 1 && strncmp(r->raw, "\xEF\xBB\xBF", 3) == 0) {
        memmove(r->raw, r->raw + 3, r->rawlen - 3); /* a byte-order mark, as spreadsheets write */
        r->rawlen -= 3;
    }
    return PST_OK;
}

static int is_blank(const char *s, size_t n)
{
    for (size_t i = 0; i < n; ++i)
        if (!strchr(" \t\r\n", s[i]))
            return 0;
    return 1;
}

/* The end of a record: a line end, and nothing but line ends after it. */
static int at_end(const char *p, const char *end)
{
    return p == end || ((*p == '\n' || *p == '\r') && is_blank(p, (size_t)(end - p)));
}

static int new_cell(pst_csv_reader *r, size_t at, char *err)
{
    PST_CHECK(r->ncells >= (size_t)PST_CSV_MAX_CELLS, PST_EINPUT, err,
              "%s:%zu:%zu: more than %d cells in a record", r->path, r->line, r->ncells + 1,
              PST_CSV_MAX_CELLS);
    if (r->ncells == r->cellcap) {
        size_t cap = r->cellcap ? 2 * r->cellcap : 64;
        size_t *g = realloc(r->cell, cap * sizeof *g);
        PST_CHECK_ALLOC(g, err, "%s:%zu: out of memory for the cells", r->path, r->line);
        r->cell = g;
        r->cellcap = cap;
    }
    r->cell[r->ncells++] = at;
    return PST_OK;
}

/* A quoted cell from p (at the opening quote) into out: the byte after the closing quote, or
 * NULL when the record ends inside the quotes (another line is needed). */
static const char *quoted(const char *p, const char *end, char **out)
{
    for (++p; p < end; ++p) {
        if (*p == '"' && (p + 1 == end || p[1] != '"'))
            return p + 1;
        p += *p == '"'; /* a doubled quote is one */
        *(*out)++ = *p;
    }
    return NULL;
}

/* Split raw into cells: *done 0 when a quoted cell is still open at the end of raw. */
static int split(pst_csv_reader *r, int *done, char *err)
{
    const int trim = r->flags & PST_CSV_TRIM;
    const char *p = r->raw, *end = r->raw + r->rawlen;
    char *o = r->text;
    r->ncells = 0;
    *done = 0;
    for (;;) {
        PST_TRY(new_cell(r, (size_t)(o - r->text), err));
        while (trim && p < end && (*p == ' ' || *p == '\t'))
            ++p;
        if (p < end && *p == '"') {
            if (!(p = quoted(p, end, &o)))
                return PST_OK;
            while (trim && p < end && (*p == ' ' || *p == '\t'))
                ++p;
            PST_CHECK(p < end && *p != ',' && !at_end(p, end), PST_EINPUT, err,
                      "%s:%zu:%zu: text after a quoted cell", r->path, r->line, r->ncells);
        } else {
            char *start = o;
            while (p < end && *p != ',' && !at_end(p, end))
                *o++ = *p++;
            while (trim && o > start && (o[-1] == ' ' || o[-1] == '\t'))
                --o;
        }
        *o++ = '\0';
        if (p == end || *p != ',')
            break;
        ++p;
    }
    *done = 1;
    return PST_OK;
}

/* The next record into cells: *got 0 at the end of the file. */
static int read_record(pst_csv_reader *r, int *got, char *err)
{
    r->rawlen = 0;
    r->line = r->nlines + 1;
    for (int done = 0; !done;) {
        PST_TRY(read_line(r, got, err));
        if (!*got) {
            PST_CHECK(r->rawlen > 0, PST_EINPUT, err, "%s:%zu:%zu: unterminated quoted cell",
                      r->path, r->line, r->ncells);
            return PST_OK;
        }
        if ((r->flags & PST_CSV_SKIP_BLANK) && r->line == r->nlines &&
            is_blank(r->raw, r->rawlen)) {
            r->rawlen = 0;
            r->line = r->nlines + 1;
            continue;
        }
        if (r->textcap < 2 * r->rawlen + 2) { /* a cell per byte at most, each with its NUL */
            char *g = realloc(r->text, 2 * r->rawlen + 2);
            PST_CHECK_ALLOC(g, err, "%s:%zu: out of memory for a record", r->path, r->line);
            r->text = g;
            r->textcap = 2 * r->rawlen + 2;
        }
        PST_TRY(split(r, &done, err));
    }
    *got = 1;
    return PST_OK;
}

/* Keep the header's cells: the current record's text and offsets. */
static int keep_header(pst_csv_reader *r, char *err)
{
    size_t len = r->cell[r->ncells - 1] + strlen(r->text + r->cell[r->ncells - 1]) + 1;
    r->head = malloc(len);
    r->head_off = malloc(r->ncells * sizeof *r->head_off);
    PST_CHECK_ALLOC(r->head && r->head_off, err, "%s:%zu:1: out of memory reading the header",
                    r->path, r->line);
    memcpy(r->head, r->text, len);
    memcpy(r->head_off, r->cell, r->ncells * sizeof *r->cell);
    r->ncols = r->ncells;
    return PST_OK;
}

static int open_stream(pst_csv_reader **out, FILE *f, const char *path, int flags, char *err)
{
    *out = NULL;
    pst_csv_reader *r = calloc(1, sizeof *r);
    size_t plen = strlen(path) + 1;
    char *p = malloc(plen);
    if (!r || !p) {
        free(r);
        free(p);
        fclose(f);
        pst_set_err(err, "%s: out of memory", path);
        return PST_ENOMEM;
    }
    r->f = f;
    r->path = memcpy(p, path, plen);
    r->flags = flags;
    int got = 0, st = read_record(r, &got, err);
    if (st == PST_OK && !got) {
        pst_set_err(err, "%s:1:1: empty file: no header line", path);
        st = PST_EINPUT;
    }
    if (st == PST_OK)
        st = keep_header(r, err);
    if (st != PST_OK) {
        pst_csv_close(r);
        return st;
    }
    *out = r;
    return PST_OK;
}

int pst_csv_open(pst_csv_reader **out, const char *path, int flags, char *err)
{
    *out = NULL;
    FILE *f = fopen(path, "rb");
    PST_CHECK(!f, PST_EIO, err, "%s: cannot open: %s", path, strerror(errno));
    return open_stream(out, f, path, flags, err);
}

int pst_csv_open_text(pst_csv_reader **out, const char *text, const char *name, int flags,
                      char *err)
{
    *out = NULL;
    size_t len = strlen(text);
    /* fmemopen may refuse an empty buffer: a lone NUL reads as the empty file */
    FILE *f = fmemopen((void *)(len ? text : ""), len ? len : 1, "rb");
    PST_CHECK(!f, PST_ENOMEM, err, "%s: cannot read the text: %s", name, strerror(errno));
    return open_stream(out, f, name, flags, err);
}

void pst_csv_close(pst_csv_reader *r)
{
    if (!r)
        return;
    fclose(r->f);
    free(r->path);
    free(r->raw);
    free(r->text);
    free(r->cell);
    free(r->head);
    free(r->head_off);
    free(r);
}

int pst_csv_next(pst_csv_reader *r, int *got, char *err)
{
    PST_TRY(read_record(r, got, err));
    size_t n = r->ncells, want = r->ncols;
    PST_CHECK(*got && n != want, PST_EINPUT, err, "%s:%zu:%zu: expected %zu columns, found %zu",
              r->path, r->line, (n < want ? n : want) + 1, want, n);
    return PST_OK;
}

size_t pst_csv_ncols(const pst_csv_reader *r) { return r->ncols; }
const char *pst_csv_name(const pst_csv_reader *r, size_t k) { return r->head + r->head_off[k]; }
const char *pst_csv_cell(const pst_csv_reader *r, size_t k) { return r->text + r->cell[k]; }
size_t pst_csv_line(const pst_csv_reader *r) { return r->line; }
const char *pst_csv_path(const pst_csv_reader *r) { return r->path; }

pst_csv_num pst_csv_parse_number(const char *cell, double *v)
{
    if (!*cell)
        return PST_CSV_EMPTY;
    char *end;
    double x = strtod(cell, &end); /* ERANGE on subnormals is fine: they round-trip */
    if (*end || end == cell)
        return PST_CSV_NOT_A_NUMBER;
    if (!isfinite(x))
        return PST_CSV_NOT_FINITE;
    *v = x;
    return PST_CSV_NUMBER;
}

int pst_csv_cell_error(const pst_csv_reader *r, size_t k, int code, char *err,
                       const char *fmt, ...)
{
    if (!err)
        return code;
    int at = snprintf(err, PST_ERRLEN, "%s:%zu:%zu: column %s: ", r->path, r->line, k + 1,
                      pst_csv_name(r, k));
    va_list ap;
    va_start(ap, fmt);
    if (at >= 0 && at < PST_ERRLEN)
        vsnprintf(err + at, (size_t)(PST_ERRLEN - at), fmt, ap);
    va_end(ap);
    return code;
}

int pst_csv_number(const pst_csv_reader *r, size_t k, double *v, char *err)
{
    const char *cell = pst_csv_cell(r, k);
    switch (pst_csv_parse_number(cell, v)) {
    case PST_CSV_NUMBER:
        return PST_OK;
    case PST_CSV_EMPTY:
        return pst_csv_cell_error(r, k, PST_EINPUT, err, "missing value");
    case PST_CSV_NOT_A_NUMBER:
        return pst_csv_cell_error(r, k, PST_EINPUT, err, "cannot parse '%.64s' as a number",
                                  cell);
    default:
        return pst_csv_cell_error(r, k, PST_EINPUT, err, "value '%.64s' is not finite", cell);
    }
}
