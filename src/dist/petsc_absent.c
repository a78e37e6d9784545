/* A library built without PETSc (CMake did not find petsc-dev): the PETSc calls of
 * include/pstencil/dist.h say so and refuse. */
#include "check.h"
#include "pstencil/dist.h"

#include <string.h>

static const char why[] = "this pstencil was built without PETSc (install petsc-dev and "
                          "configure again)";

int pst_petsc_available(void) { return 0; }

const char *pst_petsc_version(void) { return ""; }

int pst_petsc_start(int *argc, char ***argv, char *err)
{
    (void)argc;
    (void)argv;
    pst_set_err(err, "%s", why);
    return PST_EINVAL;
}

void pst_petsc_stop(void) {}

int pst_petsc_solve(const pst_op *op, const pst_part *p, const double *b, double *u,
                    const pst_petsc_opts *o, pst_solve_result *r, char *err)
{
    (void)op;
    (void)p;
    (void)b;
    (void)u;
    (void)o;
    if (r)
        memset(r, 0, sizeof *r);
    pst_set_err(err, "%s", why);
    return PST_EINVAL;
}
