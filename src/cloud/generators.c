/* Cloud generators: the jittered node lattice (choice 4, the QSFDI paper's §3.1) and the
 * Lukyanov–Vuik cell-centred layout with face particles (LV §5.1). Every particle is computed
 * from its own index alone (position, jitter from the counter-based RNG, kind, normal), so the
 * parallel fill gives the same bits for every thread count. Formulas: docs/clouds.md. */
#include "cloud_layout.h"
#include "check.h"

#include <math.h>

/* A validated description of the lattice, shared by both layouts. */
typedef struct {
    int dim;
    uint32_t n[3];          /* spacings (cells) per axis                          */
    double lo[3], hi[3];
    double s0, jitter;
    uint64_t seed;
    int boundary_layer;
    int periodic[3];        /* periodic axes: no hi end, no faces, positions folded */
    int rotate;             /* angle != 0: rotating by 0 would still round        */
    double centre[2], cosa, sina;
} grid;

static const char axis_name[] = "xyz";

static int setup_grid(grid *g, const pst_lattice_opts *o, const char *who, char *err)
{
    PST_CHECK(!o, PST_EINVAL, err, "%s: no options given", who);
    PST_CHECK(o->dim != 2 && o->dim != 3, PST_EINVAL, err, "%s: dim must be 2 or 3 (got %d)", who,
              o->dim);
    PST_CHECK(!(o->s0 > 0) || !isfinite(o->s0), PST_EINVAL, err,
              "%s: spacing s0 must be finite and > 0 (got %g)", who, o->s0);
    PST_CHECK(!(o->jitter >= 0) || !isfinite(o->jitter), PST_EINVAL, err,
              "%s: jitter K must be finite and >= 0 (got %g)", who, o->jitter);
    PST_CHECK(!(o->h_ratio > 0) || !isfinite(o->h_ratio * o->s0), PST_EINVAL, err,
              "%s: h_ratio must be > 0 with h = h_ratio*s0 finite (got %g)", who, o->h_ratio);
    PST_CHECK(!isfinite(o->angle), PST_EINVAL, err, "%s: rotation angle must be finite (got %g)",
              who, o->angle);
    PST_CHECK(o->boundary_layer != 0 && o->boundary_layer != 1, PST_EINVAL, err,
              "%s: boundary_layer must be 0 or 1 (got %d)", who, o->boundary_layer);
    int periodic = 0;
    for (int d = 0; d < 3; ++d) {
        g->periodic[d] = d < o->dim && o->periodic[d] != 0;
        periodic |= g->periodic[d];
    }
    PST_CHECK(periodic && o->angle != 0, PST_EINVAL, err,
              "%s: a periodic box cannot be rotated (angle %g): its axes are the box's", who,
              o->angle);
    g->dim = o->dim;
    for (int d = 0; d < o->dim; ++d) {
        double lo = o->lo[d], hi = o->hi[d];
        PST_CHECK(!isfinite(lo) || !isfinite(hi) || !(hi > lo), PST_EINVAL, err,
                  "%s: box along %c must be finite with hi > lo (got [%g, %g])", who, axis_name[d],
                  lo, hi);
        double r = (hi - lo) / o->s0;
        PST_CHECK(!(r <= (double)UINT32_MAX), PST_EINVAL, err,
                  "%s: box along %c is %g spacings, too many", who, axis_name[d], r);
        double rn = round(r);
        PST_CHECK(rn < 1 || fabs(r - rn) > 1e-9 * r, PST_EINVAL, err,
                  "%s: box length along %c (%.17g) is not a whole number of spacings s0 = %.17g "
                  "(ratio %.17g)",
                  who, axis_name[d], hi - lo, o->s0, r);
        g->n[d] = (uint32_t)rn;
        g->lo[d] = lo;
        g->hi[d] = hi;
    }
    g->s0 = o->s0;
    g->jitter = o->jitter;
    g->seed = o->seed;
    g->boundary_layer = o->boundary_layer;
    g->rotate = o->angle != 0;
    g->centre[0] = 0.5 * (o->lo[0] + o->hi[0]);
    g->centre[1] = 0.5 * (o->lo[1] + o->hi[1]);
    g->cosa = cos(o->angle);
    g->sina = sin(o->angle);
    return PST_OK;
}

/* Multiply counts, failing (0) above the 32-bit particle-index limit. */
static int mul_count(uint64_t *acc, uint64_t f)
{
    if (f != 0 && *acc > (uint64_t)UINT32_MAX / f)
        return 0;
    *acc *= f;
    return 1;
}

/* Create the cloud and set the properties common to every particle. */
static int make_cloud(pst_cloud **out, const grid *g, uint64_t count, const pst_lattice_opts *o,
                      const char *who, char *err)
{
    PST_CHECK(count > UINT32_MAX, PST_EINVAL, err,
              "%s: more than %lu particles (the 32-bit index limit)", who,
              (unsigned long)UINT32_MAX);
    int st = pst_cloud_create(out, g->dim, (size_t)count, NULL);
    PST_CHECK(st != PST_OK, st, err, "%s: cannot allocate a cloud of %llu particles", who,
              (unsigned long long)count);
    pst_cloud_set_h_uniform(*out, o->h_ratio * o->s0, NULL); /* finite and > 0: checked */
    return PST_OK;
}

/* Rotate a point about the box centre and a normal about the origin, in the x-y plane. */
static void rotate_xy(const grid *g, double x[3], double nrm[3])
{
    double dx = x[0] - g->centre[0], dy = x[1] - g->centre[1];
    x[0] = g->centre[0] + (g->cosa * dx - g->sina * dy);
    x[1] = g->centre[1] + (g->sina * dx + g->cosa * dy);
    double nx = nrm[0], ny = nrm[1];
    nrm[0] = g->cosa * nx - g->sina * ny;
    nrm[1] = g->sina * nx + g->cosa * ny;
}

static void jitter(const grid *g, uint64_t p, double x[3])
{
    for (int d = 0; d < g->dim; ++d)
        x[d] += g->jitter * pst_rng_symmetric(g->seed, p, (uint64_t)d) * g->s0;
}

static void store(pst_cloud *c, size_t p, const double x[3], const double nrm[3], int kind,
                  double V)
{
    for (int d = 0; d < c->dim; ++d) {
        c->x[d][p] = x[d];
        c->normal[d][p] = nrm[d];
    }
    c->kind[p] = (uint8_t)kind;
    c->V[p] = V;
}

static double cell_volume(const grid *g)
{
    return g->dim == 2 ? g->s0 * g->s0 : g->s0 * g->s0 * g->s0;
}

void pst_lattice_defaults(pst_lattice_opts *o)
{
    *o = (pst_lattice_opts){
        .dim = 2,
        .lo = {0, 0, 0},
        .hi = {1, 1, 1},
        .s0 = 0.1,
        .jitter = 0,
        .seed = 1,
        .boundary_layer = 0,
        .h_ratio = 1.2,
        .angle = 0,
    };
}

/* Particle p of a layout: its position, normal and kind, from p alone. */
typedef void (*point_fn)(const grid *g, size_t p, size_t ninterior, double x[3], double nrm[3],
                         int *kind);

/* Fill every particle of c, each from its own index (the same bits for every thread count). */
static void fill(pst_cloud *c, const grid *g, point_fn point, size_t ninterior)
{
    double V = cell_volume(g);
    size_t n = c->n;
#pragma omp parallel for schedule(static)
    for (size_t p = 0; p < n; ++p) {
        double x[3] = {0, 0, 0}, nrm[3] = {0, 0, 0};
        int kind;
        point(g, p, ninterior, x, nrm, &kind);
        store(c, p, x, nrm, kind, V);
    }
}

/* Nodes of the lattice along axis d: n_d + 1, or n_d on a periodic axis (hi is lo again). */
static size_t nodes(const grid *g, int d) { return (size_t)g->n[d] + !g->periodic[d]; }

/* Fold the periodic coordinates of x into [lo, hi) after a jitter (as pst_cloud_wrap). */
static void fold(const grid *g, double x[3])
{
    for (int d = 0; d < g->dim; ++d) {
        if (!g->periodic[d] || (x[d] >= g->lo[d] && x[d] < g->hi[d]))
            continue;
        double P = g->hi[d] - g->lo[d], t = x[d] - g->lo[d];
        double w = g->lo[d] + (t - P * floor(t / P));
        x[d] = w >= g->hi[d] || w < g->lo[d] ? g->lo[d] : w;
    }
}

/* Node p of the lattice, x fastest: p = i + m_x*(j + m_y*k), m_d = nodes(g, d). There are no
 * interior particles listed first, so ninterior is not used. */
static void lattice_point(const grid *g, size_t p, size_t ninterior, double x[3], double nrm[3],
                          int *kind)
{
    (void)ninterior;
    size_t rest = p;
    int faces = 0;
    for (int d = 0; d < g->dim; ++d) {
        size_t m = nodes(g, d), i = rest % m;
        rest /= m;
        /* the far node is hi itself, so a boundary layer lies exactly on the box */
        x[d] = i == g->n[d] ? g->hi[d] : g->lo[d] + (double)i * g->s0;
        nrm[d] = g->periodic[d] ? 0.0 : i == 0 ? -1.0 : i == g->n[d] ? 1.0 : 0.0;
        faces += nrm[d] != 0;
    }
    if (g->boundary_layer && faces > 0) {
        /* edges and corners: the normalised sum of the face normals (the bisector) */
        double scale = 1.0 / sqrt((double)faces);
        for (int d = 0; d < g->dim; ++d)
            nrm[d] *= scale;
        *kind = PST_DIRICHLET;
    } else {
        for (int d = 0; d < g->dim; ++d)
            nrm[d] = 0;
        jitter(g, p, x);
        fold(g, x);
        *kind = PST_INTERIOR;
    }
    if (g->rotate)
        rotate_xy(g, x, nrm);
}

/* The generated cloud gets the grid's periodic box. */
static void set_box(pst_cloud *c, const grid *g)
{
    pst_cloud_set_periodic(c, g->periodic, g->lo, g->hi, NULL); /* lo < hi: checked */
}

int pst_cloud_lattice(pst_cloud **out, const pst_lattice_opts *o, char *err)
{
    static const char who[] = "lattice";
    *out = NULL;
    grid g;
    PST_TRY(setup_grid(&g, o, who, err));
    uint64_t count = 1;
    int ok = 1;
    for (int d = 0; d < g.dim; ++d)
        ok = ok && mul_count(&count, (uint64_t)nodes(&g, d));
    pst_cloud *c;
    PST_TRY(make_cloud(&c, &g, ok ? count : UINT64_MAX, o, who, err));
    fill(c, &g, lattice_point, 0);
    set_box(c, &g);
    *out = c;
    return PST_OK;
}

/* Face particles on one face normal to axis (none on a periodic axis). */
static uint64_t face_size(const grid *g, int axis)
{
    if (g->periodic[axis])
        return 0;
    uint64_t s = 1;
    for (int e = 0; e < g->dim; ++e)
        if (e != axis)
            s *= g->n[e];
    return s;
}

/* Particle p of the cell-centred layout: first the n_x*n_y(*n_z) cell centres, x fastest;
 * then the face particles, face by face in the order x = lo, x = hi, y = lo, y = hi,
 * z = lo, z = hi, each face's cells with the lower remaining axis fastest. */
static void cell_point(const grid *g, size_t p, size_t ninterior, double x[3], double nrm[3],
                       int *kind)
{
    if (p < ninterior) {
        size_t rest = p;
        for (int d = 0; d < g->dim; ++d) {
            size_t i = rest % g->n[d];
            rest /= g->n[d];
            x[d] = g->lo[d] + ((double)i + 0.5) * g->s0;
            nrm[d] = 0;
        }
        jitter(g, p, x);
        fold(g, x);
        *kind = PST_INTERIOR;
    } else {
        size_t q = p - ninterior;
        int face = 0;
        while (q >= face_size(g, face / 2))
            q -= face_size(g, face++ / 2);
        int axis = face / 2, high = face % 2;
        for (int d = 0; d < g->dim; ++d) {
            nrm[d] = 0;
            if (d == axis)
                continue;
            size_t i = q % g->n[d];
            q /= g->n[d];
            x[d] = g->lo[d] + ((double)i + 0.5) * g->s0;
        }
        x[axis] = high ? g->hi[axis] : g->lo[axis];
        nrm[axis] = high ? 1.0 : -1.0;
        *kind = PST_DIRICHLET;
    }
    if (g->rotate)
        rotate_xy(g, x, nrm);
}

int pst_cloud_cell_centred(pst_cloud **out, const pst_lattice_opts *o, char *err)
{
    static const char who[] = "cell-centred layout";
    *out = NULL;
    grid g;
    PST_TRY(setup_grid(&g, o, who, err));
    uint64_t ninterior = 1, count;
    int ok = 1;
    for (int d = 0; d < g.dim; ++d)
        ok = ok && mul_count(&ninterior, g.n[d]);
    count = ninterior;
    for (int d = 0; ok && d < g.dim; ++d) {
        uint64_t f = 2;
        ok = mul_count(&f, face_size(&g, d));
        count += f; /* at most 7 terms <= UINT32_MAX: no wrap */
    }
    pst_cloud *c;
    PST_TRY(make_cloud(&c, &g, ok ? count : UINT64_MAX, o, who, err));
    fill(c, &g, cell_point, (size_t)ninterior);
    set_box(c, &g);
    *out = c;
    return PST_OK;
}
