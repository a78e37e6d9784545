/* The pstencil program: command dispatch, option parsing and the main job.
 *
 * Exit codes (docs/cli.md): 0 ok, 1 usage, 2 bad input, 3 numerical failure, 4 out of memory. */
#define _POSIX_C_SOURCE 200809L /* sigaction */

#include "cli.h"
#include "progress.h"

#include <errno.h>
#include <math.h>
#include <mpi.h>
#include <omp.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int cli_exit_code(int status)
{
    switch (status) {
    case PST_OK: return CLI_OK;
    case PST_EINVAL: return CLI_USAGE;
    case PST_EINPUT:
    case PST_EIO: return CLI_BAD_INPUT;
    case PST_ENUMERIC: return CLI_NUMERIC;
    case PST_ENOMEM: return CLI_NOMEM;
    default: return CLI_NUMERIC;
    }
}

int cli_fail(int status, const char *what, const char *detail)
{
    char msg[4 * PST_ERRLEN];
    snprintf(msg, sizeof msg, "%s: %s%s%s", what, pst_strerror(status),
             detail && *detail ? ": " : "", detail ? detail : "");
    pst_escape_controls(msg, sizeof msg); /* whatever made the message, one printable line */
    fprintf(stderr, "pstencil: %s\n", msg);
    return cli_exit_code(status);
}

static int usage_error(const char *fmt, const char *arg)
{
    fprintf(stderr, "pstencil: ");
    fprintf(stderr, fmt, arg);
    fprintf(stderr, "\nTry 'pstencil --help'.\n");
    return CLI_USAGE;
}

static void print_help(void)
{
    printf("pstencil %s — meshless Laplacian and div(M grad u) operators on particle clouds\n\n"
           "usage: pstencil [--threads N] [--quiet] [--progress] COMMAND [ARGS]\n\n"
           "commands:\n"
           "  run [SCENE] [K=V]   run a scene file (default: the built-in scene, the QSFDI\n"
           "                      Laplacian and gradient on a 3D cloud of 10^6 particles);\n"
           "                      --plan prints what it would compute\n"
           "  sweep SWEEP.json    run a scene over a grid of key values: a CSV row per run\n"
           "                      and task, a summary with means and convergence slopes\n"
           "  plot RESULTS.csv    PNG plots of a sweep (gnuplot): error against s0 and time,\n"
           "                      time ratios, phase costs, solver iterations\n"
           "  analyse SCENE [K=V] the stability of the scene's operator: its spectrum (LAPACK),\n"
           "                      von Neumann growth factors, monotonicity audit, discrete\n"
           "                      maximum principle; CSV, PNG and JSON (--out DIR)\n"
           "  help scene          every scene key: type, default, units, meaning\n"
           "  cloud [OPTIONS]     generate a particle cloud and write it as CSV\n"
           "  neighbours FILE     read a cloud (CSV, VTU), build its neighbour list, print statistics\n"
           "  apply [OPTIONS]     apply a scheme's operator to a field of a CSV cloud, write\n"
           "                      L u and the row status per particle as CSV\n"
           "  stencil [OPTIONS]   assemble a scheme's operator on a CSV cloud, write it as\n"
           "                      MatrixMarket\n"
           "  sysinfo             cores, caches and NUMA nodes (hwloc), threads, BLAS, flags\n\n"
           "global options:\n"
           "  --threads N         OpenMP threads (default: OMP_NUM_THREADS or all cores)\n"
           "  --quiet             print results only\n"
           "  --progress          progress lines on stderr also when it is not a terminal\n"
           "                      (a log: a line a second and one per phase)\n"
           "  --help, --version\n\n"
           "'pstencil COMMAND --help' describes a command's options.\n"
           "exit codes: 0 ok, 1 usage, 2 bad input, 3 numerical failure, 4 out of memory\n",
           pst_version());
}

int cli_parse_double(const char *s, double *out)
{
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (end == s || *end != '\0' || errno == ERANGE || !isfinite(v))
        return -1;
    *out = v;
    return 0;
}

int cli_parse_long(const char *s, long *out)
{
    char *end;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (end == s || *end != '\0' || errno == ERANGE)
        return -1;
    *out = v;
    return 0;
}

int cli_option(int argc, char **argv, int *i, const char *name, const char **value)
{
    const char *a = argv[*i];
    size_t len = strlen(name);
    if (strncmp(a, name, len) != 0)
        return 0;
    if (a[len] == '=') {
        *value = a + len + 1;
        return 1;
    }
    if (a[len] != '\0')
        return 0;
    if (*i + 1 >= argc) {
        *value = NULL;
        return 1;
    }
    *value = argv[++*i];
    return 1;
}

/* hypre, the AMG preconditioner, needs MPI, and MPI belongs to the program, not the library
 * (docs/solving.md, "MPI"): one process, initialised for serialised use from any thread, with
 * MPI errors returned as codes instead of aborting. The runner calls this before its first AMG
 * set-up, so a run without AMG skips Open MPI's start-up (0.2-0.4 s). */
static int mpi_started; /* 1: MPI_Finalize at exit; -1: the start failed */

int cli_start_mpi(void)
{
    int provided = 0;
    if (mpi_started == 0) {
        mpi_started = MPI_Init_thread(NULL, NULL, MPI_THREAD_SERIALIZED, &provided) ==
                              MPI_SUCCESS
                          ? 1
                          : -1;
        if (mpi_started == 1)
            MPI_Comm_set_errhandler(MPI_COMM_SELF, MPI_ERRORS_RETURN);
    }
    return mpi_started == 1 ? 0 : -1;
}

int cli_start_petsc(char *err)
{
    if (cli_start_mpi() != 0) {
        snprintf(err, PST_ERRLEN, "MPI, which PETSc runs on, could not be started");
        return -1;
    }
    if (mpi_started == 1)
        MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
    return pst_petsc_start(NULL, NULL, err) == PST_OK ? 0 : -1;
}

/* The first of Open MPI's, MPICH's and PMIx's variables for one count that is set to a
 * number in [lo, PST_PART_MAX_RANKS], or `none`. */
static int launcher_count(const char *const vars[3], long lo, int none)
{
    for (size_t k = 0; k < 3; ++k) {
        const char *v = getenv(vars[k]);
        long n;
        if (v && cli_parse_long(v, &n) == 0 && n >= lo && n <= PST_PART_MAX_RANKS)
            return (int)n;
    }
    return none;
}

int cli_launched_ranks(void)
{
    static const char *const vars[3] = {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE"};
    return launcher_count(vars, 1, 1);
}

int cli_launched_rank(void)
{
    static const char *const vars[3] = {"OMPI_COMM_WORLD_RANK", "PMI_RANK", "PMIX_RANK"};
    return launcher_count(vars, 0, 0);
}

int cli_node_ranks(void)
{
    static const char *const vars[3] = {"OMPI_COMM_WORLD_LOCAL_SIZE", "MPI_LOCALNRANKS",
                                        "PMIX_LOCAL_SIZE"};
    return launcher_count(vars, 1, 0);
}

/* SIGINT, SIGTERM, SIGHUP: remove the temporary files of the writes in progress, then die of
 * the signal as if there were no handler (SA_RESETHAND restored the default action). */
static void on_signal(int sig)
{
    pst_write_atomic_cleanup();
    raise(sig);
}

static void install_signal_cleanup(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sa.sa_flags = SA_RESETHAND;
    sigemptyset(&sa.sa_mask);
    const int sigs[] = {SIGINT, SIGTERM, SIGHUP};
    for (size_t k = 0; k < sizeof sigs / sizeof *sigs; ++k) {
        struct sigaction old;
        /* a signal ignored by the parent (nohup) stays ignored */
        if (sigaction(sigs[k], NULL, &old) == 0 && old.sa_handler != SIG_IGN)
            sigaction(sigs[k], &sa, NULL);
    }
}

int main(int argc, char **argv)
{
    cli_default_wait_policy(argv); /* first: it may execute the program again */
    cli_ctx ctx = {.quiet = 0};
    install_signal_cleanup();
    /* Global options may appear anywhere; strip them so that commands see only their own. */
    int nargs = 0;
    char **args = calloc((size_t)argc + 1, sizeof *args);
    if (!args)
        return CLI_NOMEM;
    for (int i = 1; i < argc; ++i) {
        const char *v;
        if (cli_option(argc, argv, &i, "--threads", &v)) {
            long t;
            if (!v || cli_parse_long(v, &t) != 0 || t < 1 || t > 4096) {
                free(args);
                return usage_error("--threads needs a positive integer (got '%s')",
                                   v ? v : "");
            }
            omp_set_num_threads((int)t);
        } else if (strcmp(argv[i], "--quiet") == 0) {
            ctx.quiet = 1;
        } else if (strcmp(argv[i], "--progress") == 0) {
            progress_force();
        } else {
            args[nargs++] = argv[i];
        }
    }
    int rc;
    int ranked = cli_launched_ranks() > 1;
    if (ranked && nargs > 0 && strcmp(args[0], "run") != 0 && strcmp(args[0], "sysinfo") != 0 &&
        strcmp(args[0], "help") != 0 && strcmp(args[0], "--help") != 0 &&
        strcmp(args[0], "--version") != 0) {
        /* every rank would write the same files */
        rc = usage_error("'%s' runs on one process: only 'pstencil run' runs over mpirun's ranks",
                         args[0]);
    } else if (nargs == 0) {
        print_help();
        rc = CLI_USAGE;
    } else if (strcmp(args[0], "help") == 0 && nargs > 1) {
        rc = cli_help(&ctx, nargs - 1, args + 1);
    } else if (strcmp(args[0], "--help") == 0 || strcmp(args[0], "-h") == 0 ||
               strcmp(args[0], "help") == 0) {
        print_help();
        rc = CLI_OK;
    } else if (strcmp(args[0], "--version") == 0) {
        printf("pstencil %s\n", pst_version());
        rc = CLI_OK;
    } else if (strcmp(args[0], "run") == 0) {
        rc = cli_run(&ctx, nargs - 1, args + 1);
    } else if (strcmp(args[0], "analyse") == 0 || strcmp(args[0], "analyze") == 0) {
        rc = cli_analyse(&ctx, nargs - 1, args + 1);
    } else if (strcmp(args[0], "sweep") == 0) {
        rc = cli_sweep(&ctx, nargs - 1, args + 1);
    } else if (strcmp(args[0], "plot") == 0) {
        rc = cli_plot(&ctx, nargs - 1, args + 1);
    } else if (strcmp(args[0], "cloud") == 0) {
        rc = cli_cloud(&ctx, nargs - 1, args + 1);
    } else if (strcmp(args[0], "neighbours") == 0 || strcmp(args[0], "neighbors") == 0) {
        rc = cli_neighbours(&ctx, nargs - 1, args + 1);
    } else if (strcmp(args[0], "sysinfo") == 0) {
        rc = cli_sysinfo(&ctx, nargs - 1, args + 1);
    } else if (strcmp(args[0], "apply") == 0) {
        rc = cli_apply(&ctx, nargs - 1, args + 1);
    } else if (strcmp(args[0], "stencil") == 0) {
        rc = cli_stencil(&ctx, nargs - 1, args + 1);
    } else {
        rc = usage_error("unknown command '%s'", args[0]);
    }
    free(args);
    int up = 0, down = 0;
    if (mpi_started == 1) {
        MPI_Initialized(&up);
        MPI_Finalized(&down);
    }
    /* a rank that failed alone would leave the others waiting in a collective: end them all */
    if (ranked && rc != CLI_OK && up && !down)
        MPI_Abort(MPI_COMM_WORLD, rc);
    pst_petsc_stop(); /* PETSc goes before the MPI it runs on */
    if (mpi_started == 1)
        MPI_Finalize();
    return rc;
}
