/* SPE10 model 2 permeability: reading one 60x220 layer (GEOS voxel files or the RTSPHEM
 * Tarbert text, layouts in docs/spe10.md, provenance in data/spe10/README.md) into a
 * Cartesian grid, and setting a cloud's mobility from the grid cell under each particle. */
#include "cloud_layout.h"
#include "check.h"

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
        PST_CHECK(ferror(r->f), PST_EIO, err, "%s:%zu: read error: %s", r->path, r->line,
                  strerror(errno));
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
    PST_CHECK(too_long, PST_EINPUT, err, "%s:%zu: token '%.20s...' is too long to be a number",
              r->path, *line, tok);
    char *end;
    double x = strtod(tok, &end); /* ERANGE on tiny values is fine: positivity decides */
    PST_CHECK(*end, PST_EINPUT, err, "%s:%zu: cannot parse '%s' as a number", r->path, *line, tok);
    PST_CHECK(!isfinite(x), PST_EINPUT, err, "%s:%zu: permeability '%s' is not finite", r->path,
              *line, tok);
    PST_CHECK(!(x > 0), PST_EINPUT, err, "%s:%zu: permeability %.17g must be > 0", r->path, *line,
              x);
    *v = x;
    return 1;
}

/* The sub-block being read: where a value of the file goes. */
typedef struct {
    int i0, j0, ni, nj;
} block;

/* Where the file's values go: component block `first + k` to out[k] for k < ncomp, restricted
 * to the sub-block. */
typedef struct {
    const block *b;
    int first, ncomp;
    double *const *out;
} target;

/* Read the values of an open file, exactly `total` of them. */
static int read_values(reader *r, size_t total, const target *t, char *err)
{
    size_t n = 0, line = 0;
    for (;;) {
        double v;
        int got = next_value(r, &v, &line, err);
        if (got <= 0) {
            PST_TRY(got);
            break;
        }
        PST_CHECK(n == total, PST_EINPUT, err, "%s:%zu: too many values: expected %zu", r->path,
                  line, total);
        int comp = (int)(n / SPE10_LAYER) - t->first;
        size_t m = n % SPE10_LAYER;
        int i = (int)(m % SPE10_NX) - t->b->i0, j = (int)(m / SPE10_NX) - t->b->j0;
        if (comp >= 0 && comp < t->ncomp && i >= 0 && i < t->b->ni && j >= 0 && j < t->b->nj)
            t->out[comp][i + (size_t)t->b->ni * (size_t)j] = v;
        ++n;
    }
    /* named at the last value's line: where the file stops */
    PST_CHECK(n < total, PST_EINPUT, err, "%s:%zu: too few values: expected %zu, found %zu",
              r->path, n ? line : r->line, total, n);
    return PST_OK;
}

/* Read a whole file of exactly `total` values laid out as consecutive components of
 * SPE10_LAYER values each (i fastest, then j) into t; the blocks t does not keep are still
 * parsed and checked, so a corrupt file is always reported. */
static int read_file(const char *path, size_t total, const target *t, char *err)
{
    reader r = {fopen(path, "r"), path, 1};
    PST_CHECK(!r.f, PST_EIO, err, "%s: cannot open: %s", path, strerror(errno));
    int st = read_values(&r, total, t, err);
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

/* The three components of the GEOS files next to `path`: one component per file, both layers
 * in each (block 0 is layer 84, block 1 is 85). */
static int read_geos(const char *path, int layer, const block *b, double *const k[3], char *err)
{
    static const char *const names[3] = {"permx.geos", "permy.geos", "permz.geos"};
    for (int c = 0; c < 3; ++c) {
        char *p = sibling(path, names[c]);
        PST_CHECK_ALLOC(p, err, "%s: out of memory", path);
        const target t = {b, layer - 84, 1, &k[c]};
        int st = read_file(p, 2 * (size_t)SPE10_LAYER, &t, err);
        free(p);
        PST_TRY(st);
    }
    return PST_OK;
}

/* Allocate g's arrays for the sub-block b and read the file(s) into them; on failure the caller
 * frees what g holds. */
static int load(pst_perm_grid *g, const char *path, int tarbert, int layer, const block *b,
                char *err)
{
    size_t cells = (size_t)b->ni * (size_t)b->nj;
    for (int c = 0; c < 3; ++c) {
        g->k[c] = pst_alloc(cells * sizeof(double));
        PST_CHECK_ALLOC(g->k[c], err, "%s: out of memory for a %dx%d grid", path, b->ni, b->nj);
    }
    const target all = {b, 0, 3, g->k};
    PST_TRY(tarbert ? read_file(path, 3 * (size_t)SPE10_LAYER, &all, err)
                    : read_geos(path, layer, b, g->k, err));
    g->nx = b->ni;
    g->ny = b->nj;
    g->nz = 1;
    g->dx = SPE10_DX;
    g->dy = SPE10_DY;
    g->dz = SPE10_DZ;
    return PST_OK;
}

int pst_spe10_read(pst_perm_grid *g, const char *path, int layer, int i0, int j0, int ni,
                   int nj, char *err)
{
    PST_CHECK(!g || !path, PST_EINVAL, err, "spe10: grid and path must not be NULL");
    memset(g, 0, sizeof *g);
    int geos = has_basename(path, "permx.geos"), tarbert = has_basename(path, "perm.txt");
    PST_CHECK(!geos && !tarbert, PST_EINVAL, err,
              "%s: unknown SPE10 file (expected a GEOS 'permx.geos' or the RTSPHEM 'perm.txt')",
              path);
    PST_CHECK(geos && layer != 84 && layer != 85, PST_EINVAL, err,
              "%s: the GEOS files hold layers 84 and 85 only (got layer %d)", path, layer);
    PST_CHECK(tarbert && layer != 0, PST_EINVAL, err,
              "%s: the Tarbert file holds one layer, pass layer 0 (got %d)", path, layer);
    /* Written so that no sum can overflow an int. */
    PST_CHECK(i0 < 0 || j0 < 0 || ni < 1 || nj < 1 || i0 > SPE10_NX - ni || j0 > SPE10_NY - nj,
              PST_EINVAL, err,
              "%s: sub-block i in [%d, %d+%d), j in [%d, %d+%d) is not inside the %dx%d layer",
              path, i0, i0, ni, j0, j0, nj, SPE10_NX, SPE10_NY);
    int st = load(g, path, tarbert, layer, &(block){i0, j0, ni, nj}, err);
    if (st != PST_OK)
        pst_perm_grid_free(g); /* a failure leaves g empty */
    return st;
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
    PST_CHECK(!c || !g, PST_EINVAL, err, "mobility from grid: cloud and grid must not be NULL");
    int dim = c->dim;
    const int nn[3] = {g->nx, g->ny, g->nz};
    const double d[3] = {g->dx, g->dy, g->dz};
    double o[3] = {0, 0, 0}, w[3] = {1, 1, 1};
    for (int a = 0; a < 3; ++a) {
        PST_CHECK(nn[a] < 1 || !(d[a] > 0) || !isfinite(d[a]), PST_EINVAL, err,
                  "mobility from grid: grid needs n >= 1 and a finite cell size > 0 along %c (got "
                  "n = %d, size %g)",
                  axis[a], nn[a], d[a]);
        if (a >= dim)
            continue; /* a 2D cloud reads layer 0: origin[2], scale[2] are not used */
        double s = scale ? scale[a] : 1.0;
        o[a] = origin ? origin[a] : 0.0;
        w[a] = d[a] * s;
        PST_CHECK(!isfinite(o[a]) || !(s > 0) || !isfinite(w[a]) || !(w[a] > 0), PST_EINVAL,
                  err, "mobility from grid: origin %g and scale %g along %c must be finite, "
                  "the scale > 0", o[a], s, axis[a]);
    }
    int ncomp = diagonal ? dim : 1;
    for (int k = 0; k < ncomp; ++k)
        PST_CHECK(!g->k[k], PST_EINVAL, err, "mobility from grid: the grid has no K%c component",
                  axis[k]);
    size_t n = c->n;
    /* Check the positions before touching the mobility, so a failure leaves the cloud as is. */
    for (size_t p = 0; p < n; ++p)
        for (int a = 0; a < dim; ++a)
            PST_CHECK(!isfinite(c->x[a][p]), PST_EINPUT, err,
                      "mobility from grid: particle %zu (id %lld) has a non-finite %c coordinate",
                      p, (long long)c->id[p], axis[a]);
    int st = pst_cloud_set_mobility(c, ncomp, NULL);
    PST_CHECK(st != PST_OK, st, err, "mobility from grid: out of memory for %d mobility components",
              ncomp);
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
