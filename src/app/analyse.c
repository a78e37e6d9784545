/* The analysis of a scene's operator: build it once, run the parts (spectrum: the unknowns'
 * block of L and LAPACKE_dgeev; von Neumann; audit; maximum principle), and write the spectrum
 * as CSV and as a gnuplot scatter. docs/stability.md. */
#include "analyse.h"

#include "gnuplot.h"
#include "pstencil.h"
#include "run.h"

#include <lapacke.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void pst_spectrum_free(pst_spectrum *sp)
{
    free(sp->re);
    free(sp->im);
    sp->re = sp->im = NULL;
    sp->n = 0;
}

typedef struct {
    double re, im;
} eig;

static int eig_cmp(const void *a, const void *b)
{
    const eig *x = a, *y = b;
    if (x->re != y->re)
        return x->re < y->re ? -1 : 1;
    return (x->im > y->im) - (x->im < y->im);
}

int pst_spectrum_compute(const pst_cloud *c, const pst_csr *a, const char *name,
                         pst_spectrum *sp, char *err, size_t errlen)
{
    memset(sp, 0, sizeof *sp);
    size_t n = pst_cloud_size(c), m = 0;
    const uint8_t *kind = pst_cloud_kinds_const(c);
    size_t *idx = malloc((n ? n : 1) * sizeof *idx); /* particle -> unknown, SIZE_MAX: none */
    double *A = NULL, *wr = NULL, *wi = NULL;
    eig *e = NULL;
    int st = PST_OK;
    if (!idx) {
        st = PST_ENOMEM;
        snprintf(err, errlen, "out of memory");
        goto done;
    }
    for (size_t i = 0; i < n; ++i)
        idx[i] = kind[i] != PST_DIRICHLET ? m++ : (size_t)-1;
    if (m == 0) {
        st = PST_EINPUT;
        snprintf(err, errlen, "%s: the cloud has no unknowns (every particle is Dirichlet)",
                 name);
        goto done;
    }
    A = calloc(m * m, sizeof *A);
    wr = malloc(m * sizeof *wr);
    wi = malloc(m * sizeof *wi);
    e = malloc(m * sizeof *e);
    if (!A || !wr || !wi || !e) {
        st = PST_ENOMEM;
        snprintf(err, errlen, "out of memory for a %zu x %zu matrix", m, m);
        goto done;
    }
    for (size_t i = 0; i < n; ++i) {
        if (idx[i] == (size_t)-1)
            continue;
        for (int64_t k = a->rowptr[i]; k < a->rowptr[i + 1]; ++k) {
            size_t j = a->col[k];
            if (idx[j] != (size_t)-1)
                A[idx[i] + idx[j] * m] += a->val[k]; /* column major */
        }
    }
    lapack_int info = LAPACKE_dgeev(LAPACK_COL_MAJOR, 'N', 'N', (lapack_int)m, A, (lapack_int)m,
                                    wr, wi, NULL, 1, NULL, 1);
    if (info != 0) {
        st = PST_ENUMERIC;
        snprintf(err, errlen, "%s: LAPACKE_dgeev failed (info %d)", name, (int)info);
        goto done;
    }
    for (size_t k = 0; k < m; ++k)
        e[k] = (eig){wr[k], wi[k]};
    qsort(e, m, sizeof *e, eig_cmp);
    sp->n = m;
    sp->particles = n;
    sp->re = wr;
    sp->im = wi;
    wr = wi = NULL;
    sp->radius = 0;
    sp->min_abs = INFINITY;
    sp->max_re = -INFINITY;
    for (size_t k = 0; k < m; ++k) {
        sp->re[k] = e[k].re;
        sp->im[k] = e[k].im;
        double ab = hypot(e[k].re, e[k].im);
        if (ab > sp->radius)
            sp->radius = ab;
        if (ab < sp->min_abs)
            sp->min_abs = ab;
        if (e[k].re > sp->max_re)
            sp->max_re = e[k].re;
        sp->wrong_sign += e[k].re >= 0;
    }
done:
    free(A);
    free(wr);
    free(wi);
    free(e);
    free(idx);
    return st;
}

void pst_analyse_defaults(pst_analyse_opts *o)
{
    o->tau = 0.25;
    o->waves = 4;
}

void pst_analysis_free(pst_analysis *an)
{
    pst_spectrum_free(&an->spectrum);
    pst_vonneumann_free(&an->vn);
    pst_cloud_destroy(an->cloud);
    free(an->status);
    an->cloud = NULL;
    an->status = NULL;
}

/* The per-particle findings as fields of the analysed cloud (kept in an->cloud, with a copy of
 * the row status): the audit bits and the largest von Neumann |lambda| over the wave vectors
 * (0 on Dirichlet particles, which have no growth factor). */
static int particle_fields(pst_cloud *c, const pst_op *op, pst_analysis *an)
{
    static const char *const names[4] = {"audit_positive_offdiag", "audit_not_dominant",
                                         "audit_lemma3_mixed", "audit_xi_large"};
    size_t n = pst_cloud_size(c);
    uint8_t *flags = malloc(n ? n : 1);
    an->status = malloc(n ? n : 1);
    double *f[5];
    int st = flags && an->status ? PST_OK : PST_ENOMEM;
    for (int b = 0; b < 4 && st == PST_OK; ++b)
        st = pst_cloud_add_field(c, names[b], &f[b], NULL);
    if (st == PST_OK)
        st = pst_cloud_add_field(c, "vn_max_abs", &f[4], NULL);
    if (st == PST_OK)
        st = pst_op_audit_flags(op, flags);
    if (st == PST_OK) {
        memcpy(an->status, pst_op_status(op), n);
        for (size_t i = 0; i < n; ++i)
            for (int b = 0; b < 4; ++b)
                f[b][i] = (flags[i] >> b) & 1;
        const pst_vonneumann *vn = &an->vn;
        for (size_t q = 0; q < vn->nk; ++q)
            for (size_t r = 0; r < vn->rows; ++r) {
                size_t k = q * vn->rows + r;
                f[4][vn->particle[r]] = fmax(f[4][vn->particle[r]], hypot(vn->re[k], vn->im[k]));
            }
    }
    free(flags);
    return st;
}

int pst_analysis_write_vtu(const pst_analysis *an, const char *path, char *err, size_t errlen)
{
    char msg[PST_ERRLEN];
    int st = pst_cloud_write_vtu(an->cloud, path, an->status, msg);
    if (st != PST_OK)
        snprintf(err, errlen, "%s", msg);
    return st;
}

/* Rows of K = -L with a diagonal <= 0 among the unknowns (pst_op_diagonal gives L's); a
 * Neumann row with the inward-flux sign. */
static int count_nonpositive_diag(const pst_cloud *c, const pst_op *op, pst_analysis *an)
{
    size_t n = pst_cloud_size(c);
    const uint8_t *kind = pst_cloud_kinds_const(c);
    double *diag = malloc((n ? n : 1) * sizeof *diag);
    if (!diag)
        return PST_ENOMEM;
    int st = pst_op_diagonal(op, diag);
    if (st == PST_OK)
        for (size_t i = 0; i < n; ++i)
            if (kind[i] != PST_DIRICHLET) {
                ++an->diag_rows;
                an->nonpositive_diag += (kind[i] == PST_NEUMANN ? diag[i] : -diag[i]) <= 0;
            }
    free(diag);
    return st;
}

/* A Neumann row of L is the outward flux n . grad u (LV eq. 100): its diagonal has the sign
 * opposite to a Laplacian row's. The spectrum takes the inward flux -n . grad u, so that -L
 * of a well-posed mixed problem is positive stable as a pure Dirichlet one is. */
static void neumann_inward(const pst_cloud *c, pst_csr *a)
{
    const uint8_t *kind = pst_cloud_kinds_const(c);
    for (size_t i = 0; i < a->n; ++i)
        if (kind[i] == PST_NEUMANN)
            for (int64_t p = a->rowptr[i]; p < a->rowptr[i + 1]; ++p)
                a->val[p] = -a->val[p];
}

int pst_analyse_scene_all(const pst_scene *s, const pst_analyse_opts *o, int quiet,
                          size_t max_unknowns, pst_analysis *an, char *err, size_t errlen)
{
    memset(an, 0, sizeof *an);
    if (!(o->tau > 0) || !isfinite(o->tau) || o->waves < 1 || o->waves > 64) {
        snprintf(err, errlen, "tau must be > 0 and the wave count N in 1..64 (got %g, %d)",
                 o->tau, o->waves);
        return PST_EINVAL;
    }
    pst_cloud *c;
    pst_nlist *nl;
    pst_op *op;
    int st = pst_run_build_operator(s, quiet, max_unknowns, &c, &nl, &op, err, errlen);
    if (st != PST_OK)
        return st;
    pst_op_options(op, &an->opts);
    /* generated clouds have a spacing; a file's cloud gets its mean nearest distance */
    double s0 = s->cloud.spacing;
    an->s0_from_spacing = s->cloud.source != SC_CLOUD_FILE;
    if (!an->s0_from_spacing)
        s0 = pst_mean_nearest_distance(c, nl);
    pst_csr a = {0};
    st = pst_vonneumann_compute(c, nl, op, s0, o->tau, o->waves, &an->vn, err, errlen);
    if (st == PST_OK) {
        st = pst_op_audit_rows(op, &an->audit);
        if (st != PST_OK)
            snprintf(err, errlen, "%s: monotonicity audit: %s", s->path, pst_strerror(st));
    }
    if (st == PST_OK) {
        st = count_nonpositive_diag(c, op, an);
        if (st != PST_OK)
            snprintf(err, errlen, "%s: diagonal: %s", s->path, pst_strerror(st));
    }
    if (st == PST_OK) {
        st = pst_op_assemble(op, &a);
        if (st != PST_OK)
            snprintf(err, errlen, "%s: cannot assemble the operator: %s", s->path,
                     pst_strerror(st));
    }
    /* the maximum principle first: its dense block is freed before dgeev allocates its own */
    if (st == PST_OK)
        st = pst_dmp_check(c, &a, &an->dmp, err, errlen);
    if (st == PST_OK) {
        neumann_inward(c, &a);
        st = pst_spectrum_compute(c, &a, s->path, &an->spectrum, err, errlen);
    }
    if (st == PST_OK && (st = particle_fields(c, op, an)) != PST_OK)
        snprintf(err, errlen, "%s: per-particle findings: %s", s->path, pst_strerror(st));
    pst_csr_free(&a);
    pst_op_destroy(op);
    pst_nlist_destroy(nl);
    an->cloud = c; /* freed by pst_analysis_free */
    if (st != PST_OK)
        pst_analysis_free(an);
    return st;
}

static void write_csv(FILE *f, const void *job)
{
    const pst_spectrum *sp = job;
    fprintf(f, "re,im\n");
    for (size_t k = 0; k < sp->n; ++k)
        fprintf(f, "%.17g,%.17g\n", sp->re[k], sp->im[k]);
}

int pst_spectrum_write_csv(const pst_spectrum *sp, const char *path, char *err, size_t errlen)
{
    char msg[PST_ERRLEN];
    int st = pst_write_atomic(path, write_csv, sp, msg);
    if (st != PST_OK)
        snprintf(err, errlen, "%s", msg);
    return st;
}

int pst_spectrum_plot(const pst_spectrum *sp, const char *path, const char *title, char *err,
                      size_t errlen)
{
    pst_gnuplot gp;
    int st = pst_gnuplot_begin(&gp, path, title, err, errlen);
    if (st != PST_OK)
        return st;
    FILE *g = gp.g;
    size_t nok = sp->n - sp->wrong_sign;
    int real = 1; /* all eigenvalues real: gnuplot cannot autoscale an empty y range */
    for (size_t k = 0; k < sp->n && real; ++k)
        real = sp->im[k] == 0;
    if (real)
        fprintf(g, "set yrange [-1:1]\n");
    fprintf(g, "set xlabel 'Re {/Symbol l}'\nset ylabel 'Im {/Symbol l}'\n"
               "set grid\nset key top left\nset xzeroaxis\nset yzeroaxis\nplot ");
    const char *sep = "";
    if (nok) {
        fprintf(g, "'-' using 1:2 with points pt 7 ps 0.5 lc rgb '#1f77b4' "
                   "title 'Re {/Symbol l} < 0 (%zu)'", nok);
        sep = ", ";
    }
    if (sp->wrong_sign)
        fprintf(g, "%s'-' using 1:2 with points pt 7 ps 0.9 lc rgb '#d62728' "
                   "title 'wrong sign: Re {/Symbol l} >= 0 (%zu)'", sep, sp->wrong_sign);
    fprintf(g, "\n");
    for (int pass = 0; pass < 2; ++pass) {
        if ((pass == 0 && !nok) || (pass == 1 && !sp->wrong_sign))
            continue;
        for (size_t k = 0; k < sp->n; ++k)
            if ((sp->re[k] >= 0) == pass)
                fprintf(g, "%.17g %.17g\n", sp->re[k], sp->im[k]);
        fprintf(g, "e\n");
    }
    return pst_gnuplot_end(&gp, err, errlen);
}
