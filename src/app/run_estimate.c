/* The estimate tasks: the Laplacian (or divergence) of a field at the interior particles, its
 * gradient and its Hessian, with the base operator. */
#include "run_state.h"

#include "progress.h"

#include <omp.h>
#include <stdio.h>

int run_estimate(run_state *r, int k, cJSON *tj)
{
    const sc_task *t = &r->s->tasks[k];
    const int dim = r->s->dim;
    int ncomp = t->type == SC_TASK_GRADIENT ? dim
                : t->type == SC_TASK_HESSIAN ? (dim == 2 ? 3 : 6)
                                             : 1;
    double *out[6] = {NULL};
    int st = run_add_outputs(r, t, ncomp, out);
    if (st != PST_OK)
        return st;
    const double *u = pst_cloud_field_by_name(r->c, t->field);
    char label[PST_MAX_NAME + 8];
    snprintf(label, sizeof label, "task %s", t->name);
    cli_progress pg; /* the applies report nothing: their line has the clock only */
    progress_begin(&pg, !r->o->quiet, label, "rows");
    pst_progress hook = progress_hook(&pg);
    pst_op_set_progress(r->base, &hook);
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
    pst_op_set_progress(r->base, NULL);
    progress_end(&pg);
    if (st != PST_OK)
        return run_fail(r, st, "%s: task '%s': the scheme cannot compute it", r->s->path, t->name);
    return run_task_norms(r, k, tj, ncomp, out, NULL, 0);
}
