/* --periodic AXES and --box x0,y0[,z0],x1,y1[,z1]: the periodic box of a cloud read from a
 * file (docs/cli.md), which the file formats do not record. The option values are checked as
 * they are parsed; against the cloud's dimension once it is read. */
#include "cli.h"

#include <stdio.h>
#include <string.h>

static int bad(const char *cmd, const char *option, const char *value, const char *why)
{
    fprintf(stderr, "pstencil: %s: option %s: %s (got '%s')\n", cmd, option, why,
            value ? value : "");
    return -1;
}

/* "xz" into periodic[]: letters among x, y, z, each once. */
static int parse_axes(const char *cmd, const char *v, cli_periodic *p)
{
    if (!v || !*v)
        return bad(cmd, "--periodic", v, "axes expected, a subset of x, y, z such as 'xy'");
    for (const char *q = v; *q; ++q) {
        const char *at = strchr("xyz", *q);
        char why[96];
        if (!at) {
            snprintf(why, sizeof why, "unknown axis '%c' (the axes are x, y and z)", *q);
            return bad(cmd, "--periodic", v, why);
        }
        if (p->periodic[at - "xyz"]) {
            snprintf(why, sizeof why, "axis '%c' is given twice", *q);
            return bad(cmd, "--periodic", v, why);
        }
        p->periodic[at - "xyz"] = 1;
    }
    p->axes = v;
    return 1;
}

/* "x0,y0,x1,y1" (2D) or "x0,y0,z0,x1,y1,z1" (3D): 4 or 6 finite numbers. */
static int parse_box(const char *cmd, const char *v, cli_periodic *p)
{
    const char *why = "4 (2D: x0,y0,x1,y1) or 6 (3D: x0,y0,z0,x1,y1,z1) comma-separated "
                      "numbers expected";
    if (!v || !*v)
        return bad(cmd, "--box", v, why);
    int n = 0;
    for (const char *q = v;; ++n) {
        size_t len = strcspn(q, ",");
        char num[64];
        if (n == 6 || len == 0 || len >= sizeof num)
            return bad(cmd, "--box", v, why);
        memcpy(num, q, len);
        num[len] = '\0';
        if (cli_parse_double(num, &p->box[n]) != 0)
            return bad(cmd, "--box", v, why);
        if (!q[len])
            break;
        q += len + 1;
    }
    if (++n != 4 && n != 6)
        return bad(cmd, "--box", v, why);
    p->nbox = n;
    return 1;
}

int cli_parse_periodic_option(int argc, char **argv, int *i, const char *cmd, cli_periodic *p)
{
    const char *v;
    if (cli_option(argc, argv, i, "--periodic", &v)) {
        if (p->axes)
            return bad(cmd, "--periodic", v, "given twice");
        return parse_axes(cmd, v, p);
    }
    if (cli_option(argc, argv, i, "--box", &v)) {
        if (p->nbox)
            return bad(cmd, "--box", v, "given twice");
        return parse_box(cmd, v, p);
    }
    return 0;
}

int cli_check_periodic(const char *cmd, const cli_periodic *p)
{
    if (!p->axes == !p->nbox)
        return CLI_OK;
    fprintf(stderr, "pstencil: %s: %s\nTry 'pstencil %s --help'.\n", cmd,
            p->axes ? "--periodic needs --box (the files record no box)"
                    : "--box needs --periodic (the box is only read on periodic axes)",
            cmd);
    return CLI_USAGE;
}

int cli_set_periodic(const char *cmd, const cli_periodic *p, pst_cloud *c, const char *path)
{
    if (!p->axes)
        return CLI_OK;
    int dim = pst_cloud_dim(c);
    for (int d = dim; d < 3; ++d)
        if (p->periodic[d]) {
            fprintf(stderr, "pstencil: %s: --periodic %s: the cloud %s is %dD, it has no %c "
                            "axis\n", cmd, p->axes, path, dim, "xyz"[d]);
            return CLI_BAD_INPUT;
        }
    if (p->nbox != 2 * dim) {
        fprintf(stderr, "pstencil: %s: --box: the cloud %s is %dD: %d numbers expected (%s), "
                        "got %d\n", cmd, path, dim, 2 * dim,
                dim == 2 ? "x0,y0,x1,y1" : "x0,y0,z0,x1,y1,z1", p->nbox);
        return CLI_BAD_INPUT;
    }
    double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    for (int d = 0; d < dim; ++d) {
        lo[d] = p->box[d];
        hi[d] = p->box[dim + d];
        if (!(hi[d] > lo[d])) {
            fprintf(stderr, "pstencil: %s: --box: hi must exceed lo along %c (lo %g, hi %g)\n",
                    cmd, "xyz"[d], lo[d], hi[d]);
            return CLI_USAGE;
        }
    }
    char err[PST_ERRLEN] = "";
    int st = pst_cloud_set_periodic(c, p->periodic, lo, hi, err);
    if (st == PST_OK)
        st = pst_cloud_validate(c, err); /* every particle inside the box along its axes */
    if (st != PST_OK) {
        fprintf(stderr, "pstencil: %s: %s: --box: %s\n", cmd, path, err);
        return cli_exit_code(st);
    }
    return CLI_OK;
}

void cli_periodic_help(void)
{
    printf("  --periodic AXES     the periodic axes, a subset of x, y, z (e.g. xy): pairs take\n"
           "                      the minimum image across the box (docs/periodic.md); needs\n"
           "                      --box\n"
           "  --box LO,HI         the periodic box, x0,y0,x1,y1 (2D) or x0,y0,z0,x1,y1,z1 (3D);\n"
           "                      read on the periodic axes, where every particle must lie in\n"
           "                      [lo, hi) and the period must exceed twice the neighbour\n"
           "                      radius; needs --periodic\n");
}
