/* The particle cloud: structure-of-arrays storage, accessors, validation and permutation. */
#include "cloud_layout.h"
#include "check.h"

#include <ctype.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static double *alloc_filled(size_t n, double value)
{
    double *a = pst_alloc(n * sizeof(double));
    if (a)
        for (size_t i = 0; i < n; ++i)
            a[i] = value;
    return a;
}

int pst_cloud_alloc_missing(pst_cloud *c)
{
    size_t n = c->n;
    int ok = 1;
    for (int d = 0; d < c->dim; ++d) {
        if (!c->x[d])
            ok = (c->x[d] = pst_calloc(n, sizeof(double))) != NULL && ok;
        if (!c->normal[d])
            ok = (c->normal[d] = pst_calloc(n, sizeof(double))) != NULL && ok;
    }
    if (!c->V)
        ok = (c->V = alloc_filled(n, 1.0)) != NULL && ok;
    if (!c->kind)
        ok = (c->kind = pst_calloc(n, 1)) != NULL && ok;
    if (!c->id) {
        ok = (c->id = pst_alloc(n * sizeof(int64_t))) != NULL && ok;
        for (size_t i = 0; c->id && i < n; ++i)
            c->id[i] = (int64_t)i;
    }
    return ok ? PST_OK : PST_ENOMEM;
}

/* A cloud with every array allocated and at its default (see pst_cloud_create); NULL when an
 * allocation fails. */
static pst_cloud *new_cloud(int dim, size_t n)
{
    pst_cloud *c = calloc(1, sizeof *c);
    if (!c)
        return NULL;
    c->dim = dim;
    c->n = n;
    c->h_uniform = 1.0;
    if (pst_cloud_alloc_missing(c) != PST_OK) {
        pst_cloud_destroy(c);
        return NULL;
    }
    return c;
}

/* Free p unless it belongs to the caller (its group's bit in c->borrowed). */
static void release(const pst_cloud *c, unsigned group, void *p)
{
    if (!(c->borrowed & group))
        pst_free(p);
}

int pst_cloud_create(pst_cloud **out, int dim, size_t n, char *err)
{
    *out = NULL;
    PST_CHECK(dim != 2 && dim != 3, PST_EINVAL, err, "cloud: dim must be 2 or 3 (got %d)", dim);
    PST_CHECK(n > (size_t)UINT32_MAX, PST_EINVAL, err, /* neighbour indices are 32-bit */
              "cloud: %zu particles exceed the 32-bit index limit", n);
    *out = new_cloud(dim, n);
    PST_CHECK_ALLOC(*out, err, "cloud: out of memory for %zu particles", n);
    return PST_OK;
}

void pst_cloud_destroy(pst_cloud *c)
{
    if (!c)
        return;
    for (int d = 0; d < 3; ++d) {
        release(c, PST_BORROW_X, c->x[d]);
        release(c, PST_BORROW_NORMAL, c->normal[d]);
        release(c, PST_BORROW_MOB, c->mob[d]);
    }
    release(c, PST_BORROW_V, c->V);
    release(c, PST_BORROW_H, c->h);
    release(c, PST_BORROW_KIND, c->kind);
    pst_free(c->id);
    for (size_t k = 0; k < c->nfields; ++k)
        pst_free(c->field[k]);
    free(c->field);
    free(c->field_name);
    free(c);
}

int pst_cloud_dim(const pst_cloud *c) { return c->dim; }
size_t pst_cloud_size(const pst_cloud *c) { return c->n; }

double *pst_cloud_coord(pst_cloud *c, int axis)
{
    return (axis >= 0 && axis < c->dim) ? c->x[axis] : NULL;
}
const double *pst_cloud_coord_const(const pst_cloud *c, int axis)
{
    return (axis >= 0 && axis < c->dim) ? c->x[axis] : NULL;
}
double *pst_cloud_volume(pst_cloud *c) { return c->V; }
const double *pst_cloud_volume_const(const pst_cloud *c) { return c->V; }
double *pst_cloud_normal(pst_cloud *c, int axis)
{
    return (axis >= 0 && axis < c->dim) ? c->normal[axis] : NULL;
}
const double *pst_cloud_normal_const(const pst_cloud *c, int axis)
{
    return (axis >= 0 && axis < c->dim) ? c->normal[axis] : NULL;
}
uint8_t *pst_cloud_kinds(pst_cloud *c) { return c->kind; }
const uint8_t *pst_cloud_kinds_const(const pst_cloud *c) { return c->kind; }
int64_t *pst_cloud_ids(pst_cloud *c) { return c->id; }
const int64_t *pst_cloud_ids_const(const pst_cloud *c) { return c->id; }

int pst_cloud_set_h_uniform(pst_cloud *c, double h, char *err)
{
    PST_CHECK(!(h > 0) || !isfinite(h), PST_EINVAL, err,
              "smoothing length must be finite and > 0 (got %g)", h);
    release(c, PST_BORROW_H, c->h); /* a borrowed array is only let go */
    c->borrowed &= ~(unsigned)PST_BORROW_H;
    c->h = NULL;
    c->h_uniform = h;
    return PST_OK;
}

double *pst_cloud_h_per_particle(pst_cloud *c)
{
    if (!c->h) {
        c->h = alloc_filled(c->n, c->h_uniform);
        if (!c->h)
            return NULL;
        c->h_uniform = 0;
    }
    return c->h;
}

int pst_cloud_h_is_uniform(const pst_cloud *c) { return c->h == NULL; }
double pst_cloud_h_uniform(const pst_cloud *c) { return c->h ? 0.0 : c->h_uniform; }
const double *pst_cloud_h_array(const pst_cloud *c) { return c->h; }

double pst_cloud_h_max(const pst_cloud *c)
{
    if (!c->h)
        return c->h_uniform;
    double m = 0;
    for (size_t i = 0; i < c->n; ++i)
        m = c->h[i] > m ? c->h[i] : m;
    return m;
}

int pst_cloud_set_mobility(pst_cloud *c, int ncomp, char *err)
{
    PST_CHECK(ncomp != 0 && ncomp != 1 && ncomp != c->dim, PST_EINVAL, err,
              "mobility has 0, 1 or %d components (got %d)", c->dim, ncomp);
    double *m[3] = {NULL, NULL, NULL};
    int ok = 1;
    for (int k = 0; k < ncomp; ++k)
        ok = ok && (m[k] = alloc_filled(c->n, 1.0)) != NULL;
    if (!ok)
        for (int k = 0; k < ncomp; ++k)
            pst_free(m[k]);
    PST_CHECK(!ok, PST_ENOMEM, err, "mobility: out of memory for %d components of %zu values",
              ncomp, c->n);
    for (int k = 0; k < 3; ++k) {
        release(c, PST_BORROW_MOB, c->mob[k]); /* borrowed arrays are only let go */
        c->mob[k] = m[k];
    }
    c->borrowed &= ~(unsigned)PST_BORROW_MOB;
    c->mob_ncomp = ncomp;
    return PST_OK;
}

int pst_cloud_mobility_ncomp(const pst_cloud *c) { return c->mob_ncomp; }
double *pst_cloud_mobility(pst_cloud *c, int comp)
{
    return (comp >= 0 && comp < c->mob_ncomp) ? c->mob[comp] : NULL;
}

/* Column names of the CSV format; a field may not shadow them. */
static const char *const reserved_names[] = {"x",  "y",  "z",  "V",  "h",  "kind", "nx",
                                             "ny", "nz", "m",  "mx", "my", "mz",   "id"};

int pst_is_reserved_column(const char *name)
{
    for (size_t k = 0; k < sizeof reserved_names / sizeof *reserved_names; ++k)
        if (strcmp(name, reserved_names[k]) == 0)
            return 1;
    return 0;
}

int pst_is_identifier(const char *name)
{
    size_t len = strlen(name);
    if (len == 0 || len >= PST_MAX_NAME || isdigit((unsigned char)name[0]))
        return 0;
    for (size_t i = 0; i < len; ++i)
        if (!isalnum((unsigned char)name[i]) && name[i] != '_')
            return 0;
    return 1;
}

int pst_cloud_add_field(pst_cloud *c, const char *name, double **data, char *err)
{
    if (data)
        *data = NULL;
    PST_CHECK(!name || !pst_is_identifier(name) || pst_is_reserved_column(name), PST_EINVAL, err,
              "invalid field name '%s' (a C identifier, not a reserved column)",
              name ? name : "(null)");
    PST_CHECK(pst_cloud_field_by_name(c, name), PST_EINVAL, err, "field '%s' already exists",
              name);
    double *a = pst_calloc(c->n, sizeof(double));
    char(*names)[PST_MAX_NAME] = realloc(c->field_name, (c->nfields + 1) * sizeof *names);
    if (names)
        c->field_name = names;
    double **fields = realloc(c->field, (c->nfields + 1) * sizeof *fields);
    if (fields)
        c->field = fields;
    if (!names || !fields)
        pst_free(a);
    PST_CHECK(!a || !names || !fields, PST_ENOMEM, err, "field '%s': out of memory for %zu values",
              name, c->n);
    snprintf(c->field_name[c->nfields], PST_MAX_NAME, "%s", name);
    c->field[c->nfields++] = a;
    if (data)
        *data = a;
    return PST_OK;
}

size_t pst_cloud_nfields(const pst_cloud *c) { return c->nfields; }
const char *pst_cloud_field_name(const pst_cloud *c, size_t k)
{
    return k < c->nfields ? c->field_name[k] : NULL;
}
double *pst_cloud_field(pst_cloud *c, size_t k) { return k < c->nfields ? c->field[k] : NULL; }
double *pst_cloud_field_by_name(pst_cloud *c, const char *name)
{
    for (size_t k = 0; k < c->nfields; ++k)
        if (strcmp(c->field_name[k], name) == 0)
            return c->field[k];
    return NULL;
}

void pst_cloud_bbox(const pst_cloud *c, double lo[3], double hi[3])
{
    for (int d = 0; d < 3; ++d)
        lo[d] = hi[d] = 0;
    for (int d = 0; d < c->dim; ++d) {
        if (c->n == 0)
            continue;
        double a = c->x[d][0], b = a;
        for (size_t i = 1; i < c->n; ++i) {
            a = c->x[d][i] < a ? c->x[d][i] : a;
            b = c->x[d][i] > b ? c->x[d][i] : b;
        }
        lo[d] = a;
        hi[d] = b;
    }
}

/* Lexicographic order of positions, for duplicate detection by sorting (qsort has no context
 * argument, so the cloud travels in a thread-local). */
static _Thread_local const pst_cloud *sort_cloud;

static int cmp_position(const void *pa, const void *pb)
{
    size_t a = *(const size_t *)pa, b = *(const size_t *)pb;
    for (int d = 0; d < sort_cloud->dim; ++d) {
        double xa = sort_cloud->x[d][a], xb = sort_cloud->x[d][b];
        if (xa < xb)
            return -1;
        if (xa > xb)
            return 1;
    }
    return (a > b) - (a < b);
}

static int same_position(const pst_cloud *c, size_t a, size_t b)
{
    for (int d = 0; d < c->dim; ++d)
        if (c->x[d][a] != c->x[d][b])
            return 0;
    return 1;
}

int pst_cloud_find_duplicate(const pst_cloud *c, size_t *a, size_t *b)
{
    if (c->n < 2)
        return 0;
    size_t *order = malloc(c->n * sizeof *order);
    if (!order)
        return PST_ENOMEM;
    for (size_t i = 0; i < c->n; ++i)
        order[i] = i;
    sort_cloud = c;
    qsort(order, c->n, sizeof *order, cmp_position);
    int found = 0;
    for (size_t k = 1; k < c->n && !found; ++k)
        if (same_position(c, order[k - 1], order[k])) {
            /* ties sort by index, so order[k-1] < order[k] */
            *a = order[k - 1];
            *b = order[k];
            found = 1;
        }
    free(order);
    return found;
}

/* The per-particle checks of pst_cloud_validate for particle i. */
static int validate_particle(const pst_cloud *c, size_t i, char *err)
{
    static const char *const axis = "xyz";
    long long id = (long long)c->id[i];
    for (int d = 0; d < c->dim; ++d) {
        PST_CHECK(!isfinite(c->x[d][i]), PST_EINPUT, err,
                  "particle %lld: coordinate %c is not finite", id, axis[d]);
        PST_CHECK(!isfinite(c->normal[d][i]), PST_EINPUT, err,
                  "particle %lld: normal component n%c is not finite", id, axis[d]);
    }
    PST_CHECK(!(c->V[i] > 0) || !isfinite(c->V[i]), PST_EINPUT, err,
              "particle %lld: volume V = %g must be finite and > 0", id, c->V[i]);
    double h = pst_cloud_h_at(c, i);
    PST_CHECK(!(h > 0) || !isfinite(h), PST_EINPUT, err,
              "particle %lld: smoothing length h = %g must be finite and > 0", id, h);
    PST_CHECK(c->kind[i] > PST_NEUMANN, PST_EINPUT, err, "particle %lld: unknown kind %d", id,
              c->kind[i]);
    for (int k = 0; k < c->mob_ncomp; ++k)
        PST_CHECK(!(c->mob[k][i] > 0) || !isfinite(c->mob[k][i]), PST_EINPUT, err,
                  "particle %lld: mobility component %d = %g must be > 0", id, k, c->mob[k][i]);
    return PST_OK;
}

int pst_cloud_check_extent_normals(const pst_cloud *c, char *err)
{
    /* finite coordinates can still span more than a double holds (+-1e308): the cell grids
     * could then neither size nor coarsen their cells */
    double lo[3], hi[3];
    pst_cloud_bbox(c, lo, hi);
    for (int d = 0; d < c->dim; ++d)
        PST_CHECK(!isfinite(hi[d] - lo[d]), PST_EINPUT, err,
                  "the cloud spans [%g, %g] along %c: the extent overflows a double", lo[d],
                  hi[d], "xyz"[d]);
    /* a flux row needs a direction: a zero normal would make it a zero row, silently */
    for (size_t i = 0; i < c->n; ++i) {
        double len = 0;
        for (int d = 0; d < c->dim; ++d)
            len += c->normal[d][i] * c->normal[d][i];
        PST_CHECK(c->kind[i] == PST_NEUMANN && !(len > 0), PST_EINPUT, err,
                  "particle %lld: Neumann particle with a zero normal (its flux row needs the "
                  "outward normal)",
                  (long long)c->id[i]);
    }
    return PST_OK;
}

int pst_cloud_validate(pst_cloud *c, char *err)
{
    for (size_t i = 0; i < c->n; ++i)
        PST_TRY(validate_particle(c, i, err));
    PST_TRY(pst_cloud_check_extent_normals(c, err));
    PST_TRY(pst_cloud_check_box(c, err));
    size_t a, b;
    int dup = pst_cloud_find_duplicate(c, &a, &b);
    PST_CHECK(dup < 0, dup, err, "out of memory for the duplicate check of %zu particles", c->n);
    PST_CHECK(dup, PST_EINPUT, err, "particles %lld and %lld are at the same coordinates",
              (long long)c->id[a], (long long)c->id[b]);
    return PST_OK;
}

/* Gather one array through the permutation into scratch, then copy back. Bandwidth-bound:
 * one streaming write and one random-ish read per element (the Morton order keeps it local). */
static void permute_doubles(double *a, const uint32_t *perm, size_t n, double *scratch)
{
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; ++i)
        scratch[i] = a[perm[i]];
    memcpy(a, scratch, n * sizeof *a);
}

/* PST_EINVAL (message in err) unless perm is a permutation of 0..n-1; seen: n zero bytes. */
static int check_permutation(const uint32_t *perm, size_t n, uint8_t *seen, char *err)
{
    for (size_t i = 0; i < n; ++i) {
        PST_CHECK(perm[i] >= n || seen[perm[i]], PST_EINVAL, err,
                  "not a permutation: entry %zu is %u", i, perm[i]);
        seen[perm[i]] = 1;
    }
    return PST_OK;
}

/* Reorder every array of c by perm, through n doubles of scratch and n bytes of bytes. */
static void permute_arrays(pst_cloud *c, const uint32_t *perm, double *scratch, uint8_t *bytes)
{
    size_t n = c->n;
    for (int d = 0; d < c->dim; ++d) {
        permute_doubles(c->x[d], perm, n, scratch);
        permute_doubles(c->normal[d], perm, n, scratch);
    }
    permute_doubles(c->V, perm, n, scratch);
    if (c->h)
        permute_doubles(c->h, perm, n, scratch);
    for (int k = 0; k < c->mob_ncomp; ++k)
        permute_doubles(c->mob[k], perm, n, scratch);
    for (size_t k = 0; k < c->nfields; ++k)
        permute_doubles(c->field[k], perm, n, scratch);
    /* ids are 8 bytes: they reuse the scratch buffer */
    int64_t *ids = (int64_t *)scratch;
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; ++i)
        ids[i] = c->id[perm[i]];
    memcpy(c->id, ids, n * sizeof *ids);
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; ++i)
        bytes[i] = c->kind[perm[i]];
    memcpy(c->kind, bytes, n);
}

int pst_cloud_permute(pst_cloud *c, const uint32_t *perm, char *err)
{
    PST_TRY(pst_cloud_check_owned(c, "permute", err));
    uint8_t *seen = pst_calloc(c->n, 1);
    double *scratch = pst_alloc(c->n * sizeof(double));
    int st = seen && scratch ? check_permutation(perm, c->n, seen, err) : PST_ENOMEM;
    if (st == PST_OK) {
        permute_arrays(c, perm, scratch, seen); /* the seen bytes become the kinds' scratch */
        c->permutations++;
    }
    pst_free(seen);
    pst_free(scratch);
    PST_CHECK(st == PST_ENOMEM, st, err, "permute: out of memory for %zu particles", c->n);
    return st;
}

void pst_cloud_to_input_order(const pst_cloud *c, const double *in, double *out)
{
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < c->n; ++i)
        out[c->id[i]] = in[i];
}

/* inv[id] = i over the particles, inv holding n entries; PST_EINVAL at a repeated or
 * out-of-range id. */
static int fill_inverse(const pst_cloud *c, size_t *inv, char *err)
{
    size_t n = c->n;
    for (size_t r = 0; r < n; ++r)
        inv[r] = SIZE_MAX;
    for (size_t i = 0; i < n; ++i) {
        int64_t id = c->id[i];
        PST_CHECK(id < 0 || (uint64_t)id >= n || inv[id] != SIZE_MAX, PST_EINVAL, err,
                  "the cloud's ids are not a permutation of 0..%zu (particle %zu has id %lld)",
                  n ? n - 1 : 0, i, (long long)id);
        inv[id] = i;
    }
    return PST_OK;
}

int pst_cloud_input_inverse(const pst_cloud *c, size_t **inv_out, char *err)
{
    size_t *inv = malloc((c->n ? c->n : 1) * sizeof *inv);
    PST_CHECK_ALLOC(inv, err, "out of memory for %zu row indices", c->n);
    int st = fill_inverse(c, inv, err);
    if (st == PST_OK)
        *inv_out = inv;
    else
        free(inv);
    return st;
}
