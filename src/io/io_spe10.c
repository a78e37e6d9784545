/* SPE10 model 2 permeability: reading one 60x220 layer (GEOS voxel files or the RTSPHEM
 * Tarbert text, layouts in shared/data/spe10/README.md and docs/spe10.md) into a
 * Cartesian grid, and setting a cloud's mobility from the grid cell under each particle. */
#include "internal.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define SPE10_NX 60
#define SPE10_NY 220
#define SPE10_LAYER (SPE10_NX * SPE10_NY) /* values per layer and component */

/* SPE10 cell sizes: 20 ft x 10 ft x 2 ft, in metres. */
#define SPE10_DX 6.096
#define SPE10_DY 3.048
#define SPE10_DZ 0.6096

/* ---- a whitespace-separated number reader that knows its line --------------------------- */

typedef struct {
    FILE *f;
    const char *path;
    size_t line;   /* line of the next character, 1-based */
} reader;

/* Longest token accepted; real values are at most ~12 characters. */
#define TOKEN_MAX 64

/* Read the next value into *v and the line it stands on into *line. Returns 1 on a value,
 * 0 at end of file, or a negative status with the message in err. Every value must be a
 * finite number > 0: the callers only read permeabilities. */
static int next_value(reader *r, double *v, size_t *line, char *err)
{
    int ch;
    while ((ch = getc(r->f)) != EOF && isspace(ch))
        r->line += ch == '\n';
    if (ch == EOF) {
        if (ferror(r->f)) {
            pst_set_err(err, "%s:%zu: read error: %s", r->path, r->line, strerror(errno));
            return PST_EIO;
        }
        return 0;
    }
    char tok[TOKEN_MAX + 1];
    size_t len = 0;
    int too_long = 0;
    for (; ch != EOF && !isspace(ch); ch = getc(r->f)) {
        if (len < TOKEN_MAX)
            tok[len++] = (char)ch;
        else
            too_long = 1;
    }
    tok[len] = '\0';
    *line = r->line;
    if (ch == '\n')
        ++r->line;
    if (too_long) {
        pst_set_err(err, "%s:%zu: token '%.20s...' is too long to be a number", r->path, *line,
                    tok);
        return PST_EINPUT;
    }
    char *end;
    double x = strtod(tok, &end); /* ERANGE on tiny values is fine: positivity decides */
    if (*end) {
        pst_set_err(err, "%s:%zu: cannot parse '%s' as a number", r->path, *line, tok);
        return PST_EINPUT;
    }
    if (!isfinite(x)) {
        pst_set_err(err, "%s:%zu: permeability '%s' is not finite", r->path, *line, tok);
        return PST_EINPUT;
    }
    if (!(x > 0)) {
        pst_set_err(err, "%s:%zu: permeability %.17g must be > 0", r->path, *line, x);
        return PST_EINPUT;
    }
    *v = x;
    return 1;
}

/* The sub-block being read: where a value of the file goes. */
typedef struct {
    int i0, j0, ni, nj;
} block;

/* Read a whole file of exactly `total` values laid out as consecutive components of
 * SPE10_LAYER values each (i fastest, then j). Component block `first + k` of the file goes to
 * out[k] for k < ncomp (restricted to the sub-block); the other blocks are still parsed and
 * checked, so a corrupt file is always reported. */
static int read_file(const char *path, size_t total, int first, int ncomp, const block *b,
                     double *const out[3], char *err)
{
    reader r = {fopen(path, "r"), path, 1};
    if (!r.f) {
        pst_set_err(err, "%s: cannot open: %s", path, strerror(errno));
        return PST_EIO;
    }
    int st = PST_OK;
    size_t n = 0, line = 0;
    for (;;) {
        double v;
        int got = next_value(&r, &v, &line, err);
        if (got < 0) {
            st = got;
            break;
        }
        if (got == 0) {
            if (n < total) { /* named at the last value's line: where the file stops */
                pst_set_err(err, "%s:%zu: too few values: expected %zu, found %zu", path,
                            n ? line : r.line, total, n);
                st = PST_EINPUT;
            }
            break;
        }
        if (n == total) {
            pst_set_err(err, "%s:%zu: too many values: expected %zu", path, line, total);
            st = PST_EINPUT;
            break;
        }
        int comp = (int)(n / SPE10_LAYER) - first;
        size_t m = n % SPE10_LAYER;
        int i = (int)(m % SPE10_NX) - b->i0, j = (int)(m / SPE10_NX) - b->j0;
        if (comp >= 0 && comp < ncomp && i >= 0 && i < b->ni && j >= 0 && j < b->nj)
            out[comp][i + (size_t)b->ni * (size_t)j] = v;
        ++n;
    }
    fclose(r.f);
    return st;
}

/* 1 when the last path component of `path` is `name`. */
static int has_basename(const char *path, const char *name)
{
    const char *slash = strrchr(path, '/');
    return strcmp(slash ? slash + 1 : path, name) == 0;
}

/* `path` with its last component replaced by `name` (malloc'd; NULL on OOM). */
static char *sibling(const char *path, const char *name)
{
    const char *slash = strrchr(path, '/');
    size_t dirlen = slash ? (size_t)(slash - path) + 1 : 0;
    char *s = malloc(dirlen + strlen(name) + 1);
    if (s) {
        memcpy(s, path, dirlen);
        strcpy(s + dirlen, name);
    }
    return s;
}

void pst_perm_grid_free(pst_perm_grid *g)
{
    if (!g)
        return;
    for (int c = 0; c < 3; ++c)
        pst_free(g->k[c]);
    memset(g, 0, sizeof *g);
}

int pst_spe10_read(pst_perm_grid *g, const char *path, int layer, int i0, int j0, int ni,
                   int nj, char *err)
{
    if (!g || !path) {
        pst_set_err(err, "spe10: grid and path must not be NULL");
        return PST_EINVAL;
    }
    memset(g, 0, sizeof *g);
    int geos = has_basename(path, "permx.geos"), tarbert = has_basename(path, "perm.txt");
    if (!geos && !tarbert) {
        pst_set_err(err, "%s: unknown SPE10 file (expected a GEOS 'permx.geos' or the RTSPHEM "
                         "'perm.txt')",
                    path);
        return PST_EINVAL;
    }
    if (geos && layer != 84 && layer != 85) {
        pst_set_err(err, "%s: the GEOS files hold layers 84 and 85 only (got layer %d)", path,
                    layer);
        return PST_EINVAL;
    }
    if (tarbert && layer != 0) {
        pst_set_err(err, "%s: the Tarbert file holds one layer, pass layer 0 (got %d)", path,
                    layer);
        return PST_EINVAL;
    }
    /* Written so that no sum can overflow an int. */
    if (i0 < 0 || j0 < 0 || ni < 1 || nj < 1 || i0 > SPE10_NX - ni || j0 > SPE10_NY - nj) {
        pst_set_err(err, "%s: sub-block i in [%d, %d+%d), j in [%d, %d+%d) is not inside the "
                         "%dx%d layer",
                    path, i0, i0, ni, j0, j0, nj, SPE10_NX, SPE10_NY);
        return PST_EINVAL;
    }
    size_t cells = (size_t)ni * (size_t)nj;
    for (int c = 0; c < 3; ++c)
        if (!(g->k[c] = pst_alloc(cells * sizeof(double)))) {
            pst_perm_grid_free(g);
            pst_set_err(err, "%s: out of memory for a %dx%d grid", path, ni, nj);
            return PST_ENOMEM;
        }
    block b = {i0, j0, ni, nj};
    int st = PST_OK;
    if (tarbert) {
        st = read_file(path, 3 * (size_t)SPE10_LAYER, 0, 3, &b, g->k, err);
    } else {
        /* One component per file, both layers in each: block 0 is layer 84, block 1 is 85. */
        static const char *const names[3] = {"permx.geos", "permy.geos", "permz.geos"};
        for (int c = 0; st == PST_OK && c < 3; ++c) {
            char *p = sibling(path, names[c]);
            if (!p) {
                pst_set_err(err, "%s: out of memory", path);
                st = PST_ENOMEM;
                break;
            }
            double *const out[3] = {g->k[c], NULL, NULL};
            st = read_file(p, 2 * (size_t)SPE10_LAYER, layer - 84, 1, &b, out, err);
            free(p);
        }
    }
    if (st != PST_OK) {
        pst_perm_grid_free(g);
        return st;
    }
    g->nx = ni;
    g->ny = nj;
    g->nz = 1;
    g->dx = SPE10_DX;
    g->dy = SPE10_DY;
    g->dz = SPE10_DZ;
    return PST_OK;
}

/* ---- grid to cloud ------------------------------------------------------------------------- */

/* The cell along one axis: floor of the scaled offset, clamped to [0, n). */
static size_t cell_of(double x, double origin, double width, int n)
{
    double t = floor((x - origin) / width);
    if (!(t > 0)) /* also catches NaN, which the caller has already excluded */
        return 0;
    if (t >= (double)n)
        return (size_t)n - 1;
    return (size_t)t;
}

int pst_cloud_mobility_from_grid(pst_cloud *c, const pst_perm_grid *g, const double origin[3],
                                 const double scale[3], int diagonal, char *err)
{
    static const char axis[] = "xyz";
    if (!c || !g) {
        pst_set_err(err, "mobility from grid: cloud and grid must not be NULL");
        return PST_EINVAL;
    }
    int dim = c->dim;
    const int nn[3] = {g->nx, g->ny, g->nz};
    const double d[3] = {g->dx, g->dy, g->dz};
    double o[3] = {0, 0, 0}, w[3] = {1, 1, 1};
    for (int a = 0; a < 3; ++a) {
        if (nn[a] < 1 || !(d[a] > 0) || !isfinite(d[a])) {
            pst_set_err(err, "mobility from grid: grid needs n >= 1 and a finite cell size > 0 "
                             "along %c (got n = %d, size %g)",
                        axis[a], nn[a], d[a]);
            return PST_EINVAL;
        }
        if (a >= dim)
            continue; /* a 2D cloud reads layer 0: origin[2], scale[2] are not used */
        double s = scale ? scale[a] : 1.0;
        o[a] = origin ? origin[a] : 0.0;
        w[a] = d[a] * s;
        if (!isfinite(o[a]) || !(s > 0) || !isfinite(w[a]) || !(w[a] > 0)) {
            pst_set_err(err, "mobility from grid: origin %g and scale %g along %c must be "
                             "finite, the scale > 0",
                        o[a], s, axis[a]);
            return PST_EINVAL;
        }
    }
    int ncomp = diagonal ? dim : 1;
    for (int k = 0; k < ncomp; ++k)
        if (!g->k[k]) {
            pst_set_err(err, "mobility from grid: the grid has no K%c component", axis[k]);
            return PST_EINVAL;
        }
    size_t n = c->n;
    /* Check the positions before touching the mobility, so a failure leaves the cloud as is. */
    for (size_t p = 0; p < n; ++p)
        for (int a = 0; a < dim; ++a)
            if (!isfinite(c->x[a][p])) {
                pst_set_err(err, "mobility from grid: particle %zu (id %lld) has a non-finite "
                                 "%c coordinate",
                            p, (long long)c->id[p], axis[a]);
                return PST_EINPUT;
            }
    int st = pst_cloud_set_mobility(c, ncomp, NULL);
    if (st != PST_OK) {
        pst_set_err(err, "mobility from grid: out of memory for %d mobility components", ncomp);
        return st;
    }
    size_t nx = (size_t)g->nx, nxy = nx * (size_t)g->ny;
#pragma omp parallel for schedule(static)
    for (size_t p = 0; p < n; ++p) {
        size_t cell = cell_of(c->x[0][p], o[0], w[0], g->nx) +
                      nx * cell_of(c->x[1][p], o[1], w[1], g->ny);
        if (dim == 3)
            cell += nxy * cell_of(c->x[2][p], o[2], w[2], g->nz);
        for (int k = 0; k < ncomp; ++k)
            c->mob[k][p] = g->k[k][cell];
    }
    return PST_OK;
}
