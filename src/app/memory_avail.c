/* The memory available to a run: MemAvailable, RLIMIT_AS headroom and cgroup room, the least
 * of them (docs/running.md "Memory estimate"). */
#define _DEFAULT_SOURCE /* sysconf(_SC_PHYS_PAGES) */
#include "memory_avail.h"

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

/* Paths: a root or mount (ROOT_LEN) plus a cgroup path (a line of self/cgroup, LINE_LEN). */
#define ROOT_LEN 512
#define LINE_LEN 1024
#define DIR_LEN (ROOT_LEN + LINE_LEN)

/* The value of the first line of `path` that starts with `key`, times `scale`; -1 when absent. */
static double read_key(const char *path, const char *key, double scale)
{
    FILE *f = fopen(path, "r");
    if (!f)
        return -1;
    char line[512];
    double v = -1;
    size_t k = strlen(key);
    while (v < 0 && fgets(line, sizeof line, f)) {
        unsigned long long x;
        if (strncmp(line, key, k) == 0 && sscanf(line + k, " %llu", &x) == 1)
            v = (double)x * scale;
    }
    fclose(f);
    return v;
}

/* A single number file (memory.max, memory.current, ...): bytes; infinity for "max" (v2) or a
 * v1 limit at or above 2^62 (its "unlimited"); -1 when absent. */
static double read_bytes(const char *path)
{
    FILE *f = fopen(path, "r");
    if (!f)
        return -1;
    char buf[64] = "";
    double v = -1;
    unsigned long long x;
    if (fgets(buf, sizeof buf, f)) {
        if (strncmp(buf, "max", 3) == 0)
            v = INFINITY;
        else if (sscanf(buf, "%llu", &x) == 1)
            v = (double)x >= 4.6e18 ? INFINITY : (double)x;
    }
    fclose(f);
    return v;
}

/* The room in one cgroup directory: limit - usage + inactive file pages (reclaimable cache,
 * counted in the usage); infinity without a limit. */
static double cgroup_room(const char *dir, int v2)
{
    char path[DIR_LEN + 32];
    snprintf(path, sizeof path, "%s/%s", dir, v2 ? "memory.max" : "memory.limit_in_bytes");
    double limit = read_bytes(path);
    if (!(limit >= 0) || isinf(limit))
        return INFINITY;
    snprintf(path, sizeof path, "%s/%s", dir, v2 ? "memory.current" : "memory.usage_in_bytes");
    double usage = read_bytes(path);
    snprintf(path, sizeof path, "%s/memory.stat", dir);
    double cache = read_key(path, v2 ? "inactive_file" : "total_inactive_file", 1.0);
    double room = limit - fmax(usage, 0) + fmax(cache, 0);
    return fmax(fmin(room, limit), 0);
}

/* The tightest room over the cgroup at `rel` (below `mount`) and its ancestors. */
static double cgroup_chain(const char *mount, const char *rel, int v2)
{
    char dir[DIR_LEN];
    snprintf(dir, sizeof dir, "%s%s", mount, rel);
    size_t root = strlen(mount);
    double room = INFINITY;
    for (;;) {
        room = fmin(room, cgroup_room(dir, v2));
        char *slash = strrchr(dir + root, '/');
        if (!slash)
            break;
        *slash = '\0'; /* the parent; the mount itself last */
    }
    return room;
}

/* The memory cgroup of the process (`proc`/self/cgroup): a v2 line "0::/path" or a v1 line
 * "N:...memory...:/path". */
static double cgroup_headroom(const char *proc, const char *cgroup)
{
    char path[ROOT_LEN + 32], line[LINE_LEN];
    snprintf(path, sizeof path, "%s/self/cgroup", proc);
    FILE *f = fopen(path, "r");
    if (!f)
        return INFINITY;
    double room = INFINITY;
    while (fgets(line, sizeof line, f)) {
        line[strcspn(line, "\n")] = '\0';
        char *c1 = strchr(line, ':'), *c2 = c1 ? strchr(c1 + 1, ':') : NULL;
        if (!c2)
            continue;
        *c1 = *c2 = '\0';
        const char *controllers = c1 + 1, *rel = c2 + 1;
        char mount[ROOT_LEN];
        if (strcmp(line, "0") == 0 && *controllers == '\0') {
            snprintf(mount, sizeof mount, "%s", cgroup); /* v2: the unified mount */
            double r = cgroup_chain(mount, strcmp(rel, "/") ? rel : "", 1);
            snprintf(mount, sizeof mount, "%s/unified", cgroup); /* hybrid layouts */
            room = fmin(room, fmin(r, cgroup_chain(mount, strcmp(rel, "/") ? rel : "", 1)));
        } else if (strstr(controllers, "memory")) {
            snprintf(mount, sizeof mount, "%s/memory", cgroup);
            room = fmin(room, cgroup_chain(mount, strcmp(rel, "/") ? rel : "", 0));
        }
    }
    fclose(f);
    return room;
}

void pst_memory_probe_at(pst_memory_avail *m, const char *proc, const char *cgroup,
                         double rlimit_as)
{
    char path[ROOT_LEN + 32];
    snprintf(path, sizeof path, "%s/meminfo", proc);
    m->mem_available = read_key(path, "MemAvailable:", 1024.0);
    m->limit = "MemAvailable";
    if (m->mem_available < 0) {
        m->mem_available = (double)sysconf(_SC_PHYS_PAGES) * (double)sysconf(_SC_PAGESIZE);
        m->limit = "physical memory";
    }
    m->rlimit_headroom = INFINITY;
    if (isfinite(rlimit_as)) {
        snprintf(path, sizeof path, "%s/self/status", proc);
        double vm = read_key(path, "VmSize:", 1024.0);
        m->rlimit_headroom = fmax(rlimit_as - fmax(vm, 0), 0);
    }
    m->cgroup_headroom = cgroup_headroom(proc, cgroup);
    m->bytes = m->mem_available;
    if (m->rlimit_headroom < m->bytes) {
        m->bytes = m->rlimit_headroom;
        m->limit = "RLIMIT_AS";
    }
    if (m->cgroup_headroom < m->bytes) {
        m->bytes = m->cgroup_headroom;
        m->limit = "cgroup";
    }
}

void pst_memory_probe(pst_memory_avail *m)
{
    struct rlimit rl;
    double as = INFINITY;
    if (getrlimit(RLIMIT_AS, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY)
        as = (double)rl.rlim_cur;
    pst_memory_probe_at(m, "/proc", "/sys/fs/cgroup", as);
}
