/* DIR/analysis.json: every number `pstencil analyse` prints, with the operator's parameters
 * and the von Neumann options (cJSON, written atomically). docs/cli.md. */
#include "analyse.h"

#include "pstencil.h"
#include "report.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

/* A number, only when finite: no NaN or infinity reaches the file. */
static void num(cJSON *o, const char *name, double v)
{
    if (isfinite(v))
        cJSON_AddNumberToObject(o, name, v);
}

static cJSON *dmp_case(const pst_dmp_case *r, int linear)
{
    cJSON *o = cJSON_CreateObject();
    num(o, "boundary_min", r->gmin);
    num(o, "boundary_max", r->gmax);
    num(o, "violations", (double)r->violations);
    num(o, "max_overshoot_fraction", r->overshoot);
    if (linear)
        num(o, "max_abs_error", r->max_err);
    return o;
}

static cJSON *build(const pst_analysis *an, const char *scene_path)
{
    cJSON *r = cJSON_CreateObject();
    cJSON_AddStringToObject(r, "scene", scene_path);
    cJSON *op = report_parameters(&an->opts); /* the thresholds and fallback chain */
    cJSON_AddStringToObject(op, "kernel", pst_kernel_name(an->opts.kernel));
    cJSON_AddItemToObject(r, "operator", op);

    const pst_spectrum *sp = &an->spectrum;
    num(r, "particles", (double)sp->particles);
    num(r, "unknowns", (double)sp->n);
    cJSON *spec = cJSON_AddObjectToObject(r, "spectrum");
    num(spec, "radius", sp->radius);
    num(spec, "min_abs", sp->min_abs);
    num(spec, "wrong_sign", (double)sp->wrong_sign);
    num(spec, "max_re", sp->max_re);

    const pst_vonneumann *vn = &an->vn;
    cJSON *v = cJSON_AddObjectToObject(r, "von_neumann");
    num(v, "tau", vn->tau);
    num(v, "waves", vn->waves);
    num(v, "s0", vn->s0);
    cJSON_AddStringToObject(v, "s0_source", an->s0_from_spacing
                                                ? "cloud.spacing"
                                                : "mean nearest-neighbour distance");
    num(v, "wave_vectors", (double)vn->nk);
    num(v, "rows", (double)vn->rows);
    num(v, "max_abs", vn->max_abs);
    num(v, "pairs_above_one", (double)vn->over);
    num(v, "fraction_above_one", vn->over_fraction);
    num(v, "particles_above_one", (double)vn->particles_over);
    num(v, "particles_above_one_boundary_adjacent", (double)vn->particles_over_adjacent);
    num(v, "boundary_adjacent_rows", (double)vn->adjacent_rows);

    const pst_op_audit *au = &an->audit;
    cJSON *m = cJSON_AddObjectToObject(r, "monotonicity");
    num(m, "rows_audited", (double)au->rows);
    num(m, "rows_positive_offdiag", (double)au->rows_positive_offdiag);
    num(m, "positive_offdiag", (double)au->positive_offdiag);
    num(m, "rows_not_dominant", (double)au->rows_not_dominant);
    if (au->lemma3_sign_mixed >= 0) { /* -1: the scheme has no Lemma 3 bracket */
        num(m, "lemma3_sign_mixed", (double)au->lemma3_sign_mixed);
        num(m, "lemma3_xi_large", (double)au->lemma3_xi_large);
    }
    num(m, "diagonal_rows", (double)an->diag_rows);
    num(m, "nonpositive_diagonal", (double)an->nonpositive_diag);

    const pst_dmp *d = &an->dmp;
    cJSON *mp = cJSON_AddObjectToObject(r, "maximum_principle");
    cJSON_AddBoolToObject(mp, "applicable", d->applicable);
    num(mp, "dirichlet", (double)d->dirichlet);
    if (d->applicable) {
        cJSON_AddBoolToObject(mp, "singular", d->singular);
        if (d->singular) {
            cJSON_AddStringToObject(mp, "finding", d->why);
        } else {
            num(mp, "step_x", d->xmid);
            cJSON_AddItemToObject(mp, "step", dmp_case(&d->step, 0));
            cJSON_AddItemToObject(mp, "linear", dmp_case(&d->linear, 1));
        }
    }
    return r;
}

static void write_text(FILE *f, const void *job)
{
    fputs(job, f);
    fputc('\n', f);
}

int pst_analysis_write_json(const pst_analysis *an, const char *scene_path, const char *path,
                            char *err, size_t errlen)
{
    cJSON *r = build(an, scene_path);
    char *text = r ? cJSON_Print(r) : NULL;
    cJSON_Delete(r);
    if (!text) {
        snprintf(err, errlen, "%s: out of memory for the JSON text", path);
        return PST_ENOMEM;
    }
    char msg[PST_ERRLEN];
    int st = pst_write_atomic(path, write_text, text, msg);
    if (st != PST_OK)
        snprintf(err, errlen, "%s", msg);
    free(text);
    return st;
}
