/* The keys of a diffuse task (docs/time-stepping.md), with the checks between them that the
 * table cannot make: which keys the method or the velocity decide. */
#include "scene_walk.h"

#include "pstencil.h"

#include <string.h>
#include <strings.h>

/* The solver's keys: an explicit method solves nothing. */
static const char *const solver_keys[] = {"solver", "precond", "restart", "max_iter", "rtol"};

/* `name` of task o, given although `why` says it does not apply. */
static int refuse_given(ctx *c, const cJSON *o, const char *name, const char *why)
{
    return scene_member(o, name) ? scene_error(c, name, "applies only %s", why) : PST_OK;
}

static int check_keys(ctx *c, const cJSON *o, const sc_task *t)
{
    int explicit = t->method == SC_METHOD_EXPLICIT, rc = PST_OK;
    if (!explicit && !scene_member(o, "dt"))
        return scene_error(c, "dt", "missing: the implicit methods need a step (the automatic "
                                    "one is the explicit method's stability limit)");
    if (!explicit)
        rc = refuse_given(c, o, "safety", "to method explicit");
    else if (scene_member(o, "dt"))
        rc = refuse_given(c, o, "safety", "without dt (the step is dt)");
    for (size_t k = 0; k < sizeof solver_keys / sizeof *solver_keys && rc == PST_OK; ++k)
        if (explicit)
            rc = refuse_given(c, o, solver_keys[k], "to the implicit methods");
    if (rc == PST_OK && !t->nvelocity)
        rc = refuse_given(c, o, "skin", "with velocity");
    if (rc == PST_OK && !t->pvd)
        rc = refuse_given(c, o, "output_every", "with pvd");
    size_t len = t->pvd ? strlen(t->pvd) : 0;
    if (rc == PST_OK && t->pvd && (len < 5 || strcasecmp(t->pvd + len - 4, ".pvd") != 0))
        rc = scene_error(c, "pvd", "'%s': expected a .pvd file name", t->pvd);
    if (rc == PST_OK && t->pvd && t->steps_csv && strcmp(t->pvd, t->steps_csv) == 0)
        rc = scene_error(c, "steps_csv", "the same file as pvd");
    return rc;
}

/* The velocity: one expression per axis. */
static int read_velocity(ctx *c, const cJSON *o, sc_task *t)
{
    const cJSON *v = scene_member(o, "velocity");
    if (!v)
        return PST_OK;
    int n = cJSON_IsArray(v) ? cJSON_GetArraySize(v) : 1;
    if (n != c->dim)
        return scene_error(c, "velocity", "needs a list of %d expressions (one per axis), got %d",
                           c->dim, n);
    for (int d = 0; d < n; ++d)
        if (scene_set_str(c, &t->velocity[d], cJSON_GetArrayItem(v, d)->valuestring) != PST_OK)
            return c->status;
    t->nvelocity = n;
    return PST_OK;
}

int scene_read_steps(ctx *c, const cJSON *o, sc_task *t)
{
    t->method = (sc_method)scene_get_enum(o, "tasks[].method");
    t->t_end = scene_get_real(o, "tasks[].t_end");
    t->dt = scene_get_real(o, "tasks[].dt");
    t->safety = scene_get_real(o, "tasks[].safety");
    t->skin = scene_get_real(o, "tasks[].skin");
    t->max_steps = (int)scene_get_real(o, "tasks[].max_steps");
    t->output_every = (int)scene_get_real(o, "tasks[].output_every");
    int rc = scene_set_str(c, &t->initial, scene_get_string(o, "tasks[].initial"));
    if (rc == PST_OK)
        rc = scene_set_str(c, &t->source, scene_get_string(o, "tasks[].source"));
    if (rc == PST_OK)
        rc = scene_set_str(c, &t->boundary_value, scene_get_string(o, "tasks[].boundary_value"));
    if (rc == PST_OK)
        rc = scene_set_str(c, &t->pvd, scene_get_string(o, "tasks[].pvd"));
    if (rc == PST_OK)
        rc = scene_set_str(c, &t->steps_csv, scene_get_string(o, "tasks[].steps_csv"));
    if (rc == PST_OK)
        rc = read_velocity(c, o, t);
    return rc == PST_OK ? check_keys(c, o, t) : rc;
}
