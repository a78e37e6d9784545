/* `pstencil neighbours FILE`: read a cloud, Morton-sort it, build its neighbour list and print
 * statistics and timings. The same report ends `pstencil run`. */
#include "cli.h"
#include "progress.h"

#include <omp.h>
#include <stdio.h>
#include <string.h>

int cli_neighbour_report(const cli_ctx *ctx, pst_cloud *c, pst_kernel kernel, double t_make,
                         const char *make_label)
{
    double support = pst_kernel_support(kernel);
    double hmax = pst_cloud_h_max(c);
    double t0 = omp_get_wtime();
    char why[PST_ERRLEN];
    int st = pst_cloud_morton_sort(c, support * hmax, why);
    if (st != PST_OK)
        return cli_fail(st, "Morton sort failed", why);
    double t1 = omp_get_wtime();
    char err[PST_ERRLEN] = "";
    pst_nlist *nl = NULL;
    cli_progress pg;
    progress_begin(&pg, !ctx->quiet, "neighbours", "rows");
    pst_progress hook = progress_list_hook(&pg);
    st = pst_nlist_build_with(&nl, c, support, &hook, err);
    progress_end(&pg);
    if (st != PST_OK)
        return cli_fail(st, "neighbour list failed", err);
    double t2 = omp_get_wtime();
    pst_nlist_stats s;
    pst_nlist_get_stats(nl, &s);
    size_t n = pst_cloud_size(c);
    double lo[3], hi[3];
    pst_cloud_bbox(c, lo, hi);
    int dim = pst_cloud_dim(c);
    if (!ctx->quiet)
        printf("\n");
    printf("particles            %zu (%dD)\n", n, dim);
    printf("bounding box         [%g, %g] x [%g, %g]", lo[0], hi[0], lo[1], hi[1]);
    if (dim == 3)
        printf(" x [%g, %g]", lo[2], hi[2]);
    printf("\n");
    if (pst_cloud_h_is_uniform(c))
        printf("smoothing length     h = %g (uniform)\n", pst_cloud_h_uniform(c));
    else
        printf("smoothing length     per particle, max %g\n", hmax);
    printf("kernel               %s, support %g h\n", pst_kernel_name(kernel), support);
    printf("neighbours           min %lld, mean %.2f, max %lld, isolated %zu\n",
           (long long)s.min, s.mean, (long long)s.max, s.isolated);
    printf("pairs stored         %lld\n", (long long)s.pairs);
    /* the list is 4 bytes per stored pair plus a per-row offset */
    double per_pair = sizeof(uint32_t);
    printf("list memory          %.1f MiB (%.0f bytes per pair + %.1f bytes per particle)\n",
           s.bytes / 1048576.0, per_pair,
           n ? ((double)s.bytes - per_pair * (double)s.pairs) / (double)n : 0.0);
    printf("threads              %d\n", pst_threads());
    printf("time %-15s %.3f s\n", make_label, t_make);
    printf("time Morton sort     %.3f s\n", t1 - t0);
    printf("time neighbours      %.3f s (%.3g particles/s)\n", t2 - t1,
           t2 > t1 ? (double)n / (t2 - t1) : 0.0);
    pst_nlist_destroy(nl);
    return CLI_OK;
}

int cli_neighbours(const cli_ctx *ctx, int argc, char **argv)
{
    const char *path = NULL;
    pst_kernel kernel = PST_KERNEL_QUINTIC;
    cli_periodic per = {0};
    for (int i = 0; i < argc; ++i) {
        const char *v;
        int rc;
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            printf("usage: pstencil neighbours CLOUD [--kernel NAME] [--periodic AXES --box "
                   "LO,HI]\n\n"
                   "Read a cloud (docs/clouds.md), Morton-sort it, build the neighbour list of\n"
                   "docs/choices.md, choice 1 (|x_j - x_i| < support * (h_i + h_j)/2) and print\n"
                   "min/mean/max neighbours, memory and timings. --kernel sets the support\n"
                   "radius: cubic, wendland_c2, wendland_c4 (2h) or quintic (3h, the default).\n\n"
                   "options:\n");
            cli_periodic_help();
            return CLI_OK;
        }
        if (cli_option(argc, argv, &i, "--kernel", &v)) {
            int k = v ? pst_kernel_from_name(v) : -1;
            if (k < 0) {
                fprintf(stderr, "pstencil: --kernel: unknown kernel '%s'\n", v ? v : "");
                return CLI_USAGE;
            }
            kernel = (pst_kernel)k;
        } else if ((rc = cli_parse_periodic_option(argc, argv, &i, "neighbours", &per))) {
            if (rc < 0)
                return CLI_USAGE;
        } else if (argv[i][0] == '-' || path) {
            fprintf(stderr, "pstencil: neighbours: unexpected argument '%s'\n", argv[i]);
            return CLI_USAGE;
        } else {
            path = argv[i];
        }
    }
    if (!path) {
        fprintf(stderr, "pstencil: neighbours: a cloud file is needed\n");
        return CLI_USAGE;
    }
    int rc = cli_check_periodic("neighbours", &per);
    if (rc != CLI_OK)
        return rc;
    char err[PST_ERRLEN] = "";
    pst_cloud *c = NULL;
    double t0 = omp_get_wtime();
    int st = pst_cloud_read(&c, path, err);
    if (st != PST_OK)
        return cli_fail(st, "cannot read the cloud", err);
    if (pst_cloud_size(c) == 0) { /* as apply, stencil and run */
        fprintf(stderr, "pstencil: %s: the cloud has no particles\n", path);
        pst_cloud_destroy(c);
        return CLI_BAD_INPUT;
    }
    rc = cli_set_periodic("neighbours", &per, c, path);
    if (rc == CLI_OK)
        rc = cli_neighbour_report(ctx, c, kernel, omp_get_wtime() - t0, "read");
    pst_cloud_destroy(c);
    return rc;
}
