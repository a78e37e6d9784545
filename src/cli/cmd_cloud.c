/* Commands that generate clouds: `pstencil cloud` (to CSV) and `pstencil run` (the main job on
 * the built-in default scene). */
#include "cli.h"
#include "memory_avail.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <string.h>

static int bad_value(const char *name, const char *value, const char *expected)
{
    fprintf(stderr, "pstencil: option %s: %s expected (got '%s')\n", name, expected,
            value ? value : "");
    return -1;
}

/* "a,b[,c]" into up to three numbers; returns the count, or -1 on a parse error. */
static int parse_triple(const char *s, double v[3])
{
    char buf[256];
    if (strlen(s) >= sizeof buf)
        return -1;
    strcpy(buf, s);
    int n = 0;
    for (char *tok = strtok(buf, ","); tok; tok = strtok(NULL, ",")) {
        if (n == 3 || cli_parse_double(tok, &v[n]) != 0)
            return -1;
        ++n;
    }
    return n;
}

void cli_cloud_options_help(void)
{
    printf("cloud options:\n"
           "  --dim 2|3               dimension\n"
           "  --lo X,Y[,Z]            lower corner of the box\n"
           "  --hi X,Y[,Z]            upper corner (hi - lo a whole number of spacings)\n"
           "  --s0 S                  lattice spacing\n"
           "  --jitter K              jitter K*delta*s0, delta uniform in [-1,1]; K in [0, 1)\n"
           "  --seed N                seed of the counter-based RNG\n"
           "  --boundary-layer        keep the outer layer unjittered and mark it Dirichlet\n"
           "  --h-ratio F             smoothing length h = F*s0\n"
           "  --angle DEG             rotate the lattice about the box centre\n"
           "  --layout lattice|cell-centred\n"
           "                          node lattice, or the Lukyanov-Vuik cell-centred layout\n"
           "  --kernel NAME           cubic | quintic | wendland_c2 | wendland_c4 (sets the\n"
           "                          neighbour radius: support 2h, 3h, 2h, 2h)\n");
}

int cli_parse_cloud_option(int argc, char **argv, int *i, cli_cloud_opts *o)
{
    pst_lattice_opts *l = &o->lattice;
    const char *v;
    double d;
    long n;
    double t[3];
    if (strcmp(argv[*i], "--boundary-layer") == 0) {
        l->boundary_layer = 1;
        return 1;
    }
    if (cli_option(argc, argv, i, "--dim", &v)) {
        if (!v || cli_parse_long(v, &n) != 0 || (n != 2 && n != 3))
            return bad_value("--dim", v, "2 or 3");
        l->dim = (int)n;
        return 1;
    }
    for (int which = 0; which < 2; ++which) {
        const char *name = which == 0 ? "--lo" : "--hi";
        if (!cli_option(argc, argv, i, name, &v))
            continue;
        int k = v ? parse_triple(v, t) : -1;
        if (k < 2)
            return bad_value(name, v, "2 or 3 comma-separated numbers");
        for (int a = 0; a < k; ++a)
            (which == 0 ? l->lo : l->hi)[a] = t[a];
        return 1;
    }
    if (cli_option(argc, argv, i, "--s0", &v)) {
        if (!v || cli_parse_double(v, &d) != 0 || !(d > 0))
            return bad_value("--s0", v, "a positive number");
        l->s0 = d;
        return 1;
    }
    if (cli_option(argc, argv, i, "--jitter", &v)) {
        /* the limit of the scenes' cloud.jitter: K >= 1 lets particles cross (or meet) */
        if (!v || cli_parse_double(v, &d) != 0 || !(d >= 0 && d < 1))
            return bad_value("--jitter", v, "a number in [0, 1)");
        l->jitter = d;
        return 1;
    }
    if (cli_option(argc, argv, i, "--seed", &v)) {
        if (!v || cli_parse_long(v, &n) != 0 || n < 0)
            return bad_value("--seed", v, "a non-negative integer");
        l->seed = (uint64_t)n;
        return 1;
    }
    if (cli_option(argc, argv, i, "--h-ratio", &v)) {
        if (!v || cli_parse_double(v, &d) != 0 || !(d > 0))
            return bad_value("--h-ratio", v, "a positive number");
        l->h_ratio = d;
        return 1;
    }
    if (cli_option(argc, argv, i, "--angle", &v)) {
        if (!v || cli_parse_double(v, &d) != 0)
            return bad_value("--angle", v, "an angle in degrees");
        l->angle = d * acos(-1.0) / 180.0;
        return 1;
    }
    if (cli_option(argc, argv, i, "--layout", &v)) {
        if (v && strcmp(v, "lattice") == 0)
            o->cell_centred = 0;
        else if (v && strcmp(v, "cell-centred") == 0)
            o->cell_centred = 1;
        else
            return bad_value("--layout", v, "lattice or cell-centred");
        return 1;
    }
    if (cli_option(argc, argv, i, "--kernel", &v)) {
        int k = v ? pst_kernel_from_name(v) : -1;
        if (k < 0)
            return bad_value("--kernel", v, "cubic, quintic, wendland_c2 or wendland_c4");
        o->kernel = (pst_kernel)k;
        return 1;
    }
    return 0;
}

int cli_generate(const cli_cloud_opts *o, pst_cloud **out)
{
    char err[PST_ERRLEN] = "";
    int st = o->cell_centred ? pst_cloud_cell_centred(out, &o->lattice, err)
                             : pst_cloud_lattice(out, &o->lattice, err);
    return st == PST_OK ? CLI_OK : cli_fail(st, "cannot generate the cloud", err);
}

/* Parse a command's cloud options; returns CLI_OK, or an exit code after a message. */
static int parse_cloud_args(int argc, char **argv, cli_cloud_opts *o, const char **output)
{
    for (int i = 0; i < argc; ++i) {
        int r = cli_parse_cloud_option(argc, argv, &i, o);
        if (r < 0)
            return CLI_USAGE;
        if (r > 0)
            continue;
        const char *v;
        if (output && (cli_option(argc, argv, &i, "-o", &v) ||
                       cli_option(argc, argv, &i, "--output", &v))) {
            if (!v) {
                fprintf(stderr, "pstencil: option -o needs a file name\n");
                return CLI_USAGE;
            }
            *output = v;
            continue;
        }
        fprintf(stderr, "pstencil: unknown option '%s'\nTry 'pstencil --help'.\n", argv[i]);
        return CLI_USAGE;
    }
    return CLI_OK;
}

static int wants_help(int argc, char **argv)
{
    for (int i = 0; i < argc; ++i)
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0)
            return 1;
    return 0;
}

/* The share of the available memory a generated cloud may take: the scenes' default
 * limits.memory_fraction. */
#define CLOUD_MEMORY_FRACTION 0.8

/* Refuse, before generating, a cloud that cannot fit: its particles (the generators' count;
 * a bad box is left to them to report) times 8 bytes per coordinate, normal component, volume
 * and id plus a kind byte, against the memory a run may use (pst_memory_probe). CLI_OK, or
 * CLI_NOMEM after a message. */
static int cloud_fits(const cli_cloud_opts *o)
{
    const pst_lattice_opts *l = &o->lattice;
    double cells[3], nodes = 1, inner = 1, faces = 0;
    for (int d = 0; d < l->dim; ++d) {
        cells[d] = round((l->hi[d] - l->lo[d]) / l->s0);
        if (!(cells[d] >= 1))
            return CLI_OK;
        nodes *= cells[d] + 1;
        inner *= cells[d];
    }
    for (int d = 0; d < l->dim; ++d)
        faces += 2 * inner / cells[d];
    double n = o->cell_centred ? inner + faces : nodes;
    double bytes = n * (8.0 * (2 * l->dim + 2) + 1);
    pst_memory_avail m;
    pst_memory_probe(&m);
    if (bytes <= CLOUD_MEMORY_FRACTION * m.bytes)
        return CLI_OK;
    fprintf(stderr, "pstencil: cloud: the cloud needs about %.2f GB (%.4g particles), more than "
                    "%.0f %% of the %.2f GB available (the limit that applies: %s); use a "
                    "coarser --s0 or a smaller box\n",
            bytes * 1e-9, n, 100 * CLOUD_MEMORY_FRACTION, m.bytes * 1e-9, m.limit);
    return CLI_NOMEM;
}

int cli_cloud(const cli_ctx *ctx, int argc, char **argv)
{
    if (wants_help(argc, argv)) {
        printf("usage: pstencil cloud [OPTIONS] -o FILE.csv\n\n"
               "Generate a cloud and write it as CSV (docs/clouds.md). Defaults: 2D unit box,\n"
               "s0 = 0.1, no jitter, h = 1.2 s0.\n\n");
        cli_cloud_options_help();
        return CLI_OK;
    }
    cli_cloud_opts o = {.kernel = PST_KERNEL_QUINTIC};
    pst_lattice_defaults(&o.lattice);
    const char *output = NULL;
    int rc = parse_cloud_args(argc, argv, &o, &output);
    if (rc != CLI_OK)
        return rc;
    if (!output) {
        fprintf(stderr, "pstencil: cloud: an output file is needed (-o FILE.csv)\n");
        return CLI_USAGE;
    }
    rc = cloud_fits(&o);
    if (rc != CLI_OK)
        return rc;
    pst_cloud *c = NULL;
    double t0 = omp_get_wtime();
    rc = cli_generate(&o, &c);
    if (rc != CLI_OK)
        return rc;
    double t1 = omp_get_wtime();
    char err[PST_ERRLEN] = "";
    int st = pst_cloud_write_csv(c, output, err);
    double t2 = omp_get_wtime();
    if (st != PST_OK) {
        pst_cloud_destroy(c);
        return cli_fail(st, "cannot write the cloud", err);
    }
    if (!ctx->quiet)
        printf("wrote %zu particles (%dD) to %s: generate %.3f s, write %.3f s\n",
               pst_cloud_size(c), pst_cloud_dim(c), output, t1 - t0, t2 - t1);
    pst_cloud_destroy(c);
    return CLI_OK;
}
