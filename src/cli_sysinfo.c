/* `pstencil sysinfo`: what the machine offers a run (hwloc topology, OpenMP threads, the BLAS
 * and the compiler flags), printed with every benchmark so numbers can be compared. */
#define _DEFAULT_SOURCE /* sysconf(_SC_PHYS_PAGES) */
#include "cli.h"

#include <cblas.h>
#include <hwloc.h>
#include <omp.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

static void print_cache(hwloc_topology_t topo, hwloc_obj_type_t type, const char *label)
{
    int n = hwloc_get_nbobjs_by_type(topo, type);
    if (n <= 0)
        return;
    hwloc_obj_t o = hwloc_get_obj_by_type(topo, type, 0);
    printf("%-20s %d x %llu KiB (line %u B)\n", label, n,
           (unsigned long long)(o->attr->cache.size / 1024), o->attr->cache.linesize);
}

int cli_sysinfo(const cli_ctx *ctx, int argc, char **argv)
{
    (void)ctx;
    if (argc > 0 && (strcmp(argv[0], "--help") == 0 || strcmp(argv[0], "-h") == 0)) {
        printf("usage: pstencil sysinfo\n\nPrint packages, cores, hardware threads, caches and\n"
               "NUMA nodes (from hwloc), memory, the OpenMP thread count, the BLAS and the\n"
               "compiler flags of this build.\n");
        return CLI_OK;
    }
    if (argc > 0) {
        fprintf(stderr, "pstencil: sysinfo: unexpected argument '%s'\n", argv[0]);
        return CLI_USAGE;
    }
    hwloc_topology_t topo;
    if (hwloc_topology_init(&topo) != 0 || hwloc_topology_load(topo) != 0) {
        fprintf(stderr, "pstencil: sysinfo: hwloc could not read the topology\n");
        return CLI_BAD_INPUT;
    }
    hwloc_obj_t root = hwloc_get_root_obj(topo);
    printf("pstencil             %s (%s build)\n", pst_version(), PSTENCIL_BUILD_TYPE);
    printf("compiler flags       %s\n", PSTENCIL_C_FLAGS);
    printf("hwloc                %s\n", HWLOC_VERSION);
    printf("packages             %d\n", hwloc_get_nbobjs_by_type(topo, HWLOC_OBJ_PACKAGE));
    printf("cores                %d\n", hwloc_get_nbobjs_by_type(topo, HWLOC_OBJ_CORE));
    printf("hardware threads     %d\n", hwloc_get_nbobjs_by_type(topo, HWLOC_OBJ_PU));
    printf("NUMA nodes           %d\n", hwloc_get_nbobjs_by_type(topo, HWLOC_OBJ_NUMANODE));
    /* a VM may expose only part of its memory in its NUMA nodes: report both views */
    double phys = (double)sysconf(_SC_PHYS_PAGES) * (double)sysconf(_SC_PAGESIZE);
    printf("memory               %.1f GiB (in hwloc's NUMA nodes: %.1f GiB)\n", phys / (1 << 30),
           (double)root->total_memory / (1 << 30));
    print_cache(topo, HWLOC_OBJ_L1CACHE, "L1 data cache");
    print_cache(topo, HWLOC_OBJ_L2CACHE, "L2 cache");
    print_cache(topo, HWLOC_OBJ_L3CACHE, "L3 cache");
    printf("OpenMP threads       %d (procs %d)\n", omp_get_max_threads(), omp_get_num_procs());
    printf("BLAS                 OpenBLAS %s, core %s\n", openblas_get_config(),
           openblas_get_corename());
    hwloc_topology_destroy(topo);
    return CLI_OK;
}
