/* Reading and writing clouds as CSV (format: docs/clouds.md). The reader checks every value
 * where it stands, so each message can name file, line and column; the writer goes through a
 * temporary file and rename() so that a destination is either the old file or the whole new
 * one. */
#define _POSIX_C_SOURCE 200809L /* getline */

#include "internal.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static const char *const kind_names[] = {"interior", "dirichlet", "neumann"};
static const char *const coord_names[] = {"x", "y", "z"};
static const char *const normal_names[] = {"nx", "ny", "nz"};
static const char *const mob_names[] = {"mx", "my", "mz"};

/* ---- reader ---------------------------------------------------------------------------- */

/* The column layout of a file: coordinates, V, h, kind, normals, mobility, fields. */
typedef struct {
    int dim, mob;         /* mobility components: 0, 1 or dim          */
    size_t ncols, nfields;
    char **name;          /* ncols names, pointing into the header copy */
    char *header;         /* owned copy of the header line              */
} layout;

static size_t col_V(const layout *l) { return (size_t)l->dim; }
static size_t col_h(const layout *l) { return (size_t)l->dim + 1; }
static size_t col_kind(const layout *l) { return (size_t)l->dim + 2; }
static size_t col_normal(const layout *l) { return (size_t)l->dim + 3; }
static size_t col_mob(const layout *l) { return 2 * (size_t)l->dim + 3; }
static size_t col_field(const layout *l) { return 2 * (size_t)l->dim + 3 + (size_t)l->mob; }

static int is_blank(const char *s)
{
    for (; *s; ++s)
        if (*s != ' ' && *s != '\t')
            return 0;
    return 1;
}

/* Trim spaces and tabs in place. */
static char *trim(char *s)
{
    while (*s == ' ' || *s == '\t')
        ++s;
    size_t len = strlen(s);
    while (len > 0 && (s[len - 1] == ' ' || s[len - 1] == '\t'))
        s[--len] = '\0';
    return s;
}

/* Strip the line terminator ("\n", "\r\n" or a trailing "\r"). */
static void chomp(char *s, ssize_t len)
{
    while (len > 0 && (s[len - 1] == '\n' || s[len - 1] == '\r'))
        s[--len] = '\0';
}

static size_t count_cells(const char *s)
{
    size_t k = 1;
    for (; *s; ++s)
        k += *s == ',';
    return k;
}

/* Cut the next cell off *cursor (NUL-terminating it) and return it trimmed. */
static char *next_cell(char **cursor)
{
    char *cell = *cursor, *comma = strchr(cell, ',');
    if (comma) {
        *comma = '\0';
        *cursor = comma + 1;
    } else {
        *cursor = cell + strlen(cell);
    }
    return trim(cell);
}

/* Parse the header line into `l`. The required columns must come first and in order, then an
 * optional mobility group, then fields. */
static int parse_header(layout *l, const char *line, const char *path, size_t lineno,
                        char *err)
{
    l->header = malloc(strlen(line) + 1);
    l->ncols = count_cells(line);
    l->name = malloc(l->ncols * sizeof *l->name);
    if (!l->header || !l->name) {
        pst_set_err(err, "%s:%zu:1: out of memory reading the header", path, lineno);
        return PST_ENOMEM;
    }
    strcpy(l->header, line);
    char *cursor = l->header;
    l->dim = 2;
    for (size_t k = 0; k < l->ncols; ++k) {
        l->name[k] = next_cell(&cursor);
        if (strcmp(l->name[k], "z") == 0)
            l->dim = 3;
    }
    const char *req[9];
    size_t nreq = 0;
    for (int d = 0; d < l->dim; ++d)
        req[nreq++] = coord_names[d];
    req[nreq++] = "V";
    req[nreq++] = "h";
    req[nreq++] = "kind";
    for (int d = 0; d < l->dim; ++d)
        req[nreq++] = normal_names[d];
    size_t k = 0;
    for (; k < nreq; ++k) {
        if (k >= l->ncols) {
            pst_set_err(err, "%s:%zu:%zu: missing column '%s' (the header starts %s)", path,
                        lineno, k + 1, req[k],
                        l->dim == 2 ? "x,y,V,h,kind,nx,ny" : "x,y,z,V,h,kind,nx,ny,nz");
            return PST_EINPUT;
        }
        if (strcmp(l->name[k], req[k]) != 0) {
            pst_set_err(err, "%s:%zu:%zu: expected column '%s' here, found '%s'", path, lineno,
                        k + 1, req[k], l->name[k]);
            return PST_EINPUT;
        }
    }
    l->mob = 0;
    if (k < l->ncols && strcmp(l->name[k], "m") == 0) {
        l->mob = 1;
        ++k;
    } else if (k < l->ncols && strcmp(l->name[k], "mx") == 0) {
        for (int d = 0; d < l->dim; ++d, ++k)
            if (k >= l->ncols || strcmp(l->name[k], mob_names[d]) != 0) {
                pst_set_err(err, "%s:%zu:%zu: expected column '%s' of the diagonal mobility, "
                                 "found '%s'",
                            path, lineno, k + 1, mob_names[d], k < l->ncols ? l->name[k] : "");
                return PST_EINPUT;
            }
        l->mob = l->dim;
    }
    l->nfields = l->ncols - k;
    for (; k < l->ncols; ++k) {
        for (size_t j = 0; j < k; ++j)
            if (strcmp(l->name[j], l->name[k]) == 0) {
                pst_set_err(err, "%s:%zu:%zu: duplicate column name '%s' (also column %zu)",
                            path, lineno, k + 1, l->name[k], j + 1);
                return PST_EINPUT;
            }
        if (pst_is_reserved_column(l->name[k])) {
            pst_set_err(err, "%s:%zu:%zu: misplaced column '%s'", path, lineno, k + 1,
                        l->name[k]);
            return PST_EINPUT;
        }
        if (!pst_is_identifier(l->name[k])) {
            pst_set_err(err, "%s:%zu:%zu: unknown column '%s' (a field name must be a C "
                             "identifier shorter than %d characters)",
                        path, lineno, k + 1, l->name[k], PST_MAX_NAME);
            return PST_EINPUT;
        }
    }
    return PST_OK;
}

/* Parse one cell of a data line; kind becomes 0, 1 or 2. */
static int parse_cell(const layout *l, size_t k, const char *cell, double *value,
                      const char *path, size_t lineno, char *err)
{
#define CELL_ERR(...)                                                                          \
    do {                                                                                       \
        char msg_[PST_ERRLEN];                                                                 \
        snprintf(msg_, sizeof msg_, __VA_ARGS__);                                              \
        pst_set_err(err, "%s:%zu:%zu: column %s: %s", path, lineno, k + 1, l->name[k], msg_);  \
        return PST_EINPUT;                                                                     \
    } while (0)
    if (k == col_kind(l)) {
        for (int t = 0; t <= PST_NEUMANN; ++t) {
            char digit[2] = {(char)('0' + t), '\0'};
            if (strcmp(cell, kind_names[t]) == 0 || strcmp(cell, digit) == 0) {
                *value = t;
                return PST_OK;
            }
        }
        CELL_ERR("unknown kind '%.64s' (interior, dirichlet, neumann or 0, 1, 2)", cell);
    }
    if (!*cell)
        CELL_ERR("missing value");
    char *end;
    double v = strtod(cell, &end); /* ERANGE on subnormals is fine: they round-trip */
    if (*end)
        CELL_ERR("cannot parse '%.64s' as a number", cell);
    if (!isfinite(v))
        CELL_ERR("value '%.64s' is not finite", cell);
    if (k == col_V(l) && !(v > 0))
        CELL_ERR("volume V = %.17g must be > 0", v);
    if (k == col_h(l) && !(v > 0))
        CELL_ERR("smoothing length h = %.17g must be > 0", v);
    if (k >= col_mob(l) && k < col_field(l) && !(v > 0))
        CELL_ERR("mobility %.17g must be > 0", v);
    *value = v;
    return PST_OK;
#undef CELL_ERR
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
    for (size_t f = 0; st == PST_OK && f < nf; ++f)
        st = pst_cloud_add_field(c, l->name[col_field(l) + f], &fields[f], NULL);
    if (st != PST_OK) {
        free(fields);
        pst_cloud_destroy(c);
        return st;
    }
    for (size_t i = 0; i < r->n; ++i) {
        const double *v = r->val + i * nc;
        for (int d = 0; d < l->dim; ++d) {
            c->x[d][i] = v[d];
            c->normal[d][i] = v[col_normal(l) + (size_t)d];
        }
        c->V[i] = v[col_V(l)];
        if (h)
            h[i] = v[col_h(l)];
        c->kind[i] = (uint8_t)v[col_kind(l)];
        for (int m = 0; m < l->mob; ++m)
            c->mob[m][i] = v[col_mob(l) + (size_t)m];
        for (size_t f = 0; f < nf; ++f)
            fields[f][i] = v[col_field(l) + f];
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
    if (found < 0) {
        pst_set_err(err, "%s: out of memory", path);
        return found;
    }
    if (found) {
        pst_set_err(err, "%s:%zu:1: duplicate particle: same coordinates as line %zu", path,
                    r->line[b], r->line[a]);
        return PST_EINPUT;
    }
    return PST_OK;
}

int pst_cloud_read_csv(pst_cloud **out, const char *path, char *err)
{
    *out = NULL;
    FILE *f = fopen(path, "r");
    if (!f) {
        pst_set_err(err, "%s: cannot open: %s", path, strerror(errno));
        return PST_EIO;
    }
    layout l = {0};
    rows r = {0};
    char *line = NULL;
    size_t linecap = 0, lineno = 0;
    int st = PST_OK, have_header = 0;
    ssize_t len;
    while (st == PST_OK && (len = getline(&line, &linecap, f)) >= 0) {
        ++lineno;
        chomp(line, len);
        char *text = line;
        if (lineno == 1 && strncmp(text, "\xEF\xBB\xBF", 3) == 0)
            text += 3; /* a UTF-8 byte-order mark, as some spreadsheets write */
        if (is_blank(text))
            continue;
        if (!have_header) {
            st = parse_header(&l, text, path, lineno, err);
            have_header = 1;
            continue;
        }
        size_t found = count_cells(text);
        if (found != l.ncols) {
            pst_set_err(err, "%s:%zu:%zu: expected %zu columns, found %zu", path, lineno,
                        (found < l.ncols ? found : l.ncols) + 1, l.ncols, found);
            st = PST_EINPUT;
            break;
        }
        if (rows_push(&r, l.ncols) != PST_OK) {
            pst_set_err(err, "%s:%zu:1: out of memory or more than %lu particles", path, lineno,
                        (unsigned long)UINT32_MAX);
            st = PST_ENOMEM;
            break;
        }
        char *cursor = text;
        double *v = r.val + r.n * l.ncols;
        for (size_t k = 0; st == PST_OK && k < l.ncols; ++k)
            st = parse_cell(&l, k, next_cell(&cursor), &v[k], path, lineno, err);
        r.line[r.n++] = lineno;
    }
    if (st == PST_OK && ferror(f)) {
        pst_set_err(err, "%s:%zu: read error: %s", path, lineno + 1, strerror(errno));
        st = PST_EIO;
    }
    if (st == PST_OK && !have_header) {
        pst_set_err(err, "%s:1:1: empty file: no header line", path);
        st = PST_EINPUT;
    }
    pst_cloud *c = NULL;
    if (st == PST_OK && (st = build_cloud(&c, &l, &r)) != PST_OK)
        pst_set_err(err, "%s: %zu particles: %s", path, r.n,
                    st == PST_EINVAL ? "more than the 32-bit index limit" : "out of memory");
    if (st == PST_OK && (st = check_duplicates(c, &r, path, err)) != PST_OK) {
        pst_cloud_destroy(c);
        c = NULL;
    }
    free(line);
    free(l.header);
    free(l.name);
    free(r.val);
    free(r.line);
    fclose(f);
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
