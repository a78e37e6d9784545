/* What a task leaves behind: its output fields on the cloud and its error norms against the
 * exact expressions (moved to u's mean where a solve fixed it), over the task's region. */
#include "run_state.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The particles of a task's region: interior particles, all, or those inside a box; *count
 * of them. A Laplacian or divergence task has no L u at its boundary rows (a Dirichlet row is
 * the identity, a Neumann row the flux n . grad u), so its region keeps interior particles
 * only. */
static uint8_t *region_mask(run_state *r, const sc_task *t, size_t *count)
{
    size_t n = pst_cloud_size(r->c);
    uint8_t *mask = malloc(n ? n : 1);
    if (!mask)
        return NULL;
    const uint8_t *kind = r->task_kinds ? r->task_kinds : pst_cloud_kinds_const(r->c);
    int rows_only = t->type == SC_TASK_LAPLACIAN || t->type == SC_TASK_DIVERGENCE;
    int interior_only = rows_only || t->region == SC_REGION_INTERIOR;
    *count = 0;
    for (size_t i = 0; i < n; ++i) {
        mask[i] = !interior_only || kind[i] == PST_INTERIOR;
        if (t->region != SC_REGION_ALL && t->region != SC_REGION_INTERIOR) {
            for (int d = 0; d < r->s->dim; ++d) {
                double x = pst_cloud_coord_const(r->c, d)[i];
                mask[i] &= x >= t->region_lo[d] && x <= t->region_hi[d];
            }
        }
        *count += mask[i];
    }
    return mask;
}

/* Field name of component a of a task's result: NAME[_infix] for one component, else
 * NAME[_infix]_x.. (gradient) or NAME[_infix]_xx.. (Hessian), the components in the order of
 * the task's result (tasks[].exact). */
static void component_name(const sc_task *t, int ncomp, int a, const char *infix, char *name)
{
    static const char *const grad[] = {"x", "y", "z"};
    static const char *const hess2[] = {"xx", "yy", "xy"};
    static const char *const hess3[] = {"xx", "yy", "zz", "xy", "xz", "yz"};
    const char *sfx = ncomp == 1                     ? NULL
                      : t->type == SC_TASK_GRADIENT ? grad[a]
                      : ncomp == 3                  ? hess2[a]
                                                    : hess3[a];
    snprintf(name, PST_MAX_NAME, "%s%s%s%s%s", t->name, infix ? "_" : "", infix ? infix : "",
             sfx ? "_" : "", sfx ? sfx : "");
}

static int add_field(run_state *r, const sc_task *t, const char *name, double **out)
{
    char why[PST_ERRLEN];
    if (pst_cloud_add_field(r->c, name, out, why) != PST_OK)
        return run_fail(r, PST_EINPUT, "%s: task '%s': output field %s: %s", r->s->path,
                        t->name, name, why);
    return PST_OK;
}

int run_add_outputs(run_state *r, const sc_task *t, int ncomp, double *out[6])
{
    for (int a = 0; a < ncomp; ++a) {
        char name[PST_MAX_NAME];
        component_name(t, ncomp, a, NULL, name);
        int st = add_field(r, t, name, &out[a]);
        if (st != PST_OK)
            return st;
    }
    return PST_OK;
}

/* NAME_exact and NAME_error (approx - exact) beside a task's output fields. */
static int add_exact_fields(run_state *r, const sc_task *t, int ncomp,
                            double *const *approx, double *const *exact)
{
    size_t n = pst_cloud_size(r->c);
    double *ex[6], *er[6];
    int st = PST_OK;
    for (int a = 0; a < ncomp && st == PST_OK; ++a) { /* all exact fields, then all errors */
        char name[PST_MAX_NAME];
        component_name(t, ncomp, a, "exact", name);
        st = add_field(r, t, name, &ex[a]);
    }
    for (int a = 0; a < ncomp && st == PST_OK; ++a) {
        char name[PST_MAX_NAME];
        component_name(t, ncomp, a, "error", name);
        st = add_field(r, t, name, &er[a]);
    }
    for (int a = 0; a < ncomp && st == PST_OK; ++a)
        for (size_t i = 0; i < n; ++i) {
            ex[a][i] = exact[a][i];
            er[a][i] = approx[a][i] - exact[a][i];
        }
    return st;
}

/* A solve that fixed the mean found u only up to a constant (sum_I V_I u_I = 0): the exact
 * solution is moved by one constant to u's V-weighted mean, over every particle as the
 * constraint is, so that the errors measure u's shape; the shift goes into the report. */
static void shift_exact(run_state *r, cJSON *tj, const double *u, double *exact)
{
    size_t n = pst_cloud_size(r->c);
    const double *V = pst_cloud_volume_const(r->c);
    double vu = 0, ve = 0, vol = 0;
    for (size_t i = 0; i < n; ++i) {
        vu += V[i] * u[i];
        ve += V[i] * exact[i];
        vol += V[i];
    }
    double shift = vol > 0 ? (vu - ve) / vol : 0;
    for (size_t i = 0; i < n; ++i)
        exact[i] += shift;
    cJSON_AddNumberToObject(tj, "exact_shift", shift);
}

int run_keep_status(run_state *r, const pst_op *op)
{
    size_t n = pst_cloud_size(r->c);
    if (!r->status && !(r->status = malloc(n ? n : 1)))
        return run_fail(r, PST_ENOMEM, "out of memory for the row status");
    memcpy(r->status, pst_op_status(op), n);
    return PST_OK;
}

/* Evaluate the task's exact expressions and its norms of approx against them; the norms go
 * into the task's report object. `pts` non-NULL: values at m points instead of particles. */
int run_task_norms(run_state *r, int k, cJSON *tj, int ncomp, double *const *approx,
                   double *const pts[3], size_t m)
{
    const sc_task *t = &r->s->tasks[k];
    if (!t->nexact || (!t->nnorms && pts))
        return PST_OK;
    if (t->nexact != ncomp)
        return run_fail(r, PST_EINPUT,
                        "%s: tasks[%d].exact: %d expressions for a result with %d "
                        "components",
                        r->s->path, k, t->nexact, ncomp);
    size_t n = pts ? m : pst_cloud_size(r->c);
    double *exact[6] = {NULL};
    size_t in_region = n;
    uint8_t *mask = pts ? NULL : region_mask(r, t, &in_region);
    int st = PST_OK;
    for (int a = 0; a < ncomp && st == PST_OK; ++a) {
        char key[64];
        snprintf(key, sizeof key, ncomp == 1 ? "tasks[%d].exact" : "tasks[%d].exact[%d]", k, a);
        exact[a] = malloc((n ? n : 1) * sizeof(double));
        if (!exact[a])
            st = run_fail(r, PST_ENOMEM, "out of memory for the exact values");
        else
            st = pts ? run_eval_at_points(r, key, t->exact[a], pts, m, exact[a])
                     : run_eval_at_particles(r, key, t->exact[a], exact[a]);
    }
    if (st == PST_OK && !pts && r->task_mean_fixed)
        shift_exact(r, tj, approx[0], exact[0]);
    if (st == PST_OK && !pts)
        st = add_exact_fields(r, t, ncomp, approx, exact);
    if (st == PST_OK && t->nnorms)
        cJSON_AddNumberToObject(tj, "region_particles", (double)in_region);
    cJSON *norms = t->nnorms ? cJSON_AddObjectToObject(tj, "norms") : NULL;
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
            st = run_fail(r, st, "%s: task '%s': %s", r->s->path, t->name, msg);
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
