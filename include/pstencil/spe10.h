/* pstencil: Permeability grids (SPE10). Part of the public API; include <pstencil.h>. */
#ifndef PSTENCIL_PUBLIC_SPE10_H
#define PSTENCIL_PUBLIC_SPE10_H

#include "pstencil/cloud.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------------------------------------------ */
/* Permeability grids (SPE10)                                                                 */
/* ------------------------------------------------------------------------------------------ */

/* A Cartesian permeability grid of nx x ny x nz cells of size dx x dy x dz (any length unit;
 * the SPE10 reader uses metres). Component c (0 = Kx, 1 = Ky, 2 = Kz) of cell (i, j, l) is
 * k[c][i + nx*(j + ny*l)]. A grid filled by pst_spe10_read owns arrays from the library's
 * allocator: free it with pst_perm_grid_free. A grid filled by hand keeps the caller's arrays
 * (the caller frees them). docs/spe10.md. */
typedef struct {
    int nx, ny, nz;
    double dx, dy, dz;
    double *k[3];
} pst_perm_grid;

/* Read one layer of SPE10 model 2 permeability (millidarcy) into `g`: the sub-block
 * i in [i0, i0+ni), j in [j0, j0+nj) of the 60 x 220 layer (i along the 60-cell x direction,
 * j along the 220-cell y direction; 0, 0, 60, 60 is the 60x60 block of LV §5.3), as a grid of
 * ni x nj x 1 cells of 6.096 m x 3.048 m x 0.6096 m (20 x 10 x 2 ft) with Kx, Ky and Kz.
 * The format follows the file name:
 *   ".../permx.geos": the GEOS voxel files; permy.geos and permz.geos are read from the same
 *                     directory; `layer` is 84 or 85;
 *   ".../perm.txt":   the RTSPHEM Tarbert layer (Kx, Ky, Kz blocks); `layer` must be 0.
 * Every value of each file is parsed and checked, including those outside the sub-block.
 * Errors: PST_EINVAL (unknown file name, bad layer, sub-block outside the layer), PST_EIO
 * (missing file), PST_EINPUT (non-numeric, non-finite or non-positive value, too few or too
 * many values: "FILE:LINE: ..." in `err`), PST_ENOMEM. On failure `g` is left empty (all
 * zero), so pst_perm_grid_free is always safe. */
int pst_spe10_read(pst_perm_grid *g, const char *path, int layer, int i0, int j0, int ni,
                   int nj, char *err);

/* Free the arrays of a grid filled by pst_spe10_read and zero it. NULL is allowed. */
void pst_perm_grid_free(pst_perm_grid *g);

/* Set the cloud's mobility from the grid cell holding each particle. Along axis a the cell
 * index is floor((x_a - origin[a]) / (d_a * scale[a])), clamped to [0, n_a - 1]: particles
 * exactly on the grid's upper outer faces (e.g. the boundary particles of a cell-centred
 * layout) and any particle outside the grid take the nearest boundary cell, so check the
 * mapping if particles may lie outside. `scale` maps grid units to cloud units (the 60x60
 * SPE10 block onto the unit square: scale = {1/(60*dx), 1/(60*dy), 1}); `origin` is the grid
 * corner in cloud units. NULL origin means 0, NULL scale means 1. A 2D cloud reads layer
 * l = 0 and ignores origin[2], scale[2]. diagonal == 0 sets a scalar mobility (Kx);
 * otherwise the diagonal tensor (Kx, Ky[, Kz]) with dim components. Values are copied as
 * they are (no unit conversion). Errors: PST_EINVAL (bad grid, scale <= 0, missing
 * component), PST_EINPUT (a non-finite particle coordinate), PST_ENOMEM; the cloud is
 * unchanged on every failure. */
int pst_cloud_mobility_from_grid(pst_cloud *c, const pst_perm_grid *g, const double origin[3],
                                 const double scale[3], int diagonal, char *err);

#ifdef __cplusplus
}
#endif

#endif /* PSTENCIL_PUBLIC_SPE10_H */
