/* The library never initialises MPI (docs/solving.md, "MPI"): without MPI initialised, an AMG
 * set-up fails with PST_EINVAL and a message saying what the program must do, through
 * pst_prec_amg, pst_krylov_create and pst_solve (stop reason PST_STOP_PRECOND_SETUP, u
 * untouched); Jacobi solves still run. This program never calls MPI_Init. With --finalised it
 * initialises MPI, builds an AMG handle, finalises MPI and checks that the set-up and the
 * handle's solves then refuse, naming the finalisation, and that the handle can be destroyed. */
#include "check.h"
#include "pstencil.h"
#include "solve.h"
#include "support.h"

#include <mpi.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    pst_cloud *c;
    pst_nlist *nl;
    pst_op *op;
    double *b, *u;
    size_t n;
} problem;

static problem make(void)
{
    problem p;
    p.c = test_lattice(2, 0.0, 1.0, 1.0 / 16, 1.2, 0.2, 5, 1);
    p.nl = test_nlist(p.c, 2.0);
    p.op = test_op(p.c, p.nl, "lv", PST_GRAD_G1, 0);
    p.n = pst_cloud_size(p.c);
    p.b = malloc(p.n * sizeof *p.b);
    p.u = calloc(p.n, sizeof *p.u);
    const uint8_t *kind = pst_cloud_kinds_const(p.c);
    for (size_t i = 0; i < p.n; ++i)
        p.b[i] = kind[i] == PST_DIRICHLET ? 0.0 : 1.0;
    return p;
}

static void destroy(problem *p)
{
    pst_op_destroy(p->op);
    pst_nlist_destroy(p->nl);
    pst_cloud_destroy(p->c);
    free(p->b);
    free(p->u);
}

static pst_solve_opts amg_opts(void)
{
    pst_solve_opts o;
    pst_solve_defaults(&o);
    o.solver = PST_SOLVER_GMRES;
    o.precond = PST_PREC_AMG;
    return o;
}

/* Every way to an AMG set-up refuses with `expect` in the message. */
static void check_refused(problem *p, const char *expect)
{
    char err[PST_ERRLEN] = "";
    pst_prec m;
    pst_solve_opts o = amg_opts();
    CHECK_INT(pst_prec_amg(&m, p->op, &o, err), PST_EINVAL);
    CHECK(strstr(err, expect) != NULL);
    printf("pst_prec_amg: %s\n", err);
    pst_krylov *s = NULL;
    CHECK_INT(pst_krylov_create(&s, p->op, &o, err), PST_EINVAL);
    CHECK(s == NULL && strstr(err, expect) != NULL);
    pst_solve_result r;
    p->u[p->n / 2] = 0.5;
    CHECK_INT(pst_solve(p->op, p->b, p->u, &o, &r, err), PST_EINVAL);
    CHECK(r.stop == PST_STOP_PRECOND_SETUP && r.iterations == 0 && p->u[p->n / 2] == 0.5);
    CHECK(strstr(r.message, expect) != NULL && strstr(r.message, "docs/solving.md") != NULL);
}

static void test_no_mpi(void)
{
    int initialized = 1;
    MPI_Initialized(&initialized);
    CHECK_INT(initialized, 0);
    problem p = make();
    check_refused(&p, "MPI is not initialised");
    /* Jacobi needs no MPI */
    pst_solve_opts o = amg_opts();
    o.precond = PST_PREC_JACOBI;
    pst_solve_result r;
    CHECK_INT(pst_solve(p.op, p.b, p.u, &o, &r, NULL), PST_OK);
    CHECK_INT(r.stop, PST_STOP_CONVERGED);
    MPI_Initialized(&initialized);
    CHECK_INT(initialized, 0); /* and the library did not initialise it */
    destroy(&p);
}

/* A handle built while MPI ran refuses to solve once MPI is finalised, and can still be
 * destroyed (its hypre objects are then left allocated: docs/solving.md). */
static void test_finalised(void)
{
    int provided = 0;
    CHECK_INT(MPI_Init_thread(NULL, NULL, MPI_THREAD_SERIALIZED, &provided), MPI_SUCCESS);
    problem p = make();
    pst_solve_opts o = amg_opts();
    pst_krylov *s = NULL;
    char err[PST_ERRLEN] = "";
    CHECK_INT(pst_krylov_create(&s, p.op, &o, err), PST_OK);
    pst_solve_result r;
    CHECK_INT(pst_krylov_solve(s, p.b, p.u, &r, err), PST_OK);
    pst_krylov_destroy(s);
    CHECK_INT(pst_krylov_create(&s, p.op, &o, err), PST_OK);
    MPI_Finalize();
    CHECK_INT(pst_krylov_solve(s, p.b, p.u, &r, err), PST_EINVAL);
    CHECK(r.stop == PST_STOP_NONE && strstr(err, "already been finalised") != NULL);
    printf("pst_krylov_solve: %s\n", err);
    check_refused(&p, "already been finalised");
    pst_krylov_destroy(s);
    destroy(&p);
}

int main(int argc, char **argv)
{
    if (argc > 1 && strcmp(argv[1], "--finalised") == 0)
        test_finalised();
    else
        test_no_mpi();
    return check_summary("test_amg_nompi");
}
