/* Write a VTU file of known contents for tests/vtu_roundtrip.py, which reads it back with VTK's
 * own reader. Usage: vtu_dump DIM S0 OUT.vtu (and vtu_dump --read FILE, below: the other
 * direction, files that VTK wrote read by pst_cloud_read_vtu)
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
#include <string.h>

/* vtu_dump --read FILE: read a cloud with pst_cloud_read_vtu and print it as CSV, particle by
 * particle in the cloud's order (which is the input order: row k of the file is particle id[k]
 * when the file has ids): a line "n,dim", then a header line
 * x,y[,z],V,h,kind,nx,ny[,nz][,m | ,mx,my[,mz]][,FIELD...], then one line per particle with
 * every value at %.17g. On failure: "error: STATUS: MESSAGE" on stderr, exit status 1. */
static int read_mode(const char *path)
{
    static const char *const axis[] = {"x", "y", "z"};
    char err[PST_ERRLEN] = "";
    pst_cloud *c;
    int st = pst_cloud_read_vtu(&c, path, err);
    if (st != PST_OK) {
        fprintf(stderr, "error: %s: %s\n", pst_strerror(st), err);
        return 1;
    }
    int dim = pst_cloud_dim(c), mob = pst_cloud_mobility_ncomp(c);
    size_t n = pst_cloud_size(c), nf = pst_cloud_nfields(c);
    printf("%zu,%d\n", n, dim);
    for (int d = 0; d < dim; ++d)
        printf("%s,", axis[d]);
    printf("V,h,kind");
    for (int d = 0; d < dim; ++d)
        printf(",n%s", axis[d]);
    if (mob == 1)
        printf(",m");
    for (int m = 0; mob > 1 && m < mob; ++m)
        printf(",m%s", axis[m]);
    for (size_t k = 0; k < nf; ++k)
        printf(",%s", pst_cloud_field_name(c, k));
    printf("\n");
    const double *h = pst_cloud_h_array(c);
    for (size_t i = 0; i < n; ++i) {
        for (int d = 0; d < dim; ++d)
            printf("%.17g,", pst_cloud_coord(c, d)[i]);
        printf("%.17g,%.17g,%d", pst_cloud_volume(c)[i], h ? h[i] : pst_cloud_h_uniform(c),
               pst_cloud_kinds(c)[i]);
        for (int d = 0; d < dim; ++d)
            printf(",%.17g", pst_cloud_normal(c, d)[i]);
        for (int m = 0; m < mob; ++m)
            printf(",%.17g", pst_cloud_mobility(c, m)[i]);
        for (size_t k = 0; k < nf; ++k)
            printf(",%.17g", pst_cloud_field(c, k)[i]);
        printf("\n");
    }
    pst_cloud_destroy(c);
    return 0;
}

int main(int argc, char **argv)
{
    if (argc == 3 && !strcmp(argv[1], "--read"))
        return read_mode(argv[2]);
    if (argc != 4) {
        fprintf(stderr, "usage: vtu_dump DIM S0 OUT.vtu | vtu_dump --read FILE\n");
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
    if (st == PST_OK)
        st = pst_cloud_morton_sort(c, o.s0, err);
    if (st != PST_OK) {
        fprintf(stderr, "vtu_dump: %s: %s\n", pst_strerror(st), err);
        return 1;
    }
    int dim = o.dim;
    size_t n = pst_cloud_size(c);
    double *h = pst_cloud_h_per_particle(c), *u, *rhs;
    st = h ? pst_cloud_set_mobility(c, dim == 2 ? 2 : 1, NULL) : PST_ENOMEM;
    if (st == PST_OK)
        st = pst_cloud_add_field(c, "u", &u, NULL);
    if (st == PST_OK)
        st = pst_cloud_add_field(c, "rhs", &rhs, NULL);
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
