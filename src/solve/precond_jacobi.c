/* The Jacobi preconditioner z = r / diag(A), from the diagonal of a pst_linop. */
#include "solve.h"

#include <math.h>
#include <stdlib.h>

typedef struct {
    size_t n;
    double *dinv;
} jacobi_ctx;

/* z = r / diag(A): memory-bound, three streams. */
static void jacobi_apply(void *ctx, const double *r, double *z)
{
    const jacobi_ctx *j = ctx;
    const double *dinv = j->dinv;
#pragma omp parallel for schedule(static) if (PST_KSP_THREADED(j->n))
    for (size_t i = 0; i < j->n; ++i)
        z[i] = dinv[i] * r[i];
}

static void jacobi_destroy(void *ctx)
{
    jacobi_ctx *j = ctx;
    if (j)
        pst_free(j->dinv);
    free(j);
}

/* d = 1 / diag(A); a zero (or non-finite) diagonal, which only an isolated row can have,
 * gets 1. */
static int inverse_diagonal(const pst_linop *A, double *d, char *err)
{
    int st = A->diagonal(A->ctx, d);
    PST_CHECK(st == PST_ENOMEM, PST_ENOMEM, err,
              "cannot allocate the Jacobi preconditioner of %zu rows", A->n);
    PST_CHECK(st != PST_OK, PST_ENUMERIC, err,
              "the operator's diagonal failed (%s): no Jacobi preconditioner", pst_strerror(st));
#pragma omp parallel for schedule(static) if (PST_KSP_THREADED(A->n))
    for (size_t i = 0; i < A->n; ++i)
        d[i] = d[i] != 0 && isfinite(d[i]) ? 1.0 / d[i] : 1.0;
    return PST_OK;
}

int pst_prec_jacobi(pst_prec *p, const pst_linop *A, char *err)
{
    *p = (pst_prec){0};
    PST_CHECK(!A->diagonal, PST_EINVAL, err,
              "the Jacobi preconditioner needs the operator's diagonal (pst_linop.diagonal is "
              "NULL): give one, a preconditioner, or precond = PST_PREC_NONE");
    jacobi_ctx *j = calloc(1, sizeof *j);
    double *d = j ? pst_alloc(A->n * sizeof *d) : NULL;
    if (!d)
        free(j);
    PST_CHECK_ALLOC(d, err, "cannot allocate the Jacobi preconditioner of %zu rows", A->n);
    int st = inverse_diagonal(A, d, err);
    if (st != PST_OK) {
        free(j);
        pst_free(d);
        return st;
    }
    j->n = A->n;
    j->dinv = d;
    p->lin = (pst_linop){.n = A->n, .apply = jacobi_apply, .ctx = j};
    p->destroy = jacobi_destroy;
    return PST_OK;
}

void pst_prec_free(pst_prec *p)
{
    if (p->destroy)
        p->destroy(p->lin.ctx);
    *p = (pst_prec){0};
}
