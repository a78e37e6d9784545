/* A row's pairs a block of PST_LW lanes at a time from the packed rows (op->xyzu, (x, y, z, u)
 * per particle): the row in lanes and its blocks' scaled offsets, what the flatness check
 * (operator_flat_sums.c) and the kernels' rows in lanes (kernels/lanes.h) share. Internal; the
 * functions are inlined. */
#ifndef PSTENCIL_OPERATOR_LANES_H
#define PSTENCIL_OPERATOR_LANES_H

#include "cloud_layout.h"
#include "lanes_level.h"

/* One row in lanes: its centre and value, 1/h, the partial sums, and the periodic box
 * (im.any = 0: none). */
typedef struct {
    const double *xyzu;
    size_t i;
    pst_vl xi, yi, zi, ui, ih, acc[PST_LSUMS];
    pst_image im;
} pst_lanes;

/* The pairs idx[e .. e + PST_LW) of the row (fewer before e1, none at or past it: the missing
 * lanes are the row's own particle, a pair at distance 0, which every scheme's rule counts as
 * degenerate with weight 0 and whose u_J - u_I is 0): the scaled offsets (x_J - x_I) / h_I as
 * the rows' gathers form them (minimum images in a periodic box, as pst_offset), and
 * u_J - u_I. Returns the neighbours (idx + e, or pad filled). */
PST_V8_INLINE const uint32_t *pst_lanes_pairs(const pst_lanes *L, const uint32_t *idx, int64_t e,
                                              int64_t e1, uint32_t pad[PST_LW], pst_vl *x,
                                              pst_vl *y, pst_vl *z, pst_vl *du)
{
    const uint32_t *j = idx + e;
    if (e1 - e < PST_LW) {
        for (int l = 0; l < PST_LW; ++l)
            pad[l] = l < e1 - e ? j[l] : (uint32_t)L->i;
        j = pad;
    }
    pst_vl X, Y, Z, U;
    pst_vl_rows4(L->xyzu, j, &X, &Y, &Z, &U);
    pst_vl dx = X - L->xi, dy = Y - L->yi, dz = Z - L->zi;
    if (L->im.any) { /* pst_offset's minimum images; a cloud without a box skips them */
        for (int l = 0; l < PST_LW; ++l) {
            dx[l] = pst_min_image(dx[l], L->im.P[0], L->im.hP[0]);
            dy[l] = pst_min_image(dy[l], L->im.P[1], L->im.hP[1]);
            dz[l] = pst_min_image(dz[l], L->im.P[2], L->im.hP[2]);
        }
    }
    *x = dx * L->ih;
    *y = dy * L->ih;
    *z = dz * L->ih;
    *du = U - L->ui;
    return j;
}

#endif /* PSTENCIL_OPERATOR_LANES_H */
