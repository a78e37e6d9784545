/* The interpolation tasks: a field and its Laplacian at points off the cloud, read from a
 * CSV file or laid on a lattice box. */
#include "run_state.h"

#include "progress.h"
#include "report.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A whole token as a finite number. */
static int parse_number(const char *tok, double *v)
{
    char *end;
    *v = strtod(tok, &end);
    return end != tok && *end == '\0' && isfinite(*v);
}

/* The x, y[, z] columns of a CSV file (any other columns are ignored) into pts[d][k]. */
static int read_points_csv(run_state *r, const char *path, double *pts[3], size_t *m)
{
    FILE *f = fopen(path, "r");
    if (!f)
        return run_fail(r, PST_EIO, "%s: cannot open the points file", path);
    char line[4096];
    int col[3] = {-1, -1, -1}, ncols = 0, st = PST_OK;
    if (fgets(line, sizeof line, f)) {
        for (char *tok = strtok(line, ",\r\n"); tok; tok = strtok(NULL, ",\r\n"), ++ncols)
            for (int d = 0; d < 3; ++d)
                if (strcmp(tok, (const char *[]){"x", "y", "z"}[d]) == 0)
                    col[d] = ncols;
    }
    for (int d = 0; d < r->s->dim && st == PST_OK; ++d)
        if (col[d] < 0)
            st = run_fail(r, PST_EINPUT, "%s:1: the header has no column '%c'", path, "xyz"[d]);
    size_t cap = 1024, n = 0;
    for (int d = 0; d < 3 && st == PST_OK; ++d)
        if (!(pts[d] = calloc(cap, sizeof(double))))
            st = run_fail(r, PST_ENOMEM, "out of memory for the points");
    for (long lineno = 2; st == PST_OK && fgets(line, sizeof line, f); ++lineno) {
        if (line[strspn(line, " \r\n")] == '\0')
            continue;
        if (n == cap) {
            cap *= 2;
            for (int d = 0; d < 3 && st == PST_OK; ++d) {
                double *grown = realloc(pts[d], cap * sizeof(double));
                if (!grown)
                    st = run_fail(r, PST_ENOMEM, "out of memory for the points");
                else
                    pts[d] = grown;
            }
        }
        int c = 0;
        for (char *tok = strtok(line, ",\r\n"); tok && st == PST_OK;
             tok = strtok(NULL, ",\r\n"), ++c)
            for (int d = 0; d < r->s->dim; ++d)
                if (c == col[d] && !parse_number(tok, &pts[d][n]))
                    st = run_fail(r, PST_EINPUT, "%s:%ld: column %c: '%s' is not a finite number",
                                  path, lineno, "xyz"[d], tok);
        if (st == PST_OK && c != ncols)
            st = run_fail(r, PST_EINPUT, "%s:%ld: %d columns, the header has %d", path, lineno, c,
                          ncols);
        ++n;
    }
    fclose(f);
    *m = n;
    return st;
}

/* The points of an interpolation task: the x, y[, z] columns of a CSV, or a lattice box. */
static int task_points(run_state *r, const sc_task *t, double *pts[3], size_t *m)
{
    if (t->points_file)
        return read_points_csv(r, t->points_file, pts, m);
    pst_lattice_opts lo;
    pst_lattice_defaults(&lo);
    lo.dim = r->s->dim;
    for (int d = 0; d < 3; ++d) {
        lo.lo[d] = t->points_lo[d];
        lo.hi[d] = t->points_hi[d];
    }
    lo.s0 = t->points_spacing;
    pst_cloud *pc = NULL;
    char msg[PST_ERRLEN];
    int st = pst_cloud_lattice(&pc, &lo, msg);
    if (st != PST_OK)
        return run_fail(r, st, "%s: task '%s': points: %s", r->s->path, t->name, msg);
    *m = pst_cloud_size(pc);
    for (int d = 0; d < 3; ++d) {
        pts[d] = malloc((*m ? *m : 1) * sizeof(double));
        for (size_t q = 0; pts[d] && q < *m; ++q)
            pts[d][q] = d < r->s->dim ? pst_cloud_coord_const(pc, d)[q] : 0.0;
    }
    pst_cloud_destroy(pc);
    if (!pts[0] || !pts[1] || !pts[2])
        return run_fail(r, PST_ENOMEM, "out of memory for %zu points", *m);
    return PST_OK;
}

int run_interpolate(run_state *r, int k, cJSON *tj)
{
    const sc_task *t = &r->s->tasks[k];
    double *pts[3] = {NULL, NULL, NULL}, *value = NULL, *lap = NULL;
    size_t m = 0, fallbacks = 0;
    int st = task_points(r, t, pts, &m);
    if (st == PST_OK) {
        value = malloc((m ? m : 1) * sizeof *value);
        lap = malloc((m ? m : 1) * sizeof *lap);
        if (!value || !lap)
            st = run_fail(r, PST_ENOMEM, "out of memory for %zu points", m);
    }
    if (st == PST_OK) {
        char msg[PST_ERRLEN], label[PST_MAX_NAME + 8];
        snprintf(label, sizeof label, "task %s", t->name);
        cli_progress pg;
        progress_begin(&pg, !r->o->quiet, label, "points");
        pst_progress hook = progress_hook(&pg);
        pst_op_set_progress(r->base, &hook);
        double t0 = omp_get_wtime();
        st = pst_op_interpolate(r->base, (const double *const *)pts, m,
                                pst_cloud_field_by_name(r->c, t->field), value, lap, &fallbacks,
                                msg);
        pst_op_set_progress(r->base, NULL);
        progress_end(&pg);
        cJSON_AddNumberToObject(tj, "seconds", omp_get_wtime() - t0);
        r->cnt.interpolations++;
        if (st != PST_OK)
            st = run_fail(r, st, "%s: task '%s': %s", r->s->path, t->name, msg);
    }
    if (st == PST_OK) {
        cJSON_AddNumberToObject(tj, "points", (double)m);
        cJSON_AddNumberToObject(tj, "fallback_points", (double)fallbacks);
        st = run_task_norms(r, k, tj, 1, &value, pts, m);
    }
    if (st == PST_OK && r->s->out.csv)
        st = report_write_points(r->s->out.csv, t->name, r->s->dim, pts, m, value, lap, r->err,
                                 r->errlen);
    if (st == PST_OK && r->s->out.csv)
        r->cnt.files++;
    for (int d = 0; d < 3; ++d)
        free(pts[d]);
    free(value);
    free(lap);
    return st;
}
