/* The machine probe of machine.h: hwloc topology, CPU model, OpenMP threads, compiler flags. */
#include "machine.h"

#include "pstencil.h"

#include <hwloc.h>
#include <omp.h>
#include <stdio.h>
#include <string.h>

#ifndef PSTENCIL_C_FLAGS
#define PSTENCIL_C_FLAGS "unknown"
#endif
#ifndef PSTENCIL_BUILD_TYPE
#define PSTENCIL_BUILD_TYPE "unknown"
#endif

static void get_cache(hwloc_topology_t topo, hwloc_obj_type_t type, pst_machine_cache *c)
{
    int n = hwloc_get_nbobjs_by_type(topo, type);
    hwloc_obj_t o = n > 0 ? hwloc_get_obj_by_type(topo, type, 0) : NULL;
    c->count = n > 0 ? n : 0;
    c->bytes = o ? (unsigned long long)o->attr->cache.size : 0;
    c->line = o ? o->attr->cache.linesize : 0;
}

/* /proc/cpuinfo's first "model name" (Linux), when hwloc has no CPUModel. */
static int cpuinfo_model(char *buf, size_t len)
{
    FILE *f = fopen("/proc/cpuinfo", "r");
    if (!f)
        return 0;
    char line[512];
    int found = 0;
    while (!found && fgets(line, sizeof line, f)) {
        const char *colon = strchr(line, ':');
        if (strncmp(line, "model name", 10) == 0 && colon) {
            colon += 1 + (colon[1] == ' ');
            snprintf(buf, len, "%s", colon);
            buf[strcspn(buf, "\n")] = '\0';
            found = 1;
        }
    }
    fclose(f);
    return found;
}

void pst_machine_probe(pst_machine *m)
{
    memset(m, 0, sizeof *m);
    m->compile_flags = PSTENCIL_C_FLAGS;
    m->build_type = PSTENCIL_BUILD_TYPE;
    m->kernel_isa = pst_isa();
    m->hwloc_version = HWLOC_VERSION;
    m->omp_threads = omp_get_max_threads();
    m->omp_procs = omp_get_num_procs();
    hwloc_topology_t topo;
    if (hwloc_topology_init(&topo) == 0) {
        if (hwloc_topology_load(topo) == 0) {
            m->topology_ok = 1;
            m->packages = hwloc_get_nbobjs_by_type(topo, HWLOC_OBJ_PACKAGE);
            m->cores = hwloc_get_nbobjs_by_type(topo, HWLOC_OBJ_CORE);
            m->hardware_threads = hwloc_get_nbobjs_by_type(topo, HWLOC_OBJ_PU);
            m->numa_nodes = hwloc_get_nbobjs_by_type(topo, HWLOC_OBJ_NUMANODE);
            m->numa_memory_bytes = (double)hwloc_get_root_obj(topo)->total_memory;
            get_cache(topo, HWLOC_OBJ_L1CACHE, &m->l1d);
            get_cache(topo, HWLOC_OBJ_L2CACHE, &m->l2);
            get_cache(topo, HWLOC_OBJ_L3CACHE, &m->l3);
            hwloc_obj_t pkg = hwloc_get_obj_by_type(topo, HWLOC_OBJ_PACKAGE, 0);
            const char *model = pkg ? hwloc_obj_get_info_by_name(pkg, "CPUModel") : NULL;
            if (model)
                snprintf(m->cpu_model, sizeof m->cpu_model, "%s", model);
        }
        hwloc_topology_destroy(topo);
    }
    if (!m->cpu_model[0] && !cpuinfo_model(m->cpu_model, sizeof m->cpu_model))
        snprintf(m->cpu_model, sizeof m->cpu_model, "unknown");
}

static void cache_text(const pst_machine_cache *c, char *buf, size_t len)
{
    if (c->count > 0)
        snprintf(buf, len, "%llu KiB x %d", c->bytes / 1024, c->count);
    else
        snprintf(buf, len, "none");
}

int pst_machine_line(const pst_machine *m, char *buf, size_t len)
{
    char l1[48], l2[48], l3[48];
    cache_text(&m->l1d, l1, sizeof l1);
    cache_text(&m->l2, l2, sizeof l2);
    cache_text(&m->l3, l3, sizeof l3);
    return snprintf(buf, len,
                    "%s, %d packages, %d cores, %d threads, L1d %s, L2 %s, L3 %s, %d NUMA, "
                    "OpenMP %d, kernels %s; flags: %s",
                    m->cpu_model, m->packages, m->cores, m->hardware_threads, l1, l2, l3,
                    m->numa_nodes, m->omp_threads, m->kernel_isa, m->compile_flags);
}

int pst_machine_pairs(const pst_machine *m, const char *keys[],
                      char values[][PST_MACHINE_VLEN], int max)
{
    int n = 0;
#define PAIR(K, ...)                                                                          \
    do {                                                                                      \
        if (n < max) {                                                                        \
            keys[n] = K;                                                                      \
            snprintf(values[n], PST_MACHINE_VLEN, __VA_ARGS__);                               \
            ++n;                                                                              \
        }                                                                                     \
    } while (0)
    PAIR("cpu", "%s", m->cpu_model);
    PAIR("packages", "%d", m->packages);
    PAIR("cores", "%d", m->cores);
    PAIR("hardware_threads", "%d", m->hardware_threads);
    PAIR("numa_nodes", "%d", m->numa_nodes);
    PAIR("l1d_bytes", "%llu", m->l1d.bytes);
    PAIR("l1d_count", "%d", m->l1d.count);
    PAIR("l2_bytes", "%llu", m->l2.bytes);
    PAIR("l2_count", "%d", m->l2.count);
    PAIR("l3_bytes", "%llu", m->l3.bytes);
    PAIR("l3_count", "%d", m->l3.count);
    PAIR("openmp_threads", "%d", m->omp_threads);
    PAIR("compiler_flags", "%s", m->compile_flags);
    PAIR("build_type", "%s", m->build_type);
    PAIR("kernel_isa", "%s", m->kernel_isa);
#undef PAIR
    return n;
}
