/* The memory a run may use: the least of the kernel's MemAvailable, the address-space headroom
 * under RLIMIT_AS and the room left in the process's memory cgroup (v2 or v1), with the name of
 * the limit that applies (docs/running.md "Memory estimate"). */
#ifndef PSTENCIL_MEMORY_AVAIL_H
#define PSTENCIL_MEMORY_AVAIL_H

typedef struct {
    double bytes;            /* the least of the three below                                 */
    const char *limit;       /* which one: "MemAvailable", "RLIMIT_AS" or "cgroup"; "physical
                                memory" when /proc/meminfo has no MemAvailable                */
    double mem_available;    /* MemAvailable, else the physical memory                       */
    double rlimit_headroom;  /* RLIMIT_AS minus the current VmSize; infinity when unlimited  */
    double cgroup_headroom;  /* the tightest (limit - usage + inactive file cache) over the
                                process's cgroup and its ancestors; infinity when none        */
} pst_memory_avail;

/* Probe this process's limits (never fails: what cannot be read counts as no limit). */
void pst_memory_probe(pst_memory_avail *m);

/* The same from other roots, for tests: `proc` stands for /proc (meminfo, self/status,
 * self/cgroup), `cgroup` for /sys/fs/cgroup; rlimit_as is the RLIMIT_AS soft limit in bytes
 * (infinity: none). */
void pst_memory_probe_at(pst_memory_avail *m, const char *proc, const char *cgroup,
                         double rlimit_as);

#endif
