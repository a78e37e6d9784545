/* Reading clouds from VTK XML files (.vtu UnstructuredGrid, .vtp PolyData): the subset is in
 * docs/io.md ("Reading VTU"). The whole file is read into memory and expat parses the XML up
 * to the appended block (which is raw bytes, not XML); the walk keeps only what a cloud
 * needs: the Piece's NumberOfPoints, the Points array and the PointData arrays. Every array is
 * decoded from its source (appended raw, inline base64 "binary" or ascii, zlib-compressed or
 * not) after its size has been checked against the bytes that are really there, so a damaged
 * file gives PST_EINPUT naming the file and the place, never a read out of bounds or a huge
 * allocation. Values are checked where they stand, like the CSV reader, with messages that
 * name the array and the point (the 0-based row of the file). */
#include "vtu_read.h"

#include "check.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

/* "FILE:LINE:COLUMN: message" for a place in the XML. */
int vtu_fail_at(reader *r, vtu_pos at, const char *fmt, ...)
{
    char msg[PST_ERRLEN];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    pst_set_err(r->err, "%s:%lu:%lu: %s", r->path, at.line, at.col, msg);
    return PST_EINPUT;
}

/* "FILE: message" (values, appended data). */
int vtu_fail(reader *r, const char *fmt, ...)
{
    char msg[PST_ERRLEN];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    pst_set_err(r->err, "%s: %s", r->path, msg);
    return PST_EINPUT;
}

int vtu_oom(reader *r)
{
    pst_set_err(r->err, "%s: out of memory", r->path);
    return PST_ENOMEM;
}

/* The roles of PointData arrays. */
enum { R_FIELD, R_ID, R_KIND, R_V, R_H, R_NORMAL, R_MSCALAR, R_MDIAG, R_STATUS };

static int role_of(const char *name)
{
    static const char *const names[] = {"id", "kind", "V", "h", "normal", "m", "M", "status"};
    for (int k = 0; k < 8; ++k)
        if (!strcmp(name, names[k]))
            return k + 1;
    return R_FIELD;
}

/* Names, component counts and the required arrays, before any value is decoded. */
static int check_arrays(reader *r, size_t *idx_h)
{
    size_t idx_V = SIZE_MAX;
    *idx_h = SIZE_MAX;
    int have_m = 0;
    size_t first = 0, again = SIZE_MAX;
    const char **names = malloc((r->na ? r->na : 1) * sizeof *names);
    if (!names)
        return vtu_oom(r);
    for (size_t k = 0; k < r->na; ++k)
        names[k] = r->a[k].name;
    int found = pst_find_repeated_name(names, r->na, &first, &again);
    free(names);
    if (found < 0)
        return vtu_oom(r);
    for (size_t k = 0; k < r->na; ++k) {
        vtu_in_array *a = &r->a[k];
        if (found && k == again)
            return vtu_fail_at(r, a->at, "two PointData arrays are named '%.64s'", a->name);
        int role = role_of(a->name);
        if (role == R_STATUS)
            continue;
        int want = role == R_NORMAL || role == R_MDIAG ? 3 : 1;
        if (role == R_FIELD && a->ncomp != 1 && a->ncomp != 3 && a->ncomp != 6)
            return vtu_fail_at(r, a->at,
                               "PointData array '%.64s' has %d components: a field has 1, "
                               "3 (a vector) or 6 (a symmetric tensor)",
                               a->name, a->ncomp);
        if (role != R_FIELD && a->ncomp != want) {
            return vtu_fail_at(r, a->at, "PointData array '%s' has %d components, expected %d",
                               a->name, a->ncomp, want);
        }
        if (role == R_MSCALAR || role == R_MDIAG) {
            if (have_m)
                return vtu_fail_at(r, a->at, "both 'm' and 'M' are present: give one mobility");
            have_m = 1;
        }
        if (role == R_V)
            idx_V = k;
        if (role == R_H)
            *idx_h = k;
    }
    if (idx_V == SIZE_MAX)
        return vtu_fail(r, "missing PointData array 'V' (the volumes; required)");
    if (*idx_h == SIZE_MAX)
        return vtu_fail(r, "missing PointData array 'h' (the smoothing lengths; required)");
    if (r->have_points && r->points.ncomp != 3)
        return vtu_fail_at(r, r->points.at, "the Points array has %d components, expected 3",
                           r->points.ncomp);
    return PST_OK;
}

/* Non-finite values of an array: the first one, by point and component. */
static int check_finite(reader *r, const vtu_in_array *a, const double *v)
{
    size_t count = (size_t)r->npoints * (size_t)a->ncomp;
    for (size_t k = 0; k < count; ++k)
        if (!isfinite(v[k])) {
            if (a->ncomp > 1)
                return vtu_fail(r,
                                "array '%.64s', point %zu, component %zu: value %g is not "
                                "finite",
                                a->name, k / (size_t)a->ncomp, k % (size_t)a->ncomp, v[k]);
            return vtu_fail(r, "array '%.64s', point %zu: value %g is not finite", a->name, k,
                            v[k]);
        }
    return PST_OK;
}

/* Store one PointData array (values v, file row k -> particle part[k]) into the cloud. */
static int store_array(reader *r, pst_cloud *c, const vtu_in_array *a, const double *v,
                       const size_t *part, size_t field)
{
    size_t n = c->n;
    int dim = c->dim, role = role_of(a->name);
    PST_TRY(check_finite(r, a, v));
    if (role == R_FIELD)
        return vtu_store_field(r, c, a, v, part, field);
    for (size_t k = 0; k < n; ++k) {
        size_t i = part[k];
        switch (role) {
        case R_KIND:
            if (!(v[k] == 0 || v[k] == 1 || v[k] == 2))
                return vtu_fail(r,
                                "array 'kind', point %zu: unknown kind %g (0 interior, 1 "
                                "dirichlet, 2 neumann)",
                                k, v[k]);
            c->kind[i] = (uint8_t)v[k];
            break;
        case R_V:
            if (!(v[k] > 0))
                return vtu_fail(r, "array 'V', point %zu: volume V = %.17g must be > 0", k, v[k]);
            c->V[i] = v[k];
            break;
        case R_H:
            if (!(v[k] > 0))
                return vtu_fail(r, "array 'h', point %zu: smoothing length h = %.17g must be > 0",
                                k, v[k]);
            if (c->h)
                c->h[i] = v[k];
            break;
        case R_NORMAL:
            for (int d = 0; d < dim; ++d)
                c->normal[d][i] = v[3 * k + (size_t)d];
            break;
        case R_MSCALAR:
        case R_MDIAG:
            for (int m = 0; m < c->mob_ncomp; ++m) {
                double x = v[(size_t)a->ncomp * k + (size_t)m];
                if (!(x > 0))
                    return vtu_fail(r, "array '%s', point %zu: mobility %.17g must be > 0", a->name,
                                    k, x);
                c->mob[m][i] = x;
            }
            break;
        default: /* id (already used), status (ignored); fields: below */
            break;
        }
    }
    return PST_OK;
}

/* The particle of each file row: part[k] = id[k] when there is an 'id' array, else k. */
static int make_order(reader *r, double *tmp, size_t *part, size_t *row)
{
    size_t n = (size_t)r->npoints;
    vtu_in_array *id = NULL;
    for (size_t k = 0; k < r->na; ++k)
        if (role_of(r->a[k].name) == R_ID)
            id = &r->a[k];
    for (size_t k = 0; k < n; ++k)
        part[k] = row[k] = k;
    if (!id)
        return PST_OK;
    PST_TRY(vtu_decode(r, id, tmp));
    for (size_t k = 0; k < n; ++k)
        row[k] = SIZE_MAX;
    for (size_t k = 0; k < n; ++k) {
        double v = tmp[k];
        if (!(v >= 0 && v < (double)n && v == floor(v)))
            return vtu_fail(r,
                            "array 'id', point %zu: id %g is not in 0..%zu (the ids must be a "
                            "permutation of 0..n-1)",
                            k, v, n ? n - 1 : 0);
        size_t i = (size_t)v;
        if (row[i] != SIZE_MAX)
            return vtu_fail(r,
                            "array 'id', point %zu: id %zu also at point %zu (the ids must be a "
                            "permutation of 0..n-1)",
                            k, i, row[i]);
        row[i] = k;
        part[k] = i;
    }
    return PST_OK;
}

/* h: uniform when every value is the same (as the CSV reader), else per particle. */
static int store_h(reader *r, pst_cloud *c, vtu_in_array *a, double *tmp,
                   const size_t *part)
{
    size_t n = c->n;
    PST_TRY(vtu_decode(r, a, tmp));
    int uniform = 1;
    for (size_t k = 1; k < n; ++k)
        uniform = uniform && tmp[k] == tmp[0];
    if (!uniform && !pst_cloud_h_per_particle(c))
        return vtu_oom(r);
    PST_TRY(store_array(r, c, a, tmp, part, 0));
    if (uniform && n > 0)
        pst_cloud_set_h_uniform(c, tmp[0], NULL);
    return PST_OK;
}

/* The fields (arrays of no other role, vectors and tensors split), added to the cloud at once
 * (after the positions: in 2D a vector gives two fields). */
static int add_fields(reader *r, pst_cloud *c)
{
    vtu_in_array **arrays = malloc((r->na ? r->na : 1) * sizeof *arrays);
    if (!arrays)
        return vtu_oom(r);
    size_t na = 0, n = 0;
    for (size_t k = 0; k < r->na; ++k)
        if (role_of(r->a[k].name) == R_FIELD)
            arrays[na++] = &r->a[k];
    char(*names)[PST_MAX_NAME] = NULL;
    int st = vtu_field_names(r, c->dim, arrays, na, &names, &n);
    free(arrays);
    if (st != PST_OK)
        return st;
    const char **list = malloc((n ? n : 1) * sizeof *list);
    for (size_t k = 0; list && k < n; ++k)
        list[k] = names[k];
    char why[PST_ERRLEN] = "";
    st = list ? pst_cloud_add_fields(c, list, n, NULL, why) : PST_ENOMEM; /* names checked */
    free(list);
    free(names);
    return st == PST_OK ? PST_OK : vtu_oom(r);
}

/* Every PointData array but h, id and status, in file order. */
static int store_others(reader *r, pst_cloud *c, size_t ih, double *tmp, const size_t *part)
{
    size_t nfield = c->nfields; /* the first new field's index */
    PST_TRY(add_fields(r, c));
    for (size_t k = 0; k < r->na; ++k) {
        vtu_in_array *a = &r->a[k];
        int role = role_of(a->name), st = PST_OK, comp[6];
        if (k == ih || role == R_ID || role == R_STATUS)
            continue;
        size_t field = nfield;
        if (role == R_FIELD)
            nfield += (size_t)vtu_field_parts(a->ncomp, c->dim, comp);
        char why[PST_ERRLEN] = "";
        if (role == R_MSCALAR || role == R_MDIAG)
            st = pst_cloud_set_mobility(c, role == R_MSCALAR ? 1 : c->dim, why);
        if (st != PST_OK)
            return st == PST_ENOMEM ? vtu_oom(r)
                                    : vtu_fail_at(r, a->at, "array '%s': %s", a->name, why);
        PST_TRY(vtu_decode(r, a, tmp));
        PST_TRY(store_array(r, c, a, tmp, part, field));
    }
    return PST_OK;
}

/* Two particles at the same place, named by their file rows. */
static int check_duplicates(reader *r, const pst_cloud *c, const size_t *row)
{
    size_t pa, pb;
    int dup = pst_cloud_find_duplicate(c, &pa, &pb);
    if (dup < 0)
        return vtu_oom(r);
    if (!dup)
        return PST_OK;
    size_t ra = row[pa] < row[pb] ? row[pa] : row[pb], rb = row[pa] ^ row[pb] ^ ra;
    return vtu_fail(r,
                    "array 'Points', point %zu: duplicate particle: same coordinates as "
                    "point %zu",
                    rb, ra);
}

/* The buffers of the builder: positions, one array's values, and the row <-> particle maps. */
typedef struct {
    double *pts, *tmp;
    size_t *part, *row;
} build_buffers;

/* The cloud of n points from the checked arrays into *c (the caller destroys it on failure). */
static int fill_cloud(reader *r, const build_buffers *b, size_t ih, pst_cloud **c)
{
    size_t n = (size_t)r->npoints;
    int dim = 2;
    if (n > 0) {
        PST_TRY(vtu_decode(r, &r->points, b->pts));
        PST_TRY(check_finite(r, &r->points, b->pts));
        for (size_t k = 0; k < n && dim == 2; ++k)
            if (b->pts[3 * k + 2] != 0)
                dim = 3;
    }
    PST_TRY(make_order(r, b->tmp, b->part, b->row));
    int st = pst_cloud_create(c, dim, n, NULL);
    if (st != PST_OK)
        return st == PST_ENOMEM ? vtu_oom(r)
                                : vtu_fail(r, "cannot create a cloud of %zu points", n);
    for (size_t k = 0; k < n; ++k)
        for (int d = 0; d < dim; ++d)
            (*c)->x[d][b->part[k]] = b->pts[3 * k + (size_t)d];
    PST_TRY(store_h(r, *c, &r->a[ih], b->tmp, b->part));
    PST_TRY(store_others(r, *c, ih, b->tmp, b->part));
    st = check_duplicates(r, *c, b->row);
    char why[PST_ERRLEN] = "";
    if (st == PST_OK && pst_cloud_check_extent_normals(*c, why) != PST_OK)
        st = vtu_fail(r, "%s", why);
    return st;
}

static int build(reader *r, pst_cloud **out)
{
    size_t ih;
    PST_TRY(check_arrays(r, &ih));
    size_t n = (size_t)r->npoints;
    /* the sizes were bounded by the file before anything this large is allocated: every
     * decode checks its byte count against the data that is there, but the buffers come
     * first, so bound n by the file size (each value takes at least one byte of appended data,
     * or 2 characters of ascii / 4/3 of base64, or 1/VTU_ZLIB_MAX_RATIO compressed) */
    size_t most = r->compressed ? r->len * VTU_ZLIB_MAX_RATIO + 64 : r->len;
    if (n > most)
        return vtu_fail(r,
                        "the Piece declares %zu points, more than the file's %zu bytes can "
                        "hold",
                        n, r->len);
    size_t m = n ? n : 1;
    /* tmp: one array at a time, at most a 6-component tensor */
    build_buffers b = {malloc(m * 3 * sizeof(double)), malloc(m * 6 * sizeof(double)),
                       malloc(m * sizeof(size_t)), malloc(m * sizeof(size_t))};
    pst_cloud *c = NULL;
    int st = b.pts && b.tmp && b.part && b.row ? fill_cloud(r, &b, ih, &c) : vtu_oom(r);
    free(b.pts);
    free(b.tmp);
    free(b.part);
    free(b.row);
    if (st != PST_OK) {
        pst_cloud_destroy(c);
        c = NULL;
    }
    *out = c;
    return st;
}

/* Read the whole file, with a NUL after the last byte. */
static int slurp(const char *path, unsigned char **buf, size_t *len, char *err)
{
    *buf = NULL;
    *len = 0;
    FILE *f = fopen(path, "rb");
    PST_CHECK(!f, PST_EIO, err, "%s: cannot open: %s", path, strerror(errno));
    size_t cap = 1 << 16, n = 0;
    unsigned char *b = malloc(cap);
    while (b) {
        n += fread(b + n, 1, cap - 1 - n, f);
        if (n < cap - 1)
            break;
        unsigned char *nb = cap <= SIZE_MAX / 2 ? realloc(b, 2 * cap) : NULL;
        if (!nb) {
            free(b);
            b = NULL;
            break;
        }
        b = nb;
        cap *= 2;
    }
    int bad = ferror(f);
    int e = errno;
    fclose(f);
    PST_CHECK_ALLOC(b, err, "%s: out of memory reading the file", path);
    if (bad) {
        free(b);
        pst_set_err(err, "%s: read error: %s", path, strerror(e));
        return PST_EIO;
    }
    b[n] = '\0';
    *buf = b;
    *len = n;
    return PST_OK;
}

int pst_cloud_read_vtu(pst_cloud **out, const char *path, char *err)
{
    *out = NULL;
    reader r;
    memset(&r, 0, sizeof r);
    r.path = path;
    r.err = err;
    unsigned char *buf;
    PST_TRY(slurp(path, &buf, &r.len, err));
    r.buf = buf;
    int st = vtu_scan_xml(&r);
    if (st == PST_OK)
        st = build(&r, out);
    for (size_t k = 0; k < r.na; ++k)
        free(r.a[k].text);
    free(r.a);
    free(r.points.text);
    free(buf);
    return st;
}
