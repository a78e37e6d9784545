/* `pstencil analyse SCENE.json [KEY=VALUE ...] [--out DIR]`: the spectrum of the scene's
 * operator on its unknowns (docs/stability.md, docs/cli.md). */
#define _POSIX_C_SOURCE 200809L /* mkdir */
#include "analyse.h"
#include "cli.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

static void analyse_help(void)
{
    printf("usage: pstencil analyse SCENE.json [KEY=VALUE ...] [--out DIR]\n\n"
           "The spectrum of the scene's operator: build its cloud, neighbour list and operator,\n"
           "assemble L, and compute every eigenvalue (LAPACKE_dgeev) of the block of its\n"
           "unknowns (interior and Neumann particles; at most %d). -L should be positive\n"
           "stable: eigenvalues with real part >= 0 have the wrong sign (a finding, exit 0).\n\n"
           "  KEY=VALUE   override a scene key (cloud.spacing=0.05, operator.scheme=icspm ...)\n"
           "  --out DIR   write DIR/spectrum.csv (re,im sorted by real part) and\n"
           "              DIR/spectrum.png (gnuplot); default: spectrum\n",
           PST_ANALYSE_MAX_UNKNOWNS);
}

int cli_analyse(const cli_ctx *ctx, int argc, char **argv)
{
    const char *path = NULL, *out = "spectrum";
    const char *overrides[64];
    int noverrides = 0;
    for (int i = 0; i < argc; ++i) {
        const char *v;
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            analyse_help();
            return CLI_OK;
        } else if (cli_option(argc, argv, &i, "--out", &v)) {
            if (!v || !*v) {
                fprintf(stderr, "pstencil analyse: --out needs a folder\n");
                return CLI_USAGE;
            }
            out = v;
        } else if (strchr(argv[i], '=') && argv[i][0] != '-') {
            if (noverrides == (int)(sizeof overrides / sizeof overrides[0])) {
                fprintf(stderr, "pstencil analyse: more than %d overrides\n", noverrides);
                return CLI_USAGE;
            }
            overrides[noverrides++] = argv[i];
        } else if (argv[i][0] == '-' || path) {
            fprintf(stderr, "pstencil analyse: unexpected argument '%s'\n"
                            "Try 'pstencil analyse --help'.\n", argv[i]);
            return CLI_USAGE;
        } else {
            path = argv[i];
        }
    }
    if (!path) {
        fprintf(stderr, "pstencil analyse: a scene file is needed\n"
                        "Try 'pstencil analyse --help'.\n");
        return CLI_USAGE;
    }
    pst_scene s;
    char err[2 * PST_ERRLEN];
    int st = pst_scene_load(&s, path, overrides, noverrides, err, sizeof err);
    if (st != PST_OK)
        return cli_fail(st, "scene", err);
    pst_spectrum sp;
    st = pst_analyse_scene(&s, ctx->quiet, PST_ANALYSE_MAX_UNKNOWNS, &sp, err, sizeof err);
    if (st != PST_OK) {
        pst_scene_free(&s);
        return cli_fail(st, "analyse", err);
    }
    struct stat sb;
    if (mkdir(out, 0777) != 0 && !(errno == EEXIST && stat(out, &sb) == 0 && S_ISDIR(sb.st_mode))) {
        snprintf(err, sizeof err, "%s: cannot create the folder: %s", out, strerror(errno));
        st = PST_EIO;
    }
    char csv[4400], png[4400], title[512];
    snprintf(csv, sizeof csv, "%s/spectrum.csv", out);
    snprintf(png, sizeof png, "%s/spectrum.png", out);
    snprintf(title, sizeof title, "spectrum of L: %s, %s, %zu unknowns, %zu wrong-sign",
             s.path, s.op.scheme, sp.n, sp.wrong_sign);
    if (st == PST_OK)
        st = pst_spectrum_write_csv(&sp, csv, err, sizeof err);
    if (st == PST_OK)
        st = pst_spectrum_plot(&sp, png, title, err, sizeof err);
    if (st == PST_OK) {
        printf("scene                %s (%s)\n", s.path, s.op.scheme);
        printf("particles            %zu\n", sp.particles);
        printf("unknowns             %zu\n", sp.n);
        printf("spectral radius      %.6g\n", sp.radius);
        printf("smallest |lambda|    %.6g\n", sp.min_abs);
        printf("wrong sign (re >= 0) %zu\n", sp.wrong_sign);
        printf("largest real part    %.6g\n", sp.max_re);
        if (!ctx->quiet)
            printf("wrote %s\nwrote %s\n", csv, png);
    }
    pst_spectrum_free(&sp);
    pst_scene_free(&s);
    if (st != PST_OK)
        return cli_fail(st, "analyse", err);
    return CLI_OK;
}
