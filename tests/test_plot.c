/* Plot series (src/plot.c, docs/plots.md) from small hand-made sweep CSVs, without gnuplot:
 * means and standard deviations over the seeds (ok rows only), the files split by a key that
 * varies within a scheme, the summary's slopes in the legend, the LP-MPS / QSFDI time ratio,
 * the phase bars at the finest spacing, the iterations of solves, the default norm and the
 * reasons of skipped plots. */
#define _POSIX_C_SOURCE 200809L /* mkstemp */
#include "check.h"
#include "plot.h"
#include "sweep.h"

#include "pstencil.h"

#include <cjson/cJSON.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char path[64];

typedef struct {
    const char *scheme, *jitter, *spacing, *seed, *task, *type, *status;
    double qsfdi11, lv95, t_pre, t_task, iterations, particles;
} row;

/* one CSV row: the grid keys given (ncols_keys of scheme, jitter, spacing, seed), the rest */
static void put_row(FILE *f, const row *r, int with_jitter)
{
    fprintf(f, "%s,", r->scheme);
    if (with_jitter)
        fprintf(f, "%s,", r->jitter);
    fprintf(f, "%s,%s,", r->spacing, r->seed);
    /* dim, particles, neighbours_estimate, task, type */
    fprintf(f, "2,%.17g,20,%s,%s,", r->particles, r->task, r->type);
    /* rel_l2 (empty), qsfdi11, qsfdi11_normalised, lv78, lv95, max_abs, max_rel */
    fprintf(f, ",%.17g,,,%.17g,,,", r->qsfdi11, r->lv95);
    /* iterations, converged, rel_residual */
    if (r->iterations > 0)
        fprintf(f, "%.17g,1,1e-9,", r->iterations);
    else
        fprintf(f, ",,,");
    /* t_cloud, t_neighbours, t_geometry, t_moments, t_inversion, t_weights, t_precompute,
     * t_task, t_total, cpu */
    fprintf(f, "0.01,0.02,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,", 0.1 * r->t_pre,
            0.5 * r->t_pre, 0.3 * r->t_pre, 0.1 * r->t_pre, r->t_pre, r->t_task,
            r->t_pre + r->t_task + 0.5, 2 * (r->t_pre + r->t_task + 0.5));
    /* peak_rss_bytes, memory_estimate, rows_*, status, message */
    fprintf(f, "1000,2000,100,0,0,0,0,%s,\n", r->status);
}

static void header(FILE *f, int with_jitter)
{
    fprintf(f, "operator.scheme,%scloud.spacing,cloud.seed", with_jitter ? "cloud.jitter," : "");
    for (int q = 0; q < pst_sweep_ncolumns; ++q)
        fprintf(f, ",%s", pst_sweep_columns[q]);
    fprintf(f, "\n");
}

static int build(pst_plot_set *ps, const char *norm, int use_summary)
{
    pst_csv_table t;
    char err[512];
    int st = pst_csv_read_table(&t, path, 0, err);
    CHECK(st == PST_OK);
    if (st != PST_OK) {
        fprintf(stderr, "%s\n", err);
        return st;
    }
    cJSON *sum = use_summary ? pst_sweep_summary(&t, "cloud.spacing", "cloud.seed") : NULL;
    CHECK(!use_summary || sum);
    st = pst_plot_build(&t, sum, norm, ps, err, sizeof err);
    if (st != PST_OK)
        printf("  pst_plot_build: %s\n", err);
    cJSON_Delete(sum);
    pst_csv_table_free(&t);
    return st;
}

static const pst_plot_series *series(const pst_plot *p, const char *label_prefix)
{
    for (int s = 0; p && s < p->nseries; ++s)
        if (strncmp(p->series[s].label, label_prefix, strlen(label_prefix)) == 0)
            return &p->series[s];
    return NULL;
}

static int skipped(const pst_plot_set *ps, const char *text)
{
    for (int i = 0; i < ps->nskipped; ++i)
        if (strstr(ps->skipped[i], text))
            return 1;
    return 0;
}

/* qsfdi and lpmps, K = 0.2 and 0.4, s0 = 0.1 and 0.05, seeds 1 and 2: qsfdi11 = a s0^p (1 -+
 * 0.1), p = 2 (qsfdi) and 1.5 (lpmps); times t_pre = (1 + seed) and t_task = 1 for qsfdi,
 * t_pre = 2 (1 + K) seed and t_task = 0 for lpmps; one failed row with absurd values. */
static void test_laplacian_sweep(void)
{
    FILE *f = fopen(path, "w");
    header(f, 1);
    const char *schemes[2] = {"qsfdi", "lpmps"}, *jit[2] = {"0.2", "0.4"};
    const char *sp[2] = {"0.1", "0.05"}, *seeds[2] = {"1", "2"};
    for (int a = 0; a < 2; ++a)
        for (int b = 0; b < 2; ++b)
            for (int c = 0; c < 2; ++c)
                for (int d = 0; d < 2; ++d) {
                    double K = atof(jit[b]), s = atof(sp[c]), seed = d + 1;
                    double p = a == 0 ? 2 : 1.5, amp = (1 + K) * (a == 0 ? 1 : 3);
                    row r = {schemes[a], jit[b], sp[c], seeds[d], "lap", "laplacian", "ok",
                             amp * pow(s, p) * (d ? 1.1 : 0.9), 0.5 * amp * pow(s, p),
                             a == 0 ? 1 + seed : 2 * (1 + K) * seed, a == 0 ? 1 : 0, 0,
                             s > 0.07 ? 100 : 400};
                    put_row(f, &r, 1);
                }
    row bad = {"qsfdi", "0.2", "0.05", "3", "lap", "laplacian", "failed", 1e9, 1e9, 1e9, 1e9,
               0, 400};
    put_row(f, &bad, 1);
    fclose(f);

    pst_plot_set ps;
    CHECK(build(&ps, NULL, 1) == PST_OK);
    CHECK(strcmp(ps.norm, "qsfdi11") == 0); /* rel_l2 is empty: the next norm of the order */

    /* error_vs_s0: split by the jitter (it varies within a scheme) */
    CHECK(pst_plot_find(&ps, "error_vs_s0") == NULL);
    const pst_plot *e2 = pst_plot_find(&ps, "error_vs_s0_jitter-0.2");
    const pst_plot *e4 = pst_plot_find(&ps, "error_vs_s0_jitter-0.4");
    CHECK(e2 && e4);
    CHECK(e2 && e2->logx && e2->logy && e2->nseries == 2 && e2->kind == PST_PLOT_LINES);
    CHECK(e2 && strstr(e2->title, "cloud.jitter = 0.2"));
    const pst_plot_series *q = series(e2, "qsfdi"), *l = series(e2, "lpmps");
    CHECK(q && l);
    if (q && l) {
        CHECK(strcmp(q->label, "qsfdi (slope 2.00)") == 0);
        CHECK(strcmp(l->label, "lpmps (slope 1.50)") == 0);
        CHECK_INT(q->n, 2);
        /* increasing x: 0.05, then 0.1; the failed row (1e9) is not in the mean */
        CHECK_NEAR(q->x[0], 0.05, 1e-15);
        CHECK_NEAR(q->x[1], 0.1, 1e-15);
        CHECK_NEAR(q->y[0], 1.2 * 0.0025, 1e-15);
        CHECK_NEAR(q->y[1], 1.2 * 0.01, 1e-15);
        /* sample std of 0.9 m and 1.1 m: 0.1 sqrt(2) m */
        CHECK_NEAR(q->err[1], 0.1 * sqrt(2.0) * 1.2 * 0.01, 1e-15);
        CHECK_NEAR(l->y[1], 3 * 1.2 * pow(0.1, 1.5), 1e-14);
    }
    q = series(e4, "qsfdi");
    CHECK(q && q->n == 2);
    if (q)
        CHECK_NEAR(q->y[0], 1.4 * 0.0025, 1e-15);

    /* error_vs_time: x = mean t_total = mean(t_pre) + t_task + 0.5, y = the same means */
    const pst_plot *t2 = pst_plot_find(&ps, "error_vs_time_jitter-0.2");
    q = series(t2, "qsfdi");
    l = series(t2, "lpmps");
    CHECK(q && l && strcmp(q->label, "qsfdi") == 0);
    if (q && l) {
        CHECK_NEAR(q->x[0], 2.5 + 1 + 0.5, 1e-14); /* both spacings: the same times */
        CHECK_NEAR(l->x[0], 2 * 1.2 * 1.5 + 0.5, 1e-14);
        CHECK_NEAR(q->y[0] + q->y[1], 1.2 * (0.0025 + 0.01), 1e-15);
    }

    /* time ratio: mean(t_pre + t_task) of lpmps over qsfdi = 3 (1 + K) / 3.5 */
    const pst_plot *rj = pst_plot_find(&ps, "time_ratio_vs_jitter");
    CHECK(rj && rj->nseries == 2 && !rj->logx && !rj->logy);
    l = series(rj, "spacing 0.05");
    CHECK(l && l->n == 2);
    if (l) {
        CHECK_NEAR(l->x[0], 0.2, 1e-15);
        CHECK_NEAR(l->x[1], 0.4, 1e-15);
        CHECK_NEAR(l->y[0], 3 * 1.2 / 3.5, 1e-14);
        CHECK_NEAR(l->y[1], 3 * 1.4 / 3.5, 1e-14);
    }
    CHECK(pst_plot_find(&ps, "time_ratio_vs_h") == NULL);
    CHECK(skipped(&ps, "time_ratio_vs_h.png: cloud.h_ratio is not a grid key"));

    /* phases at the finest spacing (0.05): 4 bars, t_moments = 0.5 t_pre */
    const pst_plot *ph = pst_plot_find(&ps, "phases");
    CHECK(ph && ph->kind == PST_PLOT_STACKED && ph->ncat == 4 && ph->nseries == 5);
    if (ph && ph->ncat == 4 && ph->nseries == 5) {
        CHECK(strcmp(ph->cat[0], "qsfdi 0.2") == 0);
        CHECK(strcmp(ph->cat[3], "lpmps 0.4") == 0);
        CHECK(strstr(ph->title, "cloud.spacing = 0.05") != NULL);
        CHECK_NEAR(ph->series[1].y[0], 0.5 * 2.5, 1e-14);  /* qsfdi moments */
        CHECK_NEAR(ph->series[4].y[0], 1, 1e-15);          /* qsfdi t_task  */
        CHECK_NEAR(ph->series[1].y[3], 0.5 * 2 * 1.4 * 1.5, 1e-14);
        CHECK_NEAR(ph->series[4].y[3], 0, 0);
    }
    CHECK(pst_plot_find(&ps, "iterations_vs_n") == NULL);
    CHECK(skipped(&ps, "iterations_vs_n.png: no ok rows of a solve task"));
    pst_plot_set_free(&ps);

    /* --norm lv95; without a summary: no slopes */
    CHECK(build(&ps, "lv95", 0) == PST_OK);
    CHECK(strcmp(ps.norm, "lv95") == 0);
    q = series(pst_plot_find(&ps, "error_vs_s0_jitter-0.4"), "qsfdi");
    CHECK(q && strcmp(q->label, "qsfdi") == 0);
    if (q) {
        CHECK_NEAR(q->y[1], 0.5 * 1.4 * 0.01, 1e-15);
        CHECK_NEAR(q->err[1], 0, 1e-18);
    }
    pst_plot_set_free(&ps);
    char err[PST_ERRLEN];
    pst_csv_table t;
    CHECK(pst_csv_read_table(&t, path, 0, err) == PST_OK);
    CHECK(pst_plot_build(&t, NULL, "l2", &ps, err, sizeof err) == PST_EINPUT);
    CHECK(strstr(err, "unknown norm 'l2'") != NULL);
    pst_csv_table_free(&t);
}

/* Solves: mean iterations against mean particles, not-converged rows left out; one scheme
 * and one jitter: no split, no ratio. */
static void test_solve_sweep(void)
{
    FILE *f = fopen(path, "w");
    header(f, 0);
    const char *sp[2] = {"0.1", "0.05"};
    for (int c = 0; c < 2; ++c)
        for (int d = 0; d < 3; ++d) {
            char seed[16];
            snprintf(seed, sizeof seed, "%d", d + 1);
            const char *status = d == 2 ? "not-converged" : "ok";
            row r = {"qsfdi", "0", sp[c], seed, "poisson", "solve", status, 0.01 / (c + 1), 0.02,
                     1, 1, d == 2 ? 2000 : 10 * (c + 1) + 2 * d, c ? 400 : 100};
            put_row(f, &r, 0);
        }
    fclose(f);
    pst_plot_set ps;
    CHECK(build(&ps, NULL, 1) == PST_OK);
    const pst_plot *it = pst_plot_find(&ps, "iterations_vs_n");
    CHECK(it && it->logx && !it->logy && it->nseries == 1);
    const pst_plot_series *s = series(it, "qsfdi");
    CHECK(s && s->n == 2);
    if (s && s->n == 2) {
        CHECK_NEAR(s->x[0], 100, 0);
        CHECK_NEAR(s->x[1], 400, 0);
        CHECK_NEAR(s->y[0], 11, 1e-14); /* 10 and 12; not 2000 */
        CHECK_NEAR(s->y[1], 21, 1e-14);
        CHECK_NEAR(s->err[1], sqrt(2.0), 1e-14);
    }
    const pst_plot *e = pst_plot_find(&ps, "error_vs_s0");
    CHECK(e && e->nseries == 1);
    CHECK(skipped(&ps, "time_ratio_vs_jitter.png: needs ok rows of both qsfdi and lpmps"));
    pst_plot_set_free(&ps);

    /* not a sweep CSV */
    f = fopen(path, "w");
    fprintf(f, "a,b\n1,2\n");
    fclose(f);
    pst_csv_table t;
    char err[PST_ERRLEN];
    CHECK(pst_csv_read_table(&t, path, 0, err) == PST_OK);
    CHECK(pst_plot_build(&t, NULL, NULL, &ps, err, sizeof err) == PST_EINPUT);
    CHECK(strstr(err, "not a sweep CSV") != NULL);
    pst_csv_table_free(&t);
}

int main(void)
{
    snprintf(path, sizeof path, "/tmp/pst_plot_XXXXXX");
    int fd = mkstemp(path);
    if (fd < 0) {
        printf("mkstemp failed\n");
        return 1;
    }
    close(fd);
    test_laplacian_sweep();
    test_solve_sweep();
    remove(path);
    return check_summary("test_plot");
}
