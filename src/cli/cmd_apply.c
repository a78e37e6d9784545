/* `pstencil apply` (L u of a field column, written per particle) and `pstencil stencil` (the
 * assembled matrix of L as MatrixMarket). Both read a cloud (pst_cloud_read), Morton-sort it
 * for locality, build an operator and write their result in input order, all or nothing. */
#include "cli.h"
#include "progress.h"
#include "pstencil.h"

#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    const char *cmd;      /* "apply" or "stencil", for messages */
    const char *in, *out;
    const char *field;    /* apply only */
    const char *mobility; /* field column copied into the scalar mobility, or NULL */
    int stored;           /* apply: pst_op_store + pst_op_apply_stored */
    const char *timers;   /* --timers FILE.json: the run's timers and counts as JSON, or NULL */
    double h;             /* > 0: uniform h overriding the file's column */
    cli_periodic periodic; /* --periodic, --box */
    pst_op_opts opts;
} apply_args;

/* What both commands build: the sorted cloud, its list and the operator, with timings. */
typedef struct {
    pst_cloud *c;
    pst_nlist *nl;
    pst_op *op;
    double support;
    double t_read, t_sort, t_nlist, t_pre;
} apply_setup;

static void setup_free(apply_setup *s)
{
    pst_op_destroy(s->op);
    pst_nlist_destroy(s->nl);
    pst_cloud_destroy(s->c);
}

static int known_scheme(const char *name)
{
    for (int i = 0; i < pst_scheme_count(); ++i)
        if (strcmp(pst_scheme_name(i), name) == 0)
            return 1;
    return 0;
}

static int unknown_scheme(const char *cmd, const char *name)
{
    fprintf(stderr, "pstencil: %s: unknown scheme '%s' (known:", cmd, name);
    for (int i = 0; i < pst_scheme_count(); ++i)
        fprintf(stderr, "%s %s", i ? "," : "", pst_scheme_name(i));
    fprintf(stderr, ")\n");
    return CLI_USAGE;
}

/* "G1".."G4" (or "g1", "1".."4") into a pst_gradient; -1 when it is none of them. */
static int parse_gradient(const char *v)
{
    if (v[0] == 'G' || v[0] == 'g')
        ++v;
    if (v[0] >= '1' && v[0] <= '4' && v[1] == '\0')
        return v[0] - '0';
    return -1;
}

/* "arithmetic" / "harmonic" into a pst_mobility_mean; -1 for anything else (or NULL). */
static int mean_from_name(const char *v)
{
    if (v && strcmp(v, "arithmetic") == 0)
        return PST_MEAN_ARITHMETIC;
    if (v && strcmp(v, "harmonic") == 0)
        return PST_MEAN_HARMONIC;
    return -1;
}

static const char *mean_name(int m) { return m == PST_MEAN_HARMONIC ? "harmonic" : "arithmetic"; }

static int bad_option(const char *cmd, const char *name, const char *value, const char *expected)
{
    fprintf(stderr, "pstencil: %s: option %s: %s expected (got '%s')\n", cmd, name, expected,
            value ? value : "");
    return CLI_USAGE;
}

static void print_help(const char *cmd)
{
    if (strcmp(cmd, "apply") == 0)
        printf("usage: pstencil apply --scheme NAME --in CLOUD --field COLUMN --out RESULT.csv\n"
               "                      [--mobility COLUMN] [--kernel NAME] [--h VALUE]\n"
               "                      [--gradient G1..G4] [--mean arithmetic|harmonic]\n"
               "                      [--periodic AXES --box LO,HI] [--stored]\n\n"
               "Apply the operator L u = div(M grad u) of a scheme to the field COLUMN of a cloud\n"
               "(docs/clouds.md) and write 'id,Lu,Au,status', one row per particle in input order.\n\n");
    else
        printf("usage: pstencil stencil --scheme NAME --in CLOUD --out A.mtx\n"
               "                        [--mobility COLUMN] [--kernel NAME] [--h VALUE]\n"
               "                        [--gradient G1..G4] [--mean arithmetic|harmonic]\n"
               "                        [--periodic AXES --box LO,HI]\n\n"
               "Assemble the matrix of L (with its diagonal) and write it as MatrixMarket\n"
               "'coordinate real general', rows and columns in input order (1-based).\n\n");
    printf("options:\n"
           "  --scheme NAME       the discretisation:");
    for (int i = 0; i < pst_scheme_count(); ++i)
        printf("%s %s", i ? "," : "", pst_scheme_name(i));
    printf("\n");
    if (strcmp(cmd, "apply") == 0)
        printf("  --field COLUMN      the named field column that is u\n");
    printf("  --mobility COLUMN   a field column (> 0) used as scalar mobility; default: the\n"
           "                      file's m or mx,my[,mz] columns, else m = 1\n"
           "  --kernel NAME       cubic | quintic | wendland_c2 | wendland_c4 (default: the\n"
           "                      scheme's own)\n"
           "  --h VALUE           uniform smoothing length; default: the file's h column\n"
           "  --gradient G1..G4   kernel-gradient variant of the LV family (default G1)\n"
           "  --variant N         scheme variant (lsmps: 0 type B, 1 type A; default 0)\n"
           "  --mean MEAN         pair mobility of the LV family: arithmetic (m_I + m_J, the\n"
           "                      paper's, default) or harmonic (4 m_I m_J / (m_I + m_J), an\n"
           "                      extension for high-contrast mobility)\n"
           "  --cond-max C        flag rows whose moment matrix has a larger condition\n"
           "                      estimate ill-conditioned (default 1e10)\n"
           "  --rank-tol R        below 1/cond of R a moment matrix is rank-deficient and the\n"
           "                      row falls back (default 1e-13)\n"
           "  --min-pair-distance E  pairs closer than E h contribute nothing (default 1e-8)\n"
           "  --on-degenerate fall_back|refuse  rank-deficient / too-few-neighbours rows take\n"
           "                      the scheme's fallback chain (default) or stop with exit 3\n"
           "  --timers FILE.json  write the counts and per-phase timers as JSON\n");
    cli_periodic_help();
    if (strcmp(cmd, "apply") == 0)
        printf("  --stored            store the weights and apply from them (default:\n"
               "                      matrix-free)\n");
    printf("  --out FILE, -o FILE the output, written all or nothing\n\n"
           "exit codes: 0 ok, 1 usage, 2 bad input, 3 numerical failure, 4 out of memory\n");
}

/* Parse the options of either command. Returns -1 to go on, or an exit code. */
static int parse_args(apply_args *a, int argc, char **argv)
{
    int is_apply = strcmp(a->cmd, "apply") == 0, rc;
    for (int i = 0; i < argc; ++i) {
        const char *v;
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            print_help(a->cmd);
            return CLI_OK;
        }
        if (cli_option(argc, argv, &i, "--scheme", &v)) {
            if (!v || !*v)
                return bad_option(a->cmd, "--scheme", v, "a scheme name");
            a->opts.scheme = v;
        } else if (cli_option(argc, argv, &i, "--in", &v)) {
            if (!v || !*v)
                return bad_option(a->cmd, "--in", v, "a file name");
            a->in = v;
        } else if (cli_option(argc, argv, &i, "--out", &v) ||
                   cli_option(argc, argv, &i, "-o", &v)) {
            if (!v || !*v)
                return bad_option(a->cmd, "--out", v, "a file name");
            a->out = v;
        } else if (is_apply && cli_option(argc, argv, &i, "--field", &v)) {
            if (!v || !*v)
                return bad_option(a->cmd, "--field", v, "a column name");
            a->field = v;
        } else if (cli_option(argc, argv, &i, "--mobility", &v)) {
            if (!v || !*v)
                return bad_option(a->cmd, "--mobility", v, "a column name");
            a->mobility = v;
        } else if (cli_option(argc, argv, &i, "--kernel", &v)) {
            int k = v ? pst_kernel_from_name(v) : -1;
            if (k < 0)
                return bad_option(a->cmd, "--kernel", v,
                                  "cubic, quintic, wendland_c2 or wendland_c4");
            a->opts.kernel = k;
        } else if (cli_option(argc, argv, &i, "--h", &v)) {
            if (!v || cli_parse_double(v, &a->h) != 0 || !(a->h > 0))
                return bad_option(a->cmd, "--h", v, "a positive number");
        } else if (cli_option(argc, argv, &i, "--gradient", &v)) {
            int g = v ? parse_gradient(v) : -1;
            if (g < 0)
                return bad_option(a->cmd, "--gradient", v, "G1, G2, G3 or G4");
            a->opts.gradient = g;
        } else if (cli_option(argc, argv, &i, "--variant", &v)) {
            long var;
            if (!v || cli_parse_long(v, &var) != 0 || var < 0 || var > 9)
                return bad_option(a->cmd, "--variant", v, "a scheme variant number (0-9)");
            a->opts.variant = (int)var;
        } else if (cli_option(argc, argv, &i, "--mean", &v)) {
            int m = mean_from_name(v);
            if (m < 0)
                return bad_option(a->cmd, "--mean", v, "arithmetic or harmonic");
            a->opts.mobility_mean = m;
        } else if (cli_option(argc, argv, &i, "--cond-max", &v)) {
            double c;
            if (!v || cli_parse_double(v, &c) != 0 || !(c >= 1))
                return bad_option(a->cmd, "--cond-max", v, "a number >= 1");
            a->opts.cond_max = c;
        } else if (cli_option(argc, argv, &i, "--rank-tol", &v)) {
            double r;
            if (!v || cli_parse_double(v, &r) != 0 || !(r > 0 && r < 1))
                return bad_option(a->cmd, "--rank-tol", v, "a number in (0, 1)");
            a->opts.rank_tol = r;
        } else if (cli_option(argc, argv, &i, "--min-pair-distance", &v)) {
            double r;
            if (!v || cli_parse_double(v, &r) != 0 || !(r > 0 && r < 0.5))
                return bad_option(a->cmd, "--min-pair-distance", v, "a number in (0, 0.5)");
            a->opts.min_pair_distance = r;
        } else if (cli_option(argc, argv, &i, "--on-degenerate", &v)) {
            if (v && strcmp(v, "fall_back") == 0)
                a->opts.on_degenerate = PST_DEGENERATE_FALL_BACK;
            else if (v && strcmp(v, "refuse") == 0)
                a->opts.on_degenerate = PST_DEGENERATE_REFUSE;
            else
                return bad_option(a->cmd, "--on-degenerate", v, "fall_back or refuse");
        } else if (cli_option(argc, argv, &i, "--timers", &v)) {
            if (!v || !*v)
                return bad_option(a->cmd, "--timers", v, "a file name");
            a->timers = v;
        } else if ((rc = cli_parse_periodic_option(argc, argv, &i, a->cmd, &a->periodic))) {
            if (rc < 0)
                return CLI_USAGE;
        } else if (is_apply && strcmp(argv[i], "--stored") == 0) {
            a->stored = 1;
        } else {
            fprintf(stderr, "pstencil: %s: unexpected argument '%s'\nTry 'pstencil %s --help'.\n",
                    a->cmd, argv[i], a->cmd);
            return CLI_USAGE;
        }
    }
    const char *missing = !a->opts.scheme           ? "--scheme"
                          : !a->in                  ? "--in"
                          : is_apply && !a->field   ? "--field"
                          : !a->out                 ? "--out"
                                                    : NULL;
    if (missing) {
        fprintf(stderr, "pstencil: %s: %s is required\nTry 'pstencil %s --help'.\n", a->cmd,
                missing, a->cmd);
        return CLI_USAGE;
    }
    if (!known_scheme(a->opts.scheme))
        return unknown_scheme(a->cmd, a->opts.scheme);
    if ((rc = cli_check_periodic(a->cmd, &a->periodic)) != CLI_OK)
        return rc;
    return -1;
}

/* The field COLUMN of the cloud, or NULL after printing the available fields. */
static double *find_field(pst_cloud *c, const char *path, const char *name)
{
    double *f = pst_cloud_field_by_name(c, name);
    if (f)
        return f;
    fprintf(stderr, "pstencil: %s: no field column '%s' (fields:", path, name);
    size_t nf = pst_cloud_nfields(c);
    for (size_t k = 0; k < nf; ++k)
        fprintf(stderr, "%s %s", k ? "," : "", pst_cloud_field_name(c, k));
    fprintf(stderr, "%s)\n", nf ? "" : " none");
    return NULL;
}

/* Read, override mobility and h, sort, build the list and the operator. An exit code. */
static int setup(const cli_ctx *ctx, const apply_args *a, apply_setup *s)
{
    char err[PST_ERRLEN] = "", why[PST_ERRLEN] = "";
    double t0 = omp_get_wtime();
    int st = pst_cloud_read(&s->c, a->in, err);
    if (st != PST_OK)
        return cli_fail(st, "cannot read the cloud", err);
    s->t_read = omp_get_wtime() - t0;
    pst_cloud *c = s->c;
    size_t n = pst_cloud_size(c);
    if (n == 0) {
        fprintf(stderr, "pstencil: %s: the cloud has no particles\n", a->in);
        return CLI_BAD_INPUT;
    }
    if ((st = cli_set_periodic(a->cmd, &a->periodic, c, a->in)) != CLI_OK)
        return st;
    /* Checked before the sort, so particle i is still data row i (line i + 2 of a file
     * without blank lines). */
    if (a->field && !find_field(c, a->in, a->field))
        return CLI_BAD_INPUT;
    if (a->mobility) {
        const double *m = find_field(c, a->in, a->mobility);
        if (!m)
            return CLI_BAD_INPUT;
        for (size_t i = 0; i < n; ++i)
            if (!(m[i] > 0)) {
                fprintf(stderr,
                        "pstencil: %s: data row %zu (line %zu): column %s: mobility %g must be "
                        "> 0\n",
                        a->in, i + 1, i + 2, a->mobility, m[i]);
                return CLI_BAD_INPUT;
            }
        st = pst_cloud_set_mobility(c, 1, why);
        double *dst = st == PST_OK ? pst_cloud_mobility(c, 0) : NULL;
        if (!dst)
            return cli_fail(st != PST_OK ? st : PST_ENOMEM, "cannot set the mobility", why);
        memcpy(dst, m, n * sizeof *dst);
    }
    if (a->h > 0 && (st = pst_cloud_set_h_uniform(c, a->h, why)) != PST_OK)
        return cli_fail(st, "cannot set h", why);

    /* the list's radius is the support of the kernel the operator will use */
    int kernel = a->opts.kernel >= 0 ? a->opts.kernel : pst_scheme_default_kernel(a->opts.scheme);
    if (kernel < 0)
        return cli_fail(PST_EINVAL, "unknown scheme", a->opts.scheme);
    s->support = pst_kernel_support((pst_kernel)kernel);
    t0 = omp_get_wtime();
    st = pst_cloud_morton_sort(c, s->support * pst_cloud_h_max(c), why);
    if (st != PST_OK)
        return cli_fail(st, "Morton sort failed", why);
    s->t_sort = omp_get_wtime() - t0;
    t0 = omp_get_wtime();
    cli_progress pg;
    progress_begin(&pg, !ctx->quiet, "neighbours", "rows");
    pst_progress hook = progress_list_hook(&pg);
    st = pst_nlist_build_with(&s->nl, c, s->support, &hook, err);
    progress_end(&pg);
    if (st != PST_OK)
        return cli_fail(st, "neighbour list failed", err);
    s->t_nlist = omp_get_wtime() - t0;
    t0 = omp_get_wtime();
    pst_op_opts oo = a->opts;
    progress_begin(&pg, !ctx->quiet, "precompute", "rows");
    oo.progress = progress_hook(&pg);
    st = pst_op_create(&s->op, c, s->nl, &oo, err);
    progress_end(&pg);
    if (st == PST_OK)
        pst_op_set_progress(s->op, NULL); /* pg ends here */
    if (st != PST_OK)
        return cli_fail(st, "cannot build the operator", err);
    s->t_pre = omp_get_wtime() - t0;
    return CLI_OK;
}

static void print_summary(const apply_args *a, const apply_setup *s)
{
    size_t counts[PST_ROW_NSTATUS];
    pst_op_status_counts(s->op, counts);
    printf("scheme               %s (gradient G%d)\n", a->opts.scheme, a->opts.gradient);
    printf("mobility mean        %s\n", mean_name(a->opts.mobility_mean));
    int kernel = a->opts.kernel >= 0 ? a->opts.kernel : pst_scheme_default_kernel(a->opts.scheme);
    printf("kernel               %s, support %g h\n", pst_kernel_name((pst_kernel)kernel),
           s->support);
    printf("particles            %zu (%dD)\n", pst_cloud_size(s->c), pst_cloud_dim(s->c));
    if (a->periodic.axes)
        printf("periodic             %s\n", a->periodic.axes);
    printf("pairs stored         %lld\n", (long long)pst_nlist_pairs(s->nl));
    printf("thresholds           cond_max %g, rank_tol %g, min_pair_distance %g h\n",
           a->opts.cond_max, a->opts.rank_tol, a->opts.min_pair_distance);
    printf("fallback             %s\n", pst_scheme_fallback(a->opts.scheme));
    printf("row status          ");
    for (int k = 0; k < PST_ROW_NSTATUS; ++k)
        printf("%s %s %zu", k ? "," : "", pst_row_status_name(k), counts[k]);
    printf("\n");
    printf("threads              %d\n", pst_threads());
    printf("time read            %.3f s\n", s->t_read);
    printf("time Morton sort     %.3f s\n", s->t_sort);
    printf("time neighbours      %.3f s\n", s->t_nlist);
    printf("time precompute      %.3f s\n", s->t_pre);
    double ph[PST_NPHASES];
    pst_op_phase_times(s->op, ph);
    for (int k = PST_PHASE_GEOMETRY; k <= PST_PHASE_WEIGHTS; ++k)
        if (ph[k] > 0)
            printf("  phase %-12s %.3f s\n", pst_phase_name(k), ph[k]);
}

/* The --timers report: everything print_summary shows, as one JSON object. */
typedef struct {
    const apply_args *a;
    const apply_setup *s;
    double t_apply, t_store;
} timers_job;

static void write_timers(FILE *f, const void *job)
{
    const timers_job *t = job;
    const pst_op *op = t->s->op;
    size_t counts[PST_ROW_NSTATUS];
    double ph[PST_NPHASES];
    pst_op_status_counts(op, counts);
    pst_op_phase_times(op, ph);
    int kernel = t->a->opts.kernel >= 0 ? t->a->opts.kernel
                                        : pst_scheme_default_kernel(t->a->opts.scheme);
    fprintf(f, "{\n  \"pstencil\": \"%s\",\n  \"command\": \"%s\",\n", pst_version(), t->a->cmd);
    fprintf(f, "  \"scheme\": \"%s\",\n  \"variant\": %d,\n  \"gradient\": %d,\n",
            t->a->opts.scheme, t->a->opts.variant, t->a->opts.gradient);
    fprintf(f, "  \"mobility_mean\": \"%s\",\n", mean_name(t->a->opts.mobility_mean));
    fprintf(f, "  \"cond_max\": %.17g,\n  \"rank_tol\": %.17g,\n", t->a->opts.cond_max,
            t->a->opts.rank_tol);
    fprintf(f, "  \"min_pair_distance\": %.17g,\n", t->a->opts.min_pair_distance);
    fprintf(f, "  \"on_degenerate\": \"%s\",\n",
            t->a->opts.on_degenerate == PST_DEGENERATE_REFUSE ? "refuse" : "fall_back");
    fprintf(f, "  \"regularisation\": \"none\",\n  \"fallback\": \"%s\",\n",
            pst_scheme_fallback(t->a->opts.scheme));
    fprintf(f, "  \"kernel\": \"%s\",\n  \"dim\": %d,\n  \"particles\": %zu,\n",
            pst_kernel_name((pst_kernel)kernel), pst_cloud_dim(t->s->c), pst_cloud_size(t->s->c));
    fprintf(f, "  \"pairs\": %lld,\n  \"threads\": %d,\n", (long long)pst_nlist_pairs(t->s->nl),
            pst_threads());
    fputs("  \"status\": {", f);
    for (int k = 0; k < PST_ROW_NSTATUS; ++k)
        fprintf(f, "%s\"%s\": %zu", k ? ", " : "", pst_row_status_name(k), counts[k]);
    fputs("},\n  \"seconds\": {", f);
    fprintf(f, "\"read\": %.6g, \"sort\": %.6g, \"neighbours\": %.6g", t->s->t_read,
            t->s->t_sort, t->s->t_nlist);
    for (int k = 0; k < PST_NPHASES; ++k)
        if (k != PST_PHASE_APPLY)
            fprintf(f, ", \"%s\": %.6g", pst_phase_name(k), ph[k]);
    if (t->t_store > 0)
        fprintf(f, ", \"store\": %.6g", t->t_store);
    if (t->t_apply > 0)
        fprintf(f, ", \"apply\": %.6g", t->t_apply);
    fputs("}\n}\n", f);
}

/* Write the --timers file when asked; an exit code. */
static int report_timers(const apply_args *a, const apply_setup *s, double t_apply,
                         double t_store)
{
    if (!a->timers)
        return CLI_OK;
    char err[PST_ERRLEN] = "";
    timers_job job = {a, s, t_apply, t_store};
    int st = pst_write_atomic(a->timers, write_timers, &job, err);
    return st == PST_OK ? CLI_OK : cli_fail(st, "cannot write the timers", err);
}

/* The writer of `apply`: rows in input order, row r from particle inv[r]. Lu is A u on the
 * interior rows and 0 on the boundary ones, as a scene's laplacian task writes it (a boundary
 * row is not L u); Au is the operator's product on every row (docs/cli.md). */
typedef struct {
    size_t n;
    const size_t *inv;
    const double *y;
    const uint8_t *status, *kind;
} lu_job;

static void write_lu(FILE *f, const void *job)
{
    const lu_job *w = job;
    fputs("id,Lu,Au,status\n", f);
    for (size_t r = 0; r < w->n; ++r) {
        size_t i = w->inv[r];
        fprintf(f, "%zu,%.17g,%.17g,%s\n", r, w->kind[i] == PST_INTERIOR ? w->y[i] : 0.0,
                w->y[i], pst_row_status_name(w->status[i]));
    }
}

int cli_apply(const cli_ctx *ctx, int argc, char **argv)
{
    apply_args a = {.cmd = "apply"};
    pst_op_defaults(&a.opts);
    a.opts.scheme = NULL; /* required: no silent default */
    int rc = parse_args(&a, argc, argv);
    if (rc >= 0)
        return rc;
    apply_setup s = {0};
    double *y = NULL;
    size_t *inv = NULL;
    rc = setup(ctx, &a, &s);
    if (rc != CLI_OK)
        goto done;
    size_t n = pst_cloud_size(s.c);
    /* look the field up again: the sort moved the particles */
    const double *u = pst_cloud_field_by_name(s.c, a.field);
    y = malloc(n * sizeof *y);
    if (!y) {
        rc = cli_fail(PST_ENOMEM, "apply", "no memory for the result");
        goto done;
    }
    double t_store = 0;
    double t0 = omp_get_wtime();
    if (a.stored) {
        int st = pst_op_store(s.op);
        if (st != PST_OK) {
            rc = cli_fail(st, "cannot store the weights", "");
            goto done;
        }
        t_store = omp_get_wtime() - t0;
        t0 = omp_get_wtime();
        st = pst_op_apply_stored(s.op, u, y);
        if (st != PST_OK) {
            rc = cli_fail(st, "stored apply failed", "");
            goto done;
        }
    } else {
        pst_op_apply(s.op, u, y);
    }
    double t_apply = omp_get_wtime() - t0;

    char err[PST_ERRLEN] = "";
    int st = pst_cloud_input_inverse(s.c, &inv, err);
    if (st == PST_OK) {
        lu_job job = {n, inv, y, pst_op_status(s.op), pst_cloud_kinds_const(s.c)};
        st = pst_write_atomic(a.out, write_lu, &job, err);
    }
    if (st != PST_OK) {
        rc = cli_fail(st, "cannot write the result", err);
        goto done;
    }
    rc = report_timers(&a, &s, t_apply, t_store);
    if (rc != CLI_OK)
        goto done;
    if (!ctx->quiet) {
        print_summary(&a, &s);
        if (a.stored)
            printf("time store           %.3f s\n", t_store);
        printf("time apply           %.3f s (%s)\n", t_apply,
               a.stored ? "stored weights" : "matrix-free");
        printf("wrote %zu rows to %s\n", n, a.out);
    }
done:
    free(inv);
    free(y);
    setup_free(&s);
    return rc;
}

int cli_stencil(const cli_ctx *ctx, int argc, char **argv)
{
    apply_args a = {.cmd = "stencil"};
    pst_op_defaults(&a.opts);
    a.opts.scheme = NULL;
    int rc = parse_args(&a, argc, argv);
    if (rc >= 0)
        return rc;
    apply_setup s = {0};
    pst_csr m = {0};
    rc = setup(ctx, &a, &s);
    if (rc != CLI_OK)
        goto done;
    double t0 = omp_get_wtime();
    int st = pst_op_assemble(s.op, &m);
    if (st != PST_OK) {
        rc = cli_fail(st, "cannot assemble the matrix", "");
        goto done;
    }
    double t_asm = omp_get_wtime() - t0;
    char err[PST_ERRLEN] = "";
    t0 = omp_get_wtime();
    /* the ids map the sorted rows back to input order */
    st = pst_csr_write_mtx(&m, pst_cloud_ids_const(s.c), a.out, err);
    if (st != PST_OK) {
        rc = cli_fail(st, "cannot write the matrix", err);
        goto done;
    }
    double t_write = omp_get_wtime() - t0;
    rc = report_timers(&a, &s, 0, 0);
    if (rc != CLI_OK)
        goto done;
    if (!ctx->quiet) {
        print_summary(&a, &s);
        printf("time assemble        %.3f s\n", t_asm);
        printf("time write           %.3f s\n", t_write);
        printf("wrote %zu x %zu matrix, %lld entries, to %s\n", m.n, m.n,
               (long long)m.rowptr[m.n], a.out);
    }
done:
    pst_csr_free(&m);
    setup_free(&s);
    return rc;
}
