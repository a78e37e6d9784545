/* The boundary groups of a solve task (docs/scenes.md, "boundary"): which boundary particles
 * each group claims, with what kind, value and normal. The result is a boundary of its own
 * (run_boundary) that the solve's operator reads, so the cloud, which the base operator and
 * the outputs read, keeps its kinds and normals. */
#include "run_state.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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

/* Group g's claims: each boundary particle no earlier group took whose nearest box side is
 * the group's (or any, for "all"). A Neumann particle gets the side's outward normal unless
 * the cloud gave it one and the group is "all". */
static void claim_group(run_state *r, const sc_group *gr, const double *vals, double *b,
                        int8_t *claim, run_boundary *bnd)
{
    size_t n = pst_cloud_size(r->c);
    const uint8_t *kind = pst_cloud_kinds_const(r->c);
    for (size_t i = 0; i < n; ++i) {
        if (kind[i] == PST_INTERIOR || claim[i] >= 0)
            continue;
        sc_side side = nearest_side(r, i);
        if (gr->where != SC_SIDE_ALL && gr->where != side)
            continue;
        claim[i] = (int8_t)(gr->neumann ? PST_NEUMANN : PST_DIRICHLET);
        bnd->kind[i] = (uint8_t)claim[i];
        b[i] = gr->neumann ? vals[i] / r->plan.mobility_factor : vals[i];
        if (!gr->neumann)
            continue;
        double len = 0;
        for (int d = 0; d < r->s->dim; ++d)
            len += bnd->normal[d][i] * bnd->normal[d][i];
        if (len == 0 || gr->where != SC_SIDE_ALL) {
            int axis = (side - SC_SIDE_XLO) / 2, high = (side - SC_SIDE_XLO) % 2;
            for (int d = 0; d < r->s->dim; ++d)
                bnd->normal[d][i] = d == axis ? (high ? 1.0 : -1.0) : 0.0;
        }
    }
}

int run_boundary_make(run_state *r, int k, double *b, int8_t *claim, run_boundary *bnd)
{
    const sc_task *t = &r->s->tasks[k];
    size_t n = pst_cloud_size(r->c);
    *bnd = (run_boundary){NULL, {NULL, NULL, NULL}};
    memset(claim, -1, n);
    int st = boundary_copy(r, bnd);
    if (st != PST_OK)
        return st;
    double *vals = malloc((n ? n : 1) * sizeof *vals);
    if (!vals)
        return run_fail(r, PST_ENOMEM, "out of memory for boundary values");
    for (int g = 0; g < t->ngroups && st == PST_OK; ++g) {
        char key[64];
        snprintf(key, sizeof key, "tasks[%d].boundary[%d].value", k, g);
        st = run_eval_at_particles(r, key, t->groups[g].value, vals);
        if (st == PST_OK)
            claim_group(r, &t->groups[g], vals, b, claim, bnd);
    }
    free(vals);
    return st;
}

void run_boundary_free(run_boundary *bnd)
{
    free(bnd->kind);
    for (int d = 0; d < 3; ++d)
        free(bnd->normal[d]);
    *bnd = (run_boundary){NULL, {NULL, NULL, NULL}};
}
