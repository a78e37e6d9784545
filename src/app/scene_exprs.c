/* Every expression of a scene compiled once before anything is computed, so that `run --plan`
 * and `sweep --plan` refuse a scene the run would refuse, with the run's message. */
#include "scene.h"

#include "pstencil.h"
#include "pstencil_expr.h"

#include <stdio.h>

/* Compile `text` (scene key `key`) in x, y[, z] and, when `timed`, t; PST_EINPUT with "PATH:
 * KEY: WHY" when it does not. */
static int compile_in(const pst_scene *s, int timed, const char *key, const char *text,
                      char *err, size_t errlen)
{
    const char *vars[4] = {"x", "y", "z", "t"};
    if (!text)
        return PST_OK;
    if (timed && s->dim == 2)
        vars[2] = "t";
    char msg[PST_ERRLEN];
    pst_expr *e = pst_expr_parse(text, vars, s->dim + timed, msg, sizeof msg);
    if (!e) {
        snprintf(err, errlen, "%s: %s: %s", s->path, key, msg);
        return PST_EINPUT;
    }
    pst_expr_free(e);
    return PST_OK;
}

static int compile(const pst_scene *s, const char *key, const char *text, char *err,
                   size_t errlen)
{
    return compile_in(s, 0, key, text, err, errlen);
}

/* A diffuse task's expressions, all of which may read t. */
static int compile_steps(const pst_scene *s, int k, char *err, size_t errlen)
{
    const sc_task *t = &s->tasks[k];
    const char *names[] = {"initial", "source", "boundary_value", "exact"};
    const char *texts[] = {t->initial, t->source, t->boundary_value, t->exact[0]};
    char key[96];
    int st = PST_OK;
    for (int a = 0; a < 4 && st == PST_OK; ++a) {
        snprintf(key, sizeof key, "tasks[%d].%s", k, names[a]);
        st = compile_in(s, 1, key, texts[a], err, errlen);
    }
    for (int d = 0; d < t->nvelocity && st == PST_OK; ++d) {
        snprintf(key, sizeof key, "tasks[%d].velocity[%d]", k, d);
        st = compile_in(s, 1, key, t->velocity[d], err, errlen);
    }
    return st;
}

int pst_scene_compile_exprs(const pst_scene *s, char *err, size_t errlen)
{
    char key[96];
    int st = PST_OK;
    for (int f = 0; f < s->nfields && st == PST_OK; ++f) {
        snprintf(key, sizeof key, "fields.%s", s->fields[f].name);
        st = compile(s, key, s->fields[f].expr, err, errlen);
    }
    for (int a = 0; s->mobility.type == SC_MOB_EXPR && a < s->mobility.ncomp && st == PST_OK;
         ++a) {
        snprintf(key, sizeof key,
                 s->mobility.ncomp == 1 ? "mobility.expression" : "mobility.expression[%d]", a);
        st = compile(s, key, s->mobility.expr[a], err, errlen);
    }
    for (int k = 0; k < s->ntasks && st == PST_OK; ++k) {
        const sc_task *t = &s->tasks[k];
        if (t->type == SC_TASK_DIFFUSE) {
            st = compile_steps(s, k, err, errlen);
            continue;
        }
        for (int a = 0; a < t->nexact && st == PST_OK; ++a) {
            snprintf(key, sizeof key, t->nexact == 1 ? "tasks[%d].exact" : "tasks[%d].exact[%d]",
                     k, a);
            st = compile(s, key, t->exact[a], err, errlen);
        }
        snprintf(key, sizeof key, "tasks[%d].rhs", k);
        if (st == PST_OK)
            st = compile(s, key, t->rhs, err, errlen);
        for (int g = 0; g < t->ngroups && st == PST_OK; ++g) {
            snprintf(key, sizeof key, "tasks[%d].boundary[%d].value", k, g);
            st = compile(s, key, t->groups[g].value, err, errlen);
            snprintf(key, sizeof key, "tasks[%d].boundary[%d].region.expr", k, g);
            if (st == PST_OK)
                st = compile(s, key, t->groups[g].region.expr, err, errlen);
        }
    }
    return st;
}
