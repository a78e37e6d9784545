/* Moving particles of a diffuse task (the Lagrangian form: each particle carries its value of
 * u): the interior particles step by dt v (explicit Euler), the Dirichlet ones stay where the
 * boundary is; a periodic cloud folds them back into its box; the Verlet list is updated
 * (pst_nlist_update: a filter of the wide list while the moves stay within the skin, a
 * rebuild otherwise); a mobility given by expressions is sampled at the new positions; the
 * operator is computed again on its handle (pst_op_refresh). docs/time-stepping.md. */
#include "run_steps.h"

#include <omp.h>
#include <stdio.h>

/* A mobility of x, y, z at the particles' present positions. */
static int resample_mobility(run_state *r)
{
    const sc_mobility *m = &r->s->mobility;
    if (m->type != SC_MOB_EXPR)
        return PST_OK; /* none or a constant: nothing depends on the positions */
    for (int a = 0; a < r->plan.mobility_ncomp; ++a) {
        char key[64];
        snprintf(key, sizeof key,
                 m->ncomp == 1 ? "mobility.expression" : "mobility.expression[%d]", a);
        double *mob = pst_cloud_mobility(r->c, a);
        int st = run_eval_at_particles(r, key, m->expr[a], mob);
        size_t n = pst_cloud_size(r->c);
        for (size_t i = 0; st == PST_OK && i < n; ++i)
            if (!(mob[i] > 0))
                return run_fail(r, PST_EINPUT, "%s: %s: the mobility must be positive, got %g "
                                "at particle %lld (input order) after it moved", r->s->path,
                                key, mob[i], (long long)pst_cloud_ids_const(r->c)[i]);
        if (st != PST_OK)
            return st;
    }
    return PST_OK;
}

int steps_move(run_state *r, pst_op *op, double dt, double *const v[3], steps_row *row)
{
    size_t n = pst_cloud_size(r->c);
    const uint8_t *kind = pst_cloud_kinds_const(r->c);
    for (int d = 0; d < r->s->dim; ++d) {
        double *x = pst_cloud_coord(r->c, d);
#pragma omp parallel for schedule(static)
        for (size_t i = 0; i < n; ++i)
            if (kind[i] == PST_INTERIOR)
                x[i] += dt * v[d][i];
    }
    if (pst_cloud_periodic(r->c, NULL, NULL, NULL) > 0)
        pst_cloud_wrap(r->c);
    char msg[PST_ERRLEN];
    pst_nlist_update_info info;
    double t0 = omp_get_wtime();
    int st = pst_nlist_update(r->nl, r->c, &info, msg);
    double t1 = omp_get_wtime();
    if (st != PST_OK)
        return run_fail(r, st, "%s: neighbours of the moved particles: %s", r->s->path, msg);
    if ((st = resample_mobility(r)) != PST_OK)
        return st;
    st = pst_op_refresh(op, msg);
    if (st != PST_OK)
        return run_fail(r, st, "%s: operator %s of the moved particles: %s", r->s->path,
                        pst_op_scheme(op), msg);
    r->cnt.refreshes++;
    row->list_s = t1 - t0;
    row->refresh_s = omp_get_wtime() - t1;
    row->rebuilt = info.rebuilt;
    return PST_OK;
}
