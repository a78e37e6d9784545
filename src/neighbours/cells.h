/* A dense uniform cell grid over a cloud's bounding box, filled by a parallel counting sort.
 * Internal to the library (neighbour lists); see docs/neighbours.md. */
#ifndef PSTENCIL_CELLS_H
#define PSTENCIL_CELLS_H

#include "cloud_layout.h"
#include "internal.h"
#include "nlist_layout.h"

typedef struct {
    int dim;
    double lo[3];       /* origin: the bounding box's lower corner (0 on unused axes)       */
    double size, inv;   /* cell edge and 1/size                                             */
    uint32_t dims[3];   /* cells per axis (1 on unused axes)                                */
    size_t ncells;      /* dims[0]*dims[1]*dims[2] (< 2^32)                                 */
    uint32_t *rank;     /* ncells, x fastest: the cell (ix, iy, iz) at (iz*dims[1] + iy)*dims[0]
                         * + ix has rank rank[that] in Morton order of (ix, iy, iz)          */
    uint32_t *start;    /* ncells + 1, by rank: cell r holds order[start[r] .. start[r+1])  */
    uint32_t *order;    /* n particle indices grouped by cell, the cells in Morton order,
                         * increasing inside each cell                                      */
} pst_cells;

/* More doublings of a cell size than the double exponent range holds (2^-1074 .. 2^1024):
 * the bound of the coarsening loops of the cell grid and the Morton sort. */
#define PST_MAX_DOUBLINGS 2200

/* Cell coordinate of position x along one axis: floor((x - lo)*inv), clamped to the grid.
 * morton.c uses the same expression, so a grid of size cell*2^k nests exactly inside the Morton
 * cells of size cell (1/(2^k cell) = inv/2^k exactly), and the result is monotone in x, which
 * the neighbour search relies on to bound the cells it visits. NaN goes to cell 0. */
static inline uint32_t pst_cell_coord(double x, double lo, double inv, uint32_t dims)
{
    double u = (x - lo) * inv;
    if (!(u > 0))
        return 0;
    if (u >= (double)dims)
        return dims - 1;
    return (uint32_t)u;
}

/* A run of cells along one axis, coordinates [l, u], whose bounds a search shifts by `shift`
 * (the image across a periodic face) when it prunes; prune 0: the search must not prune
 * along this axis. */
typedef struct {
    uint32_t l, u;
    double shift;
    int prune;
} pst_cell_run;

/* The runs of cells along axis d that hold every particle whose offset from a reach [lo, hi]
 * (coordinates along d) can be within it: one run on an axis that is not periodic; on a
 * periodic axis (im->P[d] > 0, box [blo[d], bhi[d]), particles inside it) up to three: the
 * part of the reach below the box seen at its upper face (shift -P), the middle, the part
 * above seen at the lower face (shift +P); and where those share a cell (a reach nearly as long
 * as the period) every cell of the axis once, unpruned, so that no cell is visited twice.
 * Returns the number of runs. */
static inline int pst_cell_runs(const pst_cells *g, const pst_image *im, const double blo[3],
                                const double bhi[3], int d, double lo, double hi,
                                pst_cell_run run[3])
{
    uint32_t top = g->dims[d] - 1;
#define PST_COORD_(x) pst_cell_coord(x, g->lo[d], g->inv, g->dims[d])
    if (im->P[d] == 0) {
        run[0] = (pst_cell_run){PST_COORD_(lo), PST_COORD_(hi), 0.0, 1};
        return 1;
    }
    double P = im->P[d];
    int m = 0;
    if (hi - lo < P) {
        if (lo < blo[d])
            run[m++] = (pst_cell_run){PST_COORD_(lo + P), top, -P, 1};
        run[m++] = (pst_cell_run){PST_COORD_(fmax(lo, blo[d])), PST_COORD_(fmin(hi, bhi[d])),
                                  0.0, 1};
        if (hi >= bhi[d])
            run[m++] = (pst_cell_run){0, PST_COORD_(hi - P), P, 1};
        for (int a = 0; a < m; ++a) /* runs that share a cell would visit it twice */
            for (int b = a + 1; b < m; ++b)
                if (run[a].l <= run[b].u && run[b].l <= run[a].u)
                    m = 0;
    }
    if (m == 0)
        run[m++] = (pst_cell_run){0, top, 0.0, 0};
#undef PST_COORD_
    return m;
}

/* The runs of every axis for a reach [lo[d], hi[d]] (pst_cell_runs; one run of cell 0 on the
 * axes above dim): runs[d][0 .. nr[d]). */
static inline void pst_cell_box_runs(const pst_cells *g, const pst_image *im, const double blo[3],
                                     const double bhi[3], const double lo[3], const double hi[3],
                                     pst_cell_run runs[3][3], int nr[3])
{
    for (int d = 0; d < 3; ++d) {
        nr[d] = 1;
        runs[d][0] = (pst_cell_run){0, 0, 0.0, 0};
    }
    for (int d = 0; d < g->dim; ++d)
        nr[d] = pst_cell_runs(g, im, blo, bhi, d, lo[d], hi[d], runs[d]);
}

/* Every cell (ix, iy, iz) of the runs of pst_cell_box_runs, z slowest, with the runs it came
 * from (rx, ry, rz: for their shifts); the body follows the macro as a loop's does. */
#define PST_FOR_EACH_CELL(runs, nr, rx, ry, rz, ix, iy, iz)                                    \
    for (int rz = 0; rz < (nr)[2]; ++rz)                                                       \
        for (uint32_t iz = (runs)[2][rz].l; iz <= (runs)[2][rz].u; ++iz)                       \
            for (int ry = 0; ry < (nr)[1]; ++ry)                                               \
                for (uint32_t iy = (runs)[1][ry].l; iy <= (runs)[1][ry].u; ++iy)               \
                    for (int rx = 0; rx < (nr)[0]; ++rx)                                       \
                        for (uint32_t ix = (runs)[0][rx].l; ix <= (runs)[0][rx].u; ++ix)

/* Exclusive prefix sum in place: v[b] becomes v[0] + .. + v[b-1]. The block sums of the
 * parallel scans (cells and neighbour lists), in a fixed order. */
static inline void pst_exclusive_scan(int64_t *v, size_t nblocks)
{
    int64_t s = 0;
    for (size_t b = 0; b < nblocks; ++b) {
        int64_t x = v[b];
        v[b] = s;
        s += x;
    }
}

/* Bin the particles of `c` into cells of edge >= min_size (> 0, finite). The edge is
 * min_size * 2^k with the smallest k for which the grid has at most 8n + 1024 cells (and fewer
 * than 2^32 in all): a sparse cloud in a huge box cannot blow up the memory. The cells are laid
 * out in Morton order of their coordinates (the order of pst_morton_key, extended to any number
 * of bits), so on a cloud Morton-sorted with cells of edge min_size (or a power-of-two fraction
 * of it) `order` is the identity. The result does not depend on the thread count. PST_ENOMEM
 * on allocation failure, PST_EINPUT for a min_size or an extent that is not finite (message in
 * err). */
int pst_cells_build(pst_cells *g, const pst_cloud *c, double min_size, char *err);

void pst_cells_free(pst_cells *g);

#endif
