/* TPFA finite-volume reference on a Cartesian grid; see tpfa_ref.h. */
#include "tpfa_ref.h"

#include <lapacke.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static double face_value(const tpfa_problem *p, int side, const double x[3])
{
    return p->value_fn ? p->value_fn(p->ctx, side, x) : p->bc_value[side];
}

/* Geometry of cell index c (the problem's order): its integer coordinates and centre. */
static void cell_coords(const tpfa_problem *p, size_t c, int idx[3], double x[3])
{
    idx[0] = (int)(c % (size_t)p->n[0]);
    idx[1] = (int)(c / (size_t)p->n[0] % (size_t)p->n[1]);
    idx[2] = p->dim == 3 ? (int)(c / ((size_t)p->n[0] * (size_t)p->n[1])) : 0;
    for (int d = 0; d < 3; ++d)
        x[d] = d < p->dim ? p->lo[d] + (idx[d] + 0.5) * p->d[d] : 0;
}

static double face_area(const tpfa_problem *p, int axis)
{
    double a = 1;
    for (int d = 0; d < p->dim; ++d)
        if (d != axis)
            a *= p->d[d];
    return a;
}

/* Half-cell transmissibility A / (d/2 / K) of a cell along axis d. */
static double half_t(const tpfa_problem *p, size_t c, int axis)
{
    return face_area(p, axis) * p->k[axis][c] / (0.5 * p->d[axis]);
}

/* Cell c's index and centre (cell_coords) and its row in the banded order of strides bstride. */
static size_t band_row(const tpfa_problem *p, size_t c, const size_t bstride[3], int idx[3],
                       double x[3])
{
    cell_coords(p, c, idx, x);
    size_t row = 0;
    for (int d = 0; d < p->dim; ++d)
        row += (size_t)idx[d] * bstride[d];
    return row;
}

int tpfa_solve(const tpfa_problem *p, double *u, char *err, size_t errlen)
{
    int dim = p->dim;
    if (dim != 2 && dim != 3) {
        snprintf(err, errlen, "tpfa: dim %d", dim);
        return -1;
    }
    size_t stride[3] = {1, (size_t)p->n[0], (size_t)p->n[0] * (size_t)p->n[1]}, n = 1;
    int any_dirichlet = 0;
    for (int d = 0; d < dim; ++d) {
        if (p->n[d] < 1 || !(p->d[d] > 0) || !p->k[d]) {
            snprintf(err, errlen, "tpfa: bad axis %d", d);
            return -1;
        }
        n *= (size_t)p->n[d];
        any_dirichlet |= p->bc_kind[2 * d] == TPFA_DIRICHLET || p->bc_kind[2 * d + 1] == TPFA_DIRICHLET;
    }
    if (!any_dirichlet) {
        snprintf(err, errlen, "tpfa: no Dirichlet side: the system is singular");
        return -1;
    }
    /* Banded order: axes by increasing extent, so the slowest axis is the longest and the
     * half-bandwidth kd is the product of the others. pos[c] is cell c's row. */
    int ax[3] = {0, 1, 2};
    for (int a = 0; a < dim; ++a)
        for (int b = a + 1; b < dim; ++b)
            if (p->n[ax[b]] < p->n[ax[a]]) {
                int t = ax[a];
                ax[a] = ax[b];
                ax[b] = t;
            }
    size_t bstride[3] = {0, 0, 0}, s = 1;
    for (int a = 0; a < dim; ++a) {
        bstride[ax[a]] = s;
        s *= (size_t)p->n[ax[a]];
    }
    size_t kd = bstride[ax[dim - 1]], ld = kd + 1;
    double *ab = calloc(ld * n, sizeof *ab), *rhs = calloc(n, sizeof *rhs);
    if (!ab || !rhs) {
        free(ab);
        free(rhs);
        snprintf(err, errlen, "tpfa: out of memory (%zu x %zu band)", ld, n);
        return -1;
    }
#define AB(i, j) ab[(kd + (i)) - (j) + ld * (j)] /* upper band, column major, i <= j */
    for (size_t c = 0; c < n; ++c) {
        int idx[3];
        double x[3];
        size_t row = band_row(p, c, bstride, idx, x);
        for (int d = 0; d < dim; ++d) {
            /* upper neighbour: harmonic transmissibility, entered once (row < its row) */
            if (idx[d] + 1 < p->n[d]) {
                size_t c2 = c + stride[d], row2 = row + bstride[d];
                double t = 1.0 / (1.0 / half_t(p, c, d) + 1.0 / half_t(p, c2, d));
                AB(row, row) += t;
                AB(row2, row2) += t;
                AB(row, row2) -= t;
            }
            for (int hi = 0; hi < 2; ++hi) {
                if (idx[d] != (hi ? p->n[d] - 1 : 0))
                    continue;
                int side = 2 * d + hi;
                double xf[3] = {x[0], x[1], x[2]};
                xf[d] = p->lo[d] + (hi ? p->n[d] : 0) * p->d[d];
                double g = face_value(p, side, xf);
                if (p->bc_kind[side] == TPFA_DIRICHLET) {
                    double t = half_t(p, c, d);
                    AB(row, row) += t;
                    rhs[row] += t * g;
                } else {
                    rhs[row] += face_area(p, d) * g; /* outward flux g: A g enters the balance */
                }
            }
        }
    }
#undef AB
    lapack_int info = LAPACKE_dpbsv(LAPACK_COL_MAJOR, 'U', (lapack_int)n, (lapack_int)kd, 1, ab,
                                    (lapack_int)ld, rhs, (lapack_int)n);
    free(ab);
    if (info != 0) {
        free(rhs);
        snprintf(err, errlen, "tpfa: dpbsv info %d", (int)info);
        return -1;
    }
    for (size_t c = 0; c < n; ++c) {
        int idx[3];
        double x[3];
        u[c] = rhs[band_row(p, c, bstride, idx, x)];
    }
    free(rhs);
    return 0;
}

double tpfa_side_flux(const tpfa_problem *p, const double *u, int side)
{
    int d = side / 2, hi = side % 2;
    size_t n = (size_t)p->n[0] * (size_t)p->n[1] * (size_t)(p->dim == 3 ? p->n[2] : 1);
    double sum = 0;
    for (size_t c = 0; c < n; ++c) {
        int idx[3];
        double x[3];
        cell_coords(p, c, idx, x);
        if (idx[d] != (hi ? p->n[d] - 1 : 0))
            continue;
        double xf[3] = {x[0], x[1], x[2]};
        xf[d] = p->lo[d] + (hi ? p->n[d] : 0) * p->d[d];
        double g = face_value(p, side, xf);
        if (p->bc_kind[side] == TPFA_DIRICHLET)
            sum += half_t(p, c, d) * (g - u[c]); /* A K (g - u_c) / (d/2): n . K grad u */
        else
            sum += face_area(p, d) * g;
    }
    return sum;
}
