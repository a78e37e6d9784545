/* The boundary groups of a solve task: which particles a group claims (the cloud's kind, the
 * nearest box side, a region) and where a Neumann group's normals come from. */
#include "scene_walk.h"

#include "pstencil.h"

#include <stdio.h>
#include <stdlib.h>

/* Both members a and b of a region object, else an error naming the shape. */
static int both(ctx *c, const cJSON *o, const char *a, const char *b, const char *shape)
{
    if (scene_member(o, a) && scene_member(o, b))
        return PST_OK;
    return scene_error(c, NULL, "%s needs both %s and %s", shape, a, b);
}

/* The group's region: exactly one of a box {lo, hi}, a ball {center, radius}, a half-space
 * {point, normal} or an expression {expr}. */
static int read_shape(ctx *c, const cJSON *g, sc_shape *sh)
{
    const cJSON *o = scene_member(g, "region");
    if (!o)
        return PST_OK;
    scene_enter(c, g, "region");
    int box = scene_member(o, "lo") || scene_member(o, "hi");
    int ball = scene_member(o, "center") || scene_member(o, "radius");
    int half = scene_member(o, "point") || scene_member(o, "normal");
    int expr = scene_member(o, "expr") != NULL;
    int rc = PST_OK;
    if (box + ball + half + expr != 1)
        rc = scene_error(c, NULL, "give one region: {lo, hi} (a box), {center, radius} (a "
                                  "ball), {point, normal} (a half-space) or {expr}");
    else if (box) {
        sh->type = SC_SHAPE_BOX;
        rc = both(c, o, "lo", "hi", "a box");
        scene_get_vec(c, o, "tasks[].boundary[].region.lo", sh->a);
        scene_get_vec(c, o, "tasks[].boundary[].region.hi", sh->b);
        if (rc == PST_OK)
            rc = scene_check_box(c, sh->a, sh->b, "hi");
    } else if (ball) {
        sh->type = SC_SHAPE_SPHERE;
        rc = both(c, o, "center", "radius", "a ball");
        scene_get_vec(c, o, "tasks[].boundary[].region.center", sh->a);
        sh->radius = scene_get_real(o, "tasks[].boundary[].region.radius");
    } else if (half) {
        sh->type = SC_SHAPE_HALF_SPACE;
        rc = both(c, o, "point", "normal", "a half-space");
        scene_get_vec(c, o, "tasks[].boundary[].region.point", sh->a);
        scene_get_vec(c, o, "tasks[].boundary[].region.normal", sh->b);
        double len = 0;
        for (int d = 0; d < c->dim; ++d)
            len += sh->b[d] * sh->b[d];
        if (rc == PST_OK && !(len > 0))
            rc = scene_error(c, "normal", "must not be zero");
    } else {
        sh->type = SC_SHAPE_EXPR;
        rc = scene_set_str(c, &sh->expr,
                           scene_get_string(o, "tasks[].boundary[].region.expr"));
    }
    scene_pop(c);
    return rc;
}

int scene_read_boundary(ctx *c, const cJSON *task, const int periodic[3], sc_task *t)
{
    const cJSON *list = scene_enter(c, task, "boundary");
    int rc = PST_OK;
    for (const cJSON *g = list ? list->child : NULL; g && rc == PST_OK; g = g->next) {
        sc_group *gr = &t->groups[t->ngroups];
        scene_push(c, g, NULL, t->ngroups);
        gr->where = (sc_side)scene_get_enum(g, "tasks[].boundary[].where");
        gr->kind = (sc_group_kind)scene_get_enum(g, "tasks[].boundary[].kind");
        gr->normals = (sc_normals)scene_get_enum(g, "tasks[].boundary[].normals");
        gr->neumann = scene_get_enum(g, "tasks[].boundary[].type");
        if (c->dim == 2 && (gr->where == SC_SIDE_ZLO || gr->where == SC_SIDE_ZHI))
            rc = scene_error(c, "where", "there is no z side in 2D");
        /* a periodic axis wraps around: its sides are interior */
        int axis = gr->where == SC_SIDE_ALL ? -1 : ((int)gr->where - SC_SIDE_XLO) / 2;
        if (rc == PST_OK && axis >= 0 && periodic[axis])
            rc = scene_error(c, "where", "the %c axis is periodic (cloud.periodic): it has no "
                             "sides", "xyz"[axis]);
        if (rc == PST_OK && !gr->neumann && scene_member(g, "normals"))
            rc = scene_error(c, "normals", "only a neumann group has normals");
        if (rc == PST_OK)
            rc = read_shape(c, g, &gr->region);
        if (rc == PST_OK &&
            (rc = scene_set_str(c, &gr->value, scene_get_string(g, "value"))) == PST_OK)
            ++t->ngroups;
        else if (gr->region.expr) { /* a group not counted is not freed with the scene */
            free(gr->region.expr);
            gr->region.expr = NULL;
        }
        scene_pop(c);
    }
    scene_pop(c);
    return rc;
}
