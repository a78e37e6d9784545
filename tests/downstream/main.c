/* A downstream program: generate a small cloud, build its neighbour list, check the count.
 * A 2D 5x5 lattice with h = s0 and the cubic kernel (support 2h): an interior particle sees the
 * 8 lattice points closer than 2 s0 (those at exactly 2 s0 are excluded; s0 = 1/8 keeps every
 * distance exact in binary). Exits 0 on success. */
#include <pstencil.h>
#include <stdio.h>

int main(void)
{
    pst_lattice_opts o;
    pst_lattice_defaults(&o);
    o.hi[0] = o.hi[1] = 0.5;
    o.s0 = 0.125;
    o.h_ratio = 1.0;
    pst_cloud *c = NULL;
    char err[PST_ERRLEN];
    if (pst_cloud_lattice(&c, &o, err) != PST_OK) {
        fprintf(stderr, "lattice: %s\n", err);
        return 1;
    }
    pst_nlist *nl = NULL;
    if (pst_nlist_build(&nl, c, pst_kernel_support(PST_KERNEL_CUBIC), err) != PST_OK) {
        fprintf(stderr, "nlist: %s\n", err);
        return 1;
    }
    pst_nlist_stats s;
    pst_nlist_get_stats(nl, &s);
    printf("pstencil %s: %zu particles, max %lld neighbours\n", pst_version(),
           pst_cloud_size(c), (long long)s.max);
    int ok = pst_cloud_size(c) == 25 && s.max == 8;
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
    return ok ? 0 : 1;
}
