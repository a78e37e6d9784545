/* The scene runner (docs/running.md): cloud, mobility, fields, neighbours, operators, tasks,
 * error norms and outputs, in that order, doing only what the plan says. Every step that
 * computes something increments its counter, which is how the tests check that a run did not
 * compute what its scene did not ask for. */
#include "run.h"

#include "pstencil.h"
#include "pstencil_expr.h"
#include "progress.h"
#include "report.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <omp.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

typedef struct {
    const pst_scene *s;
    const pst_run_opts *o;
    pst_plan plan;
    pst_run_counters cnt;
    pst_cloud *c;
    pst_nlist *nl;
    pst_op *base;
    cJSON *report, *tasks;
    int solve_failed;
    char *err;
    size_t errlen;
} run_state;

static int fail(run_state *r, int status, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static int fail(run_state *r, int status, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(r->err, r->errlen, fmt, ap);
    va_end(ap);
    return status;
}

/* ---- expressions ------------------------------------------------------------------------- */

/* Evaluate expression `text` (scene key `key`) at n positions cols[d][k] into out[]. Its
 * variables are the coordinates x, y (and z in 3D). A non-finite value is an error naming the
 * particle (by its input id, when ids is given) or the point. */
static int eval_columns(run_state *r, const char *key, const char *text,
                        const double *const cols[3], size_t n, const int64_t *ids, double *out)
{
    static const char *const vars[] = {"x", "y", "z"};
    char msg[PST_ERRLEN];
    pst_expr *e = pst_expr_parse(text, vars, r->s->dim, msg, sizeof msg);
    if (!e)
        return fail(r, PST_EINPUT, "%s: %s: %s", r->s->path, key, msg);
    pst_expr_eval_many(e, n, cols, out);
    pst_expr_free(e);
    for (size_t k = 0; k < n; ++k)
        if (!isfinite(out[k]))
            return fail(r, PST_EINPUT, "%s: %s: '%s' is not finite at %s %lld", r->s->path, key,
                        text, ids ? "particle (input order)" : "point",
                        ids ? (long long)ids[k] : (long long)k);
    return PST_OK;
}

static int eval_at_particles(run_state *r, const char *key, const char *text, double *out)
{
    const double *cols[3] = {NULL, NULL, NULL};
    for (int d = 0; d < r->s->dim; ++d)
        cols[d] = pst_cloud_coord_const(r->c, d);
    return eval_columns(r, key, text, cols, pst_cloud_size(r->c), pst_cloud_ids_const(r->c),
                        out);
}

static int eval_at_points(run_state *r, const char *key, const char *text, double *const pts[3],
                          size_t m, double *out)
{
    const double *cols[3] = {pts[0], pts[1], pts[2]};
    return eval_columns(r, key, text, cols, m, NULL, out);
}

/* ---- cloud ------------------------------------------------------------------------------- */

static int make_cloud(run_state *r)
{
    const pst_scene *s = r->s;
    const sc_cloud *sc = &s->cloud;
    char msg[PST_ERRLEN];
    int st;
    if (sc->source == SC_CLOUD_FILE) {
        size_t len = strlen(sc->file);
        int vtu = len > 4 && strcmp(sc->file + len - 4, ".vtu") == 0;
        st = vtu ? pst_cloud_read_vtu(&r->c, sc->file, msg)
                 : pst_cloud_read_csv(&r->c, sc->file, msg);
        if (st == PST_OK && pst_cloud_dim(r->c) != s->dim)
            return fail(r, PST_EINPUT, "%s: cloud.file %s is %dD, the scene is %dD", s->path,
                        sc->file, pst_cloud_dim(r->c), s->dim);
        if (st == PST_OK && sc->h_ratio_set)
            st = pst_cloud_set_h_uniform(r->c, sc->h_ratio * sc->spacing, NULL);
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
        st = sc->source == SC_CLOUD_LATTICE ? pst_cloud_lattice(&r->c, &lo, msg)
                                            : pst_cloud_cell_centred(&r->c, &lo, msg);
    }
    if (st != PST_OK)
        return fail(r, st, "%s: cloud: %s", s->path, msg);
    return PST_OK;
}

/* The mobility arrays the plan asks for (none for a constant: it is a factor). */
static int make_mobility(run_state *r)
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
            return fail(r, st, "%s: mobility.file: %s", s->path, msg);
        double scale[3] = {s->cloud.spacing / g.dx, s->cloud.spacing / g.dy,
                           s->cloud.spacing / g.dz};
        st = pst_cloud_mobility_from_grid(r->c, &g, s->cloud.lo, scale, 1, msg);
        pst_perm_grid_free(&g);
        if (st != PST_OK)
            return fail(r, st, "%s: mobility: %s", s->path, msg);
    } else {
        if (pst_cloud_set_mobility(r->c, ncomp, NULL) != PST_OK)
            return fail(r, PST_ENOMEM, "out of memory for the mobility");
        for (int a = 0; a < ncomp; ++a) {
            char key[64];
            snprintf(key, sizeof key, ncomp == 1 ? "mobility.expression" : "mobility.expression[%d]",
                     a);
            double *mob = pst_cloud_mobility(r->c, a);
            int st = eval_at_particles(r, key, m->expr[a], mob);
            if (st != PST_OK)
                return st;
            size_t n = pst_cloud_size(r->c);
            for (size_t i = 0; i < n; ++i)
                if (!(mob[i] > 0))
                    return fail(r, PST_EINPUT, "%s: %s: the mobility must be positive, got %g "
                                               "at particle %lld (input order)",
                                s->path, key, mob[i], (long long)pst_cloud_ids_const(r->c)[i]);
        }
    }
    r->cnt.mobility_arrays += ncomp;
    return PST_OK;
}

static int make_fields(run_state *r)
{
    for (int f = 0; f < r->s->nfields; ++f) {
        double *data;
        char key[96], why[PST_ERRLEN];
        snprintf(key, sizeof key, "fields.%s", r->s->fields[f].name);
        if (pst_cloud_add_field(r->c, r->s->fields[f].name, &data, why) != PST_OK)
            return fail(r, PST_EINPUT, "%s: %s: %s", r->s->path, key, why);
        int st = eval_at_particles(r, key, r->s->fields[f].expr, data);
        if (st != PST_OK)
            return st;
        r->cnt.fields++;
    }
    return PST_OK;
}

/* ---- operators --------------------------------------------------------------------------- */

void pst_scene_op_opts(const pst_scene *s, pst_op_opts *oo)
{
    pst_op_defaults(oo);
    oo->scheme = s->op.scheme;
    oo->kernel = s->op.kernel;
    if (s->op.gradient)
        oo->gradient = s->op.gradient;
    oo->variant = s->op.variant;
    oo->cond_max = s->op.cond_max;
    oo->rank_tol = s->op.rank_tol;
    oo->min_pair_distance = s->op.min_pair_distance;
    oo->on_degenerate = s->op.on_degenerate;
    oo->mobility_mean = s->op.mobility_mean;
}

static int make_operator(run_state *r, int laplacian, pst_op **op)
{
    pst_op_opts oo;
    pst_scene_op_opts(r->s, &oo);
    oo.laplacian = laplacian;
    char msg[PST_ERRLEN];
    cli_progress pg;
    progress_begin(&pg, !r->o->quiet, "precompute");
    int st = pst_op_create(op, r->c, r->nl, &oo, msg);
    progress_end(&pg);
    if (st != PST_OK)
        return fail(r, st, "%s: operator %s: %s", r->s->path, oo.scheme, msg);
    if (laplacian)
        r->cnt.laplacian_precomputes++;
    else
        r->cnt.derivative_operators++;
    report_operator(r->report, *op);
    return PST_OK;
}

/* ---- error norms ------------------------------------------------------------------------- */

/* The particles of a task's region: interior particles, all, or those inside a box. */
static uint8_t *region_mask(run_state *r, const sc_task *t)
{
    size_t n = pst_cloud_size(r->c);
    uint8_t *mask = malloc(n ? n : 1);
    if (!mask)
        return NULL;
    const uint8_t *kind = pst_cloud_kinds_const(r->c);
    for (size_t i = 0; i < n; ++i) {
        if (t->region == SC_REGION_ALL) {
            mask[i] = 1;
        } else if (t->region == SC_REGION_INTERIOR) {
            mask[i] = kind[i] == PST_INTERIOR;
        } else {
            mask[i] = 1;
            for (int d = 0; d < r->s->dim; ++d) {
                double x = pst_cloud_coord_const(r->c, d)[i];
                mask[i] &= x >= t->region_lo[d] && x <= t->region_hi[d];
            }
        }
    }
    return mask;
}

/* Evaluate the task's exact expressions and its norms of approx against them; the norms go
 * into the task's report object. `pts` non-NULL: values at m points instead of particles. */
static int task_norms(run_state *r, int k, cJSON *tj, int ncomp, double *const *approx,
                      double *const pts[3], size_t m)
{
    const sc_task *t = &r->s->tasks[k];
    if (!t->nexact || !t->nnorms)
        return PST_OK;
    if (t->nexact != ncomp)
        return fail(r, PST_EINPUT, "%s: tasks[%d].exact: %d expressions for a result with %d "
                                   "components", r->s->path, k, t->nexact, ncomp);
    size_t n = pts ? m : pst_cloud_size(r->c);
    double *exact[6] = {NULL};
    uint8_t *mask = pts ? NULL : region_mask(r, t);
    int st = PST_OK;
    for (int a = 0; a < ncomp && st == PST_OK; ++a) {
        char key[64];
        snprintf(key, sizeof key, ncomp == 1 ? "tasks[%d].exact" : "tasks[%d].exact[%d]", k, a);
        exact[a] = malloc((n ? n : 1) * sizeof(double));
        if (!exact[a])
            st = fail(r, PST_ENOMEM, "out of memory for the exact values");
        else
            st = pts ? eval_at_points(r, key, t->exact[a], pts, m, exact[a])
                     : eval_at_particles(r, key, t->exact[a], exact[a]);
    }
    cJSON *norms = cJSON_AddObjectToObject(tj, "norms");
    for (int q = 0; q < t->nnorms && st == PST_OK; ++q) {
        double v;
        char msg[PST_ERRLEN];
        const double *const *ap = (const double *const *)approx;
        const double *const *ex = (const double *const *)exact;
        if (pts) {
            st = pst_error_norm_points(n, ncomp, ap, ex, t->norms[q], &v, msg);
        } else {
            st = pst_error_norm(r->c, ncomp, ap, ex, mask, t->norms[q], &v, msg);
        }
        if (st != PST_OK) {
            st = fail(r, st, "%s: task '%s': %s", r->s->path, t->name, msg);
            break;
        }
        cJSON_AddNumberToObject(norms, pst_norm_name(t->norms[q]), v);
        r->cnt.norms++;
    }
    for (int a = 0; a < ncomp; ++a)
        free(exact[a]);
    free(mask);
    return st;
}

/* ---- tasks ------------------------------------------------------------------------------- */

/* Output fields of a task: `name` for one component, name_x.. / name_xx.. for more. */
static int add_outputs(run_state *r, const sc_task *t, int ncomp, double *out[6])
{
    static const char *const grad[] = {"x", "y", "z"};
    static const char *const hess2[] = {"xx", "yy", "xy"};
    static const char *const hess3[] = {"xx", "yy", "zz", "xy", "xz", "yz"};
    for (int a = 0; a < ncomp; ++a) {
        char name[PST_MAX_NAME];
        if (ncomp == 1)
            snprintf(name, sizeof name, "%s", t->name);
        else
            snprintf(name, sizeof name, "%s_%s", t->name,
                     t->type == SC_TASK_GRADIENT ? grad[a]
                     : ncomp == 3                ? hess2[a]
                                                 : hess3[a]);
        char why[PST_ERRLEN];
        if (pst_cloud_add_field(r->c, name, &out[a], why) != PST_OK)
            return fail(r, PST_EINPUT, "%s: task '%s': output field %s: %s", r->s->path,
                        t->name, name, why);
    }
    return PST_OK;
}

static const double *input_field(run_state *r, const sc_task *t)
{
    return pst_cloud_field_by_name(r->c, t->field);
}

static int run_estimate(run_state *r, int k, cJSON *tj)
{
    const sc_task *t = &r->s->tasks[k];
    const int dim = r->s->dim;
    int ncomp = t->type == SC_TASK_GRADIENT ? dim
                : t->type == SC_TASK_HESSIAN ? (dim == 2 ? 3 : 6)
                                             : 1;
    double *out[6] = {NULL};
    int st = add_outputs(r, t, ncomp, out);
    if (st != PST_OK)
        return st;
    const double *u = input_field(r, t);
    double t0 = omp_get_wtime();
    if (t->type == SC_TASK_GRADIENT) {
        st = pst_op_gradient(r->base, u, out);
        r->cnt.gradients++;
    } else if (t->type == SC_TASK_HESSIAN) {
        st = pst_op_hessian(r->base, u, out);
        r->cnt.hessians++;
    } else {
        st = pst_op_apply(r->base, u, out[0]);
        r->cnt.applies++;
        size_t n = pst_cloud_size(r->c);
        const uint8_t *kind = pst_cloud_kinds_const(r->c);
        for (size_t i = 0; i < n; ++i) /* boundary rows are not estimates (docs/running.md) */
            out[0][i] = kind[i] == PST_INTERIOR ? r->plan.mobility_factor * out[0][i] : 0.0;
    }
    cJSON_AddNumberToObject(tj, "seconds", omp_get_wtime() - t0);
    if (st != PST_OK)
        return fail(r, st, "%s: task '%s': the scheme cannot compute it", r->s->path, t->name);
    return task_norms(r, k, tj, ncomp, out, NULL, 0);
}

/* A whole token as a finite number. */
static int parse_number(const char *tok, double *v)
{
    char *end;
    *v = strtod(tok, &end);
    return end != tok && *end == '\0' && isfinite(*v);
}

/* The x, y[, z] columns of a CSV file (any other columns are ignored) into pts[d][k]. */
static int read_points_csv(run_state *r, const char *path, double *pts[3], size_t *m)
{
    FILE *f = fopen(path, "r");
    if (!f)
        return fail(r, PST_EIO, "%s: cannot open the points file", path);
    char line[4096];
    int col[3] = {-1, -1, -1}, ncols = 0, st = PST_OK;
    if (fgets(line, sizeof line, f)) {
        for (char *tok = strtok(line, ",\r\n"); tok; tok = strtok(NULL, ",\r\n"), ++ncols)
            for (int d = 0; d < 3; ++d)
                if (strcmp(tok, (const char *[]){"x", "y", "z"}[d]) == 0)
                    col[d] = ncols;
    }
    for (int d = 0; d < r->s->dim && st == PST_OK; ++d)
        if (col[d] < 0)
            st = fail(r, PST_EINPUT, "%s:1: the header has no column '%c'", path, "xyz"[d]);
    size_t cap = 1024, n = 0;
    for (int d = 0; d < 3 && st == PST_OK; ++d)
        if (!(pts[d] = calloc(cap, sizeof(double))))
            st = fail(r, PST_ENOMEM, "out of memory for the points");
    for (long lineno = 2; st == PST_OK && fgets(line, sizeof line, f); ++lineno) {
        if (line[strspn(line, " \r\n")] == '\0')
            continue;
        if (n == cap) {
            cap *= 2;
            for (int d = 0; d < 3 && st == PST_OK; ++d) {
                double *grown = realloc(pts[d], cap * sizeof(double));
                if (!grown)
                    st = fail(r, PST_ENOMEM, "out of memory for the points");
                else
                    pts[d] = grown;
            }
        }
        int c = 0;
        for (char *tok = strtok(line, ",\r\n"); tok && st == PST_OK; tok = strtok(NULL, ",\r\n"), ++c)
            for (int d = 0; d < r->s->dim; ++d)
                if (c == col[d] && !parse_number(tok, &pts[d][n]))
                    st = fail(r, PST_EINPUT, "%s:%ld: column %c: '%s' is not a finite number",
                              path, lineno, "xyz"[d], tok);
        if (st == PST_OK && c != ncols)
            st = fail(r, PST_EINPUT, "%s:%ld: %d columns, the header has %d", path, lineno, c,
                      ncols);
        ++n;
    }
    fclose(f);
    *m = n;
    return st;
}

/* The points of an interpolation task: the x, y[, z] columns of a CSV, or a lattice box. */
static int task_points(run_state *r, const sc_task *t, double *pts[3], size_t *m)
{
    if (t->points_file)
        return read_points_csv(r, t->points_file, pts, m);
    pst_lattice_opts lo;
    pst_lattice_defaults(&lo);
    lo.dim = r->s->dim;
    for (int d = 0; d < 3; ++d) {
        lo.lo[d] = t->points_lo[d];
        lo.hi[d] = t->points_hi[d];
    }
    lo.s0 = t->points_spacing;
    pst_cloud *pc = NULL;
    char msg[PST_ERRLEN];
    int st = pst_cloud_lattice(&pc, &lo, msg);
    if (st != PST_OK)
        return fail(r, st, "%s: task '%s': points: %s", r->s->path, t->name, msg);
    *m = pst_cloud_size(pc);
    for (int d = 0; d < 3; ++d) {
        pts[d] = malloc((*m ? *m : 1) * sizeof(double));
        for (size_t q = 0; pts[d] && q < *m; ++q)
            pts[d][q] = d < r->s->dim ? pst_cloud_coord_const(pc, d)[q] : 0.0;
    }
    pst_cloud_destroy(pc);
    if (!pts[0] || !pts[1] || !pts[2])
        return fail(r, PST_ENOMEM, "out of memory for %zu points", *m);
    return PST_OK;
}

static int run_interpolate(run_state *r, int k, cJSON *tj)
{
    const sc_task *t = &r->s->tasks[k];
    double *pts[3] = {NULL, NULL, NULL}, *value = NULL, *lap = NULL;
    size_t m = 0, fallbacks = 0;
    int st = task_points(r, t, pts, &m);
    if (st == PST_OK) {
        value = malloc((m ? m : 1) * sizeof *value);
        lap = malloc((m ? m : 1) * sizeof *lap);
        if (!value || !lap)
            st = fail(r, PST_ENOMEM, "out of memory for %zu points", m);
    }
    if (st == PST_OK) {
        char msg[PST_ERRLEN];
        double t0 = omp_get_wtime();
        st = pst_op_interpolate(r->base, (const double *const *)pts, m, input_field(r, t),
                                value, lap, &fallbacks, msg);
        cJSON_AddNumberToObject(tj, "seconds", omp_get_wtime() - t0);
        r->cnt.interpolations++;
        if (st != PST_OK)
            st = fail(r, st, "%s: task '%s': %s", r->s->path, t->name, msg);
    }
    if (st == PST_OK) {
        cJSON_AddNumberToObject(tj, "points", (double)m);
        cJSON_AddNumberToObject(tj, "fallback_points", (double)fallbacks);
        st = task_norms(r, k, tj, 1, &value, pts, m);
    }
    if (st == PST_OK && r->s->out.csv)
        st = report_write_points(r->s->out.csv, t->name, r->s->dim, pts, m, value, lap, r->err,
                                 r->errlen);
    if (st == PST_OK && r->s->out.csv)
        r->cnt.files++;
    for (int d = 0; d < 3; ++d)
        free(pts[d]);
    free(value);
    free(lap);
    return st;
}

/* ---- solves ------------------------------------------------------------------------------ */

/* The box side a boundary particle lies on (the nearest face of the cloud's box). */
static sc_side nearest_side(run_state *r, size_t i)
{
    double best = INFINITY;
    sc_side side = SC_SIDE_ALL;
    for (int d = 0; d < r->s->dim; ++d) {
        double x = pst_cloud_coord_const(r->c, d)[i];
        double dl = fabs(x - r->s->cloud.lo[d]), dh = fabs(r->s->cloud.hi[d] - x);
        if (dl < best) {
            best = dl;
            side = (sc_side)(SC_SIDE_XLO + 2 * d);
        }
        if (dh < best) {
            best = dh;
            side = (sc_side)(SC_SIDE_XHI + 2 * d);
        }
    }
    return side;
}

typedef struct {
    cli_progress *pg;
    double rtol;
} monitor_ctx;

static void solve_monitor(int it, double rel, void *ctx)
{
    monitor_ctx *m = ctx;
    char detail[96];
    snprintf(detail, sizeof detail, "iteration %d, residual %.2e", it, rel);
    double frac = rel > 0 && rel < 1 ? log(rel) / log(m->rtol) : 0;
    progress_update(m->pg, frac > 1 ? 1 : frac, detail);
}

/* Boundary kinds of a solve task: each boundary particle takes the first group containing its
 * nearest box side (or "all"); claim[i] becomes that group's kind (-1: in no group). Neumann
 * particles get the side's outward normal unless the cloud gave them one and the group is
 * "all". b gets the group values (fluxes divided by a constant mobility's factor). */
static int apply_groups(run_state *r, int k, double *b, int8_t *claim)
{
    const sc_task *t = &r->s->tasks[k];
    const int dim = r->s->dim;
    size_t n = pst_cloud_size(r->c);
    uint8_t *kind = pst_cloud_kinds(r->c);
    memset(claim, -1, n);
    double *vals = malloc((n ? n : 1) * sizeof *vals);
    if (!vals)
        return fail(r, PST_ENOMEM, "out of memory for boundary values");
    int st = PST_OK;
    for (int g = 0; g < t->ngroups && st == PST_OK; ++g) {
        const sc_group *gr = &t->groups[g];
        char key[64];
        snprintf(key, sizeof key, "tasks[%d].boundary[%d].value", k, g);
        st = eval_at_particles(r, key, gr->value, vals);
        for (size_t i = 0; i < n && st == PST_OK; ++i) {
            if (kind[i] == PST_INTERIOR || claim[i] >= 0)
                continue;
            sc_side side = nearest_side(r, i);
            if (gr->where != SC_SIDE_ALL && gr->where != side)
                continue;
            claim[i] = (int8_t)(gr->neumann ? PST_NEUMANN : PST_DIRICHLET);
            b[i] = gr->neumann ? vals[i] / r->plan.mobility_factor : vals[i];
            if (!gr->neumann)
                continue;
            double len = 0;
            for (int d = 0; d < dim; ++d)
                len += pst_cloud_normal(r->c, d)[i] * pst_cloud_normal(r->c, d)[i];
            if (len == 0 || gr->where != SC_SIDE_ALL) {
                int axis = (side - SC_SIDE_XLO) / 2, high = (side - SC_SIDE_XLO) % 2;
                for (int d = 0; d < dim; ++d)
                    pst_cloud_normal(r->c, d)[i] = d == axis ? (high ? 1.0 : -1.0) : 0.0;
            }
        }
    }
    free(vals);
    for (size_t i = 0; i < n; ++i)
        if (claim[i] >= 0)
            kind[i] = (uint8_t)claim[i];
    return st;
}

static void save_kinds(run_state *r, uint8_t *kind_saved, double *const normal_saved[3])
{
    size_t n = pst_cloud_size(r->c);
    memcpy(kind_saved, pst_cloud_kinds(r->c), n);
    for (int d = 0; d < r->s->dim; ++d)
        memcpy(normal_saved[d], pst_cloud_normal(r->c, d), n * sizeof(double));
}

static void restore_kinds(run_state *r, const uint8_t *kind_saved, double *const normal_saved[3])
{
    size_t n = pst_cloud_size(r->c);
    memcpy(pst_cloud_kinds(r->c), kind_saved, n);
    for (int d = 0; d < r->s->dim; ++d)
        memcpy(pst_cloud_normal(r->c, d), normal_saved[d], n * sizeof(double));
}

static int run_solve(run_state *r, int k, cJSON *tj)
{
    const sc_task *t = &r->s->tasks[k];
    size_t n = pst_cloud_size(r->c);
    double *u[6] = {NULL}, *b = calloc(n ? n : 1, sizeof *b), *ue = NULL;
    uint8_t *kind_saved = malloc(n ? n : 1);
    double *normal_saved[3] = {NULL, NULL, NULL};
    for (int d = 0; d < r->s->dim; ++d)
        normal_saved[d] = malloc((n ? n : 1) * sizeof(double));
    if (!b || !kind_saved || !normal_saved[0] || !normal_saved[1] ||
        (r->s->dim == 3 && !normal_saved[2])) {
        free(b);
        free(kind_saved);
        for (int d = 0; d < 3; ++d)
            free(normal_saved[d]);
        return fail(r, PST_ENOMEM, "out of memory for the right-hand side");
    }
    int st = add_outputs(r, t, 1, u);
    char key[64];
    snprintf(key, sizeof key, "tasks[%d].rhs", k);
    if (st == PST_OK)
        st = eval_at_particles(r, key, t->rhs, b);
    for (size_t i = 0; st == PST_OK && i < n; ++i)
        b[i] /= r->plan.mobility_factor;
    if (st == PST_OK && t->exact[0]) {
        ue = malloc(n * sizeof *ue);
        snprintf(key, sizeof key, "tasks[%d].exact", k);
        st = ue ? eval_at_particles(r, key, t->exact[0], ue) : PST_ENOMEM;
    }
    int grouped = t->ngroups > 0;
    int8_t *claim = grouped ? malloc(n ? n : 1) : NULL;
    if (st == PST_OK && grouped && !claim)
        st = fail(r, PST_ENOMEM, "out of memory for the boundary groups");
    int saved = 0; /* the cloud's own kinds and normals, restored after a grouped solve */
    if (st == PST_OK && grouped) {
        save_kinds(r, kind_saved, normal_saved);
        saved = 1;
        st = apply_groups(r, k, b, claim);
    }
    /* Boundary particles no group claimed keep their kind and the exact solution's value. */
    const uint8_t *kind = pst_cloud_kinds_const(r->c);
    for (size_t i = 0; st == PST_OK && i < n; ++i) {
        if (kind[i] == PST_INTERIOR || (claim && claim[i] >= 0))
            continue;
        if (kind[i] == PST_NEUMANN)
            st = fail(r, PST_EINPUT, "%s: task '%s': the cloud's Neumann particles need a "
                                     "boundary group with their flux", r->s->path, t->name);
        else if (!ue)
            st = fail(r, PST_EINPUT, "%s: task '%s': boundary particles outside every "
                                     "boundary group take the exact solution, which is not "
                                     "given (tasks[%d].exact)", r->s->path, t->name, k);
        else
            b[i] = ue[i];
    }
    free(claim);
    pst_op *op = r->base;
    if (st == PST_OK && grouped)
        st = make_operator(r, 1, &op);
    if (st == PST_OK && r->plan.task_stored[k]) {
        st = pst_op_store(op);
        r->cnt.stored_weights++;
        if (st != PST_OK)
            st = fail(r, st, "%s: task '%s': cannot store the operator's weights", r->s->path,
                      t->name);
    }
    if (st == PST_OK) {
        pst_solve_opts so;
        pst_solve_defaults(&so);
        so.solver = r->plan.task_solver[k];
        so.precond = t->precond;
        so.amg_source = t->amg_source;
        so.restart = t->restart;
        so.max_iter = t->max_iter;
        so.rtol = t->rtol;
        so.stored = r->plan.task_stored[k];
        so.history = 1;
        cli_progress pg;
        monitor_ctx mc = {&pg, t->rtol};
        so.monitor = solve_monitor;
        so.monitor_ctx = &mc;
        pst_solve_result res;
        char msg[PST_ERRLEN];
        progress_begin(&pg, !r->o->quiet, "solve");
        int ss = pst_solve(op, b, u[0], &so, &res, msg);
        progress_end(&pg);
        r->cnt.solves++;
        report_solve(tj, &res);
        cJSON_AddNumberToObject(tj, "seconds", res.seconds);
        pst_solve_result_free(&res);
        if (ss == PST_ENUMERIC) {
            r->solve_failed = 1; /* outputs are still written, marked in the report */
            snprintf(r->err, r->errlen, "%s: task '%s': %s", r->s->path, t->name, msg);
        } else if (ss != PST_OK) {
            st = fail(r, ss, "%s: task '%s': %s", r->s->path, t->name, msg);
        }
    }
    if (op != r->base)
        pst_op_destroy(op);
    if (saved)
        restore_kinds(r, kind_saved, normal_saved);
    if (st == PST_OK)
        st = task_norms(r, k, tj, 1, u, NULL, 0);
    free(b);
    free(ue);
    free(kind_saved);
    for (int d = 0; d < 3; ++d)
        free(normal_saved[d]);
    return st;
}

/* ---- the run ----------------------------------------------------------------------------- */

/* User + system CPU time of the process: with the wall-clock total it shows the parallel
 * efficiency of a run. */
static double cpu_seconds(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return (double)(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) +
           1e-6 * (double)(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
}

static int run_tasks(run_state *r)
{
    const pst_scene *s = r->s;
    if (r->plan.base_operator) {
        int st = make_operator(r, r->plan.base_laplacian, &r->base);
        if (st != PST_OK)
            return st;
    }
    for (int k = 0; k < s->ntasks; ++k) {
        cJSON *tj = cJSON_CreateObject();
        cJSON_AddItemToArray(r->tasks, tj);
        report_task_header(tj, &s->tasks[k]);
        int st;
        switch (s->tasks[k].type) {
        case SC_TASK_INTERPOLATE: st = run_interpolate(r, k, tj); break;
        case SC_TASK_SOLVE: st = run_solve(r, k, tj); break;
        default: st = run_estimate(r, k, tj); break;
        }
        if (st != PST_OK)
            return st;
    }
    return PST_OK;
}

static int build(run_state *r)
{
    const pst_scene *s = r->s;
    double t0 = omp_get_wtime();
    int st = make_cloud(r);
    size_t n = r->c ? pst_cloud_size(r->c) : 0;
    if (st == PST_OK && s->cloud.source == SC_CLOUD_FILE)
        st = pst_plan_make(&r->plan, s, n, r->err, r->errlen); /* now with the true count */
    if (st == PST_OK)
        st = make_mobility(r);
    if (st == PST_OK)
        st = make_fields(r);
    double t1 = omp_get_wtime();
    report_timer(r->report, "cloud", t1 - t0);
    if (st != PST_OK || !r->plan.need_neighbours)
        return st;
    char msg[PST_ERRLEN];
    cli_progress pg;
    progress_begin(&pg, !r->o->quiet, "neighbours");
    double cell = r->plan.support * pst_cloud_h_max(r->c);
    st = pst_cloud_morton_sort(r->c, cell, NULL);
    if (st == PST_OK)
        st = pst_nlist_build(&r->nl, r->c, r->plan.support, msg);
    else
        snprintf(msg, sizeof msg, "Morton sort: %s", pst_strerror(st));
    progress_end(&pg);
    if (st != PST_OK)
        return fail(r, st, "%s: neighbours: %s", s->path, msg);
    r->cnt.neighbour_lists++;
    report_timer(r->report, "neighbours", omp_get_wtime() - t1);
    return PST_OK;
}

int pst_run_scene(const pst_scene *s, const pst_run_opts *o, pst_plan *plan,
                  pst_run_counters *counters, pst_cloud **cloud, char *err, size_t errlen)
{
    run_state r = {.s = s, .o = o, .err = err, .errlen = errlen};
    err[0] = '\0';
    if (o->report)
        *o->report = NULL;
    if (cloud)
        *cloud = NULL;
    int st = pst_plan_make(&r.plan, s, pst_plan_particles(s), err, errlen);
    if (st == PST_OK && o->plan_only) {
        pst_plan_print(stdout, &r.plan, s);
        if (plan)
            *plan = r.plan;
        return PST_OK;
    }
    r.report = report_begin(s);
    r.tasks = cJSON_AddArrayToObject(r.report, "tasks");
    double t0 = omp_get_wtime(), cpu0 = cpu_seconds();
    if (st == PST_OK)
        st = build(&r);
    if (st == PST_OK)
        st = run_tasks(&r);
    if (st == PST_OK) {
        report_timer(r.report, "total", omp_get_wtime() - t0);
        report_timer(r.report, "cpu", cpu_seconds() - cpu0);
        report_peak_memory(r.report);
        report_finish(r.report, &r.plan, &r.cnt, r.c);
        st = report_write_outputs(s, r.c, r.base, r.report, &r.cnt, err, errlen);
    }
    if (st == PST_OK && !o->quiet)
        report_summary(stdout, r.report);
    if (st == PST_OK && r.solve_failed)
        st = PST_ENUMERIC; /* err holds the solver's message */
    if (plan)
        *plan = r.plan;
    if (counters)
        *counters = r.cnt;
    if (o->report && (st == PST_OK || (st == PST_ENUMERIC && r.solve_failed)))
        *o->report = r.report;
    else
        cJSON_Delete(r.report);
    pst_op_destroy(r.base);
    pst_nlist_destroy(r.nl);
    if (cloud && (st == PST_OK || (st == PST_ENUMERIC && r.solve_failed)))
        *cloud = r.c;
    else
        pst_cloud_destroy(r.c);
    return st;
}

/* The boundary kinds (and Neumann normals) of the scene's first solve task with boundary
 * groups, so that the operator is the one that task solves with; no such task: the cloud's
 * own kinds. */
static int solve_boundary_kinds(run_state *r)
{
    for (int k = 0; k < r->s->ntasks; ++k) {
        if (r->s->tasks[k].type != SC_TASK_SOLVE || r->s->tasks[k].ngroups == 0)
            continue;
        size_t n = pst_cloud_size(r->c);
        double *b = calloc(n ? n : 1, sizeof *b);
        int8_t *claim = malloc(n ? n : 1);
        int st = b && claim ? apply_groups(r, k, b, claim)
                            : fail(r, PST_ENOMEM, "out of memory for the boundary groups");
        free(b);
        free(claim);
        return st;
    }
    return PST_OK;
}

int pst_run_build_operator(const pst_scene *s, int quiet, size_t max_unknowns, pst_cloud **cloud,
                           pst_nlist **nl, pst_op **op, char *err, size_t errlen)
{
    pst_run_opts o = {.quiet = quiet};
    run_state r = {.s = s, .o = &o, .err = err, .errlen = errlen};
    err[0] = '\0';
    *cloud = NULL;
    *nl = NULL;
    *op = NULL;
    int st = pst_plan_make(&r.plan, s, pst_plan_particles(s), err, errlen);
    r.report = report_begin(s);
    r.plan.need_neighbours = 1;
    if (st == PST_OK)
        st = build(&r);
    if (st == PST_OK && !r.nl)
        st = fail(&r, PST_EINPUT, "%s: no task of the scene uses the operator", s->path);
    if (st == PST_OK)
        st = solve_boundary_kinds(&r);
    if (st == PST_OK && max_unknowns) {
        size_t n = pst_cloud_size(r.c), m = 0;
        const uint8_t *kind = pst_cloud_kinds_const(r.c);
        for (size_t i = 0; i < n; ++i)
            m += kind[i] != PST_DIRICHLET;
        if (m > max_unknowns)
            st = fail(&r, PST_EINPUT, "%s: %zu unknowns (interior and Neumann particles), more "
                                      "than %zu: use a coarser cloud.spacing", s->path, m,
                      max_unknowns);
    }
    if (st == PST_OK)
        st = make_operator(&r, 1, &r.base);
    cJSON_Delete(r.report);
    if (st != PST_OK) {
        pst_op_destroy(r.base);
        pst_nlist_destroy(r.nl);
        pst_cloud_destroy(r.c);
        return st;
    }
    *cloud = r.c;
    *nl = r.nl;
    *op = r.base;
    return PST_OK;
}
