/* Neighbours of arbitrary points (not particles) in a cloud, for interpolation: the cell grid
 * of cells.c over the cloud, cells of edge >= radius, and for each point the cells its ball
 * overlaps. Each point's row is built by one thread and sorted by particle index, so the
 * result does not depend on the thread count. */
#include "cells.h"
#include "check.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>

/* Visit the particles within `radius` of point k of pts: count them (row == NULL) or write
 * them into row. The cell range per axis is monotone in the coordinate (pst_cell_coord clamps),
 * so every cell that can hold a neighbour is visited; along a periodic axis the range wraps
 * through the faces (pst_cell_runs) and the offsets are minimum images. Bound by the distance
 * tests, ~3^dim cells of ~(3h/s0)^dim particles each. */
static size_t visit(const pst_cells *g, const pst_cloud *c, const pst_image *im,
                    const double *const pts[3], size_t k, double radius, uint32_t *row)
{
    double p[3] = {0, 0, 0};
    for (int d = 0; d < c->dim; ++d)
        p[d] = pts[d][k];
    double lo[3], hi[3];
    for (int d = 0; d < 3; ++d) {
        lo[d] = p[d] - radius;
        hi[d] = p[d] + radius;
    }
    pst_cell_run runs[3][3];
    int nr[3];
    pst_cell_box_runs(g, im, c->box_lo, c->box_hi, lo, hi, runs, nr);
    double r2 = radius * radius;
    size_t count = 0;
    PST_FOR_EACH_CELL(runs, nr, rx, ry, rz, ix, iy, iz) {
        size_t r = g->rank[((size_t)iz * g->dims[1] + iy) * g->dims[0] + ix];
        for (uint32_t s = g->start[r]; s < g->start[r + 1]; ++s) {
            uint32_t j = g->order[s];
            double d2 = 0;
            for (int d = 0; d < g->dim; ++d) {
                double t = pst_min_image(c->x[d][j] - p[d], im->P[d], im->hP[d]);
                d2 += t * t;
            }
            if (d2 < r2) {
                if (row)
                    row[count] = j;
                ++count;
            }
        }
    }
    return count;
}

int pst_points_check(const pst_cloud *c, const double *const pts[3], size_t m, double radius,
                     char *err)
{
    const pst_image im = pst_cloud_image(c);
    for (int d = 0; d < c->dim; ++d) {
        for (size_t k = 0; k < m; ++k)
            PST_CHECK(!isfinite(pts[d][k]), PST_EINPUT, err, "point %zu: %c = %g is not finite",
                      k, "xyz"[d], pts[d][k]);
        if (im.P[d] == 0)
            continue;
        PST_CHECK(!(2 * radius < im.P[d]), PST_EINPUT, err,
                  "point neighbours: the period %g along %c must exceed twice the radius %g",
                  im.P[d], "xyz"[d], radius);
        for (size_t k = 0; k < m; ++k)
            PST_CHECK(!(pts[d][k] >= c->box_lo[d] && pts[d][k] < c->box_hi[d]), PST_EINPUT, err,
                      "point %zu: %c = %g lies outside the periodic box [%g, %g)", k, "xyz"[d],
                      pts[d][k], c->box_lo[d], c->box_hi[d]);
    }
    return PST_OK;
}

int pst_points_neighbours(const pst_cloud *c, const double *const pts[3], size_t m,
                          double radius, int64_t **off_out, uint32_t **idx_out, char *err)
{
    *off_out = NULL;
    *idx_out = NULL;
    const pst_image im = pst_cloud_image(c);
    PST_TRY(pst_points_check(c, pts, m, radius, err));
    int64_t *off = pst_calloc(m + 1, sizeof *off);
    PST_CHECK_ALLOC(off, err, "point neighbours: cannot allocate %zu rows", m);
    if (c->n == 0 || m == 0) {
        *off_out = off;
        *idx_out = pst_alloc(0);
        return *idx_out ? PST_OK : PST_ENOMEM;
    }
    pst_cells g;
    int st = pst_cells_build(&g, c, radius, err);
    if (st != PST_OK) {
        pst_free(off);
        return st;
    }
#pragma omp parallel for schedule(dynamic, 256)
    for (size_t k = 0; k < m; ++k)
        off[k + 1] = (int64_t)visit(&g, c, &im, pts, k, radius, NULL);
    for (size_t k = 0; k < m; ++k)
        off[k + 1] += off[k];
    uint32_t *idx = pst_alloc((size_t)off[m] * sizeof *idx);
    if (!idx) {
        pst_cells_free(&g);
        pst_free(off);
        pst_set_err(err, "point neighbours: cannot allocate %lld entries", (long long)off[m]);
        return PST_ENOMEM;
    }
#pragma omp parallel for schedule(dynamic, 256)
    for (size_t k = 0; k < m; ++k) {
        uint32_t *row = idx + off[k];
        size_t len = visit(&g, c, &im, pts, k, radius, row);
        for (size_t a = 1; a < len; ++a) { /* insertion sort: rows are short */
            uint32_t v = row[a];
            size_t b = a;
            for (; b > 0 && row[b - 1] > v; --b)
                row[b] = row[b - 1];
            row[b] = v;
        }
    }
    pst_cells_free(&g);
    *off_out = off;
    *idx_out = idx;
    return PST_OK;
}
