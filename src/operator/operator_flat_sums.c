/* The sums of the flatness check (operator_flat_sums.h) a block of neighbours at a time, the
 * blocks of the kernels' rows in lanes (operator_lanes.h). A file compiled once per ISA level
 * (src/core/isa.h), so that its blocks, and the 10 x 8 partial sums it carries from block to
 * block, are as wide as the level's vectors (src/core/lanes_level.h): as one target_clones
 * function in 8-lane vectors its x86-64-v3 copy kept them in memory and took 3.1-4.5x the
 * AVX-512 copy's time, in 4-lane blocks 1.1-1.4x (3D 10^6, perf samples of the lv and cspm
 * precomputes). */
#include "operator_flat_sums.h"

#include "internal.h"
#include "operator_lanes.h"

#include <math.h>

/* Row i's sums for the constant dimension D and h layout PH (1: h per particle). The
 * neighbours come PST_LW at a time from the packed positions (op->xyzu), in whole groups of
 * 8, the lanes past the row's end being the row's own particle (distance 0: not live); the
 * sums of neighbour c go to lane c mod 8 of 8 partial sums, combined in pst_v8_sum's order, so
 * that every level gives the same bits. Bound by the loads and the ~25 vector operations per
 * block. Measured (3D 10^6, perf, 1 thread): 12 % of lv's precompute with element gathers and
 * an omp simd reduction, 10 % in 8-lane blocks with AVX-512. */
static inline __attribute__((always_inline)) void flat_sums(const pst_op *op, int D, int PH,
                                                            size_t i, double *s)
{
    const pst_cloud *c = op->cloud;
    const int64_t *off = pst_nlist_offsets(op->nl), e0 = off[i], e1 = off[i + 1];
    const uint32_t *idx = pst_nlist_indices(op->nl);
    const double hi = pst_cloud_h_at(c, i), ih = 1.0 / hi, supp = pst_kernel_support(op->kernel);
    const double eps2 = op->opts.min_pair_distance * op->opts.min_pair_distance, *h = c->h;
    const double *p = op->xyzu + 4 * i;
    const pst_vl zero = pst_vl_splat(0.0);
    const pst_lanes L = {.xyzu = op->xyzu, .i = i, .xi = pst_vl_splat(p[0]),
                         .yi = pst_vl_splat(p[1]), .zi = pst_vl_splat(p[2]),
                         .ui = pst_vl_splat(p[3]), .ih = pst_vl_splat(ih),
                         .im = pst_cloud_image(c)};
    pst_vl acc[PST_FLAT_SUMS][PST_LSUMS];
    for (int k = 0; k < PST_FLAT_SUMS; ++k)
        for (int b = 0; b < PST_LSUMS; ++b)
            acc[k][b] = zero;
    for (int64_t g = e0; g < e1; g += PST_LANES) {
#pragma GCC unroll 4
        for (int b = 0; b < PST_LSUMS; ++b) { /* block b of the group: partial sums acc[.][b] */
            uint32_t pad[PST_LW];
            pst_vl dx, dy, dz, du, r = pst_vl_splat(supp);
            const uint32_t *j =
                pst_lanes_pairs(&L, idx, g + b * PST_LW, e1, pad, &dx, &dy, &dz, &du);
            if (D == 2)
                dz = zero;
            const pst_vl d2 = dx * dx + dy * dy + dz * dz;
            if (PH) /* the larger h's support, in h_I */
                for (int l = 0; l < PST_LW; ++l)
                    r[l] = supp * fmax(hi, h[j[l]]) * ih;
            pst_vl live = zero;
#pragma omp simd
            for (int l = 0; l < PST_LW; ++l)
                live[l] = ((d2[l] > eps2) & (d2[l] < r[l] * r[l])) ? 1.0 : 0.0;
            const pst_vl v[PST_FLAT_SUMS] = {
                live,           live * dx,      live * dy,      live * dz,      live * dx * dx,
                live * dx * dy, live * dx * dz, live * dy * dy, live * dy * dz, live * dz * dz};
            for (int k = 0; k < PST_FLAT_SUMS; ++k)
                acc[k][b] += v[k];
        }
    }
    for (int k = 0; k < PST_FLAT_SUMS; ++k)
        s[k] = pst_lanes_sum(acc[k]);
}

void PST_LEVEL_NAME(pst_flat_sums)(const pst_op *op, size_t i, double s[PST_FLAT_SUMS])
{
    const int ph = op->cloud->h != NULL;
    if (op->dim == 2)
        ph ? flat_sums(op, 2, 1, i, s) : flat_sums(op, 2, 0, i, s);
    else
        ph ? flat_sums(op, 3, 1, i, s) : flat_sums(op, 3, 0, i, s);
}
