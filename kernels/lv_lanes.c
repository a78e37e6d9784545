/* The Lukyanov-Vuik family's G1 rows in lanes (docs/operators.md, "Matrix-free rows in lanes"):
 * the matrix-free apply of the operators of the default gradient G1, any mobility (none,
 * scalar, diagonal tensor), either pair mean, one h or h per particle, a block of pairs at a
 * time from the packed rows like qsfdi's, through the pair rules of lv_family.h, so with the
 * chunk rows' weights bit for bit. A file of its own, compiled once per ISA level
 * (src/core/isa.h) so that its blocks are as wide as the level's vectors (kernels/lanes.h), and
 * so that its 64 instantiations (dimension, kernel, tensor, pair mean, h layout) compile beside
 * lv_rows.c and lv_half_lanes.c. */
#include "lv_lanes.h"
#include "isa.h"

/* Row i of the matrix-free apply for such a row (not a Neumann row), a block at a time like
 * qsfdi's, each block taken one ahead (kernels/lanes.h): the weights of row_t's chunks
 * (lv_rows.c) without their passes through arrays. The row's last block reads on into the list
 * like row_t's (the lanes past the row computed and kept out of the sum); the list's last row
 * pads. */
PST_KHOT void g1_lane_row(const lv_ctx *k, int D, pst_kernel K, int T, int H, int HS,
                          const int64_t *off, const uint32_t *idx, size_t i, double *y)
{
    lv_lane_row r = lane_row_of(k, D, T, i);
    pst_lanes L = pst_lanes_row(&k->c, i, 1.0);
    PST_LANES_EACH_TO(L, D, idx, off[i], off[i + 1], k->list_end, b, {
        pst_vl mj[3]; /* one declarator per line: the block is a macro argument */
        pst_vl hj;
        pst_vl av;
        pst_vl vj = g1_lane_gathers(k, D, T, HS, &r, b, mj, &hj);
        L.acc[b->s] =
            pst_lanes_add(L.acc[b->s],
                          g1_lane_weights(K, D, T, H, HS, &r, b, vj, mj, hj, &av) * b->du, b->n);
    });
    y[i] = pst_lanes_sum(L.acc);
}

/* g1_lane_row for the rows [i0, i1) that are neither Dirichlet nor Neumann rows, per dimension,
 * kernel, mobility (T), pair mean and h layout. */
#define LV_LANE_ROWS(D, K, name, T, H, HS)                                                     \
    static void lane_rows_##D##_##name##_##T##_##H##_##HS(                                     \
        const lv_ctx *k, const int64_t *off, const uint32_t *idx, size_t i0, size_t i1,       \
        double *y)                                                                             \
    {                                                                                          \
        for (size_t i = i0; i < i1; ++i)                                                       \
            if (k->c.kind[i] != PST_DIRICHLET && k->c.kind[i] != PST_NEUMANN)                  \
                g1_lane_row(k, D, K, T, H, HS, off, idx, i, y);                                \
    }
#define LV_LANE_ROWS_T(D, K, name, T)                                                          \
    LV_LANE_ROWS(D, K, name, T, 0, 0)                                                          \
    LV_LANE_ROWS(D, K, name, T, 0, 1)                                                          \
    LV_LANE_ROWS(D, K, name, T, 1, 0) LV_LANE_ROWS(D, K, name, T, 1, 1)
#define LV_LANE_ROWS_K(D, K, name) LV_LANE_ROWS_T(D, K, name, 0) LV_LANE_ROWS_T(D, K, name, 1)
PST_FOR_KERNELS(LV_LANE_ROWS_K, 2)
PST_FOR_KERNELS(LV_LANE_ROWS_K, 3)
#define LV_LANE_ENTRY_T(D, name, T)                                                            \
    {{lane_rows_##D##_##name##_##T##_0_0, lane_rows_##D##_##name##_##T##_0_1},                 \
     {lane_rows_##D##_##name##_##T##_1_0, lane_rows_##D##_##name##_##T##_1_1}}
#define LV_LANE_ENTRY(D, name) {LV_LANE_ENTRY_T(D, name, 0), LV_LANE_ENTRY_T(D, name, 1)}
static const lv_lane_rows_fn lane_rows_table[2][4][2][2][2] = PST_KERNEL_TABLE(LV_LANE_ENTRY);

/* The lane rows serve the G1 operators (the default gradient), whatever their mobility, pair
 * mean and h; NULL for G2-G4 (the chunk rows serve every operator, and the Neumann rows of
 * these). */
lv_lane_rows_fn PST_LEVEL_NAME(lv_lane_rows_for)(const lv_ctx *k)
{
    if (k->variant != PST_GRAD_G1)
        return NULL;
    return lane_rows_table[k->c.dim - 2][k->c.kernel][k->c.ncomp > 1][k->harmonic]
                          [k->c.h != NULL];
}
