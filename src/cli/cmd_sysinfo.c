/* `pstencil sysinfo`: what the machine offers a run (hwloc topology, OpenMP threads, the BLAS
 * and the compiler flags), printed with every benchmark so numbers can be compared. The probe
 * is src/machine.c, shared with the sweep summary and the benchmarks. */
#define _DEFAULT_SOURCE /* sysconf(_SC_PHYS_PAGES) */
#include "cli.h"
#include "machine.h"
#include "memory_avail.h"

#include <cblas.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

static void print_cache(const pst_machine_cache *c, const char *label)
{
    if (c->count <= 0)
        return;
    printf("%-20s %d x %llu KiB (line %u B)\n", label, c->count, c->bytes / 1024, c->line);
}

int cli_sysinfo(const cli_ctx *ctx, int argc, char **argv)
{
    (void)ctx;
    if (argc > 0 && (strcmp(argv[0], "--help") == 0 || strcmp(argv[0], "-h") == 0)) {
        printf("usage: pstencil sysinfo\n\nPrint the CPU model, packages, cores, hardware threads,\n"
               "caches and NUMA nodes (from hwloc), memory, the OpenMP thread count, the BLAS\n"
               "the OpenMP wait policy and the compiler flags of this build.\n");
        return CLI_OK;
    }
    if (argc > 0) {
        fprintf(stderr, "pstencil: sysinfo: unexpected argument '%s'\n", argv[0]);
        return CLI_USAGE;
    }
    pst_machine m;
    pst_machine_probe(&m);
    if (!m.topology_ok) {
        fprintf(stderr, "pstencil: sysinfo: hwloc could not read the topology\n");
        return CLI_BAD_INPUT;
    }
    printf("pstencil             %s (%s build)\n", pst_version(), m.build_type);
    printf("compiler flags       %s\n", m.compile_flags);
    printf("kernel instructions  %s\n", m.kernel_isa);
    printf("hwloc                %s\n", m.hwloc_version);
    printf("CPU model            %s\n", m.cpu_model);
    printf("packages             %d\n", m.packages);
    printf("cores                %d\n", m.cores);
    printf("hardware threads     %d\n", m.hardware_threads);
    printf("NUMA nodes           %d\n", m.numa_nodes);
    /* a VM may expose only part of its memory in its NUMA nodes: report both views */
    double phys = (double)sysconf(_SC_PHYS_PAGES) * (double)sysconf(_SC_PAGESIZE);
    printf("memory               %.1f GiB (in hwloc's NUMA nodes: %.1f GiB)\n", phys / (1 << 30),
           m.numa_memory_bytes / (1 << 30));
    /* what a run's memory estimate is checked against, and which limit sets it */
    pst_memory_avail avail;
    pst_memory_probe(&avail);
    printf("memory available     %.2f GiB (limit: %s; MemAvailable %.2f GiB",
           avail.bytes / (1 << 30), avail.limit, avail.mem_available / (1 << 30));
    if (isfinite(avail.rlimit_headroom))
        printf(", RLIMIT_AS headroom %.2f GiB", avail.rlimit_headroom / (1 << 30));
    if (isfinite(avail.cgroup_headroom))
        printf(", cgroup room %.2f GiB", avail.cgroup_headroom / (1 << 30));
    printf(")\n");
    print_cache(&m.l1d, "L1 data cache");
    print_cache(&m.l2, "L2 cache");
    print_cache(&m.l3, "L3 cache");
    printf("OpenMP threads       %d (procs %d)\n", m.omp_threads, m.omp_procs);
    printf("wait policy          %s\n", cli_wait_policy());
    printf("BLAS                 OpenBLAS %s, core %s\n", openblas_get_config(),
           openblas_get_corename());
    if (pst_petsc_available())
        printf("PETSc                %s (solves in PETSc, mpirun ranks)\n", pst_petsc_version());
    else
        printf("PETSc                not built in (petsc-dev absent at configure time)\n");
    return CLI_OK;
}
