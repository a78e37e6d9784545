/* Internal interface between the pstencil program's command files. */
#ifndef PSTENCIL_CLI_H
#define PSTENCIL_CLI_H

#include "pstencil.h"

/* Exit codes of the program (docs/cli.md). */
enum { CLI_OK = 0, CLI_USAGE = 1, CLI_BAD_INPUT = 2, CLI_NUMERIC = 3, CLI_NOMEM = 4 };

typedef struct {
    int quiet; /* print results only, no progress or headings */
} cli_ctx;

/* Map a library status to the program's exit code. */
int cli_exit_code(int status);
/* Print "pstencil: WHAT: <status name>: DETAIL" to stderr and return the exit code. */
int cli_fail(int status, const char *what, const char *detail);

/* Start MPI for hypre once, on the first call (src/cli/main.c finalises it at exit): the hook
 * the runner calls before its first AMG set-up (pst_run_opts.start_mpi). 0, or -1 when MPI
 * cannot be started. */
int cli_start_mpi(void);

/* Start MPI (cli_start_mpi) and PETSc on it once: the runner's hook before its first PETSc
 * solve (pst_run_opts.start_petsc). 0, or -1 with the reason in err (PST_ERRLEN bytes). */
int cli_start_petsc(char *err);

/* The number of ranks mpirun (Open MPI, MPICH) started the program with, from their
 * environment: 1 when it was not started by mpirun. */
int cli_launched_ranks(void);

/* This process's rank among them (0 when not started by mpirun), from the same environment,
 * before MPI is started. */
int cli_launched_rank(void);

/* How many of the ranks mpirun started on this node (Open MPI's, MPICH's or PMIx's local
 * size); 0 when the launcher does not say. */
int cli_node_ranks(void);

/* Passive OpenMP waiting unless the user set OMP_WAIT_POLICY: re-executes the program with
 * OMP_WAIT_POLICY=PASSIVE, so it must run first in main, before any OpenMP call (libgomp reads
 * the variable when it is loaded). Returns only in the re-executed program, when the user set
 * a policy, or when the re-exec is impossible (the policy stays libgomp's default). */
void cli_default_wait_policy(char **argv);
/* The policy the program runs under, for sysinfo: "passive (default)",
 * "active (OMP_WAIT_POLICY)" (the user's value, lower case), or libgomp's default. */
const char *cli_wait_policy(void);

/* Strict number parsing: the whole string must be a finite number. 0 on success. */
int cli_parse_double(const char *s, double *out);
int cli_parse_long(const char *s, long *out);

/* Match option `name` at argv[*i] as "--name VALUE" or "--name=VALUE". Returns 1 on a match
 * (with *value NULL when the value is missing), 0 otherwise; advances *i past a separate
 * value. */
int cli_option(int argc, char **argv, int *i, const char *name, const char **value);

/* Options shared by the commands that generate a cloud. */
typedef struct {
    pst_lattice_opts lattice;
    int cell_centred; /* 1: the Lukyanov–Vuik cell-centred layout */
    pst_kernel kernel;
} cli_cloud_opts;

/* Parse one cloud option at argv[*i]: returns 1 if consumed, 0 if not a cloud option, and
 * CLI_USAGE (negated, -1) after printing a message for a bad value. */
int cli_parse_cloud_option(int argc, char **argv, int *i, cli_cloud_opts *o);
/* Print the cloud options' help lines. */
void cli_cloud_options_help(void);
/* Generate the cloud the options describe; prints the error and returns an exit code. */
int cli_generate(const cli_cloud_opts *o, pst_cloud **out);

/* --periodic AXES and --box LO,HI of the commands that read a cloud (periodic_opt.c). */
typedef struct {
    const char *axes; /* the --periodic value; NULL when not given                      */
    int periodic[3];  /* 1 on the axes it names                                         */
    double box[6];    /* the --box numbers: lo of every axis, then hi of every axis      */
    int nbox;         /* how many (4 or 6; 0 when not given)                             */
} cli_periodic;

/* Parse --periodic or --box at argv[*i] for command `cmd`: 1 if consumed, 0 if neither, -1
 * after printing why the value is bad (an unknown or repeated axis, a malformed box). */
int cli_parse_periodic_option(int argc, char **argv, int *i, const char *cmd, cli_periodic *p);
/* After the options: --periodic and --box come together or not at all. CLI_OK or CLI_USAGE,
 * after printing the reason. */
int cli_check_periodic(const char *cmd, const cli_periodic *p);
/* Make the cloud read from `path` periodic as the options say (nothing without them): the
 * axes within its dimension, 2 dim numbers in the box with lo < hi, every particle inside it
 * along the periodic axes. An exit code, after printing the reason. */
int cli_set_periodic(const char *cmd, const cli_periodic *p, pst_cloud *c, const char *path);
/* Print the two options' help lines. */
void cli_periodic_help(void);

/* Morton-sort `c`, build its neighbour list for `kernel`, print statistics and timings. */
int cli_neighbour_report(const cli_ctx *ctx, pst_cloud *c, pst_kernel kernel, double t_make,
                         const char *make_label);

/* The commands. argv[0] is the first argument after the command name. */
int cli_run(const cli_ctx *ctx, int argc, char **argv);
/* `pstencil sweep SWEEP.json [--resume] [--plan]` (docs/sweeps.md). */
int cli_sweep(const cli_ctx *ctx, int argc, char **argv);
/* `pstencil plot RESULTS.csv [--summary F] [--out DIR] [--norm N]` (docs/plots.md). */
int cli_plot(const cli_ctx *ctx, int argc, char **argv);
int cli_cloud(const cli_ctx *ctx, int argc, char **argv);
int cli_neighbours(const cli_ctx *ctx, int argc, char **argv);
int cli_sysinfo(const cli_ctx *ctx, int argc, char **argv);
int cli_apply(const cli_ctx *ctx, int argc, char **argv);
int cli_stencil(const cli_ctx *ctx, int argc, char **argv);
/* `pstencil analyse SCENE.json [K=V ...] [--out DIR]`: the operator's spectrum. */
int cli_analyse(const cli_ctx *ctx, int argc, char **argv);
/* `pstencil help scene [--markdown]`: the scene keys as text or as docs/scenes.md. */
int cli_help(const cli_ctx *ctx, int argc, char **argv);

#endif
