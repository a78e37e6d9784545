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
 * them into row. The cell range per axis is monotone in the coordinate (pst_cell_coord clamps), so every
 * cell that can hold a neighbour is visited. Bound by the distance tests, ~3^dim cells of
 * ~(3h/s0)^dim particles each. */
static size_t visit(const pst_cells *g, const pst_cloud *c, const double *const pts[3], size_t k,
                    double radius, uint32_t *row)
{
    double p[3] = {0, 0, 0};
    for (int d = 0; d < c->dim; ++d)
        p[d] = pts[d][k];
    uint32_t lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    for (int d = 0; d < g->dim; ++d) {
        lo[d] = pst_cell_coord(p[d] - radius, g->lo[d], g->inv, g->dims[d]);
        hi[d] = pst_cell_coord(p[d] + radius, g->lo[d], g->inv, g->dims[d]);
    }
    double r2 = radius * radius;
    size_t count = 0;
    for (uint32_t iz = lo[2]; iz <= hi[2]; ++iz)
        for (uint32_t iy = lo[1]; iy <= hi[1]; ++iy)
            for (uint32_t ix = lo[0]; ix <= hi[0]; ++ix) {
                size_t r = g->rank[((size_t)iz * g->dims[1] + iy) * g->dims[0] + ix];
                for (uint32_t s = g->start[r]; s < g->start[r + 1]; ++s) {
                    uint32_t j = g->order[s];
                    double d2 = 0;
                    for (int d = 0; d < g->dim; ++d) {
                        double t = c->x[d][j] - p[d];
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

int pst_points_neighbours(const pst_cloud *c, const double *const pts[3], size_t m,
                          double radius, int64_t **off_out, uint32_t **idx_out, char *err)
{
    *off_out = NULL;
    *idx_out = NULL;
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
        off[k + 1] = (int64_t)visit(&g, c, pts, k, radius, NULL);
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
        size_t len = visit(&g, c, pts, k, radius, row);
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
