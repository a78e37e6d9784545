/* pst_petsc_solve on a rank's part (docs/distributed.md), in one process: a part with fewer
 * rings of ghosts than the scheme's rows read (pst_scheme_halo) is refused with the counts in
 * the message, and the part of the scheme's rings solves to the answer of the whole operator.
 * Built only with PETSc; test_ranks.sh runs the parts of two ranks. */
#include "check.h"
#include "pstencil.h"
#include "support.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int main(int argc, char **argv)
{
    char err[PST_ERRLEN] = "";
    CHECK_INT(pst_petsc_start(&argc, &argv, err), PST_OK);
    /* csph2g: its rows weigh the neighbours by volumes from their own lists (two rings) */
    pst_cloud *c = test_lattice(2, 0.0, 1.0, 0.05, 1.2, 0.3, 7, 1);
    const double support = pst_kernel_support(pst_scheme_default_kernel("csph2g"));
    const size_t n = pst_cloud_size(c);
    double *b = malloc(n * sizeof *b), *u = malloc(n * sizeof *u), *uw = calloc(n, sizeof *uw);
    const uint8_t *kind = pst_cloud_kinds_const(c);
    for (size_t i = 0; i < n; ++i) {
        double x[3];
        test_position(c, i, x);
        b[i] = kind[i] == PST_DIRICHLET ? sin(x[0] + 2 * x[1]) : -5 * sin(x[0] + 2 * x[1]);
    }
    pst_petsc_opts o;
    pst_petsc_defaults(&o);
    o.rtol = 1e-12;
    pst_nlist *nl = test_nlist(c, support);
    pst_op *whole = test_op(c, nl, "csph2g", PST_GRAD_G1, 0);
    CHECK_INT(pst_petsc_solve(whole, NULL, b, uw, &o, NULL, err), PST_OK);
    CHECK_INT(pst_scheme_halo("csph2g"), 2);
    for (int hops = 1; hops <= 2; ++hops) {
        pst_part *p = NULL;
        CHECK_INT(pst_part_create(&p, c, NULL, NULL, 1, 0, support, hops, err), PST_OK);
        const pst_cloud *lc = pst_part_cloud(p);
        pst_nlist *lnl = test_nlist(lc, support);
        pst_op *op = test_op(lc, lnl, "csph2g", PST_GRAD_G1, 0);
        memset(u, 0, n * sizeof *u);
        int st = pst_petsc_solve(op, p, b, u, &o, NULL, err);
        if (hops == 1) {
            CHECK_INT(st, PST_EINVAL);
            CHECK(strstr(err, "csph2g's rows read 2 rings of neighbours, the part holds 1"));
        } else {
            CHECK_INT(st, PST_OK);
            double d = 0, m = 0;
            for (size_t i = 0; i < n; ++i) {
                d = fmax(d, fabs(u[i] - uw[i]));
                m = fmax(m, fabs(uw[i]));
            }
            CHECK(d <= 1e-10 * m);
        }
        pst_op_destroy(op);
        pst_nlist_destroy(lnl);
        pst_part_destroy(p);
    }
    pst_op_destroy(whole);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
    free(b);
    free(u);
    free(uw);
    pst_petsc_stop();
    return check_summary("test_petsc_part");
}
