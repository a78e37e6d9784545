/* Von Neumann growth factors (LV eq. 83) from two matrix-free applies per wave vector, their
 * counts, the CSV and the complex-plane plot. docs/stability.md. */
#include "analyse_vonneumann.h"

#include "gnuplot.h"
#include "pstencil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void pst_vonneumann_free(pst_vonneumann *vn)
{
    free(vn->k);
    free(vn->particle);
    free(vn->id);
    free(vn->adjacent);
    free(vn->re);
    free(vn->im);
    memset(vn, 0, sizeof *vn);
}

double pst_mean_nearest_distance(const pst_cloud *c, const pst_nlist *nl)
{
    size_t n = pst_cloud_size(c), counted = 0;
    int dim = pst_cloud_dim(c);
    const double *x[3] = {0};
    for (int d = 0; d < dim; ++d)
        x[d] = pst_cloud_coord_const(c, d);
    const int64_t *off = pst_nlist_offsets(nl);
    const uint32_t *nb = pst_nlist_indices(nl);
    double sum = 0;
    for (size_t i = 0; i < n; ++i) {
        double best = INFINITY;
        for (int64_t p = off[i]; p < off[i + 1]; ++p) {
            double r2 = 0;
            for (int d = 0; d < dim; ++d) {
                double dx = x[d][nb[p]] - x[d][i];
                r2 += dx * dx;
            }
            if (nb[p] != i && r2 < best)
                best = r2;
        }
        if (best < INFINITY) {
            sum += sqrt(best);
            ++counted;
        }
    }
    return counted ? sum / (double)counted : 0.0;
}

/* Wave vector q of the set (pi / s0) (a, b[, c]) / N, a, b, c in 0..N, without k = 0: the
 * counter q + 1 written in base N + 1 gives the digits (c is the fastest). */
static void wave(int dim, int waves, double s0, size_t q, double k[3])
{
    size_t t = q + 1, base = (size_t)waves + 1;
    k[0] = k[1] = k[2] = 0;
    for (int d = dim - 1; d >= 0; --d) {
        k[d] = 3.14159265358979323846 / s0 * (double)(t % base) / waves;
        t /= base;
    }
}

/* Mark the boundary-adjacent unknown rows. */
static void mark_adjacent(const pst_cloud *c, const pst_nlist *nl, pst_vonneumann *vn)
{
    const uint8_t *kind = pst_cloud_kinds_const(c);
    const int64_t *off = pst_nlist_offsets(nl);
    const uint32_t *nb = pst_nlist_indices(nl);
    for (size_t r = 0; r < vn->rows; ++r) {
        size_t i = vn->particle[r];
        int adj = kind[i] == PST_NEUMANN;
        for (int64_t p = off[i]; p < off[i + 1] && !adj; ++p)
            adj = kind[nb[p]] != PST_INTERIOR;
        vn->adjacent[r] = (uint8_t)adj;
        vn->adjacent_rows += (size_t)adj;
    }
}

int pst_vonneumann_compute(const pst_cloud *c, const pst_nlist *nl, const pst_op *op, double s0,
                           double tau, int waves, pst_vonneumann *vn, char *err, size_t errlen)
{
    memset(vn, 0, sizeof *vn);
    if (!(tau > 0) || !isfinite(tau) || waves < 1 || waves > 64 || !(s0 > 0) || !isfinite(s0)) {
        snprintf(err, errlen, "von Neumann: need tau > 0, 1 <= N <= 64 and s0 > 0 (got tau %g, "
                              "N %d, s0 %g)", tau, waves, s0);
        return PST_EINVAL;
    }
    int dim = pst_cloud_dim(c);
    size_t n = pst_cloud_size(c), nk = 1;
    for (int d = 0; d < dim; ++d)
        nk *= (size_t)waves + 1;
    --nk;
    const uint8_t *kind = pst_cloud_kinds_const(c);
    const int64_t *ids = pst_cloud_ids_const(c);
    size_t rows = 0;
    for (size_t i = 0; i < n; ++i)
        rows += kind[i] != PST_DIRICHLET;
    if (rows == 0) {
        snprintf(err, errlen, "von Neumann: the cloud has no unknowns (every particle is "
                              "Dirichlet)");
        return PST_EINVAL;
    }
    *vn = (pst_vonneumann){.dim = dim, .tau = tau, .s0 = s0, .waves = waves, .nk = nk,
                           .rows = rows};
    vn->k = malloc(3 * nk * sizeof *vn->k);
    vn->particle = malloc(rows * sizeof *vn->particle);
    vn->id = malloc(rows * sizeof *vn->id);
    vn->adjacent = calloc(rows, 1);
    vn->re = malloc(nk * rows * sizeof *vn->re);
    vn->im = malloc(nk * rows * sizeof *vn->im);
    double *cs = malloc(4 * n * sizeof *cs); /* cos, sin, L cos, L sin */
    uint8_t *grows = calloc(rows, 1);        /* row r grows for some k */
    int st = PST_OK;
    if (!vn->k || !vn->particle || !vn->id || !vn->adjacent || !vn->re || !vn->im || !cs ||
        !grows) {
        snprintf(err, errlen, "von Neumann: out of memory for %zu x %zu growth factors", rows,
                 nk);
        st = PST_ENOMEM;
        goto done;
    }
    for (size_t i = 0, r = 0; i < n; ++i)
        if (kind[i] != PST_DIRICHLET) {
            vn->particle[r] = i;
            vn->id[r++] = ids[i];
        }
    mark_adjacent(c, nl, vn);
    const double *x[3] = {0};
    for (int d = 0; d < dim; ++d)
        x[d] = pst_cloud_coord_const(c, d);
    double *co = cs, *si = cs + n, *lco = cs + 2 * n, *lsi = cs + 3 * n;
    double scale = tau * s0 * s0;
    for (size_t q = 0; q < nk; ++q) {
        double *k = vn->k + 3 * q;
        wave(dim, waves, s0, q, k);
        for (size_t i = 0; i < n; ++i) {
            double ph = 0;
            for (int d = 0; d < dim; ++d)
                ph += k[d] * x[d][i];
            co[i] = cos(ph);
            si[i] = sin(ph);
        }
        st = pst_op_apply(op, co, lco);
        if (st == PST_OK)
            st = pst_op_apply(op, si, lsi);
        if (st != PST_OK) {
            snprintf(err, errlen, "von Neumann: apply failed: %s", pst_strerror(st));
            goto done;
        }
        for (size_t r = 0; r < rows; ++r) {
            size_t i = vn->particle[r];
            /* e^{-i ph} (L cos + i L sin); a Neumann row with the inward-flux sign */
            double sc = kind[i] == PST_NEUMANN ? -scale : scale;
            double re = 1 + sc * (co[i] * lco[i] + si[i] * lsi[i]);
            double im = sc * (co[i] * lsi[i] - si[i] * lco[i]);
            if (!isfinite(re) || !isfinite(im)) {
                snprintf(err, errlen, "von Neumann: a non-finite growth factor at particle "
                                      "%lld", (long long)ids[i]);
                st = PST_ENUMERIC;
                goto done;
            }
            vn->re[q * rows + r] = re;
            vn->im[q * rows + r] = im;
            double ab = hypot(re, im);
            if (ab > vn->max_abs)
                vn->max_abs = ab;
            if (ab > 1 + PST_VN_TOL) {
                ++vn->over;
                grows[r] = 1;
            }
        }
    }
    vn->over_fraction = (double)vn->over / ((double)rows * (double)nk);
    for (size_t r = 0; r < rows; ++r) {
        vn->particles_over += grows[r];
        vn->particles_over_adjacent += (size_t)(grows[r] && vn->adjacent[r]);
    }
done:
    free(cs);
    free(grows);
    if (st != PST_OK)
        pst_vonneumann_free(vn);
    return st;
}

static void write_csv(FILE *f, const void *job)
{
    const pst_vonneumann *vn = job;
    fprintf(f, "k,kx,ky,kz,id,re,im,abs\n");
    for (size_t q = 0; q < vn->nk; ++q) {
        const double *k = vn->k + 3 * q;
        for (size_t r = 0; r < vn->rows; ++r) {
            double re = vn->re[q * vn->rows + r], im = vn->im[q * vn->rows + r];
            fprintf(f, "%zu,%.17g,%.17g,%.17g,%lld,%.17g,%.17g,%.17g\n", q, k[0], k[1], k[2],
                    (long long)vn->id[r], re, im, hypot(re, im));
        }
    }
}

int pst_vonneumann_write_csv(const pst_vonneumann *vn, const char *path, char *err,
                             size_t errlen)
{
    char msg[PST_ERRLEN];
    int st = pst_write_atomic(path, write_csv, vn, msg);
    if (st != PST_OK)
        snprintf(err, errlen, "%s", msg);
    return st;
}

int pst_vonneumann_plot(const pst_vonneumann *vn, const char *path, const char *title,
                        char *err, size_t errlen)
{
    pst_gnuplot gp;
    int st = pst_gnuplot_begin(&gp, path, title, err, errlen);
    if (st != PST_OK)
        return st;
    FILE *g = gp.g;
    size_t total = vn->rows * vn->nk, inside = total - vn->over;
    /* equal axis scales and a square window holding the whole unit circle */
    double R = 1.05 * fmax(1.0, vn->max_abs);
    fprintf(g, "set xrange [%.17g:%.17g]\nset yrange [%.17g:%.17g]\n", -R, R, -R, R);
    fprintf(g, "set xlabel 'Re {/Symbol l}'\nset ylabel 'Im {/Symbol l}'\nset grid\n"
               "set size ratio -1\nset key outside bottom center horizontal\n"
               "set object 1 circle at 0,0 size 1 fs empty border lc rgb '#333333' lw 1.5 "
               "front\nplot ");
    const char *sep = "";
    if (inside) {
        fprintf(g, "'-' using 1:2 with points pt 7 ps 0.4 lc rgb '#1f77b4' "
                   "title '|{/Symbol l}| <= 1 (%zu)'", inside);
        sep = ", ";
    }
    if (vn->over)
        fprintf(g, "%s'-' using 1:2 with points pt 7 ps 0.7 lc rgb '#d62728' "
                   "title '|{/Symbol l}| > 1 (%zu)'", sep, vn->over);
    fprintf(g, "\n");
    for (int pass = 0; pass < 2; ++pass) {
        if ((pass == 0 && !inside) || (pass == 1 && !vn->over))
            continue;
        for (size_t p = 0; p < total; ++p)
            if ((hypot(vn->re[p], vn->im[p]) > 1 + PST_VN_TOL) == pass)
                fprintf(g, "%.17g %.17g\n", vn->re[p], vn->im[p]);
        fprintf(g, "e\n");
    }
    return pst_gnuplot_end(&gp, err, errlen);
}
