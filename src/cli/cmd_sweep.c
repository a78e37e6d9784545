/* `pstencil sweep SWEEP.json [--resume] [--plan] [--jobs N]`: run a scene over a grid of key
 * values, one CSV row per (run, task) and a summary JSON (docs/sweeps.md). The machine (hwloc)
 * and the compiler flags come from the shared probe (machine.h) and are handed to the
 * summary. Small runs go several at once to workers, which are this program again with
 * `--worker DIGEST` (an internal option, left out of the help). */
#include "cli.h"
#include "machine.h"
#include "sweep.h"

#include <cjson/cJSON.h>
#include <stdio.h>
#include <string.h>

static void sweep_help(void)
{
    printf("usage: pstencil sweep SWEEP.json [--resume] [--plan] [--jobs N]\n\n"
           "Run a scene for every combination of the sweep file's grid of key values (the\n"
           "last key fastest), each run quiet, and write one CSV row per (run, task) after\n"
           "every run, then a summary JSON: means and standard deviations over the repeat\n"
           "key (cloud.seed) and convergence slopes against the resolution key\n"
           "(cloud.spacing). docs/sweeps.md describes the file and the outputs.\n\n"
           "  --resume    keep the runs of an existing CSV whose rows are ok or not-converged,\n"
           "              rerun the rest (the CSV's header must be this sweep's)\n"
           "  --plan      parse and plan every combination, print the count, run nothing\n"
           "  --jobs N    small runs at once, each in its own process with threads / N\n"
           "              threads (default: the thread count; 1: one run at a time, all\n"
           "              threads); large runs always run alone with all threads\n\n"
           "exit codes: 0 every run ok (not-converged solves included), 1 usage, 2 bad sweep\n"
           "file or CSV, 4 a combination's plan does not fit (--plan), 16 + N when N runs\n"
           "failed (N capped at 100), the CSV and summary written all the same\n");
}

static void add_cache(cJSON *m, const pst_machine_cache *c, const char *name)
{
    char key[32];
    snprintf(key, sizeof key, "%s_bytes", name);
    if (c->count > 0)
        cJSON_AddNumberToObject(m, key, (double)c->bytes);
    else
        cJSON_AddNullToObject(m, key);
    snprintf(key, sizeof key, "%s_count", name);
    cJSON_AddNumberToObject(m, key, c->count);
}

/* {"machine": {cores, hardware_threads, l2_bytes, l3_bytes, ..., openmp_threads},
 *  "compiler_flags": "...", "build_type": "...", "pstencil": "..."} */
static cJSON *machine_info(void)
{
    pst_machine mi;
    pst_machine_probe(&mi);
    cJSON *root = cJSON_CreateObject();
    cJSON *m = cJSON_AddObjectToObject(root, "machine");
    if (mi.topology_ok) {
        cJSON_AddNumberToObject(m, "packages", mi.packages);
        cJSON_AddNumberToObject(m, "cores", mi.cores);
        cJSON_AddNumberToObject(m, "hardware_threads", mi.hardware_threads);
        add_cache(m, &mi.l1d, "l1d");
        add_cache(m, &mi.l2, "l2");
        add_cache(m, &mi.l3, "l3");
    }
    cJSON_AddNumberToObject(m, "openmp_threads", mi.omp_threads);
    cJSON_AddStringToObject(root, "compiler_flags", mi.compile_flags);
    cJSON_AddStringToObject(root, "build_type", mi.build_type);
    cJSON_AddStringToObject(root, "pstencil", pst_version());
    return root;
}

/* `--worker DIGEST`: serve the runs a sweep sends on fd 3 (sweep_jobs.c). */
static int serve(const pst_sweep *sw, const char *digest)
{
    char err[2 * PST_ERRLEN + 1024];
    pst_sweep_opts o = {.quiet = 1, .start_mpi = cli_start_mpi, .start_petsc = cli_start_petsc};
    int st = pst_sweep_serve(sw, digest, &o, 3, err, sizeof err);
    return st == PST_OK ? CLI_OK : cli_fail(st, "sweep worker", err);
}

int cli_sweep(const cli_ctx *ctx, int argc, char **argv)
{
    const char *path = NULL, *worker = NULL, *v;
    int resume = 0, plan = 0;
    long jobs = pst_threads();
    for (int i = 0; i < argc; ++i) {
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            sweep_help();
            return CLI_OK;
        } else if (cli_option(argc, argv, &i, "--jobs", &v)) {
            if (!v || cli_parse_long(v, &jobs) != 0 || jobs < 1 || jobs > 256) {
                fprintf(stderr, "pstencil sweep: --jobs needs an integer from 1 to 256 (got "
                                "'%s')\nTry 'pstencil sweep --help'.\n", v ? v : "");
                return CLI_USAGE;
            }
        } else if (cli_option(argc, argv, &i, "--worker", &v) && v) {
            worker = v;
        } else if (strcmp(argv[i], "--resume") == 0) {
            resume = 1;
        } else if (strcmp(argv[i], "--plan") == 0) {
            plan = 1;
        } else if (argv[i][0] == '-' || path) {
            fprintf(stderr, "pstencil sweep: unexpected argument '%s'\n"
                            "Try 'pstencil sweep --help'.\n", argv[i]);
            return CLI_USAGE;
        } else {
            path = argv[i];
        }
    }
    if (!path) {
        fprintf(stderr, "pstencil sweep: no sweep file\nTry 'pstencil sweep --help'.\n");
        return CLI_USAGE;
    }
    pst_sweep sw;
    char err[2 * PST_ERRLEN + 1024];
    int st = pst_sweep_load(&sw, path, err, sizeof err);
    if (st != PST_OK)
        return cli_fail(st, "sweep", err);
    if (worker) {
        st = serve(&sw, worker);
        pst_sweep_free(&sw);
        return st;
    }
    if (plan) {
        size_t bad = 0;
        st = pst_sweep_check(&sw, &bad, err, sizeof err);
        if (!ctx->quiet || st != PST_OK)
            printf("%s: %zu combinations of %d keys, %zu do not parse or plan\n", path,
                   sw.ncombos, sw.nkeys, bad);
        pst_sweep_free(&sw);
        return st == PST_OK ? CLI_OK : cli_fail(st, "sweep --plan", err);
    }
    cJSON *machine = machine_info();
    pst_sweep_opts o = {.resume = resume, .quiet = ctx->quiet, .machine = machine,
                        .start_mpi = cli_start_mpi, .start_petsc = cli_start_petsc,
                        .jobs = (int)jobs,
                        .worker_exe = "/proc/self/exe"};
    pst_sweep_stats stats;
    st = pst_sweep_run(&sw, &o, &stats, err, sizeof err);
    cJSON_Delete(machine);
    if (st != PST_OK) {
        pst_sweep_free(&sw);
        return cli_fail(st, "sweep", err);
    }
    if (!ctx->quiet) {
        printf("%s: %zu combinations, %ld run, %ld kept from the CSV, %ld failed, %ld with a "
               "solve that did not converge\n", path, sw.ncombos, stats.runs, stats.skipped,
               stats.failed, stats.not_converged);
        if (stats.in_workers)
            printf("  %ld of them small, run up to %ld at once in worker processes\n",
                   stats.in_workers, jobs);
        if (stats.dropped)
            printf("  %ld rows of the old CSV match no combination and were dropped\n",
                   stats.dropped);
        printf("  wrote %s (%zu rows) and %s\n", sw.csv, stats.rows, sw.summary);
    }
    if (stats.failed)
        fprintf(stderr, "pstencil: sweep: %ld of %zu runs failed (status failed in %s)\n",
                stats.failed, sw.ncombos, sw.csv);
    pst_sweep_free(&sw);
    return stats.failed ? 16 + (int)(stats.failed < 100 ? stats.failed : 100) : CLI_OK;
}
