/* Write a VTU file of known contents for tests/vtu_roundtrip.py, which reads it back with VTK's
 * own reader. Usage: vtu_dump DIM S0 OUT.vtu
 *
 * The cloud: the unit box lattice of spacing S0, jittered (K = 0.3, seed 5) with an unjittered
 * Dirichlet outer layer, Morton-sorted so that storage order differs from input order. Every
 * other value is a function of the position x (what the script checks):
 *   h = 0.1 + 0.05 x0                    V = S0^DIM (the generator's)
 *   normal[d] = x_d - 0.5                 2D: M = (1 + x0, 2 + x1, 0)   3D: m = 1 + x0 x1 x2
 *   u = sin(3 x0) + x1^2 [+ cos(x2)]      rhs = x0 - 2 x1
 *   status = id % 5 (given in cloud order, as pst_op_status would be)                       */
#include "pstencil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

int main(int argc, char **argv)
{
    if (argc != 4) {
        fprintf(stderr, "usage: vtu_dump DIM S0 OUT.vtu\n");
        return 2;
    }
    char err[PST_ERRLEN] = "";
    pst_lattice_opts o;
    pst_lattice_defaults(&o);
    o.dim = atoi(argv[1]);
    o.s0 = atof(argv[2]);
    o.hi[2] = 1.0;
    o.jitter = 0.3;
    o.seed = 5;
    o.boundary_layer = 1;
    pst_cloud *c;
    int st = pst_cloud_lattice(&c, &o, err);
    if (st == PST_OK && (st = pst_cloud_morton_sort(c, o.s0)) != PST_OK)
        snprintf(err, sizeof err, "%s", pst_cloud_error(c));
    if (st != PST_OK) {
        fprintf(stderr, "vtu_dump: %s: %s\n", pst_strerror(st), err);
        return 1;
    }
    int dim = o.dim;
    size_t n = pst_cloud_size(c);
    double *h = pst_cloud_h_per_particle(c), *u, *rhs;
    st = h ? pst_cloud_set_mobility(c, dim == 2 ? 2 : 1) : PST_ENOMEM;
    if (st == PST_OK)
        st = pst_cloud_add_field(c, "u", &u);
    if (st == PST_OK)
        st = pst_cloud_add_field(c, "rhs", &rhs);
    uint8_t *status = malloc(n ? n : 1);
    if (st != PST_OK || !status) {
        fprintf(stderr, "vtu_dump: cannot fill the cloud\n");
        return 1;
    }
    const double *x = pst_cloud_coord(c, 0), *y = pst_cloud_coord(c, 1),
                 *z = dim == 3 ? pst_cloud_coord(c, 2) : NULL;
    for (size_t i = 0; i < n; ++i) {
        h[i] = 0.1 + 0.05 * x[i];
        for (int d = 0; d < dim; ++d)
            pst_cloud_normal(c, d)[i] = pst_cloud_coord(c, d)[i] - 0.5;
        if (dim == 2) {
            pst_cloud_mobility(c, 0)[i] = 1 + x[i];
            pst_cloud_mobility(c, 1)[i] = 2 + y[i];
        } else {
            pst_cloud_mobility(c, 0)[i] = 1 + x[i] * y[i] * z[i];
        }
        u[i] = sin(3 * x[i]) + y[i] * y[i] + (z ? cos(z[i]) : 0.0);
        rhs[i] = x[i] - 2 * y[i];
        status[i] = (uint8_t)(pst_cloud_ids(c)[i] % 5);
    }
    st = pst_cloud_write_vtu(c, argv[3], status, err);
    if (st != PST_OK)
        fprintf(stderr, "vtu_dump: %s: %s\n", pst_strerror(st), err);
    else
        printf("%zu\n", n);
    free(status);
    pst_cloud_destroy(c);
    return st == PST_OK ? 0 : 1;
}
