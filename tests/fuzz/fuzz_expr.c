/* libFuzzer harness of the expression compiler (pst_expr_parse, docs/expressions.md): any
 * bytes as an expression in x, y, z and t. A compiled expression is evaluated at a few points,
 * one by one and with pst_expr_eval_many, which must agree bit for bit; a failure must name a
 * column (only a program too long to compile has none). */
#include "fuzz_input.h"
#include "pstencil_expr.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { NPOINTS = 5 };

/* Two results agree when their bits do, or both are NaN (the payload of a NaN is not
 * specified). */
static int same(double a, double b)
{
    return (isnan(a) && isnan(b)) || memcmp(&a, &b, sizeof a) == 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static const char *const vars[] = {"x", "y", "z", "t"};
    static const double cols[4][NPOINTS] = {{0, 1, -0.5, 1e-300, 3.75},
                                            {0, -2, 0.25, 1e300, -1},
                                            {0, 0.5, 7, -0.0, 2},
                                            {0, 1, 2, 3, 1e-8}};
    char *text = fuzz_text(data, size);
    char err[256] = "";
    pst_expr *e = pst_expr_parse(text, vars, 4, err, sizeof err);
    free(text);
    if (!e) {
        if (strncmp(err, "column ", 7) != 0 && strcmp(err, "expression too complex") != 0) {
            fprintf(stderr, "a failure without a column: '%s'\n", err);
            abort();
        }
        return 0;
    }
    const double *columns[4] = {cols[0], cols[1], cols[2], cols[3]};
    double many[NPOINTS];
    pst_expr_eval_many(e, NPOINTS, columns, many);
    for (int k = 0; k < NPOINTS; ++k) {
        double at[4] = {cols[0][k], cols[1][k], cols[2][k], cols[3][k]};
        if (!same(pst_expr_eval(e, at), many[k])) {
            fprintf(stderr, "point %d: pst_expr_eval and pst_expr_eval_many differ\n", k);
            abort();
        }
    }
    if (pst_expr_is_constant(e) && pst_expr_length(e) != 1) {
        fprintf(stderr, "a constant of %zu instructions\n", pst_expr_length(e));
        abort();
    }
    pst_expr_free(e);
    return 0;
}
