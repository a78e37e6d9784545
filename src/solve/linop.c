/* The operator contract: an engine operator seen as a pst_linop (docs/solving.md, "The
 * operator contract"). */
#include "solve.h"

/* The two apply paths and the diagonal, behind the linop's callbacks. Their statuses are
 * known to be PST_OK: pst_op_linop checked the rows and the stored weights. */
static void apply_free(void *ctx, const double *x, double *y)
{
    (void)pst_op_apply(ctx, x, y);
}

static void apply_stored(void *ctx, const double *x, double *y)
{
    (void)pst_op_apply_stored(ctx, x, y);
}

static int diagonal(void *ctx, double *d)
{
    return pst_op_diagonal(ctx, d);
}

int pst_op_linop(const pst_op *op, int stored, pst_linop *out, char *err)
{
    PST_CHECK(!op || !out, PST_EINVAL, err, "pst_op_linop needs an operator and an output");
    PST_CHECK(!pst_op_has_rows(op), PST_EINVAL, err,
              "the operator was built without rows (laplacian = 0): it cannot be solved");
    PST_CHECK(stored && !pst_op_has_store(op), PST_EINVAL, err,
              "stored = 1 needs the weights: call pst_op_store(op) first");
    /* the callbacks take ctx as void *; they only read the operator */
    *out = (pst_linop){.n = op->n, .apply = stored ? apply_stored : apply_free,
                       .diagonal = diagonal, .ctx = (void *)op};
    return PST_OK;
}
