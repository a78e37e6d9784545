#include "report.h"

#include "pstencil.h"
#include "text_file.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

cJSON *report_begin(const pst_scene *s)
{
    cJSON *r = cJSON_CreateObject();
    cJSON_AddStringToObject(r, "pstencil", pst_version());
    cJSON_AddStringToObject(r, "scene", s->path);
    if (s->title)
        cJSON_AddStringToObject(r, "title", s->title);
    cJSON_AddNumberToObject(r, "threads", pst_threads());
    cJSON_AddStringToObject(r, "kernel_isa", pst_isa());
    cJSON_AddNumberToObject(r, "dim", s->dim);
    cJSON_AddObjectToObject(r, "timers");
    cJSON_AddArrayToObject(r, "operators");
    return r;
}

void report_timer(cJSON *report, const char *name, double seconds)
{
    cJSON_AddNumberToObject(cJSON_GetObjectItem(report, "timers"), name, seconds);
}

void report_peak_memory(cJSON *report)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    cJSON_AddNumberToObject(report, "peak_rss_bytes", 1024.0 * (double)ru.ru_maxrss);
}

cJSON *report_parameters(const pst_op_opts *oo)
{
    cJSON *p = cJSON_CreateObject();
    const char *fallback = pst_scheme_fallback(oo->scheme);
    cJSON_AddStringToObject(p, "scheme", oo->scheme);
    cJSON_AddNumberToObject(p, "gradient", oo->gradient);
    cJSON_AddNumberToObject(p, "variant", oo->variant);
    cJSON_AddStringToObject(p, "mobility_mean",
                            oo->mobility_mean == PST_MEAN_HARMONIC ? "harmonic" : "arithmetic");
    cJSON_AddNumberToObject(p, "cond_max", oo->cond_max);
    cJSON_AddNumberToObject(p, "rank_tol", oo->rank_tol);
    cJSON_AddNumberToObject(p, "min_pair_distance", oo->min_pair_distance);
    cJSON_AddStringToObject(p, "on_degenerate",
                            oo->on_degenerate == PST_DEGENERATE_REFUSE ? "refuse" : "fall_back");
    cJSON_AddStringToObject(p, "regularisation", "none");
    cJSON_AddStringToObject(p, "fallback", fallback ? fallback : "unknown scheme");
    return p;
}

void report_operator(cJSON *report, const pst_op *op)
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddItemToArray(cJSON_GetObjectItem(report, "operators"), o);
    cJSON_AddStringToObject(o, "scheme", pst_op_scheme(op));
    cJSON_AddStringToObject(o, "kernel", pst_kernel_name(pst_op_kernel(op)));
    cJSON_AddBoolToObject(o, "laplacian_rows", pst_op_has_rows(op));
    pst_op_opts oo;
    pst_op_options(op, &oo);
    cJSON_AddItemToObject(o, "parameters", report_parameters(&oo));
    double t[PST_NPHASES];
    pst_op_phase_times(op, t);
    cJSON *ph = cJSON_AddObjectToObject(o, "phases");
    for (int k = 0; k < PST_NPHASES; ++k)
        if (k != PST_PHASE_APPLY)
            cJSON_AddNumberToObject(ph, pst_phase_name(k), t[k]);
    size_t counts[PST_ROW_NSTATUS];
    pst_op_status_counts(op, counts);
    cJSON *sc = cJSON_AddObjectToObject(o, "row_status");
    for (int k = 0; k < PST_ROW_NSTATUS; ++k)
        cJSON_AddNumberToObject(sc, pst_row_status_name(k), (double)counts[k]);
}

void report_task_header(cJSON *task, const sc_task *t)
{
    static const char *const types[] = {"laplacian", "divergence", "gradient",
                                        "hessian",   "interpolate", "solve", "diffuse"};
    cJSON_AddStringToObject(task, "name", t->name);
    cJSON_AddStringToObject(task, "type", types[t->type]);
    if (t->field)
        cJSON_AddStringToObject(task, "field", t->field);
}

const char *report_operator_use(int stored)
{
    static const char *const names[] = {"matrix_free", "stored", "stored_float"};
    return names[stored];
}

void report_solve(cJSON *task, const pst_solve_result *res, int stored, int fix_mean)
{
    static const char *const solvers[] = {"auto", "cg", "gmres", "bicgstab"};
    cJSON *s = cJSON_AddObjectToObject(task, "solver");
    cJSON_AddStringToObject(s, "method", solvers[res->solver]);
    cJSON_AddStringToObject(s, "operator", report_operator_use(stored));
    cJSON_AddBoolToObject(s, "converged", res->converged);
    cJSON_AddNumberToObject(s, "iterations", res->iterations);
    cJSON_AddNumberToObject(s, "relative_residual", res->rel_residual);
    cJSON_AddStringToObject(s, "message", res->message);
    cJSON_AddNumberToObject(s, "setup_seconds", res->setup_seconds);
    cJSON_AddBoolToObject(s, "fix_mean", fix_mean);
    if (fix_mean)
        cJSON_AddNumberToObject(s, "mean_shift", res->mean_shift);
    if (res->history)
        cJSON_AddItemToObject(s, "history", cJSON_CreateDoubleArray(res->history, res->nhistory));
}

/* Numbers of a report object, in the order given. */
typedef struct {
    const char *name;
    double v;
} named_number;

static void add_numbers(cJSON *o, const named_number *rows, size_t nrows)
{
    for (size_t q = 0; q < nrows; ++q)
        cJSON_AddNumberToObject(o, rows[q].name, rows[q].v);
}

void report_finish(cJSON *report, const pst_plan *p, const pst_run_counters *cnt,
                   const pst_cloud *c)
{
    cJSON *pl = cJSON_AddObjectToObject(report, "plan");
    const named_number plan[] = {{"particles", (double)pst_cloud_size(c)},
                                 {"neighbours_estimate", p->neighbours},
                                 {"mobility_components", p->mobility_ncomp},
                                 {"mobility_factor", p->mobility_factor}};
    add_numbers(pl, plan, sizeof plan / sizeof plan[0]);
    cJSON_AddNumberToObject(pl, "ranks", p->ranks);
    if (p->ranks > 1) { /* the plan's part, beside the task's petsc.rank0_owned and _ghosts */
        cJSON_AddNumberToObject(pl, "part_owned_estimate", (double)p->part_owned);
        cJSON_AddNumberToObject(pl, "part_ghosts_estimate", (double)p->part_ghosts);
    }
    cJSON_AddBoolToObject(pl, "base_operator", p->base_operator);
    cJSON_AddBoolToObject(pl, "base_laplacian_rows", p->base_laplacian);
    cJSON_AddBoolToObject(pl, "half_list", p->half_list);
    cJSON_AddBoolToObject(pl, "keeps_gradient", (p->base_keep & PST_KEEP_GRADIENT) != 0);
    cJSON_AddBoolToObject(pl, "keeps_hessian", (p->base_keep & PST_KEEP_HESSIAN) != 0);
    const named_number memory[] = {{"cloud", p->bytes_cloud},
                                   {"neighbours", p->bytes_neighbours},
                                   {"half_list", p->bytes_half_list},
                                   {"operators", p->bytes_operators},
                                   {"weights", p->bytes_weights},
                                   {"solver", p->bytes_solver},
                                   {"total", p->bytes_total},
                                   {"available", p->bytes_available}};
    add_numbers(cJSON_AddObjectToObject(pl, "memory_estimate_bytes"), memory,
                sizeof memory / sizeof memory[0]);
    const named_number counters[] = {{"mobility_arrays", (double)cnt->mobility_arrays},
                                     {"fields", (double)cnt->fields},
                                     {"neighbour_lists", (double)cnt->neighbour_lists},
                                     {"laplacian_precomputes", (double)cnt->laplacian_precomputes},
                                     {"derivative_operators", (double)cnt->derivative_operators},
                                     {"stored_weights", (double)cnt->stored_weights},
                                     {"half_lists", (double)cnt->half_lists},
                                     {"applies", (double)cnt->applies},
                                     {"gradients", (double)cnt->gradients},
                                     {"hessians", (double)cnt->hessians},
                                     {"interpolations", (double)cnt->interpolations},
                                     {"solves", (double)cnt->solves},
                                     {"steps", (double)cnt->steps},
                                     {"refreshes", (double)cnt->refreshes},
                                     {"norms", (double)cnt->norms}};
    add_numbers(cJSON_AddObjectToObject(report, "counters"), counters,
                sizeof counters / sizeof counters[0]);
}

/* ---- files ------------------------------------------------------------------------------- */

/* Whether the outputs.fields entry `entry` selects the cloud's field `field`: its own name,
 * and for a task's name every field the task added (NAME_x.., NAME_exact.., NAME_error..). */
static int selected(const pst_scene *s, const char *entry, const char *field)
{
    if (strcmp(entry, field) == 0)
        return 1;
    size_t len = strlen(entry);
    if (strncmp(entry, field, len) != 0 || field[len] != '_')
        return 0;
    for (int k = 0; k < s->ntasks; ++k)
        if (strcmp(s->tasks[k].name, entry) == 0)
            return 1;
    return 0;
}

/* A copy of the cloud's particles with only the named fields, so that the writers (which
 * write every field) write the selection. */
static int select_fields(const pst_scene *s, const pst_cloud *c, char *const *names, int nnames,
                         pst_cloud **out, char *err, size_t errlen)
{
    const int dim = pst_cloud_dim(c);
    size_t n = pst_cloud_size(c);
    pst_cloud *o = NULL;
    if (pst_cloud_create(&o, dim, n, NULL) != PST_OK) {
        snprintf(err, errlen, "out of memory for the output selection");
        return PST_ENOMEM;
    }
    for (int d = 0; d < dim; ++d) {
        memcpy(pst_cloud_coord(o, d), pst_cloud_coord_const(c, d), n * sizeof(double));
        memcpy(pst_cloud_normal(o, d), pst_cloud_normal_const(c, d), n * sizeof(double));
    }
    memcpy(pst_cloud_volume(o), pst_cloud_volume_const(c), n * sizeof(double));
    memcpy(pst_cloud_kinds(o), pst_cloud_kinds_const(c), n);
    memcpy(pst_cloud_ids(o), pst_cloud_ids_const(c), n * sizeof(int64_t));
    pst_cloud *cm = (pst_cloud *)c; /* mobility and fields have no const accessors; read only */
    int st = PST_OK;
    if (pst_cloud_h_is_uniform(c)) {
        st = pst_cloud_set_h_uniform(o, pst_cloud_h_uniform(c), NULL);
    } else {
        double *h = pst_cloud_h_per_particle(o);
        if (h)
            memcpy(h, pst_cloud_h_array(c), n * sizeof(double));
        else
            st = PST_ENOMEM;
    }
    int nm = pst_cloud_mobility_ncomp(c);
    if (st == PST_OK && nm)
        st = pst_cloud_set_mobility(o, nm, NULL);
    for (int a = 0; st == PST_OK && a < nm; ++a)
        memcpy(pst_cloud_mobility(o, a), pst_cloud_mobility(cm, a), n * sizeof(double));
    for (int f = 0; st == PST_OK && f < nnames; ++f) {
        int found = 0;
        for (size_t q = 0; st == PST_OK && q < pst_cloud_nfields(c); ++q) {
            const char *name = pst_cloud_field_name(c, q);
            double *dst;
            if (!selected(s, names[f], name))
                continue;
            st = pst_cloud_add_field(o, name, &dst, NULL);
            if (st == PST_OK)
                memcpy(dst, pst_cloud_field_by_name(cm, name), n * sizeof(double));
            found = 1;
        }
        if (st == PST_OK && !found) {
            pst_cloud_destroy(o);
            snprintf(err, errlen, "outputs.fields: no field named '%s' (the scene's fields "
                                  "and task outputs are)", names[f]);
            return PST_EINPUT;
        }
    }
    if (st != PST_OK) {
        pst_cloud_destroy(o);
        snprintf(err, errlen, "cannot build the output selection: %s", pst_strerror(st));
        return st;
    }
    *out = o;
    return PST_OK;
}

int report_write_outputs(const pst_scene *s, const pst_cloud *c, const uint8_t *status,
                         cJSON *report, pst_run_counters *cnt, char *err, size_t errlen)
{
    const pst_cloud *out = c;
    pst_cloud *sel = NULL;
    int st = PST_OK;
    if ((s->out.csv || s->out.vtu) && s->out.nfields > 0) {
        st = select_fields(s, c, s->out.fields, s->out.nfields, &sel, err, errlen);
        out = sel;
    }
    char msg[PST_ERRLEN];
    if (st == PST_OK && s->out.csv) {
        st = pst_cloud_write_csv(out, s->out.csv, msg);
        if (st != PST_OK)
            snprintf(err, errlen, "outputs.csv: %s", msg);
        else
            cnt->files++;
    }
    if (st == PST_OK && s->out.vtu) {
        st = pst_cloud_write_vtk(out, s->out.vtu, status, s->out.vtu_compress ? PST_VTK_ZLIB : 0,
                                 msg);
        if (st != PST_OK)
            snprintf(err, errlen, "outputs.vtu: %s", msg);
        else
            cnt->files++;
    }
    pst_cloud_destroy(sel);
    if (st == PST_OK && s->out.report) {
        st = pst_write_atomic(s->out.report, pst_write_json, report, msg);
        if (st != PST_OK)
            snprintf(err, errlen, "outputs.report: %s", msg);
        else
            cnt->files++;
    }
    return st;
}

typedef struct {
    int dim;
    double *const *pts;
    size_t m;
    const double *value, *lap;
} points_job;

static void write_points(FILE *f, const void *job)
{
    const points_job *j = job;
    fprintf(f, j->dim == 2 ? "x,y,value,laplacian\n" : "x,y,z,value,laplacian\n");
    for (size_t q = 0; q < j->m; ++q) {
        for (int d = 0; d < j->dim; ++d)
            fprintf(f, "%.17g,", j->pts[d][q]);
        fprintf(f, "%.17g,%.17g\n", j->value[q], j->lap[q]);
    }
}

int report_write_points(const char *csv, const char *task, int dim, double *const pts[3],
                        size_t m, const double *value, const double *lap, char *err,
                        size_t errlen)
{
    char path[4096];
    const char *dot = strrchr(csv, '.'), *slash = strrchr(csv, '/');
    int stem = dot && (!slash || dot > slash) ? (int)(dot - csv) : (int)strlen(csv);
    snprintf(path, sizeof path, "%.*s_%s.csv", stem, csv, task);
    points_job job = {dim, pts, m, value, lap};
    char msg[PST_ERRLEN];
    int st = pst_write_atomic(path, write_points, &job, msg);
    if (st != PST_OK)
        snprintf(err, errlen, "task '%s': points output: %s", task, msg);
    return st;
}

/* One line for a solve's boundary groups: each group's type and count, and for a Neumann
 * group where its normals came from (the sources that gave none are left out). */
static void summary_groups(FILE *f, const cJSON *groups)
{
    if (!cJSON_GetArraySize(groups))
        return;
    fprintf(f, "    boundary groups:");
    int g = 0;
    const cJSON *o, *q;
    cJSON_ArrayForEach(o, groups) {
        fprintf(f, "%s %d %s %.0f", g ? "," : "", g,
                cJSON_GetStringValue(cJSON_GetObjectItem(o, "type")),
                cJSON_GetNumberValue(cJSON_GetObjectItem(o, "particles")));
        const char *sep = " (normals:";
        cJSON_ArrayForEach(q, cJSON_GetObjectItem(o, "normals")) {
            if (q->valuedouble > 0) {
                fprintf(f, "%s %s %.0f", sep, q->string, q->valuedouble);
                sep = ",";
            }
        }
        if (sep[0] == ',')
            fprintf(f, ")");
        ++g;
    }
    fprintf(f, "\n");
}

/* One line for a diffuse task's steps: the method, the step and its limit, the solver's work. */
static void summary_steps(FILE *f, const cJSON *sp)
{
    if (!sp)
        return;
    const cJSON *limit = cJSON_GetObjectItem(sp, "dt_limit");
    fprintf(f, "    %s: %.0f steps of dt %.4g (%s) to t = %.4g; rho %.4g, forward-Euler limit "
               "dt <= ",
            cJSON_GetStringValue(cJSON_GetObjectItem(sp, "method")),
            cJSON_GetNumberValue(cJSON_GetObjectItem(sp, "steps_done")),
            cJSON_GetNumberValue(cJSON_GetObjectItem(sp, "dt")),
            cJSON_GetStringValue(cJSON_GetObjectItem(sp, "dt_from")),
            cJSON_GetNumberValue(cJSON_GetObjectItem(sp, "t_reached")),
            cJSON_GetNumberValue(cJSON_GetObjectItem(sp, "rho")));
    if (limit)
        fprintf(f, "%.4g", limit->valuedouble);
    else
        fprintf(f, "any");
    fprintf(f, "; %.0f solver iterations, %.0f set-ups\n",
            cJSON_GetNumberValue(cJSON_GetObjectItem(sp, "iterations")),
            cJSON_GetNumberValue(cJSON_GetObjectItem(sp, "solver_setups")));
}

void report_summary(FILE *f, const cJSON *report)
{
    const cJSON *plan = cJSON_GetObjectItem(report, "plan");
    fprintf(f, "%s: %.0f particles, %d threads\n", cJSON_GetStringValue(cJSON_GetObjectItem(report, "scene")),
            cJSON_GetNumberValue(cJSON_GetObjectItem(plan, "particles")),
            (int)cJSON_GetNumberValue(cJSON_GetObjectItem(report, "threads")));
    const cJSON *t;
    cJSON_ArrayForEach(t, cJSON_GetObjectItem(report, "timers"))
        fprintf(f, "  %-12s %.3f s\n", t->string, t->valuedouble);
    cJSON_ArrayForEach(t, cJSON_GetObjectItem(report, "operators")) {
        const cJSON *st, *ph = cJSON_GetObjectItem(t, "phases");
        fprintf(f, "  operator %s (%s kernel): precompute %.3f s, rows:",
                cJSON_GetStringValue(cJSON_GetObjectItem(t, "scheme")),
                cJSON_GetStringValue(cJSON_GetObjectItem(t, "kernel")),
                cJSON_GetNumberValue(cJSON_GetObjectItem(ph, "precompute")));
        if (!cJSON_IsTrue(cJSON_GetObjectItem(t, "laplacian_rows")))
            fprintf(f, " none (derivatives only)");
        else
            cJSON_ArrayForEach(st, cJSON_GetObjectItem(t, "row_status"))
                if (st->valuedouble > 0)
                    fprintf(f, " %s %.0f", st->string, st->valuedouble);
        const cJSON *p = cJSON_GetObjectItem(t, "parameters");
        fprintf(f, "\n    cond_max %g, rank_tol %g, min_pair_distance %g h; fallback: %s\n",
                cJSON_GetNumberValue(cJSON_GetObjectItem(p, "cond_max")),
                cJSON_GetNumberValue(cJSON_GetObjectItem(p, "rank_tol")),
                cJSON_GetNumberValue(cJSON_GetObjectItem(p, "min_pair_distance")),
                cJSON_GetStringValue(cJSON_GetObjectItem(p, "fallback")));
    }
    cJSON_ArrayForEach(t, cJSON_GetObjectItem(report, "tasks")) {
        fprintf(f, "  task %s (%s)", cJSON_GetStringValue(cJSON_GetObjectItem(t, "name")),
                cJSON_GetStringValue(cJSON_GetObjectItem(t, "type")));
        const cJSON *sv = cJSON_GetObjectItem(t, "solver"), *nv;
        if (sv)
            fprintf(f, ": %s", cJSON_GetStringValue(cJSON_GetObjectItem(sv, "message")));
        const cJSON *shift = cJSON_GetObjectItem(sv, "mean_shift");
        if (shift)
            fprintf(f, "; mean of u fixed (periodic, no Dirichlet particle), lambda %.3e",
                    shift->valuedouble);
        const cJSON *es = cJSON_GetObjectItem(t, "exact_shift");
        if (es)
            fprintf(f, "; exact shifted by %.6g to u's mean", es->valuedouble);
        cJSON_ArrayForEach(nv, cJSON_GetObjectItem(t, "norms"))
            fprintf(f, ", %s %.3e", nv->string, nv->valuedouble);
        const cJSON *rp = cJSON_GetObjectItem(t, "region_particles");
        if (rp && cJSON_GetObjectItem(t, "norms"))
            fprintf(f, " over %.0f particles", rp->valuedouble);
        fprintf(f, ", %.3f s", cJSON_GetNumberValue(cJSON_GetObjectItem(t, "seconds")));
        if (sv)
            fprintf(f, " (set-up %.3f s)",
                    cJSON_GetNumberValue(cJSON_GetObjectItem(sv, "setup_seconds")));
        fprintf(f, "\n");
        summary_groups(f, cJSON_GetObjectItem(t, "boundary_groups"));
        summary_steps(f, cJSON_GetObjectItem(t, "steps"));
    }
}
