/*
 * pstencil expressions — the arithmetic of scene files (fields, exact solutions, right-hand
 * sides) such as `0.75*exp(-((9*x-2)^2 + (9*y-2)^2)/4)`. Grammar, functions, precedence,
 * limits and messages: docs/expressions.md.
 *
 * An expression is compiled once into a flat postfix program (constant subtrees folded) and
 * then evaluated any number of times, from any number of threads: a compiled expression is
 * never modified. Evaluation never fails; NaN and infinities (log(-1), 1/0) are results like
 * any other, for the caller to check.
 */
#ifndef PSTENCIL_EXPR_H
#define PSTENCIL_EXPR_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* At most this many variables per expression. */
#define PST_EXPR_MAX_VARS 16
/* At most this many nested levels: each parenthesis, function call, unary sign and exponent
 * opens one, so `((x))`, `-(-x)` and `2^-x` are at depth 2. */
#define PST_EXPR_MAX_DEPTH 256

typedef struct pst_expr pst_expr;

/* Compile `text` with the variable names vars[0..nvars-1] (e.g. {"x", "y", "z"}; identifiers,
 * distinct, at most PST_EXPR_MAX_VARS; vars may be NULL when nvars is 0). A variable name
 * shadows the constants pi and e. On error returns NULL and writes to err (errlen bytes, NULL
 * or 0 for none) one line naming the 1-based byte column, e.g. "column 7: unknown function
 * 'sinn'", "column 4: expected ')'", "column 1: unknown variable 'q' (known: x, y, z)".
 * Free the result with pst_expr_free. */
pst_expr *pst_expr_parse(const char *text, const char *const *vars, int nvars, char *err,
                         size_t errlen);

/* The value at values[i] for vars[i] (values may be NULL when no variable is used; a used
 * variable without a value reads as NaN). Thread-safe. NaN for e == NULL. */
double pst_expr_eval(const pst_expr *e, const double *values);

/* out[k] = pst_expr_eval with values[i] = columns[i][k], for k < n, bit for bit, in parallel
 * (OpenMP) over k. columns[i] may be NULL for a variable the expression does not use (a used
 * one reads as NaN); columns itself may be NULL when none is used. */
void pst_expr_eval_many(const pst_expr *e, size_t n, const double *const *columns, double *out);

/* 1 if variable index var appears in the compiled expression, else 0. */
int pst_expr_uses(const pst_expr *e, int var);

/* 1 if the expression uses no variable (its value is then a single folded constant). */
int pst_expr_is_constant(const pst_expr *e);

/* Instructions in the compiled program after constant folding (1 for a constant); for tests
 * and diagnostics. */
size_t pst_expr_length(const pst_expr *e);

/* Free a compiled expression (NULL is ignored). */
void pst_expr_free(pst_expr *e);

#ifdef __cplusplus
}
#endif

#endif
