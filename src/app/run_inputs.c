/* The inputs of a run: the cloud, the mobility and the fields, and the expressions they are
 * written in, evaluated at the particles or at points. */
#include "run_state.h"

#include "pstencil_expr.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Evaluate expression `text` (scene key `key`) at n positions cols[d][k] into out[]. Its
 * variables are the coordinates x, y (and z in 3D), and t when r->time is set. A non-finite
 * value is an error naming the particle (by its input id, when ids is given) or the point. */
static int eval_columns(run_state *r, const char *key, const char *text,
                        const double *const cols[3], size_t n, const int64_t *ids, double *out)
{
    const char *vars[4] = {"x", "y", "z", "t"};
    const double *columns[4] = {cols[0], cols[1], cols[2], NULL};
    int dim = r->s->dim, nvars = dim + (r->time != NULL);
    double *tcol = NULL;
    if (r->time) { /* the expression reads t as one more column */
        vars[dim] = "t";
        if (!(tcol = malloc((n ? n : 1) * sizeof *tcol)))
            return run_fail(r, PST_ENOMEM, "out of memory for %s", key);
        for (size_t k = 0; k < n; ++k)
            tcol[k] = *r->time;
        columns[dim] = tcol;
    }
    char msg[PST_ERRLEN];
    pst_expr *e = pst_expr_parse(text, vars, nvars, msg, sizeof msg);
    if (!e) {
        free(tcol);
        return run_fail(r, PST_EINPUT, "%s: %s: %s", r->s->path, key, msg);
    }
    pst_expr_eval_many(e, n, columns, out);
    pst_expr_free(e);
    free(tcol);
    for (size_t k = 0; k < n; ++k)
        if (!isfinite(out[k]))
            return run_fail(r, PST_EINPUT, "%s: %s: '%s' is not finite at %s %lld", r->s->path, key,
                            text, ids ? "particle (input order)" : "point",
                            ids ? (long long)ids[k] : (long long)k);
    return PST_OK;
}

int run_eval_at_particles(run_state *r, const char *key, const char *text, double *out)
{
    const double *cols[3] = {NULL, NULL, NULL};
    for (int d = 0; d < r->s->dim; ++d)
        cols[d] = pst_cloud_coord_const(r->c, d);
    return eval_columns(r, key, text, cols, pst_cloud_size(r->c), pst_cloud_ids_const(r->c),
                        out);
}

int run_eval_at_points(run_state *r, const char *key, const char *text, double *const pts[3],
                       size_t m, double *out)
{
    const double *cols[3] = {pts[0], pts[1], pts[2]};
    return eval_columns(r, key, text, cols, m, NULL, out);
}

/* cloud.h_ratio on a file cloud: h = h_ratio s0 with s0 the scene's cloud.spacing when it is
 * given, else each particle's own spacing V_i^(1/D) (uniform h when the volumes are). */
static int set_file_h(pst_cloud *c, const sc_cloud *sc, char *msg)
{
    if (sc->spacing_set)
        return pst_cloud_set_h_uniform(c, sc->h_ratio * sc->spacing, NULL);
    size_t n = pst_cloud_size(c);
    const double *V = pst_cloud_volume_const(c);
    int same = 1;
    for (size_t i = 1; i < n && same; ++i)
        same = V[i] == V[0];
    double e = 1.0 / pst_cloud_dim(c);
    if (same)
        return n ? pst_cloud_set_h_uniform(c, sc->h_ratio * pow(V[0], e), NULL) : PST_OK;
    double *h = pst_cloud_h_per_particle(c);
    if (!h) {
        snprintf(msg, PST_ERRLEN, "out of memory for the h of %zu particles", n);
        return PST_ENOMEM;
    }
    for (size_t i = 0; i < n; ++i)
        h[i] = sc->h_ratio * pow(V[i], e);
    return PST_OK;
}

/* cloud.box on a file cloud: its periodic axes, and every particle inside the box along
 * them (the files record no box; a particle outside is refused here, naming the scene key,
 * rather than folded in silently). */
static int file_box(run_state *r)
{
    const pst_scene *s = r->s;
    char msg[PST_ERRLEN];
    int st = pst_cloud_set_periodic(r->c, s->cloud.periodic, s->cloud.box_lo, s->cloud.box_hi,
                                    msg);
    if (st == PST_OK)
        st = pst_cloud_validate(r->c, msg);
    if (st != PST_OK)
        return run_fail(r, st, "%s: cloud.box: %s", s->path, msg);
    return PST_OK;
}

int run_make_cloud(run_state *r)
{
    const pst_scene *s = r->s;
    const sc_cloud *sc = &s->cloud;
    char msg[PST_ERRLEN];
    int st;
    if (sc->source == SC_CLOUD_FILE) {
        st = pst_cloud_read(&r->c, sc->file, msg); /* the reader by the extension */
        if (st == PST_OK && pst_cloud_size(r->c) == 0) /* as apply, stencil and neighbours */
            return run_fail(r, PST_EINPUT, "%s: cloud.file %s: the cloud has no particles",
                            s->path, sc->file);
        if (st == PST_OK && pst_cloud_dim(r->c) != s->dim)
            return run_fail(r, PST_EINPUT, "%s: cloud.file %s is %dD, the scene is %dD", s->path,
                            sc->file, pst_cloud_dim(r->c), s->dim);
        if (st == PST_OK && sc->h_ratio_set)
            st = set_file_h(r->c, sc, msg);
        if (st == PST_OK && pst_scene_periodic_axes(s))
            return file_box(r);
    } else {
        pst_lattice_opts lo;
        pst_lattice_defaults(&lo);
        lo.dim = s->dim;
        for (int d = 0; d < 3; ++d) {
            lo.lo[d] = sc->lo[d];
            lo.hi[d] = sc->hi[d];
        }
        lo.s0 = sc->spacing;
        lo.jitter = sc->jitter;
        lo.seed = (uint64_t)sc->seed;
        lo.boundary_layer = sc->boundary_layer;
        lo.h_ratio = sc->h_ratio;
        lo.angle = sc->angle * (3.14159265358979323846 / 180.0);
        for (int d = 0; d < 3; ++d)
            lo.periodic[d] = sc->periodic[d];
        st = sc->source == SC_CLOUD_LATTICE ? pst_cloud_lattice(&r->c, &lo, msg)
                                            : pst_cloud_cell_centred(&r->c, &lo, msg);
    }
    if (st != PST_OK)
        return run_fail(r, st, "%s: cloud: %s", s->path, msg);
    return PST_OK;
}

/* The mobility arrays the plan asks for (none for a constant: it is a factor). */
int run_make_mobility(run_state *r)
{
    const pst_scene *s = r->s;
    const sc_mobility *m = &s->mobility;
    int ncomp = r->plan.mobility_ncomp;
    if (!ncomp)
        return PST_OK;
    char msg[PST_ERRLEN];
    if (m->type == SC_MOB_SPE10) {
        /* One permeability cell per spacing of the cloud, from the scene's first cell on. */
        int cells[2];
        for (int d = 0; d < 2; ++d)
            cells[d] = (int)lround((s->cloud.hi[d] - s->cloud.lo[d]) / s->cloud.spacing);
        pst_perm_grid g;
        int st = pst_spe10_read(&g, m->file, m->layer, m->i0, m->j0, cells[0], cells[1], msg);
        if (st != PST_OK)
            return run_fail(r, st, "%s: mobility.file: %s", s->path, msg);
        double scale[3] = {s->cloud.spacing / g.dx, s->cloud.spacing / g.dy,
                           s->cloud.spacing / g.dz};
        st = pst_cloud_mobility_from_grid(r->c, &g, s->cloud.lo, scale, 1, msg);
        pst_perm_grid_free(&g);
        if (st != PST_OK)
            return run_fail(r, st, "%s: mobility: %s", s->path, msg);
    } else {
        if (pst_cloud_set_mobility(r->c, ncomp, NULL) != PST_OK)
            return run_fail(r, PST_ENOMEM, "out of memory for the mobility");
        for (int a = 0; a < ncomp; ++a) {
            char key[64];
            snprintf(key, sizeof key,
                     ncomp == 1 ? "mobility.expression" : "mobility.expression[%d]", a);
            double *mob = pst_cloud_mobility(r->c, a);
            int st = run_eval_at_particles(r, key, m->expr[a], mob);
            if (st != PST_OK)
                return st;
            size_t n = pst_cloud_size(r->c);
            for (size_t i = 0; i < n; ++i)
                if (!(mob[i] > 0))
                    return run_fail(r, PST_EINPUT,
                                    "%s: %s: the mobility must be positive, got %g "
                                    "at particle %lld (input order)",
                                    s->path, key, mob[i], (long long)pst_cloud_ids_const(r->c)[i]);
        }
    }
    r->cnt.mobility_arrays += ncomp;
    return PST_OK;
}

int run_make_fields(run_state *r)
{
    for (int f = 0; f < r->s->nfields; ++f) {
        double *data;
        char key[96], why[PST_ERRLEN];
        snprintf(key, sizeof key, "fields.%s", r->s->fields[f].name);
        if (pst_cloud_add_field(r->c, r->s->fields[f].name, &data, why) != PST_OK)
            return run_fail(r, PST_EINPUT, "%s: %s: %s", r->s->path, key, why);
        int st = run_eval_at_particles(r, key, r->s->fields[f].expr, data);
        if (st != PST_OK)
            return st;
        r->cnt.fields++;
    }
    return PST_OK;
}
