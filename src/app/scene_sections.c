/* The sections of a scene (cloud, mobility, operator, fields, tasks, outputs) into a
 * pst_scene, with the checks that involve more than one key. */
#include "scene_walk.h"

#include "pstencil.h"

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>

static const char axis_name[3] = {'x', 'y', 'z'};

int scene_check_box(ctx *c, const double lo[3], const double hi[3], const char *hi_name)
{
    for (int d = 0; d < c->dim; ++d)
        if (!(hi[d] > lo[d]))
            return scene_error(c, hi_name, "must exceed lo along %c (lo %.15g, hi %.15g)",
                               axis_name[d], lo[d], hi[d]);
    return PST_OK;
}

/* ---- the sections of a scene ---------------------------------------------------------------- */

/* cloud.periodic against the other cloud keys, and a file cloud's cloud.box: a generated
 * cloud's box is its lattice's, a file records none (docs/io.md), so the scene gives it. */
static int read_periodic(ctx *c, const cJSON *o, pst_scene *s)
{
    sc_cloud *cl = &s->cloud;
    int periodic = pst_scene_periodic_axes(s);
    if (periodic && cl->source == SC_CLOUD_LATTICE && cl->angle != 0)
        return scene_error(c, "angle", "a periodic lattice cannot be rotated (cloud.periodic): "
                           "its axes are the box's");
    const cJSON *box = scene_member(o, "box");
    if (cl->source != SC_CLOUD_FILE || (!box && !periodic))
        return PST_OK;
    if (!box)
        return scene_error(c, "box", "missing: a file cloud with periodic axes (cloud.periodic) "
                           "needs its periodic box {lo, hi}");
    scene_enter(c, o, "box");
    int rc = periodic ? PST_OK
                      : scene_error(c, NULL, "no axis is periodic (cloud.periodic): the box "
                                    "applies only to periodic axes");
    scene_get_vec(c, box, "cloud.box.lo", cl->box_lo);
    scene_get_vec(c, box, "cloud.box.hi", cl->box_hi);
    if (rc == PST_OK)
        rc = scene_check_box(c, cl->box_lo, cl->box_hi, "hi");
    scene_pop(c);
    return rc;
}

int scene_read_cloud(ctx *c, const cJSON *root, pst_scene *s)
{
    const cJSON *o = scene_enter(c, root, "cloud");
    sc_cloud *cl = &s->cloud;
    cl->source = (sc_cloud_source)scene_get_enum(o, "cloud.source");
    int rc = scene_set_path(c, &cl->file, s->dir, scene_get_string(o, "cloud.file"));
    scene_get_vec(c, o, "cloud.lo", cl->lo);
    scene_get_vec(c, o, "cloud.hi", cl->hi);
    cl->spacing = scene_get_real(o, "cloud.spacing");
    cl->jitter = scene_get_real(o, "cloud.jitter");
    cl->seed = (long)scene_get_real(o, "cloud.seed");
    cl->boundary_layer = scene_get_bool(o, "cloud.boundary_layer");
    cl->angle = scene_get_real(o, "cloud.angle");
    cl->h_ratio = scene_get_real(o, "cloud.h_ratio");
    cl->h_ratio_set = scene_member(o, "h_ratio") != NULL;
    cl->spacing_set = scene_member(o, "spacing") != NULL;
    scene_get_axes(c, o, "cloud.periodic", cl->periodic);
    if (rc == PST_OK && cl->source != SC_CLOUD_FILE) {
        rc = scene_check_box(c, cl->lo, cl->hi, "hi");
        /* the generators' rule (generators.c): a whole number of spacings, to 1e-9 */
        for (int d = 0; d < c->dim && rc == PST_OK; ++d) {
            double r = (cl->hi[d] - cl->lo[d]) / cl->spacing, rn = round(r);
            if (!(r <= 4294967295.0) || rn < 1 || fabs(r - rn) > 1e-9 * r)
                rc = scene_error(c, "spacing",
                                 "the box length along %c (%.15g) is not a whole number of "
                                 "spacings (ratio %.15g)",
                                 axis_name[d], cl->hi[d] - cl->lo[d], r);
        }
    }
    if (rc == PST_OK)
        rc = read_periodic(c, o, s);
    scene_pop(c);
    return rc;
}

int pst_scene_periodic_axes(const pst_scene *s)
{
    return s->cloud.periodic[0] + s->cloud.periodic[1] + s->cloud.periodic[2];
}

/* An expression or a list of them into out[], with the count the context needs (`need`; 0:
 * one or dim). */
static int read_exprs(ctx *c, const cJSON *obj, const char *name, int need, const char *what,
                      char **out, int *count)
{
    const cJSON *v = scene_member(obj, name);
    if (!v)
        return PST_OK;
    int n = cJSON_IsArray(v) ? cJSON_GetArraySize(v) : 1;
    if (need == 0 && n != 1 && n != c->dim)
        return scene_error(
            c, name, "expected one expression or a list of %d (one per axis), got %d", c->dim, n);
    if (need > 1 && n != need)
        return scene_error(c, name, "%s needs a list of %d expressions, got %s%d", what, need,
                           cJSON_IsArray(v) ? "" : "a single expression, not ", n);
    if (need == 1 && n != 1)
        return scene_error(c, name, "%s needs a single expression, got a list of %d", what, n);
    for (int k = 0; k < n; ++k) {
        const cJSON *e = cJSON_IsArray(v) ? cJSON_GetArrayItem(v, k) : v;
        if (scene_set_str(c, &out[k], e->valuestring) != PST_OK)
            return c->status;
    }
    *count = n;
    return PST_OK;
}

int scene_read_mobility(ctx *c, const cJSON *root, pst_scene *s)
{
    const cJSON *o = scene_enter(c, root, "mobility");
    sc_mobility *m = &s->mobility;
    m->type = (sc_mobility_type)scene_get_enum(o, "mobility.type");
    m->value = m->type == SC_MOB_CONSTANT ? scene_get_real(o, "mobility.value") : 0.0;
    m->ncomp = m->type == SC_MOB_NONE ? 0 : 1;
    int rc = read_exprs(c, o, "expression", 0, "", m->expr, &m->ncomp);
    if (rc == PST_OK)
        rc = scene_set_path(c, &m->file, s->dir, scene_get_string(o, "mobility.file"));
    m->layer = (int)scene_get_real(o, "mobility.layer");
    m->i0 = (int)scene_get_real(o, "mobility.i0");
    m->j0 = (int)scene_get_real(o, "mobility.j0");
    scene_pop(c);
    return rc;
}

int scene_read_operator(ctx *c, const cJSON *root, pst_scene *s)
{
    const cJSON *o = scene_member(root, "operator");
    /* the library's names (pst_kernel_name), then the scenes' older wendland2, wendland4 */
    static const int kernels[] = {-1, PST_KERNEL_CUBIC, PST_KERNEL_QUINTIC,
                                  PST_KERNEL_WENDLAND_C2, PST_KERNEL_WENDLAND_C4,
                                  PST_KERNEL_WENDLAND_C2, PST_KERNEL_WENDLAND_C4};
    const char *scheme = scene_get_string(o, "operator.scheme");
    char buf[64];
    s->op.kernel = kernels[scene_get_enum(o, "operator.kernel")];
    s->op.gradient = PST_GRAD_G1 + scene_get_enum(o, "operator.gradient");
    s->op.variant = (int)scene_get_real(o, "operator.variant");
    s->op.cond_max = scene_get_real(o, "operator.cond_max");
    s->op.rank_tol = scene_get_real(o, "operator.rank_tol");
    s->op.min_pair_distance = scene_get_real(o, "operator.min_pair_distance");
    s->op.on_degenerate = scene_get_enum(o, "operator.on_degenerate");
    s->op.mobility_mean = scene_get_enum(o, "operator.mobility_mean");
    return scene_set_str(c, &s->op.scheme,
                         scheme ? scheme : scene_default_text("operator.scheme", buf, sizeof buf));
}

int scene_read_fields(ctx *c, const cJSON *root, pst_scene *s)
{
    const cJSON *o = scene_enter(c, root, "fields");
    int rc = PST_OK;
    for (const cJSON *m = o ? o->child : NULL; m && rc == PST_OK; m = m->next) {
        scene_push_member(c, m);
        if (!pst_is_identifier(m->string))
            rc = scene_error(c, NULL,
                             "a field name must be a C identifier (letters, digits and _, "
                             "not starting with a digit, at most %d characters)",
                             PST_MAX_NAME - 1);
        else if (pst_is_reserved_column(m->string))
            rc = scene_error(c, NULL, "'%s' is a column of the CSV format, not a field name",
                             m->string);
        scene_pop(c);
        if (rc == PST_OK) {
            sc_field *f = &s->fields[s->nfields++];
            if ((rc = scene_set_str(c, &f->name, m->string)) == PST_OK)
                rc = scene_set_str(c, &f->expr, m->valuestring);
        }
    }
    scene_pop(c);
    return rc;
}

static int find_field(const pst_scene *s, const char *name)
{
    for (int k = 0; k < s->nfields; ++k)
        if (strcmp(s->fields[k].name, name) == 0)
            return k;
    return -1;
}

/* "field 'w' is not declared in 'fields' (did you mean 'u'?)" */
static int unknown_name(ctx *c, const char *extra, const char *what, const char *name,
                        const char *const *known, int nknown, const char *where)
{
    const char *best = NULL;
    int bestd = 1000;
    for (int k = 0; k < nknown; ++k)
        scene_consider(name, known[k], &best, &bestd);
    if (best)
        return scene_error(c, extra, "%s '%s' is not %s (did you mean '%s'?)", what, name, where,
                           best);
    return scene_error(c, extra, "%s '%s' is not %s", what, name, where);
}

static int read_region(ctx *c, const cJSON *task, sc_task *t)
{
    const cJSON *r = scene_member(task, "region");
    if (!cJSON_IsObject(r)) {
        t->region = (sc_region_type)scene_get_enum(task, "tasks[].region");
        return PST_OK;
    }
    t->region = SC_REGION_BOX;
    scene_get_vec(c, r, "tasks[].region.lo", t->region_lo);
    scene_get_vec(c, r, "tasks[].region.hi", t->region_hi);
    scene_enter(c, task, "region");
    int rc = scene_check_box(c, t->region_lo, t->region_hi, "hi");
    scene_pop(c);
    return rc;
}

static int read_points(ctx *c, const cJSON *task, pst_scene *s, sc_task *t)
{
    const cJSON *o = scene_enter(c, task, "points");
    int rc = PST_OK;
    if (o) {
        const char *file = scene_get_string(o, "tasks[].points.file");
        int nbox = !!scene_member(o, "lo") + !!scene_member(o, "hi") + !!scene_member(o, "spacing");
        if (file && nbox)
            rc = scene_error(c, NULL, "give either 'file' or 'lo', 'hi' and 'spacing', not both");
        else if (!file && nbox < 3)
            rc = scene_error(c,
                             !scene_member(o, "lo")   ? "lo"
                             : !scene_member(o, "hi") ? "hi"
                                                      : "spacing",
                             "missing (a point lattice needs lo, hi and spacing)");
        else if (file)
            rc = scene_set_path(c, &t->points_file, s->dir, file);
        else {
            scene_get_vec(c, o, "tasks[].points.lo", t->points_lo);
            scene_get_vec(c, o, "tasks[].points.hi", t->points_hi);
            t->points_spacing = scene_get_real(o, "tasks[].points.spacing");
            rc = scene_check_box(c, t->points_lo, t->points_hi, "hi");
        }
    }
    scene_pop(c);
    return rc;
}

static const char *const norm_names[SC_NNORMS] = {"rel_l2", "qsfdi11", "qsfdi11_normalised",
                                                  "lv78",   "lv95",    "max_abs",
                                                  "max_rel"};

static int read_norms(ctx *c, const cJSON *task, sc_task *t)
{
    const cJSON *list = scene_member(task, "norms");
    if (!list) {
        if (t->nexact) { /* errors are wanted whenever there is something to compare with */
            t->norms[t->nnorms++] = SC_NORM_REL_L2;
            t->norms[t->nnorms++] = SC_NORM_MAX_ABS;
        }
        return PST_OK;
    }
    if (!t->nexact)
        return scene_error(c, "norms", "error norms need an exact solution ('exact')");
    int rc = PST_OK;
    scene_enter(c, task, "norms");
    for (const cJSON *e = list->child; e && rc == PST_OK; e = e->next) {
        int k = scene_value_index(sc_param_find("tasks[].norms")->values, e->valuestring);
        for (int j = 0; j < t->nnorms; ++j)
            if (t->norms[j] == k) {
                scene_push(c, e, NULL, t->nnorms);
                rc = scene_error(c, NULL, "norm '%s' is listed twice", norm_names[k]);
                scene_pop(c);
            }
        t->norms[t->nnorms++] = k;
    }
    scene_pop(c);
    return rc;
}

static int read_task(ctx *c, const cJSON *o, pst_scene *s, sc_task *t)
{
    static const char *const what[] = {"a laplacian task", "a divergence task",
                                       "a gradient task", "a hessian task",
                                       "an interpolate task", "a solve task",
                                       "a diffuse task"};
    static const sc_operator_use stored[] = {SC_OPERATOR_AUTO, SC_OPERATOR_STORED,
                                             SC_OPERATOR_MATRIX_FREE, SC_OPERATOR_STORED_FLOAT};
    t->type = (sc_task_type)scene_get_enum(o, "tasks[].type");
    int rc = scene_set_str(c, &t->name, scene_get_string(o, "tasks[].name"));
    const char *field = scene_get_string(o, "tasks[].field");
    if (rc == PST_OK && field && find_field(s, field) < 0) {
        const char *known[SC_MAX_FIELDS];
        for (int k = 0; k < s->nfields; ++k)
            known[k] = s->fields[k].name;
        rc = unknown_name(c, "field", "field", field, known, s->nfields, "declared in 'fields'");
    }
    if (rc == PST_OK)
        rc = scene_set_str(c, &t->field, field);
    int need = t->type == SC_TASK_GRADIENT  ? c->dim
               : t->type == SC_TASK_HESSIAN ? (c->dim == 2 ? 3 : 6)
                                            : 1;
    if (rc == PST_OK) {
        char what_dim[64];
        snprintf(what_dim, sizeof what_dim, "%s in %dD", what[t->type], c->dim);
        rc = read_exprs(c, o, "exact", need, need > 1 ? what_dim : what[t->type], t->exact,
                        &t->nexact);
    }
    if (rc == PST_OK)
        rc = read_norms(c, o, t);
    if (rc == PST_OK)
        rc = read_region(c, o, t);
    if (rc == PST_OK && t->type == SC_TASK_INTERPOLATE)
        rc = read_points(c, o, s, t);
    if (rc == PST_OK)
        rc = scene_set_str(c, &t->rhs, scene_get_string(o, "tasks[].rhs"));
    if (rc == PST_OK)
        rc = scene_set_str(c, &t->petsc, scene_get_string(o, "tasks[].petsc"));
    if (rc == PST_OK)
        rc = scene_read_boundary(c, o, s->cloud.periodic, t);
    if (rc == PST_OK && t->type == SC_TASK_DIFFUSE)
        rc = scene_read_steps(c, o, t);
    /* periodic along every axis, a generated cloud has no boundary to give values to */
    int boundless = pst_scene_periodic_axes(s) == c->dim && s->cloud.source != SC_CLOUD_FILE;
    if (rc == PST_OK && t->type == SC_TASK_SOLVE && t->ngroups == 0 && t->nexact == 0 &&
        !boundless)
        rc =
            scene_error(c, NULL, "a solve without 'boundary' needs 'exact' (its Dirichlet values)");
    t->solver = scene_get_enum(o, "tasks[].solver");
    t->precond = scene_get_enum(o, "tasks[].precond");
    t->amg_source = scene_get_enum(o, "tasks[].amg_source");
    t->amg_radius = scene_get_real(o, "tasks[].amg_radius");
    t->amg_aggressive = (int)scene_get_real(o, "tasks[].amg_aggressive");
    t->amg_strong = scene_get_real(o, "tasks[].amg_strong");
    t->amg_coarsen = scene_get_enum(o, "tasks[].amg_coarsen");
    t->amg_interp = scene_get_enum(o, "tasks[].amg_interp");
    t->amg_pmax = (int)scene_get_real(o, "tasks[].amg_pmax");
    t->restart = (int)scene_get_real(o, "tasks[].restart");
    t->max_iter = (int)scene_get_real(o, "tasks[].max_iter");
    t->rtol = scene_get_real(o, "tasks[].rtol");
    t->stored = stored[scene_get_enum(o, "tasks[].operator")];
    return rc;
}

/* 1 when `name` is a field or the name of a task before `upto`. */
static int name_taken(const pst_scene *s, const char *name, int upto)
{
    if (find_field(s, name) >= 0)
        return 1;
    for (int k = 0; k < upto; ++k)
        if (s->tasks[k].name && strcmp(s->tasks[k].name, name) == 0)
            return 1;
    return 0;
}

/* Task names: given ones are identifiers, unique, and not field names; the others become the
 * type, numbered from _2 when taken. */
static int name_tasks(ctx *c, const cJSON *list, pst_scene *s)
{
    static const char *const type_names[] = {"laplacian",   "divergence", "gradient", "hessian",
                                              "interpolate", "solve",      "diffuse"};
    int rc = PST_OK;
    for (int i = 0; i < s->ntasks && rc == PST_OK; ++i) {
        const char *name = s->tasks[i].name;
        if (!name)
            continue;
        scene_push(c, cJSON_GetArrayItem(list, i), NULL, i);
        if (!pst_is_identifier(name) || pst_is_reserved_column(name))
            rc = scene_error(c, "name",
                             "a task name must be a C identifier (at most %d characters) "
                             "and not a CSV column name, got '%s'",
                             PST_MAX_NAME - 1, name);
        else if (find_field(s, name) >= 0)
            rc = scene_error(c, "name", "'%s' is already the name of a field", name);
        for (int k = 0; k < i && rc == PST_OK; ++k)
            if (s->tasks[k].name && strcmp(s->tasks[k].name, name) == 0)
                rc = scene_error(c, "name", "duplicate task name '%s' (also tasks.%d.name)", name,
                                 k);
        scene_pop(c);
    }
    for (int i = 0; i < s->ntasks && rc == PST_OK; ++i) {
        sc_task *t = &s->tasks[i];
        if (t->name)
            continue;
        char buf[PST_MAX_NAME];
        snprintf(buf, sizeof buf, "%s", type_names[t->type]);
        for (int k = 2; name_taken(s, buf, s->ntasks); ++k)
            snprintf(buf, sizeof buf, "%s_%d", type_names[t->type], k);
        rc = scene_set_str(c, &t->name, buf);
    }
    return rc;
}

int scene_read_tasks(ctx *c, const cJSON *root, pst_scene *s)
{
    const cJSON *list = scene_enter(c, root, "tasks");
    int rc = PST_OK;
    for (const cJSON *o = list ? list->child : NULL; o && rc == PST_OK; o = o->next) {
        scene_push(c, o, NULL, s->ntasks);
        rc = read_task(c, o, s, &s->tasks[s->ntasks++]);
        scene_pop(c);
    }
    /* moving particles change the cloud every other task reads */
    for (int k = 0; k < s->ntasks && rc == PST_OK && s->ntasks > 1; ++k)
        if (s->tasks[k].nvelocity) {
            scene_push(c, cJSON_GetArrayItem(list, k), NULL, k);
            rc = scene_error(c, "velocity", "moves the particles, so the task must be the "
                                            "scene's only one (there are %d)", s->ntasks);
            scene_pop(c);
        }
    if (rc == PST_OK)
        rc = name_tasks(c, list, s);
    scene_pop(c);
    return rc;
}

/* outputs.vtu names the dataset by its extension (any case). */
static int vtk_extension(const char *path)
{
    size_t len = strlen(path);
    return len >= 4 && (strcasecmp(path + len - 4, ".vtu") == 0 ||
                        strcasecmp(path + len - 4, ".vtp") == 0);
}

int scene_read_outputs(ctx *c, const cJSON *root, pst_scene *s)
{
    const cJSON *o = scene_enter(c, root, "outputs");
    sc_outputs *out = &s->out;
    int rc = scene_set_str(c, &out->csv, scene_get_string(o, "outputs.csv"));
    if (rc == PST_OK)
        rc = scene_set_str(c, &out->vtu, scene_get_string(o, "outputs.vtu"));
    if (rc == PST_OK && out->vtu && !vtk_extension(out->vtu)) {
        scene_enter(c, o, "vtu");
        rc = scene_error(c, NULL, "'%s': expected a .vtu (UnstructuredGrid) or .vtp (PolyData) "
                                  "file name", out->vtu);
        scene_pop(c);
    }
    out->vtu_compress = scene_get_bool(o, "outputs.vtu_compress");
    if (rc == PST_OK)
        rc = scene_set_str(c, &out->report, scene_get_string(o, "outputs.report"));
    if (rc == PST_OK)
        rc = scene_check_output_paths(c, s);
    const cJSON *list = scene_member(o, "fields");
    if (list && rc == PST_OK) {
        scene_enter(c, o, "fields");
        const char *known[SC_MAX_FIELDS + SC_MAX_TASKS];
        int nknown = 0;
        for (int k = 0; k < s->nfields; ++k)
            known[nknown++] = s->fields[k].name;
        for (int k = 0; k < s->ntasks; ++k)
            known[nknown++] = s->tasks[k].name;
        for (const cJSON *e = list->child; e && rc == PST_OK; e = e->next) {
            const char *name = e->valuestring;
            scene_push(c, e, NULL, out->nfields);
            if (!name_taken(s, name, s->ntasks))
                rc = unknown_name(c, NULL, "name", name, known, nknown,
                                  "a field or a task name");
            for (int k = 0; k < out->nfields && rc == PST_OK; ++k)
                if (strcmp(out->fields[k], name) == 0)
                    rc = scene_error(c, NULL, "'%s' is listed twice", name);
            scene_pop(c);
            if (rc == PST_OK && (rc = scene_set_str(c, &out->fields[out->nfields], name)) == PST_OK)
                ++out->nfields;
        }
        scene_pop(c);
    }
    scene_pop(c);
    return rc;
}
