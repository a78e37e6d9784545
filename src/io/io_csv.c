/* Reading and writing clouds as CSV (format: docs/clouds.md). The reader takes the records of
 * the CSV tokenizer (csv_reader.c) and checks every value where it stands, so each message can
 * name file, line and column; the writer goes through a
 * temporary file and rename() so that a destination is either the old file or the whole new
 * one. */
#include "cloud_layout.h"
#include "check.h"

#include <stdlib.h>
#include <string.h>

static const char *const kind_names[] = {"interior", "dirichlet", "neumann"};
static const char *const coord_names[] = {"x", "y", "z"};
static const char *const normal_names[] = {"nx", "ny", "nz"};
static const char *const mob_names[] = {"mx", "my", "mz"};

/* ---- reader ---------------------------------------------------------------------------- */

/* The column layout of a file: coordinates, V, h, then optionally kind, the normals and the
 * mobility, then fields. An absent kind or normal column is NO_COL. */
#define NO_COL SIZE_MAX
typedef struct {
    int dim, mob;         /* mobility components: 0, 1 or dim                  */
    size_t ncols, nfields;
    size_t kind, normal, mob0, field; /* first column of each group, or NO_COL  */
    const char **name;    /* ncols names, the reader's header (valid while open) */
} layout;

static size_t col_V(const layout *l) { return (size_t)l->dim; }
static size_t col_h(const layout *l) { return (size_t)l->dim + 1; }

/* The columns at *k on named names[0..n), in order; `what` names the group in messages. The
 * group is absent when its first name is not there (nothing is read, 0 returned in *found). */
static int check_group(const layout *l, const pst_csv_reader *r, size_t *k,
                       const char *const *names, int n, int required, const char *what,
                       int *found, char *err)
{
    const char *path = pst_csv_path(r);
    const size_t line = pst_csv_line(r);
    *found = *k < l->ncols && strcmp(l->name[*k], names[0]) == 0;
    if (!*found && !required)
        return PST_OK;
    for (int a = 0; a < n; ++a, ++*k) {
        PST_CHECK(*k >= l->ncols, PST_EINPUT, err,
                  "%s:%zu:%zu: missing column '%s' (the header starts %s)", path, line, *k + 1,
                  names[a], l->dim == 2 ? "x,y,V,h" : "x,y,z,V,h");
        PST_CHECK(strcmp(l->name[*k], names[a]) != 0, PST_EINPUT, err,
                  "%s:%zu:%zu: expected column '%s'%s here, found '%s'", path, line, *k + 1,
                  names[a], what, l->name[*k]);
    }
    *found = 1;
    return PST_OK;
}

/* The required columns x,y[,z],V,h first and in order, then the optional kind and normals. */
static int check_required(layout *l, const pst_csv_reader *r, size_t *k, char *err)
{
    const char *req[5];
    int n = 0, found;
    for (int d = 0; d < l->dim; ++d)
        req[n++] = coord_names[d];
    req[n++] = "V";
    req[n++] = "h";
    *k = 0;
    PST_TRY(check_group(l, r, k, req, n, 1, "", &found, err));
    static const char *const kind[1] = {"kind"};
    l->kind = *k;
    PST_TRY(check_group(l, r, k, kind, 1, 0, "", &found, err));
    l->kind = found ? l->kind : NO_COL;
    l->normal = *k;
    PST_TRY(check_group(l, r, k, normal_names, l->dim, 0, " of the normal", &found, err));
    l->normal = found ? l->normal : NO_COL;
    return PST_OK;
}

/* The optional mobility group at column *k: m, or mx,my[,mz]. */
static int check_mobility(layout *l, const pst_csv_reader *r, size_t *k, char *err)
{
    l->mob = 0;
    l->mob0 = *k;
    if (*k < l->ncols && strcmp(l->name[*k], "m") == 0) {
        l->mob = 1;
        ++*k;
    } else if (*k < l->ncols && strcmp(l->name[*k], "mx") == 0) {
        for (int d = 0; d < l->dim; ++d, ++*k)
            PST_CHECK(*k >= l->ncols || strcmp(l->name[*k], mob_names[d]) != 0, PST_EINPUT,
                      err, "%s:%zu:%zu: expected column '%s' of the diagonal mobility, found "
                           "'%s'",
                      pst_csv_path(r), pst_csv_line(r), *k + 1, mob_names[d],
                      *k < l->ncols ? l->name[*k] : "");
        l->mob = l->dim;
    }
    return PST_OK;
}

/* Field columns from k on: at most PST_MAX_FIELDS, unique identifiers that are not reserved
 * names; each column's first problem is reported, in column order. */
static int check_fields(const layout *l, const pst_csv_reader *r, size_t k, char *err)
{
    const char *path = pst_csv_path(r);
    const size_t line = pst_csv_line(r);
    PST_CHECK(l->ncols - k > PST_MAX_FIELDS, PST_EINPUT, err,
              "%s:%zu:%zu: %zu field columns, more than the %d a cloud file may have", path, line,
              k + PST_MAX_FIELDS + 1, l->ncols - k, PST_MAX_FIELDS);
    size_t first = 0, again = SIZE_MAX;
    int found = pst_find_repeated_name(l->name, l->ncols, &first, &again);
    PST_CHECK(found < 0, PST_ENOMEM, err, "%s:%zu:1: out of memory reading the header", path,
              line);
    for (; k < l->ncols; ++k) {
        PST_CHECK(found && k == again, PST_EINPUT, err,
                  "%s:%zu:%zu: duplicate column name '%s' (also column %zu)", path, line,
                  k + 1, l->name[k], first + 1);
        PST_CHECK(pst_is_reserved_column(l->name[k]), PST_EINPUT, err,
                  "%s:%zu:%zu: misplaced column '%s'", path, line, k + 1, l->name[k]);
        PST_CHECK(!pst_is_identifier(l->name[k]), PST_EINPUT, err,
                  "%s:%zu:%zu: unknown column '%s' (a field name must be a C identifier "
                  "shorter than %d characters)",
                  path, line, k + 1, l->name[k], PST_MAX_NAME);
    }
    return PST_OK;
}

/* The layout of the reader's header: the required columns, an optional mobility group, then
 * fields. */
static int parse_header(layout *l, const pst_csv_reader *r, char *err)
{
    l->ncols = pst_csv_ncols(r);
    l->name = malloc(l->ncols * sizeof *l->name);
    PST_CHECK_ALLOC(l->name, err, "%s:%zu:1: out of memory reading the header",
                    pst_csv_path(r), pst_csv_line(r));
    l->dim = 2;
    for (size_t k = 0; k < l->ncols; ++k) {
        l->name[k] = pst_csv_name(r, k);
        if (strcmp(l->name[k], "z") == 0)
            l->dim = 3;
    }
    size_t k;
    PST_TRY(check_required(l, r, &k, err));
    PST_TRY(check_mobility(l, r, &k, err));
    l->field = k;
    l->nfields = l->ncols - k;
    return check_fields(l, r, k, err);
}

/* Cell k of the current record; kind becomes 0, 1 or 2. */
static int parse_cell(const layout *l, const pst_csv_reader *r, size_t k, double *value,
                      char *err)
{
    const char *cell = pst_csv_cell(r, k);
    if (k == l->kind) {
        for (int t = 0; t <= PST_NEUMANN; ++t) {
            char digit[2] = {(char)('0' + t), '\0'};
            if (strcmp(cell, kind_names[t]) == 0 || strcmp(cell, digit) == 0) {
                *value = t;
                return PST_OK;
            }
        }
        return pst_csv_cell_error(r, k, PST_EINPUT, err, "unknown kind '%.64s' (interior, "
                                  "dirichlet, neumann or 0, 1, 2)", cell);
    }
    double v;
    PST_TRY(pst_csv_number(r, k, &v, err));
    if (k == col_V(l) && !(v > 0))
        return pst_csv_cell_error(r, k, PST_EINPUT, err, "volume V = %.17g must be > 0", v);
    if (k == col_h(l) && !(v > 0))
        return pst_csv_cell_error(r, k, PST_EINPUT, err,
                                  "smoothing length h = %.17g must be > 0", v);
    if (k >= l->mob0 && k < l->field && !(v > 0))
        return pst_csv_cell_error(r, k, PST_EINPUT, err, "mobility %.17g must be > 0", v);
    *value = v;
    return PST_OK;
}

/* Rows read so far: ncols values per row plus the file line of each row. */
typedef struct {
    double *val;
    size_t *line;
    size_t n, cap;
} rows;

static int rows_push(rows *r, size_t ncols)
{
    if (r->n < r->cap)
        return PST_OK;
    size_t cap = r->cap ? 2 * r->cap : 1024;
    if (cap > (size_t)UINT32_MAX + 1 || cap > SIZE_MAX / sizeof(double) / ncols)
        return PST_ENOMEM;
    double *v = realloc(r->val, cap * ncols * sizeof *v);
    if (!v)
        return PST_ENOMEM;
    r->val = v;
    size_t *ln = realloc(r->line, cap * sizeof *ln);
    if (!ln)
        return PST_ENOMEM;
    r->line = ln;
    r->cap = cap;
    return PST_OK;
}

/* Move the parsed rows into a new cloud (particle i = data row i). */
static int build_cloud(pst_cloud **out, const layout *l, const rows *r)
{
    pst_cloud *c;
    int st = pst_cloud_create(&c, l->dim, r->n, NULL);
    if (st != PST_OK)
        return st;
    size_t nc = l->ncols;
    int h_uniform = 1;
    for (size_t i = 1; i < r->n; ++i)
        h_uniform = h_uniform && r->val[i * nc + col_h(l)] == r->val[col_h(l)];
    double *h = NULL;
    if (r->n > 0 && h_uniform)
        pst_cloud_set_h_uniform(c, r->val[col_h(l)], NULL); /* > 0: checked when parsed */
    else if (r->n > 0 && !(h = pst_cloud_h_per_particle(c)))
        st = PST_ENOMEM;
    if (st == PST_OK)
        st = pst_cloud_set_mobility(c, l->mob, NULL);
    size_t nf = l->nfields;
    double **fields = malloc((nf ? nf : 1) * sizeof *fields);
    if (!fields)
        st = PST_ENOMEM;
    if (st == PST_OK) /* names checked in the header: only memory can fail */
        st = pst_cloud_add_fields(c, l->name + l->field, nf, fields, NULL);
    if (st != PST_OK) {
        free(fields);
        pst_cloud_destroy(c);
        return st;
    }
    for (size_t i = 0; i < r->n; ++i) {
        const double *v = r->val + i * nc;
        for (int d = 0; d < l->dim; ++d) {
            c->x[d][i] = v[d];
            c->normal[d][i] = l->normal == NO_COL ? 0.0 : v[l->normal + (size_t)d];
        }
        c->V[i] = v[col_V(l)];
        if (h)
            h[i] = v[col_h(l)];
        c->kind[i] = l->kind == NO_COL ? PST_INTERIOR : (uint8_t)v[l->kind];
        for (int m = 0; m < l->mob; ++m)
            c->mob[m][i] = v[l->mob0 + (size_t)m];
        for (size_t f = 0; f < nf; ++f)
            fields[f][i] = v[l->field + f];
    }
    free(fields);
    *out = c;
    return PST_OK;
}

/* Duplicate positions, reported by the file lines of the two particles. */
static int check_duplicates(const pst_cloud *c, const rows *r, const char *path, char *err)
{
    size_t a, b;
    int found = pst_cloud_find_duplicate(c, &a, &b);
    PST_CHECK(found < 0, found, err, "%s: out of memory", path);
    PST_CHECK(found, PST_EINPUT, err,
              "%s:%zu:1: duplicate particle: same coordinates as line %zu",
              path, r->line[b], r->line[a]);
    return PST_OK;
}

/* The extent and the Neumann normals (pst_cloud_check_extent_normals), the file named. */
static int check_shape(const pst_cloud *c, const char *path, char *err)
{
    char why[PST_ERRLEN] = "";
    int st = pst_cloud_check_extent_normals(c, why);
    PST_CHECK(st != PST_OK, st, err, "%s: %s", path, why);
    return PST_OK;
}

/* The data records of an open reader into rows, each value checked where it stands. */
static int read_rows(const layout *l, pst_csv_reader *csv, rows *r, char *err)
{
    for (int got = 1;;) {
        PST_TRY(pst_csv_next(csv, &got, err));
        if (!got)
            return PST_OK;
        PST_CHECK(rows_push(r, l->ncols) != PST_OK, PST_ENOMEM, err,
                  "%s:%zu:1: out of memory or more than %lu particles", pst_csv_path(csv),
                  pst_csv_line(csv), (unsigned long)UINT32_MAX);
        double *v = r->val + r->n * l->ncols;
        for (size_t k = 0; k < l->ncols; ++k)
            PST_TRY(parse_cell(l, csv, k, &v[k], err));
        r->line[r->n++] = pst_csv_line(csv);
    }
}

int pst_cloud_read_csv(pst_cloud **out, const char *path, char *err)
{
    *out = NULL;
    pst_csv_reader *csv;
    PST_TRY(pst_csv_open(&csv, path, PST_CSV_TRIM | PST_CSV_SKIP_BLANK, err));
    layout l = {0};
    rows r = {0};
    pst_cloud *c = NULL;
    int st;
    PST_TRY_GOTO(st, parse_header(&l, csv, err), done);
    PST_TRY_GOTO(st, read_rows(&l, csv, &r, err), done);
    st = build_cloud(&c, &l, &r);
    PST_CHECK_GOTO(st != PST_OK, st, st, done, err, "%s: %zu particles: %s", path, r.n,
                   st == PST_EINVAL ? "more than the 32-bit index limit" : "out of memory");
    if ((st = check_duplicates(c, &r, path, err)) != PST_OK ||
        (st = check_shape(c, path, err)) != PST_OK) {
        pst_cloud_destroy(c);
        c = NULL;
    }
done:
    pst_csv_close(csv);
    free(l.name);
    free(r.val);
    free(r.line);
    *out = c;
    return st;
}

/* ---- writer ---------------------------------------------------------------------------- */

static void write_rows(FILE *f, const pst_cloud *c, const size_t *inv)
{
    int dim = c->dim;
    for (int d = 0; d < dim; ++d)
        fprintf(f, "%s,", coord_names[d]);
    fputs("V,h,kind", f);
    for (int d = 0; d < dim; ++d)
        fprintf(f, ",%s", normal_names[d]);
    if (c->mob_ncomp == 1)
        fputs(",m", f);
    else
        for (int m = 0; m < c->mob_ncomp; ++m)
            fprintf(f, ",%s", mob_names[m]);
    for (size_t k = 0; k < c->nfields; ++k)
        fprintf(f, ",%s", c->field_name[k]);
    fputc('\n', f);
    for (size_t r = 0; r < c->n && !ferror(f); ++r) {
        size_t i = inv[r];
        for (int d = 0; d < dim; ++d)
            fprintf(f, "%.17g,", c->x[d][i]);
        fprintf(f, "%.17g,%.17g,", c->V[i], pst_cloud_h_at(c, i));
        if (c->kind[i] <= PST_NEUMANN)
            fputs(kind_names[c->kind[i]], f);
        else
            fprintf(f, "%d", c->kind[i]); /* not a valid kind: the reader will say so */
        for (int d = 0; d < dim; ++d)
            fprintf(f, ",%.17g", c->normal[d][i]);
        for (int m = 0; m < c->mob_ncomp; ++m)
            fprintf(f, ",%.17g", c->mob[m][i]);
        for (size_t k = 0; k < c->nfields; ++k)
            fprintf(f, ",%.17g", c->field[k][i]);
        fputc('\n', f);
    }
}

/* The writer callback of pst_write_atomic: the header, then the rows in input order. */
typedef struct {
    const pst_cloud *c;
    const size_t *inv;
} csv_job;

static void write_csv(FILE *f, const void *job)
{
    const csv_job *w = job;
    write_rows(f, w->c, w->inv);
}

int pst_cloud_write_csv(const pst_cloud *c, const char *path, char *err)
{
    size_t *inv;
    int st = pst_cloud_input_inverse(c, &inv, err);
    if (st != PST_OK)
        return st;
    csv_job job = {c, inv};
    st = pst_write_atomic(path, write_csv, &job, err);
    free(inv);
    return st;
}
