/* The files of a diffuse task: the time series (tasks[].pvd: a VTK Collection of one VTU per
 * output step) and the per-step table (tasks[].steps_csv). Every file goes through
 * pst_write_atomic, whole or not at all; the .pvd is written again after each VTU, so that an
 * interrupted run leaves a series of whole files. */
#include "run_steps.h"

#include "text_file.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int steps_series_open(run_state *r, int k, size_t count, steps_series *sr)
{
    const char *pvd = r->s->tasks[k].pvd;
    *sr = (steps_series){0};
    if (!pvd)
        return PST_OK;
    size_t len = strlen(pvd) - 4; /* the scene checked the .pvd extension */
    sr->stem = malloc(len + 1);
    sr->d = calloc(count, sizeof *sr->d);
    sr->names = calloc(count, sizeof *sr->names);
    if (!sr->stem || !sr->d || !sr->names)
        return run_fail(r, PST_ENOMEM, "out of memory for the time series");
    memcpy(sr->stem, pvd, len);
    sr->stem[len] = '\0';
    sr->cap = count;
    return PST_OK;
}

int steps_series_add(run_state *r, int k, steps_series *sr, int step, double t,
                     const pst_op *op)
{
    const sc_task *task = &r->s->tasks[k];
    if (!sr->stem)
        return PST_OK;
    if (sr->n == sr->cap) /* the count was made from the same rule */
        return run_fail(r, PST_EINVAL, "%s: task '%s': more outputs than counted", r->s->path,
                        task->name);
    char path[4096], msg[PST_ERRLEN];
    int len = snprintf(path, sizeof path, "%s_%06d.vtu", sr->stem, step);
    if (len < 0 || (size_t)len >= sizeof path)
        return run_fail(r, PST_EINPUT, "%s: tasks[%d].pvd: the path is too long", r->s->path, k);
    const char *slash = strrchr(path, '/');
    if (!(sr->names[sr->n] = pst_strdup(slash ? slash + 1 : path)))
        return run_fail(r, PST_ENOMEM, "out of memory for the time series");
    int flags = r->s->out.vtu_compress ? PST_VTK_ZLIB : 0;
    int st = pst_cloud_write_vtk(r->c, path, pst_op_status(op), flags, msg);
    if (st != PST_OK)
        return run_fail(r, st, "%s: task '%s': time series: %s", r->s->path, task->name, msg);
    sr->d[sr->n] = (pst_pvd_dataset){t, 0, sr->names[sr->n]};
    ++sr->n;
    r->cnt.files += sr->n == 1 ? 2 : 1; /* the .pvd counts once */
    st = pst_write_pvd(task->pvd, sr->d, sr->n, msg);
    return st == PST_OK
               ? PST_OK
               : run_fail(r, st, "%s: task '%s': time series: %s", r->s->path, task->name, msg);
}

void steps_series_free(steps_series *sr)
{
    for (size_t q = 0; q < sr->n; ++q)
        free(sr->names[q]);
    free(sr->names);
    free(sr->d);
    free(sr->stem);
    *sr = (steps_series){0};
}

typedef struct {
    const steps_row *rows;
    size_t n;
} table_job;

static void write_table(FILE *f, const void *job)
{
    const table_job *j = job;
    fputs("step,t,dt,neighbour_seconds,rebuilt,refresh_seconds,apply_seconds,"
          "solver_setup_seconds,solve_seconds,iterations,residual,rho,max_abs_u\n",
          f);
    for (size_t q = 0; q < j->n; ++q) {
        const steps_row *w = &j->rows[q];
        fprintf(f, "%zu,%.17g,%.17g,%.6g,%d,%.6g,%.6g,%.6g,%.6g,%d,%.6g,%.17g,%.17g\n", q + 1,
                w->t, w->dt, w->list_s, w->rebuilt, w->refresh_s, w->apply_s, w->setup_s,
                w->solve_s, w->iterations, w->residual, w->rho, w->max_abs);
    }
}

int steps_write_table(run_state *r, int k, const steps_row *rows, size_t n)
{
    const sc_task *t = &r->s->tasks[k];
    if (!t->steps_csv)
        return PST_OK;
    table_job job = {rows, n};
    char msg[PST_ERRLEN];
    int st = pst_write_atomic(t->steps_csv, write_table, &job, msg);
    if (st != PST_OK)
        return run_fail(r, st, "%s: task '%s': steps_csv: %s", r->s->path, t->name, msg);
    r->cnt.files++;
    return PST_OK;
}
