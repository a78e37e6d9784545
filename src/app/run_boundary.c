/* The boundary groups of a solve task (docs/boundaries.md): which particles each group claims,
 * with what kind, value and normal. The result is a boundary of its own (run_boundary) that the
 * solve's operator reads, so the cloud, which the base operator reads, keeps its kinds and
 * normals; the solve's own kinds and normals go to the outputs as fields. */
#include "run_state.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* What a group did, for the report. */
typedef struct {
    size_t claimed, from_file, from_face, estimated, degenerate;
} group_count;

/* The box side a particle lies nearest to (of the cloud's box; a periodic axis has none). */
static sc_side nearest_side(run_state *r, size_t i)
{
    double best = INFINITY;
    sc_side side = SC_SIDE_ALL;
    for (int d = 0; d < r->s->dim; ++d) {
        if (r->s->cloud.periodic[d])
            continue;
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

/* A copy of the cloud's kinds and normals. */
static int boundary_copy(run_state *r, run_boundary *bnd)
{
    size_t n = pst_cloud_size(r->c);
    bnd->kind = malloc(n ? n : 1);
    for (int d = 0; d < r->s->dim; ++d)
        bnd->normal[d] = malloc((n ? n : 1) * sizeof(double));
    if (!bnd->kind || !bnd->normal[0] || !bnd->normal[1] || (r->s->dim == 3 && !bnd->normal[2]))
        return run_fail(r, PST_ENOMEM, "out of memory for the boundary groups");
    memcpy(bnd->kind, pst_cloud_kinds_const(r->c), n);
    for (int d = 0; d < r->s->dim; ++d)
        memcpy(bnd->normal[d], pst_cloud_normal_const(r->c, d), n * sizeof(double));
    return PST_OK;
}

static int kind_matches(sc_group_kind want, uint8_t kind)
{
    switch (want) {
    case SC_GKIND_BOUNDARY: return kind != PST_INTERIOR;
    case SC_GKIND_DIRICHLET: return kind == PST_DIRICHLET;
    case SC_GKIND_NEUMANN: return kind == PST_NEUMANN;
    case SC_GKIND_INTERIOR: return kind == PST_INTERIOR;
    case SC_GKIND_ANY: return 1;
    }
    return 0;
}

/* Particle i inside the group's region (`level`: the region expression's values). */
static int in_region(run_state *r, const sc_shape *sh, const double *level, size_t i)
{
    double dot = 0, r2 = 0;
    int in = 1;
    for (int d = 0; d < r->s->dim; ++d) {
        double x = pst_cloud_coord_const(r->c, d)[i], dx = x - sh->a[d];
        in &= sh->type != SC_SHAPE_BOX || (x >= sh->a[d] && x <= sh->b[d]);
        r2 += dx * dx;
        dot += dx * sh->b[d];
    }
    switch (sh->type) {
    case SC_SHAPE_NONE: return 1;
    case SC_SHAPE_BOX: return in;
    case SC_SHAPE_SPHERE: return sqrt(r2) <= sh->radius;
    case SC_SHAPE_HALF_SPACE: return dot >= 0;
    case SC_SHAPE_EXPR: return level[i] > 0;
    }
    return 0;
}

/* The outward normal of box side `side` into particle i's normal (zero for no side: a cloud
 * periodic along every axis has none, and the operator refuses the Neumann row). */
static void face_normal(run_state *r, sc_side side, run_boundary *bnd, size_t i)
{
    int axis = side == SC_SIDE_ALL ? -1 : ((int)side - SC_SIDE_XLO) / 2;
    int high = ((int)side - SC_SIDE_XLO) % 2;
    for (int d = 0; d < r->s->dim; ++d)
        bnd->normal[d][i] = d == axis ? (high ? 1.0 : -1.0) : 0.0;
}

/* Group g's claims: each particle no earlier group took that every selector of the group
 * matches. A Neumann particle's normal: the cloud's (its nearest face's when it has none),
 * the face's, or left for the estimate (pick[i] = 1). */
static void claim_group(run_state *r, const sc_group *gr, const double *vals,
                        const double *level, double *b, int8_t *claim, uint8_t *pick,
                        run_boundary *bnd, group_count *cnt)
{
    size_t n = pst_cloud_size(r->c);
    const uint8_t *kind = pst_cloud_kinds_const(r->c);
    for (size_t i = 0; i < n; ++i) {
        if (claim[i] >= 0 || !kind_matches(gr->kind, kind[i]))
            continue;
        sc_side side = nearest_side(r, i);
        if ((gr->where != SC_SIDE_ALL && gr->where != side) || !in_region(r, &gr->region, level, i))
            continue;
        claim[i] = (int8_t)(gr->neumann ? PST_NEUMANN : PST_DIRICHLET);
        bnd->kind[i] = (uint8_t)claim[i];
        b[i] = gr->neumann ? vals[i] / r->plan.mobility_factor : vals[i];
        cnt->claimed++;
        if (!gr->neumann)
            continue;
        double len = 0;
        for (int d = 0; d < r->s->dim; ++d)
            len += bnd->normal[d][i] * bnd->normal[d][i];
        if (gr->normals == SC_NORMALS_ESTIMATE) {
            pick[i] = 1;
            cnt->estimated++;
        } else if (gr->normals == SC_NORMALS_FACE || len == 0) {
            face_normal(r, gr->where != SC_SIDE_ALL ? gr->where : side, bnd, i);
            cnt->from_face++;
        } else
            cnt->from_file++;
    }
}

/* The normals the group asked to estimate (pick[i] = 1), into bnd; a degenerate estimate
 * (not on a surface, docs/boundaries.md) falls back to the particle's nearest face. */
static int estimate_normals(run_state *r, const uint8_t *pick, run_boundary *bnd,
                            group_count *cnt)
{
    char msg[PST_ERRLEN];
    if (r->dist)
        return run_fail(r, PST_EINPUT, "%s: boundary normals: estimated normals need the whole "
                        "cloud's neighbour list, which a run over several ranks does not build: "
                        "give the normals in the cloud file or take the box faces' "
                        "(docs/distributed.md)", r->s->path);
    int st = pst_normals_estimate(r->c, r->nl, (pst_kernel)r->plan.kernel, pick, bnd->normal,
                                  &cnt->degenerate, msg);
    if (st != PST_OK)
        return run_fail(r, st, "%s: boundary normals: %s", r->s->path, msg);
    size_t n = pst_cloud_size(r->c);
    for (size_t i = 0; i < n && cnt->degenerate; ++i) {
        double len = 0;
        for (int d = 0; d < r->s->dim; ++d)
            len += bnd->normal[d][i] * bnd->normal[d][i];
        if (pick[i] && len == 0)
            face_normal(r, nearest_side(r, i), bnd, i);
    }
    return PST_OK;
}

/* The report's line for group g: its type, the particles it claimed and their normals. */
static void report_group(cJSON *list, const sc_group *gr, const group_count *cnt)
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "type", gr->neumann ? "neumann" : "dirichlet");
    cJSON_AddNumberToObject(o, "particles", (double)cnt->claimed);
    if (gr->neumann) {
        cJSON *nm = cJSON_AddObjectToObject(o, "normals");
        cJSON_AddNumberToObject(nm, "file", (double)cnt->from_file);
        cJSON_AddNumberToObject(nm, "face", (double)cnt->from_face);
        cJSON_AddNumberToObject(nm, "estimated", (double)cnt->estimated);
        cJSON_AddNumberToObject(nm, "degenerate", (double)cnt->degenerate);
    }
    cJSON_AddItemToArray(list, o);
}

/* Values of group g's value expression and region expression at the particles. */
static int group_values(run_state *r, int k, int g, double *vals, double *level)
{
    const sc_group *gr = &r->s->tasks[k].groups[g];
    char key[64];
    snprintf(key, sizeof key, "tasks[%d].boundary[%d].value", k, g);
    int st = run_eval_at_particles(r, key, gr->value, vals);
    snprintf(key, sizeof key, "tasks[%d].boundary[%d].region.expr", k, g);
    if (st == PST_OK && gr->region.type == SC_SHAPE_EXPR)
        st = run_eval_at_particles(r, key, gr->region.expr, level);
    return st;
}

int run_boundary_make(run_state *r, int k, double *b, int8_t *claim, run_boundary *bnd,
                      cJSON *tj)
{
    const sc_task *t = &r->s->tasks[k];
    size_t n = pst_cloud_size(r->c);
    *bnd = (run_boundary){NULL, {NULL, NULL, NULL}};
    memset(claim, -1, n);
    int st = boundary_copy(r, bnd);
    if (st != PST_OK)
        return st;
    double *vals = malloc((n ? n : 1) * sizeof *vals), *level = malloc((n ? n : 1) * sizeof *level);
    uint8_t *pick = calloc(n ? n : 1, 1);
    if (!vals || !level || !pick)
        st = run_fail(r, PST_ENOMEM, "out of memory for boundary values");
    cJSON *list = cJSON_AddArrayToObject(tj, "boundary_groups");
    for (int g = 0; g < t->ngroups && st == PST_OK; ++g) {
        group_count cnt = {0, 0, 0, 0, 0};
        memset(pick, 0, n);
        st = group_values(r, k, g, vals, level);
        if (st == PST_OK)
            claim_group(r, &t->groups[g], vals, level, b, claim, pick, bnd, &cnt);
        if (st == PST_OK && cnt.estimated)
            st = estimate_normals(r, pick, bnd, &cnt);
        report_group(list, &t->groups[g], &cnt);
    }
    free(vals);
    free(level);
    free(pick);
    return st;
}

void run_boundary_free(run_boundary *bnd)
{
    free(bnd->kind);
    for (int d = 0; d < 3; ++d)
        free(bnd->normal[d]);
    *bnd = (run_boundary){NULL, {NULL, NULL, NULL}};
}
