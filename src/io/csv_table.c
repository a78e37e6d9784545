/* A small CSV file held whole (docs/io.md): the tokenizer's records as strings, and each cell
 * parsed once as a number so that statistics over a column never re-parse text. */
#include "check.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Room for row `row` (0: the header). */
static int grow(pst_csv_table *t, size_t row, char *err)
{
    if (row < t->cap)
        return PST_OK;
    size_t cap = t->cap ? 2 * t->cap : 16, nc = (size_t)t->ncols;
    char **cell = realloc(t->cell, cap * nc * sizeof *cell);
    if (cell)
        t->cell = cell;
    double *num = cell ? realloc(t->num, cap * nc * sizeof *num) : NULL;
    if (num)
        t->num = num;
    PST_CHECK_ALLOC(num, err, "out of memory for %zu rows of %d cells", cap, t->ncols);
    t->cap = cap;
    return PST_OK;
}

/* Copies of a row's cells and their numbers (NAN for the header). */
static int copy_row(char **dst, double *num, const char *const *cells, size_t nc, int header,
                    char *err)
{
    for (size_t k = 0; k < nc; ++k) {
        size_t len = strlen(cells[k]) + 1;
        if (!(dst[k] = malloc(len))) {
            while (k > 0)
                free(dst[--k]);
            pst_set_err(err, "out of memory for a row of %zu cells", nc);
            return PST_ENOMEM;
        }
        memcpy(dst[k], cells[k], len);
        num[k] = NAN;
        if (!header)
            pst_csv_parse_number(dst[k], &num[k]);
    }
    return PST_OK;
}

int pst_csv_table_add(pst_csv_table *t, int ncols, const char *const *cells, char *err)
{
    const int header = !t->cell;
    PST_CHECK(ncols <= 0 || ncols > PST_CSV_MAX_CELLS || (!header && ncols != t->ncols),
              PST_EINVAL, err, "a row of %d cells for a table of %d columns", ncols, t->ncols);
    PST_CHECK(t->nrows >= (size_t)PST_CSV_MAX_ROWS, PST_EINPUT, err, "more than %d data rows",
              PST_CSV_MAX_ROWS);
    t->ncols = ncols;
    const size_t row = header ? 0 : t->nrows + 1, nc = (size_t)ncols;
    int st = grow(t, row, err);
    if (st == PST_OK)
        st = copy_row(t->cell + row * nc, t->num + row * nc, cells, nc, header, err);
    if (st != PST_OK && header) { /* no header: back to the zeroed table */
        free(t->cell);
        free(t->num);
        memset(t, 0, sizeof *t);
    }
    t->nrows += st == PST_OK && !header;
    return st;
}

void pst_csv_table_free(pst_csv_table *t)
{
    if (!t)
        return;
    for (size_t i = 0; t->cell && i < (t->nrows + 1) * (size_t)t->ncols; ++i)
        free(t->cell[i]);
    free(t->cell);
    free(t->num);
    memset(t, 0, sizeof *t);
}

int pst_csv_table_column(const pst_csv_table *t, const char *name, int below)
{
    for (int q = 0; t->cell && q < below && q < t->ncols; ++q)
        if (strcmp(t->cell[q], name) == 0)
            return q;
    return -1;
}

/* Every record of an open reader, the header first, into t. */
static int read_all(pst_csv_table *t, pst_csv_reader *r, char *err)
{
    const size_t nc = pst_csv_ncols(r);
    const char **cells = malloc(nc * sizeof *cells);
    PST_CHECK_ALLOC(cells, err, "%s: out of memory", pst_csv_path(r));
    int st = PST_OK, got = 1;
    for (size_t k = 0; k < nc; ++k)
        cells[k] = pst_csv_name(r, k);
    char msg[PST_ERRLEN];
    PST_TRY_GOTO(st, pst_csv_table_add(t, (int)nc, cells, msg), fail);
    while ((st = pst_csv_next(r, &got, err)) == PST_OK && got) {
        for (size_t k = 0; k < nc; ++k)
            cells[k] = pst_csv_cell(r, k);
        PST_TRY_GOTO(st, pst_csv_table_add(t, (int)nc, cells, msg), fail);
    }
    free(cells);
    return st;
fail:
    pst_set_err(err, "%s:%zu:1: %s", pst_csv_path(r), pst_csv_line(r), msg);
    free(cells);
    return st;
}

static int table_from(pst_csv_table *t, pst_csv_reader *r, int st, char *err)
{
    memset(t, 0, sizeof *t);
    if (st == PST_OK)
        st = read_all(t, r, err);
    pst_csv_close(r);
    if (st != PST_OK)
        pst_csv_table_free(t);
    return st;
}

int pst_csv_read_table(pst_csv_table *t, const char *path, int flags, char *err)
{
    pst_csv_reader *r;
    int st = pst_csv_open(&r, path, flags, err);
    return table_from(t, r, st, err);
}

int pst_csv_parse_table(pst_csv_table *t, const char *text, const char *name, int flags,
                        char *err)
{
    pst_csv_reader *r;
    int st = pst_csv_open_text(&r, text, name, flags, err);
    return table_from(t, r, st, err);
}
