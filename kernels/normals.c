/* Outward normals from the gradient of the Shepard sum (include/pstencil/normals.h). The loop
 * is one pass over each selected row's neighbours with one kernel derivative per pair; it runs
 * once per solve set-up on boundary particles only, so it is not tuned. */
#include "check.h"
#include "min_image.h"

#include "pstencil.h"

#include <math.h>

/* Minus the Shepard gradient at particle i into g, and the sum of |W'| V_j as its scale. */
static double shepard_gradient(const pst_cloud *c, const pst_nlist *nl, pst_kernel kernel,
                               size_t i, double g[3])
{
    int dim = pst_cloud_dim(c);
    const double *x[3] = {NULL, NULL, NULL};
    for (int d = 0; d < dim; ++d)
        x[d] = pst_cloud_coord_const(c, d);
    int per[3];
    double lo[3], hi[3], P[3], hP[3];
    pst_cloud_periodic(c, per, lo, hi);
    for (int d = 0; d < 3; ++d) { /* offsets through a periodic box's faces: minimum images */
        P[d] = per[d] ? hi[d] - lo[d] : 0;
        hP[d] = per[d] ? 0.5 * P[d] : INFINITY;
    }
    const double *V = pst_cloud_volume_const(c), *harr = pst_cloud_h_array(c);
    double h = harr ? harr[i] : pst_cloud_h_uniform(c);
    double reach = pst_kernel_support(kernel) * h, scale = 0;
    const int64_t *off = pst_nlist_offsets(nl);
    const uint32_t *idx = pst_nlist_indices(nl);
    g[0] = g[1] = g[2] = 0;
    for (int64_t q = off[i]; q < off[i + 1]; ++q) {
        uint32_t j = idx[q];
        double dx[3] = {0, 0, 0}, r2 = 0;
        for (int d = 0; d < dim; ++d) {
            dx[d] = pst_min_image(x[d][i] - x[d][j], P[d], hP[d]);
            r2 += dx[d] * dx[d];
        }
        double r = sqrt(r2);
        if (!(r > 0) || r >= reach)
            continue;
        double dw = V[j] * pst_kernel_dw(kernel, dim, r, h);
        for (int d = 0; d < dim; ++d)
            g[d] -= dw * dx[d] / r;
        scale += fabs(dw);
    }
    return scale;
}

int pst_normals_estimate(const pst_cloud *c, const pst_nlist *nl, pst_kernel kernel,
                         const uint8_t *select, double *const normal[3], size_t *degenerate,
                         char *err)
{
    PST_CHECK(!c || !nl || !normal, PST_EINVAL, err, "normals: NULL cloud, list or normals");
    size_t n = pst_cloud_size(c);
    int dim = pst_cloud_dim(c);
    PST_CHECK(pst_nlist_rows(nl) != n, PST_EINVAL, err,
              "normals: the neighbour list has %zu rows for a cloud of %zu particles",
              pst_nlist_rows(nl), n);
    PST_CHECK(pst_nlist_is_half(nl), PST_EINVAL, err,
              "normals: the neighbour list must be a full one, not a half list");
    PST_CHECK((int)kernel < PST_KERNEL_CUBIC || (int)kernel > PST_KERNEL_WENDLAND_C4,
              PST_EINVAL, err, "normals: unknown kernel %d", (int)kernel);
    for (int d = 0; d < dim; ++d)
        PST_CHECK(!normal[d], PST_EINVAL, err, "normals: normal[%d] is NULL", d);
    const uint8_t *kind = pst_cloud_kinds_const(c);
    size_t bad = 0;
#pragma omp parallel for schedule(dynamic, 256) reduction(+ : bad)
    for (size_t i = 0; i < n; ++i) {
        if (select ? !select[i] : kind[i] == PST_INTERIOR)
            continue;
        double g[3];
        double scale = shepard_gradient(c, nl, kernel, i, g);
        double len = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
        int flat = !(len > 1e-10 * scale);
        bad += (size_t)flat;
        for (int d = 0; d < dim; ++d)
            normal[d][i] = flat ? 0.0 : g[d] / len;
    }
    if (degenerate)
        *degenerate = bad;
    return PST_OK;
}
