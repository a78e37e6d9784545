/* `pstencil analyse SCENE.json [KEY=VALUE ...] [--tau T] [--waves N] [--out DIR]`: the
 * stability of the scene's operator on its unknowns: spectrum, von Neumann growth factors,
 * monotonicity audit, discrete maximum principle (docs/stability.md, docs/cli.md). */
#define _POSIX_C_SOURCE 200809L /* mkdir */
#include "analyse.h"
#include "cli.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

static void analyse_help(void)
{
    printf("usage: pstencil analyse SCENE.json [KEY=VALUE ...] [--tau T] [--waves N] "
           "[--out DIR]\n\n"
           "The stability of the scene's operator: build its cloud, neighbour list and operator\n"
           "and report, on its unknowns (interior and Neumann particles; at most %d):\n"
           "  - the spectrum: every eigenvalue (LAPACKE_dgeev) of L's block on the unknowns;\n"
           "    -L should be positive stable: real part >= 0 is the wrong sign;\n"
           "  - von Neumann growth factors (LV eq. 83) lambda = 1 + tau s0^2 e^{-ik.r} L[e^{ik.r}]\n"
           "    for k = (pi/s0)(a,b[,c])/N, a,b,c in 0..N, k != 0; |lambda| > 1 grows;\n"
           "  - the monotonicity audit of K = -L (positive off-diagonals, dominance, Lemma 3);\n"
           "  - the discrete maximum principle: L u = 0 with Dirichlet data g = step in x and\n"
           "    g = x, by dense LU; unknowns outside [min g, max g] violate it.\n"
           "Findings (wrong signs, growth, violations, a singular block) exit 0.\n\n"
           "  KEY=VALUE   override a scene key (cloud.spacing=0.05, operator.scheme=icspm ...)\n"
           "  --tau T     von Neumann step dt = T s0^2, T > 0 (default 0.25)\n"
           "  --waves N   wave vectors per axis, 1..64 (default 4)\n"
           "  --out DIR   write DIR/spectrum.csv (re,im sorted by real part), DIR/spectrum.png,\n"
           "              DIR/vonneumann.csv, DIR/vonneumann.png, DIR/analysis.json and\n"
           "              DIR/analysis.vtu (row status, audit bits and max |lambda| per\n"
           "              particle); default: spectrum\n",
           PST_ANALYSE_MAX_UNKNOWNS);
}

/* One "name   value" line, names padded to the column of the existing lines. */
#define LINE(name, ...)                                                                        \
    do {                                                                                       \
        printf("%-20s ", name);                                                                \
        printf(__VA_ARGS__);                                                                   \
        printf("\n");                                                                          \
    } while (0)

static void print_dmp_case(const char *name, const pst_dmp_case *r, int linear)
{
    char key[32];
    snprintf(key, sizeof key, "DMP %s range", name);
    LINE(key, "[%.6g, %.6g]", r->gmin, r->gmax);
    snprintf(key, sizeof key, "DMP %s outside", name);
    LINE(key, "%zu", r->violations);
    snprintf(key, sizeof key, "DMP %s overshoot", name);
    LINE(key, "%.6g", r->overshoot);
    if (linear)
        LINE("DMP linear |u - x|", "%.6g", r->max_err);
}

static void print_analysis(const pst_analysis *an, const char *scene_path)
{
    const pst_spectrum *sp = &an->spectrum;
    printf("scene                %s (%s)\n", scene_path, an->opts.scheme);
    printf("thresholds           cond_max %g, rank_tol %g, min_pair_distance %g h\n",
           an->opts.cond_max, an->opts.rank_tol, an->opts.min_pair_distance);
    printf("fallback             %s\n", pst_scheme_fallback(an->opts.scheme));
    printf("particles            %zu\n", sp->particles);
    printf("unknowns             %zu\n", sp->n);
    printf("spectral radius      %.6g\n", sp->radius);
    printf("smallest |lambda|    %.6g\n", sp->min_abs);
    printf("wrong sign (re >= 0) %zu\n", sp->wrong_sign);
    printf("largest real part    %.6g\n", sp->max_re);

    const pst_vonneumann *vn = &an->vn;
    LINE("tau", "%.6g", vn->tau);
    LINE("waves N", "%d (%zu wave vectors)", vn->waves, vn->nk);
    LINE("s0", "%.6g (%s)", vn->s0,
         an->s0_from_spacing ? "cloud.spacing" : "mean nearest-neighbour distance");
    LINE("max |growth factor|", "%.12g", vn->max_abs);
    LINE("growth > 1 pairs", "%zu of %zu (fraction %.6g)", vn->over, vn->rows * vn->nk,
         vn->over_fraction);
    LINE("growth > 1 particles", "%zu", vn->particles_over);
    LINE("... boundary-adj.", "%zu (of %zu boundary-adjacent rows)", vn->particles_over_adjacent,
         vn->adjacent_rows);

    const pst_op_audit *au = &an->audit;
    LINE("audited rows", "%zu", au->rows);
    LINE("rows pos. off-diag", "%zu (%lld entries)", au->rows_positive_offdiag,
         (long long)au->positive_offdiag);
    LINE("rows not dominant", "%zu", au->rows_not_dominant);
    if (au->lemma3_sign_mixed >= 0) {
        LINE("Lemma 3 mixed signs", "%lld", (long long)au->lemma3_sign_mixed);
        LINE("Lemma 3 |xi| d >= 1", "%lld", (long long)au->lemma3_xi_large);
    } else {
        LINE("Lemma 3", "not applicable (no bracket 1 - xi.x in %s)", an->opts.scheme);
    }
    LINE("K diagonal <= 0", "%zu of %zu unknown rows", an->nonpositive_diag, an->diag_rows);

    const pst_dmp *d = &an->dmp;
    if (!d->applicable) {
        LINE("maximum principle", "not applicable (no Dirichlet particles)");
    } else if (d->singular) {
        LINE("maximum principle", "singular: %s", d->why);
    } else {
        LINE("DMP step at x >", "%.6g", d->xmid);
        print_dmp_case("step", &d->step, 0);
        print_dmp_case("linear", &d->linear, 1);
    }
}

/* A bad option value: a message naming the option, exit 1. */
static int bad_value(const char *option, const char *value, const char *what)
{
    if (value)
        fprintf(stderr, "pstencil analyse: %s '%s': %s\n", option, value, what);
    else
        fprintf(stderr, "pstencil analyse: %s %s\n", option, what);
    return CLI_USAGE;
}

int cli_analyse(const cli_ctx *ctx, int argc, char **argv)
{
    const char *path = NULL, *out = "spectrum";
    const char *overrides[64];
    int noverrides = 0;
    pst_analyse_opts ao;
    pst_analyse_defaults(&ao);
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
        } else if (cli_option(argc, argv, &i, "--tau", &v)) {
            if (!v || cli_parse_double(v, &ao.tau) != 0 || !(ao.tau > 0))
                return bad_value("--tau", v, "needs a number > 0");
        } else if (cli_option(argc, argv, &i, "--waves", &v)) {
            long w;
            if (!v || cli_parse_long(v, &w) != 0 || w < 1 || w > 64)
                return bad_value("--waves", v, "needs a whole number in 1..64");
            ao.waves = (int)w;
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
    pst_analysis an;
    st = pst_analyse_scene_all(&s, &ao, ctx->quiet, PST_ANALYSE_MAX_UNKNOWNS, &an, err,
                               sizeof err);
    if (st != PST_OK) {
        pst_scene_free(&s);
        return cli_fail(st, "analyse", err);
    }
    struct stat sb;
    if (mkdir(out, 0777) != 0 && !(errno == EEXIST && stat(out, &sb) == 0 && S_ISDIR(sb.st_mode))) {
        snprintf(err, sizeof err, "%s: cannot create the folder: %s", out, strerror(errno));
        st = PST_EIO;
    }
    char csv[4400], png[4400], vcsv[4400], vpng[4400], json[4400], vtu[4400], title[512],
        vtitle[512];
    snprintf(csv, sizeof csv, "%s/spectrum.csv", out);
    snprintf(png, sizeof png, "%s/spectrum.png", out);
    snprintf(vcsv, sizeof vcsv, "%s/vonneumann.csv", out);
    snprintf(vpng, sizeof vpng, "%s/vonneumann.png", out);
    snprintf(json, sizeof json, "%s/analysis.json", out);
    snprintf(vtu, sizeof vtu, "%s/analysis.vtu", out);
    snprintf(title, sizeof title, "spectrum of L: %s, %s, %zu unknowns, %zu wrong-sign",
             s.path, an.opts.scheme, an.spectrum.n, an.spectrum.wrong_sign);
    snprintf(vtitle, sizeof vtitle, "von Neumann growth factors: %s, %s, tau %g, N %d, "
             "max |lambda| %.6g", s.path, an.opts.scheme, an.vn.tau, an.vn.waves, an.vn.max_abs);
    if (st == PST_OK)
        st = pst_spectrum_write_csv(&an.spectrum, csv, err, sizeof err);
    if (st == PST_OK)
        st = pst_spectrum_plot(&an.spectrum, png, title, err, sizeof err);
    if (st == PST_OK)
        st = pst_vonneumann_write_csv(&an.vn, vcsv, err, sizeof err);
    if (st == PST_OK)
        st = pst_vonneumann_plot(&an.vn, vpng, vtitle, err, sizeof err);
    if (st == PST_OK)
        st = pst_analysis_write_json(&an, s.path, json, err, sizeof err);
    if (st == PST_OK)
        st = pst_analysis_write_vtu(&an, vtu, err, sizeof err);
    if (st == PST_OK) {
        print_analysis(&an, s.path);
        if (!ctx->quiet)
            printf("wrote %s\nwrote %s\nwrote %s\nwrote %s\nwrote %s\nwrote %s\n", csv, png, vcsv,
                   vpng, json, vtu);
    }
    pst_analysis_free(&an);
    pst_scene_free(&s);
    if (st != PST_OK)
        return cli_fail(st, "analyse", err);
    return CLI_OK;
}
