/* `pstencil run [SCENE.json] [key=value ...] [--plan]`: read a scene (or take the built-in
 * default), plan it, run it. docs/scenes.md, docs/running.md. */
#include "cli.h"
#include "run.h"

#include <stdio.h>
#include <string.h>

static void run_help(void)
{
    printf("usage: pstencil run [SCENE.json] [KEY=VALUE ...] [--plan] [--petsc OPTIONS]\n"
           "       mpirun -n RANKS pstencil run SCENE.json ...\n\n"
           "Run a scene: generate or read the cloud, compute the tasks it asks for (Laplacian,\n"
           "div(M grad u), gradient, Hessian, interpolation, Poisson solves) and write its\n"
           "outputs (CSV, VTU, JSON report). Without SCENE.json, the built-in default scene\n"
           "(scenes/default.json): the QSFDI Laplacian and gradient on a 3D jittered cloud of\n"
           "about 10^6 particles.\n\n"
           "  KEY=VALUE   override a scene key: cloud.spacing=0.02, operator.scheme=lv,\n"
           "              tasks.0.rtol=1e-8, fields.u='sin(x)', cloud.lo=[0,0] ...\n"
           "  --plan      print what would be computed, with the memory estimate, and stop\n"
           "  --petsc OPTIONS\n"
           "              solve in PETSc's KSP with these PETSc options, after each task's own\n"
           "              (tasks.K.petsc): --petsc '-ksp_type bcgs -pc_type jacobi'\n\n"
           "Under mpirun with several ranks, each rank owns a Morton range of the cloud and its\n"
           "ghosts, every solve runs in PETSc over the ranks, and rank 0 writes the outputs\n"
           "(docs/distributed.md; needs a pstencil built with PETSc).\n\n"
           "'pstencil help scene' lists every key with its type, default and meaning.\n");
}

int cli_run(const cli_ctx *ctx, int argc, char **argv)
{
    const char *path = NULL;
    const char *overrides[64];
    const char *petsc = NULL;
    int noverrides = 0, plan_only = 0;
    for (int i = 0; i < argc; ++i) {
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            run_help();
            return CLI_OK;
        } else if (cli_option(argc, argv, &i, "--petsc", &petsc)) {
            if (!petsc) {
                fprintf(stderr, "pstencil run: --petsc needs the PETSc options\n");
                return CLI_USAGE;
            }
        } else if (strcmp(argv[i], "--plan") == 0) {
            plan_only = 1;
        } else if (strchr(argv[i], '=') && argv[i][0] != '-') {
            if (noverrides == (int)(sizeof overrides / sizeof overrides[0])) {
                fprintf(stderr, "pstencil run: more than %d overrides\n", noverrides);
                return CLI_USAGE;
            }
            overrides[noverrides++] = argv[i];
        } else if (argv[i][0] == '-' || path) {
            fprintf(stderr, "pstencil run: unexpected argument '%s'\nTry 'pstencil run --help'.\n",
                    argv[i]);
            return CLI_USAGE;
        } else {
            path = argv[i];
        }
    }
    pst_scene s;
    char err[2 * PST_ERRLEN];
    int st = path ? pst_scene_load(&s, path, overrides, noverrides, err, sizeof err)
                  : pst_scene_default(&s, overrides, noverrides, err, sizeof err);
    if (st != PST_OK)
        return cli_fail(st, "scene", err);
    pst_run_opts ro = {.quiet = ctx->quiet, .plan_only = plan_only, .start_mpi = cli_start_mpi,
                       .petsc_options = petsc, .start_petsc = cli_start_petsc,
                       .node_ranks = cli_node_ranks()};
    if (cli_launched_ranks() > 1 && plan_only) { /* the plan of one rank, without MPI */
        ro.ranks = cli_launched_ranks();
        ro.rank = cli_launched_rank();
    } else if (cli_launched_ranks() > 1) { /* every rank runs the scene on its part */
        st = cli_start_petsc(err) == 0 ? PST_OK : PST_EINVAL;
        pst_mpi_rank(&ro.rank, &ro.ranks);
        ro.quiet = ro.quiet || ro.rank > 0;
    }
    if (st == PST_OK)
        st = pst_run_scene(&s, &ro, NULL, NULL, NULL, err, sizeof err);
    pst_scene_free(&s);
    if (st != PST_OK)
        return cli_fail(st, "run", err);
    return CLI_OK;
}
