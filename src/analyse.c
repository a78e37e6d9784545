/* The spectrum of a scene's operator: assemble L, take the unknowns' block, LAPACKE_dgeev,
 * and write it as CSV and as a gnuplot scatter. docs/stability.md. */
#define _POSIX_C_SOURCE 200809L /* popen, pclose, getpid */
#include "analyse.h"

#include "internal.h"
#include "run.h"

#include <lapacke.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

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

int pst_analyse_scene(const pst_scene *s, int quiet, size_t max_unknowns, pst_spectrum *sp,
                      char *err, size_t errlen)
{
    memset(sp, 0, sizeof *sp);
    pst_cloud *c;
    pst_nlist *nl;
    pst_op *op;
    int st = pst_run_build_operator(s, quiet, max_unknowns, &c, &nl, &op, err, errlen);
    if (st != PST_OK)
        return st;
    pst_csr a = {0};
    size_t n = pst_cloud_size(c), m = 0;
    const uint8_t *kind = pst_cloud_kinds_const(c);
    size_t *idx = malloc((n ? n : 1) * sizeof *idx); /* particle -> unknown, SIZE_MAX: none */
    double *A = NULL, *wr = NULL, *wi = NULL;
    eig *e = NULL;
    if (!idx) {
        st = PST_ENOMEM;
        snprintf(err, errlen, "out of memory");
        goto done;
    }
    for (size_t i = 0; i < n; ++i)
        idx[i] = kind[i] != PST_DIRICHLET ? m++ : (size_t)-1;
    st = pst_op_assemble(op, &a);
    if (st != PST_OK) {
        snprintf(err, errlen, "%s: cannot assemble the operator: %s", s->path, pst_strerror(st));
        goto done;
    }
    if (m == 0) {
        st = PST_EINPUT;
        snprintf(err, errlen, "%s: the cloud has no unknowns (every particle is Dirichlet)",
                 s->path);
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
        for (int64_t k = a.rowptr[i]; k < a.rowptr[i + 1]; ++k) {
            size_t j = a.col[k];
            if (idx[j] != (size_t)-1)
                A[idx[i] + idx[j] * m] += a.val[k]; /* column major */
        }
    }
    lapack_int info = LAPACKE_dgeev(LAPACK_COL_MAJOR, 'N', 'N', (lapack_int)m, A, (lapack_int)m,
                                    wr, wi, NULL, 1, NULL, 1);
    if (info != 0) {
        st = PST_ENUMERIC;
        snprintf(err, errlen, "%s: LAPACKE_dgeev failed (info %d)", s->path, (int)info);
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
    pst_csr_free(&a);
    pst_op_destroy(op);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
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

/* A gnuplot single-quoted string: only a quote is special, written twice. */
static void put_quoted(FILE *g, const char *s)
{
    fputc('\'', g);
    for (; *s; ++s) {
        if (*s == '\'')
            fputc('\'', g);
        fputc(*s, g);
    }
    fputc('\'', g);
}

/* 1 when the file starts with the PNG signature. */
static int is_png(const char *path)
{
    static const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    unsigned char buf[8];
    FILE *f = fopen(path, "rb");
    if (!f)
        return 0;
    size_t got = fread(buf, 1, 8, f);
    fclose(f);
    return got == 8 && memcmp(buf, sig, 8) == 0;
}

int pst_spectrum_plot(const pst_spectrum *sp, const char *path, const char *title, char *err,
                      size_t errlen)
{
    char tmp[4400];
    snprintf(tmp, sizeof tmp, "%s.%ld.tmp", path, (long)getpid());
    /* gnuplot's messages go to our stderr; the plot goes to the temporary file */
    FILE *g = popen("exec gnuplot", "w");
    if (!g) {
        snprintf(err, errlen, "cannot start gnuplot (install gnuplot-nox)");
        return PST_EIO;
    }
    size_t nok = sp->n - sp->wrong_sign;
    fprintf(g, "set encoding utf8\n"
               "if (strstrt(GPVAL_TERMINALS, 'pngcairo') > 0) {\n"
               "  set terminal pngcairo enhanced size 900,700 font ',10'\n"
               "} else {\n"
               "  set terminal png enhanced size 900,700\n"
               "}\n"
               "set output ");
    put_quoted(g, tmp);
    fprintf(g, "\nset title ");
    put_quoted(g, title);
    fprintf(g, " noenhanced\nset xlabel 'Re {/Symbol l}'\nset ylabel 'Im {/Symbol l}'\n"
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
    fprintf(g, "unset output\nexit\n");
    int status = pclose(g);
    if (status != 0 || !is_png(tmp)) {
        remove(tmp);
        snprintf(err, errlen, "gnuplot failed (no PNG written)");
        return PST_EIO;
    }
    if (rename(tmp, path) != 0) {
        remove(tmp);
        snprintf(err, errlen, "cannot rename %s to %s", tmp, path);
        return PST_EIO;
    }
    return PST_OK;
}
