/* One machine probe for the program (sysinfo, the sweep summary) and the benchmarks: the hwloc
 * topology (packages, cores, hardware threads, caches, NUMA nodes), the CPU model, the OpenMP
 * thread count and the compiler flags of this build (PSTENCIL_C_FLAGS, defined on the
 * pstencil_machine library so every caller reports the same string). */
#ifndef PSTENCIL_MACHINE_H
#define PSTENCIL_MACHINE_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    unsigned long long bytes; /* one instance; 0 when hwloc reports none */
    unsigned line;            /* line size in bytes */
    int count;                /* instances in the machine */
} pst_machine_cache;

typedef struct {
    int topology_ok;       /* hwloc read the topology (else the counts below are 0) */
    char cpu_model[128];   /* hwloc's CPUModel info, else /proc/cpuinfo, else "unknown" */
    int packages, cores, hardware_threads, numa_nodes;
    double numa_memory_bytes; /* memory in hwloc's NUMA nodes */
    pst_machine_cache l1d, l2, l3;
    int omp_threads, omp_procs; /* omp_get_max_threads(), omp_get_num_procs() at the probe */
    const char *compile_flags;  /* "<compiler> <version>: <flags>" */
    const char *build_type;     /* CMAKE_BUILD_TYPE */
    const char *kernel_isa;     /* pst_isa(): the instruction set of the dispatched kernels */
    const char *hwloc_version;  /* the hwloc headers this build used */
} pst_machine;

/* Fill m (never fails: a topology hwloc cannot read leaves topology_ok 0). */
void pst_machine_probe(pst_machine *m);

/* One line: "<cpu>, P packages, C cores, T threads, L1d 48 KiB x 2, L2 ..., L3 ..., N NUMA,
 * OpenMP T, kernels <isa>; flags: <flags>". Returns what snprintf returns. */
int pst_machine_line(const pst_machine *m, char *buf, size_t len);

/* Key/value pairs (no JSON): up to max pairs written to keys[] / values[] (values are
 * vlen-byte buffers per pair, keys are static strings); returns the number of pairs. */
#define PST_MACHINE_NPAIRS 14
#define PST_MACHINE_VLEN 256
int pst_machine_pairs(const pst_machine *m, const char *keys[],
                      char values[][PST_MACHINE_VLEN], int max);

#ifdef __cplusplus
}
#endif

#endif
