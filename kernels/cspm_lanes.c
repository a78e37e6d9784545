/* The CSPM family's matrix-free rows in lanes (docs/operators.md, "Matrix-free rows in lanes"):
 * a block of pairs at a time from the packed rows, as qsfdi's, each weight cs_weight_xyz's, so
 * the emission's bit for bit, and the sums in the stored apply's lanes. A file compiled once per
 * ISA level (src/core/isa.h), so that its blocks are as wide as the level's vectors
 * (kernels/lanes.h). */
#include "cspm_family.h"
#include "cspm_lanes.h"
#include "isa.h"
#include "lanes.h"

/* The weights of a block of row i's pairs (offsets unscaled: the row's factor is 1), V_J
 * gathered as a vector. */
PST_KHOT pst_vl cs_lane_weights(pst_kernel K, int D, const cs_kc *kc, const double *Ki,
                                const double *V, const pst_lanes_block *b)
{
    const pst_vl vj = pst_vl_gather(V, b->j);
    pst_vl a;
#pragma omp simd
    for (int l = 0; l < PST_LW; ++l)
        a[l] = cs_weight_xyz(K, D, kc, Ki, b->x[l], b->y[l], b->z[l], b->q[l], vj[l]);
    return a;
}

/* Rows [i0, i1) of the matrix-free apply for the constant D and kernel K, a block at a time
 * (kernels/lanes.h). Compute-bound: per pair a sqrt, a division and ~60 flops (the two kernel
 * shapes, the two quadratic forms, mu . r) against 4 bytes of index, 8 of V_J and a 32-byte
 * packed row (in cache: the neighbours of Morton-ordered rows overlap). */
PST_KHOT void cs_lane_rows(const cs_ctx *k, int D, pst_kernel K, size_t i0, size_t i1, double *y)
{
    const int64_t *off = k->c.off;
    const uint32_t *idx = k->c.idx;
    for (size_t i = i0; i < i1; ++i) {
        if (k->c.kind[i] == PST_DIRICHLET)
            continue;
        const double *Ki = k->K + (size_t)cs_ncoef(D) * i;
        const cs_kc kc = kc_of(k, D, pst_h(&k->c, i));
        pst_lanes L = pst_lanes_row(&k->c, i, 1.0);
        PST_LANES_ROW(L, D, idx, off[i], off[i + 1], b,
                      cs_lane_weights(K, D, &kc, Ki, k->V, b));
        y[i] = pst_lanes_sum(L.acc);
    }
}

/* cs_lane_rows instantiated per dimension and kernel. */
typedef void (*cs_rows_fn)(const cs_ctx *, size_t, size_t, double *);
#define CS_ROWS(D, K, name)                                                                    \
    static void cs_rows_##D##_##name(const cs_ctx *k, size_t i0, size_t i1, double *y)         \
    {                                                                                          \
        cs_lane_rows(k, D, K, i0, i1, y);                                                      \
    }
PST_FOR_KERNELS(CS_ROWS, 2)
PST_FOR_KERNELS(CS_ROWS, 3)
#define CS_ROWS_ENTRY(D, name) cs_rows_##D##_##name
static const cs_rows_fn cs_rows_table[2][4] = PST_KERNEL_TABLE(CS_ROWS_ENTRY);

/* Matrix-free apply: each pair's weight from the positions, V_J and the row's coefficients, a
 * block at a time (cs_lane_rows), blocks of rows per thread. */
void PST_LEVEL_NAME(pst_cs_apply)(const pst_op *op, const double *u, double *y)
{
    (void)u; /* read from op->xyzu */
    cs_ctx k = make_ctx(op);
    cs_rows_fn rows = cs_rows_table[k.c.dim - 2][k.c.kernel];
    PST_LANES_ROW_BLOCKS(op->n, i0, i1, rows(&k, i0, i1, y));
}
