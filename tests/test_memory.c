/* The memory a run may use (pst_memory_probe_at, src/app/memory_avail.c) on made-up /proc and
 * cgroup trees: the least of MemAvailable, the RLIMIT_AS headroom and the cgroup room
 * (ancestors included, v1 and v2), with the name of the limit that applies. */
#define _DEFAULT_SOURCE /* mkdtemp */
#include "check.h"
#include "memory_avail.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static char root[256];

/* Write `text` to root/rel, making its folders. */
static void put(const char *rel, const char *text)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", root, rel);
    for (char *p = path + strlen(root) + 1; (p = strchr(p, '/')); ++p) {
        *p = '\0';
        mkdir(path, 0700);
        *p = '/';
    }
    FILE *f = fopen(path, "w");
    CHECK(f != NULL);
    if (f) {
        fputs(text, f);
        fclose(f);
    }
}

int main(void)
{
    snprintf(root, sizeof root, "/tmp/pst_memory_XXXXXX");
    CHECK(mkdtemp(root) != NULL);
    char proc[300], cg[300];
    snprintf(proc, sizeof proc, "%s/proc", root);
    snprintf(cg, sizeof cg, "%s/cg", root);
    put("proc/meminfo", "MemTotal:       8000000 kB\nMemAvailable:   4000000 kB\n");
    put("proc/self/status", "Name: x\nVmSize:   100000 kB\nVmRSS: 5000 kB\n");

    /* no limits: MemAvailable */
    put("proc/self/cgroup", "0::/\n");
    pst_memory_avail m;
    pst_memory_probe_at(&m, proc, cg, INFINITY);
    CHECK_NEAR(m.bytes, 4000000 * 1024.0, 0);
    CHECK(strcmp(m.limit, "MemAvailable") == 0);
    CHECK(isinf(m.rlimit_headroom) && isinf(m.cgroup_headroom));

    /* RLIMIT_AS: the limit minus the current VmSize */
    pst_memory_probe_at(&m, proc, cg, 800000 * 1024.0);
    CHECK_NEAR(m.bytes, 700000 * 1024.0, 0);
    CHECK(strcmp(m.limit, "RLIMIT_AS") == 0);

    /* cgroup v2: the tightest of the process's cgroup and its ancestors, limit - usage +
     * inactive file cache; "max" is no limit */
    put("proc/self/cgroup", "0::/a/b\n");
    put("cg/memory.max", "max\n");
    put("cg/a/memory.max", "1000000000\n");
    put("cg/a/memory.current", "600000000\n");
    put("cg/a/memory.stat", "anon 1\ninactive_file 100000000\n");
    put("cg/a/b/memory.max", "max\n");
    pst_memory_probe_at(&m, proc, cg, 800000 * 1024.0);
    CHECK_NEAR(m.cgroup_headroom, 500000000.0, 0);
    CHECK_NEAR(m.bytes, 500000000.0, 0);
    CHECK(strcmp(m.limit, "cgroup") == 0);

    /* cgroup v1: memory.limit_in_bytes, its huge "unlimited", total_inactive_file */
    put("proc/self/cgroup", "4:memory:/job\n1:cpu:/\n");
    put("cg/memory/memory.limit_in_bytes", "9223372036854771712\n");
    put("cg/memory/job/memory.limit_in_bytes", "300000000\n");
    put("cg/memory/job/memory.usage_in_bytes", "250000000\n");
    put("cg/memory/job/memory.stat", "cache 1\ntotal_inactive_file 50000000\n");
    pst_memory_probe_at(&m, proc, cg, INFINITY);
    CHECK_NEAR(m.cgroup_headroom, 100000000.0, 0);
    CHECK(strcmp(m.limit, "cgroup") == 0);

    /* the real machine: some positive amount, and a name */
    pst_memory_probe(&m);
    CHECK(m.bytes > 0 && m.limit != NULL);
    char cmd[300];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", root);
    CHECK(system(cmd) == 0);
    return check_summary("test_memory");
}
