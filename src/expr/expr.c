/* Expressions for scene files (docs/expressions.md). A recursive-descent parser emits postfix
 * code as it goes, so no syntax tree is built and a left-associative chain of any length needs
 * no recursion; a constant operation is folded the moment it is emitted, which folds every
 * constant subtree bottom-up. One evaluator runs the code on blocks of points, slot by slot, so
 * that a single point and a block of them compute the same operations in the same order. */
#include "pstencil_expr.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Per nesting level at most four values wait on the stack (a sum's left term, a product's left
 * factor, a power's base, a function's first argument), plus the result. */
#define STACK_MAX (4 * (PST_EXPR_MAX_DEPTH + 1) + 1)
/* Stack doubles per block of pst_expr_eval_many: the block holds BLOCK_DOUBLES / depth points. */
#define BLOCK_DOUBLES 4096
#define BLOCK_MAX 256

enum {
    OP_CONST, OP_VAR, OP_NEG,
    /* two operands */
    OP_ADD, OP_SUB, OP_MUL, OP_DIV, OP_POW, OP_ATAN2, OP_MIN, OP_MAX, OP_HYPOT,
    /* one operand */
    OP_SIN, OP_COS, OP_TAN, OP_ASIN, OP_ACOS, OP_ATAN, OP_SINH, OP_COSH, OP_TANH, OP_EXP,
    OP_LOG, OP_LOG10, OP_SQRT, OP_ABS, OP_FLOOR, OP_CEIL, OP_SIGN
};

static int arity(int code)
{
    return code <= OP_VAR ? 0 : code == OP_NEG || code >= OP_SIN ? 1 : 2;
}

typedef struct {
    double k;      /* OP_CONST: the value */
    uint8_t code;
    uint8_t var;   /* OP_VAR: the index  */
} op;

struct pst_expr {
    size_t n;            /* instructions */
    size_t depth;        /* stack slots the code needs, >= 1 */
    int nvars;
    unsigned uses;       /* bit i: variable i appears */
    op code[];
};

static const struct {
    const char *name;
    int code, nargs;
} functions[] = {
    {"sin", OP_SIN, 1},     {"cos", OP_COS, 1},     {"tan", OP_TAN, 1},
    {"asin", OP_ASIN, 1},   {"acos", OP_ACOS, 1},   {"atan", OP_ATAN, 1},
    {"atan2", OP_ATAN2, 2}, {"sinh", OP_SINH, 1},   {"cosh", OP_COSH, 1},
    {"tanh", OP_TANH, 1},   {"exp", OP_EXP, 1},     {"log", OP_LOG, 1},
    {"log10", OP_LOG10, 1}, {"sqrt", OP_SQRT, 1},   {"abs", OP_ABS, 1},
    {"pow", OP_POW, 2},     {"min", OP_MIN, 2},     {"max", OP_MAX, 2},
    {"floor", OP_FLOOR, 1}, {"ceil", OP_CEIL, 1},   {"sign", OP_SIGN, 1},
    {"hypot", OP_HYPOT, 2},
};

/* ---- evaluation ------------------------------------------------------------------------ */

static double add(double a, double b) { return a + b; }
static double sub(double a, double b) { return a - b; }
static double mul(double a, double b) { return a * b; }
static double dvd(double a, double b) { return a / b; }
/* Squares are the common power in scene files and pow() is slow; x*x is what C compilers
 * make of pow(x, 2) too, and is correctly rounded. */
static double power(double a, double b) { return b == 2 ? a * a : pow(a, b); }
/* -1, 0 or 1; keeps the sign of a zero and propagates NaN. */
static double sgn(double a) { return a > 0 ? 1.0 : a < 0 ? -1.0 : a; }

/* Run `code` on m points. Slot s of point j is st[s*m + j] (st holds depth*m doubles); variable
 * v of point j is src[v][j], NaN when src[v] is NULL. The result goes to out[0..m-1]. */
static void run(const op *code, size_t n, size_t m, const double *const *src, double *st,
                double *out)
{
    size_t sp = 0; /* slots in use */
    for (size_t i = 0; i < n; ++i) {
        const op *o = &code[i];
        double *t = st + (sp ? sp - 1 : 0) * m; /* the top slot */
        switch (o->code) {
        case OP_CONST:
            t = st + sp++ * m;
            for (size_t j = 0; j < m; ++j)
                t[j] = o->k;
            break;
        case OP_VAR: {
            const double *v = src[o->var];
            t = st + sp++ * m;
            for (size_t j = 0; j < m; ++j)
                t[j] = v ? v[j] : NAN;
            break;
        }
        case OP_NEG:
            for (size_t j = 0; j < m; ++j)
                t[j] = -t[j];
            break;
#define BINARY(OPC, F)                                                                          \
    case OPC:                                                                                  \
        t -= m;                                                                                \
        --sp;                                                                                  \
        for (size_t j = 0; j < m; ++j)                                                         \
            t[j] = F(t[j], t[m + j]);                                                          \
        break;
#define UNARY(OPC, F)                                                                           \
    case OPC:                                                                                  \
        for (size_t j = 0; j < m; ++j)                                                         \
            t[j] = F(t[j]);                                                                    \
        break;
        BINARY(OP_ADD, add)
        BINARY(OP_SUB, sub)
        BINARY(OP_MUL, mul)
        BINARY(OP_DIV, dvd)
        BINARY(OP_POW, power)
        BINARY(OP_ATAN2, atan2)
        BINARY(OP_MIN, fmin)
        BINARY(OP_MAX, fmax)
        BINARY(OP_HYPOT, hypot)
        UNARY(OP_SIN, sin)
        UNARY(OP_COS, cos)
        UNARY(OP_TAN, tan)
        UNARY(OP_ASIN, asin)
        UNARY(OP_ACOS, acos)
        UNARY(OP_ATAN, atan)
        UNARY(OP_SINH, sinh)
        UNARY(OP_COSH, cosh)
        UNARY(OP_TANH, tanh)
        UNARY(OP_EXP, exp)
        UNARY(OP_LOG, log)
        UNARY(OP_LOG10, log10)
        UNARY(OP_SQRT, sqrt)
        UNARY(OP_ABS, fabs)
        UNARY(OP_FLOOR, floor)
        UNARY(OP_CEIL, ceil)
        UNARY(OP_SIGN, sgn)
#undef BINARY
#undef UNARY
        default:
            break;
        }
    }
    memcpy(out, st, m * sizeof *out);
}

double pst_expr_eval(const pst_expr *e, const double *values)
{
    if (!e)
        return NAN;
    const double *src[PST_EXPR_MAX_VARS];
    for (int i = 0; i < e->nvars; ++i)
        src[i] = values ? values + i : NULL;
    double st[STACK_MAX], out;
    run(e->code, e->n, 1, src, st, &out);
    return out;
}

void pst_expr_eval_many(const pst_expr *e, size_t n, const double *const *columns, double *out)
{
    if (!e) {
        for (size_t k = 0; k < n; ++k)
            out[k] = NAN;
        return;
    }
    size_t block = BLOCK_DOUBLES / e->depth;
    if (block > BLOCK_MAX)
        block = BLOCK_MAX;
    size_t nblocks = (n + block - 1) / block;
#pragma omp parallel for schedule(static) if (nblocks > 4)
    for (size_t b = 0; b < nblocks; ++b) {
        size_t k0 = b * block, m = n - k0 < block ? n - k0 : block;
        const double *src[PST_EXPR_MAX_VARS];
        for (int i = 0; i < e->nvars; ++i)
            src[i] = columns && columns[i] ? columns[i] + k0 : NULL;
        double st[BLOCK_DOUBLES];
        run(e->code, e->n, m, src, st, out + k0);
    }
}

int pst_expr_uses(const pst_expr *e, int var)
{
    return e && var >= 0 && var < e->nvars && (e->uses >> var & 1u);
}

int pst_expr_is_constant(const pst_expr *e) { return e && !e->uses; }

size_t pst_expr_length(const pst_expr *e) { return e ? e->n : 0; }

void pst_expr_free(pst_expr *e) { free(e); }

/* ---- lexer ----------------------------------------------------------------------------- */

enum { T_END, T_NUM, T_NAME, T_CHAR };

typedef struct {
    int kind;
    const char *s;  /* where it starts */
    size_t len;
    double value;   /* T_NUM */
} token;

typedef struct {
    const char *text, *cur; /* cur: just past the current token */
    token tok;
    const char *const *vars;
    int nvars, depth, failed;
    op *code;
    size_t n, cap;
    char *err;
    size_t errlen;
} parser;

static void fail(parser *ps, const char *at, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* Record the first error only: later ones are consequences of it. */
static void fail(parser *ps, const char *at, const char *fmt, ...)
{
    if (ps->failed)
        return;
    ps->failed = 1;
    if (!ps->err || !ps->errlen)
        return;
    int w = at ? snprintf(ps->err, ps->errlen, "column %zu: ", (size_t)(at - ps->text) + 1) : 0;
    if (w < 0 || (size_t)w >= ps->errlen)
        return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(ps->err + w, ps->errlen - (size_t)w, fmt, ap);
    va_end(ap);
}

/* When `cond` holds: record the error at `at` (fail) and leave the (void) parsing function. */
#define REJECT_IF(cond, ps, at, ...)                                                               \
    do {                                                                                           \
        if (cond) {                                                                                \
            fail((ps), (at), __VA_ARGS__);                                                         \
            return;                                                                                \
        }                                                                                          \
    } while (0)

static int is_digit(char c) { return c >= '0' && c <= '9'; }
static int is_alpha(char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_'; }
static int is_space(char c) { return c == ' ' || (c >= '\t' && c <= '\r'); } /* \t\n\v\f\r */

/* Describe a token for a message: "end of input", "')'", "'sinn'" (cut at 32 characters). */
static const char *describe(const token *t, char *buf, size_t size)
{
    if (t->kind == T_END)
        return "end of input";
    snprintf(buf, size, "'%.*s'%s", (int)(t->len > 32 ? 32 : t->len), t->s,
             t->len > 32 ? "..." : "");
    return buf;
}

static void lex_number(parser *ps, const char *s)
{
    ps->tok = (token){T_END, s, 0, 0}; /* what a failure leaves: nothing parses past it */
    ps->cur = s;
    const char *p = s;
    while (is_digit(*p))
        ++p;
    if (*p == '.')
        for (++p; is_digit(*p);)
            ++p;
    if (*p == 'e' || *p == 'E') {
        const char *q = p + 1 + (p[1] == '+' || p[1] == '-');
        REJECT_IF(!is_digit(*q), ps, s, "malformed number '%.*s' (exponent without digits)",
                  (int)(q - s > 32 ? 32 : q - s), s);
        for (p = q; is_digit(*p);)
            ++p;
    }
    /* strtod accepts more (hex, inf, nan), so it gets exactly the token. */
    size_t len = (size_t)(p - s);
    char small[64], *buf = len < sizeof small ? small : malloc(len + 1);
    REJECT_IF(!buf, ps, s, "out of memory");
    memcpy(buf, s, len);
    buf[len] = '\0';
    char *end;
    double v = strtod(buf, &end); /* ERANGE on underflow is fine: tiny values are values */
    int whole = end == buf + len;
    if (buf != small)
        free(buf);
    REJECT_IF(!whole, ps, s, "malformed number '%.*s'", (int)(len > 32 ? 32 : len), s);
    REJECT_IF(isinf(v), ps, s, "number '%.*s%s' is out of range", (int)(len > 32 ? 32 : len), s,
              len > 32 ? "..." : "");
    ps->tok = (token){T_NUM, s, len, v};
    ps->cur = p;
}

/* Make the token at the cursor current. */
static void advance(parser *ps)
{
    const char *s = ps->cur;
    while (is_space(*s))
        ++s;
    if (!*s) {
        ps->tok = (token){T_END, s, 0, 0};
        ps->cur = s;
    } else if (is_digit(*s) || (*s == '.' && is_digit(s[1]))) {
        lex_number(ps, s);
    } else if (is_alpha(*s)) {
        const char *p = s;
        while (is_alpha(*p) || is_digit(*p))
            ++p;
        ps->tok = (token){T_NAME, s, (size_t)(p - s), 0};
        ps->cur = p;
    } else {
        ps->tok = (token){T_CHAR, s, 1, 0};
        ps->cur = s + 1;
        if (!strchr("+-*/^(),", *s)) {
            unsigned char c = (unsigned char)*s;
            if (c < 0x20 || c > 0x7e)
                fail(ps, s, "unexpected byte 0x%02X", c);
            else
                fail(ps, s, "unexpected character '%c'", c);
        }
    }
}

static int is_char(const parser *ps, char c) { return ps->tok.kind == T_CHAR && ps->tok.s[0] == c; }

static int name_is(const token *t, const char *name)
{
    return t->len == strlen(name) && !memcmp(t->s, name, t->len);
}

/* ---- code generation ------------------------------------------------------------------- */

/* Append an instruction; fold it with its operands when they are all constants. In postfix
 * code a constant is a whole operand, so the last arity(code) instructions being constants
 * means they are exactly this operation's operands. */
static void emit(parser *ps, int code, int var, double k)
{
    if (ps->failed)
        return;
    if (ps->n == ps->cap) {
        size_t cap = ps->cap ? 2 * ps->cap : 32;
        op *p = realloc(ps->code, cap * sizeof *p);
        REJECT_IF(!p, ps, NULL, "out of memory");
        ps->code = p;
        ps->cap = cap;
    }
    ps->code[ps->n++] = (op){k, (uint8_t)code, (uint8_t)var};
    size_t a = (size_t)arity(code);
    if (!a || ps->n < a + 1)
        return;
    for (size_t i = ps->n - 1 - a; i < ps->n - 1; ++i)
        if (ps->code[i].code != OP_CONST)
            return;
    /* The evaluator itself folds, so a folded value is bit for bit the evaluated one. */
    double st[3], v;
    run(ps->code + ps->n - 1 - a, a + 1, 1, NULL, st, &v);
    ps->n -= a;
    ps->code[ps->n - 1] = (op){v, OP_CONST, 0};
}

/* ---- parser ---------------------------------------------------------------------------- */

static void parse_expr(parser *ps);
static void parse_unary(parser *ps);

/* Open a nesting level at `at`; 0 (and an error) beyond the limit. */
static int enter(parser *ps, const char *at)
{
    if (++ps->depth > PST_EXPR_MAX_DEPTH) {
        fail(ps, at, "expression nested too deeply (limit %d levels)", PST_EXPR_MAX_DEPTH);
        return 0;
    }
    return 1;
}

static void expect_close(parser *ps)
{
    if (ps->failed)
        return;
    REJECT_IF(!is_char(ps, ')'), ps, ps->tok.s, "expected ')'");
    advance(ps);
}

static void parse_call(parser *ps, token name)
{
    int f = -1;
    for (int i = 0; i < (int)(sizeof functions / sizeof *functions); ++i)
        if (name_is(&name, functions[i].name))
            f = i;
    REJECT_IF(f < 0, ps, name.s, "unknown function '%.*s'", (int)(name.len > 32 ? 32 : name.len),
              name.s);
    advance(ps); /* past '(' */
    if (!enter(ps, name.s))
        return;
    int nargs = 0;
    if (is_char(ps, ')')) {
        advance(ps);
    } else {
        for (;;) {
            parse_expr(ps);
            if (ps->failed)
                return;
            ++nargs;
            if (is_char(ps, ',')) {
                advance(ps);
            } else if (is_char(ps, ')')) {
                advance(ps);
                break;
            } else {
                /* Name the separator the function still needs, ')' once it has enough. */
                fail(ps, ps->tok.s, "expected '%c'", nargs < functions[f].nargs ? ',' : ')');
                return;
            }
        }
    }
    --ps->depth;
    REJECT_IF(nargs != functions[f].nargs, ps, name.s, "function '%s' takes %d argument%s",
              functions[f].name, functions[f].nargs, functions[f].nargs == 1 ? "" : "s");
    emit(ps, functions[f].code, 0, 0);
}

/* A name not followed by '(': a variable, then a constant. */
static void parse_name(parser *ps, token name)
{
    int len = (int)(name.len > 32 ? 32 : name.len);
    for (int i = 0; i < ps->nvars; ++i)
        if (name_is(&name, ps->vars[i])) {
            emit(ps, OP_VAR, i, 0);
            return;
        }
    if (name_is(&name, "pi")) {
        emit(ps, OP_CONST, 0, 3.14159265358979323846);
        return;
    }
    if (name_is(&name, "e")) {
        emit(ps, OP_CONST, 0, 2.71828182845904523536);
        return;
    }
    for (size_t i = 0; i < sizeof functions / sizeof *functions; ++i)
        REJECT_IF(name_is(&name, functions[i].name), ps, name.s,
                  "function '%s' needs its arguments in parentheses: %s(...)", functions[i].name,
                  functions[i].name);
    char known[PST_EXPR_MAX_VARS * 40 + 8] = "none";
    size_t w = 0;
    for (int i = 0; i < ps->nvars; ++i)
        w += (size_t)snprintf(known + w, sizeof known - w, "%s%.32s", i ? ", " : "", ps->vars[i]);
    fail(ps, name.s, "unknown variable '%.*s' (known: %s)", len, name.s, known);
}

/* primary := number | name | name '(' [expr {',' expr}] ')' | '(' expr ')' */
static void parse_primary(parser *ps)
{
    if (ps->failed)
        return;
    token t = ps->tok;
    if (t.kind == T_NUM) {
        emit(ps, OP_CONST, 0, t.value);
        advance(ps);
    } else if (t.kind == T_NAME) {
        advance(ps);
        if (is_char(ps, '('))
            parse_call(ps, t);
        else
            parse_name(ps, t);
    } else if (is_char(ps, '(')) {
        advance(ps);
        if (!enter(ps, t.s))
            return;
        parse_expr(ps);
        --ps->depth;
        expect_close(ps);
    } else if (t.kind == T_END && t.s == ps->text + strspn(ps->text, " \t\n\r\v\f")) {
        fail(ps, ps->text, "empty expression");
    } else {
        char d[48];
        fail(ps, t.s, "expected a number, name or '(', found %s", describe(&t, d, sizeof d));
    }
}

/* power := primary ['^' unary]: right-associative, and tighter than a sign on its left
 * (-x^2 = -(x^2)) but not on its right (2^-1). */
static void parse_power(parser *ps)
{
    parse_primary(ps);
    if (ps->failed || !is_char(ps, '^'))
        return;
    const char *at = ps->tok.s;
    advance(ps);
    if (!enter(ps, at))
        return;
    parse_unary(ps);
    --ps->depth;
    emit(ps, OP_POW, 0, 0);
}

/* unary := ('+' | '-') unary | power */
static void parse_unary(parser *ps)
{
    if (ps->failed)
        return;
    if (!is_char(ps, '-') && !is_char(ps, '+')) {
        parse_power(ps);
        return;
    }
    token sign = ps->tok;
    advance(ps);
    if (!enter(ps, sign.s))
        return;
    parse_unary(ps);
    --ps->depth;
    if (sign.s[0] == '-')
        emit(ps, OP_NEG, 0, 0);
}

/* term := unary {('*' | '/') unary} */
static void parse_term(parser *ps)
{
    parse_unary(ps);
    while (!ps->failed && (is_char(ps, '*') || is_char(ps, '/'))) {
        int code = ps->tok.s[0] == '*' ? OP_MUL : OP_DIV;
        advance(ps);
        parse_unary(ps);
        emit(ps, code, 0, 0);
    }
}

/* expr := term {('+' | '-') term} */
static void parse_expr(parser *ps)
{
    parse_term(ps);
    while (!ps->failed && (is_char(ps, '+') || is_char(ps, '-'))) {
        int code = ps->tok.s[0] == '+' ? OP_ADD : OP_SUB;
        advance(ps);
        parse_term(ps);
        emit(ps, code, 0, 0);
    }
}

static int valid_name(const char *s)
{
    if (!s || !is_alpha(*s))
        return 0;
    while (is_alpha(*s) || is_digit(*s))
        ++s;
    return !*s;
}

/* The variables must be distinct names. */
static void check_vars(parser *ps)
{
    REJECT_IF(ps->nvars < 0 || ps->nvars > PST_EXPR_MAX_VARS || (ps->nvars && !ps->vars), ps, NULL,
              "bad number of variables %d (at most %d)", ps->nvars, PST_EXPR_MAX_VARS);
    for (int i = 0; i < ps->nvars; ++i) {
        const char *v = ps->vars[i];
        REJECT_IF(!valid_name(v), ps, NULL, "variable %d: '%.32s' is not a name", i + 1,
                  v ? v : "");
        for (int j = 0; j < i; ++j)
            REJECT_IF(!strcmp(v, ps->vars[j]), ps, NULL, "variable '%.32s' given twice", v);
    }
}

/* Parse the whole text into ps->code. */
static void compile(parser *ps)
{
    REJECT_IF(!ps->text, ps, NULL, "no expression");
    advance(ps);
    parse_expr(ps);
    if (!ps->failed && ps->tok.kind != T_END) {
        char d[48];
        fail(ps, ps->tok.s, "expected an operator or the end, found %s",
             describe(&ps->tok, d, sizeof d));
    }
}

/* The expression of the parsed code, with the stack depth and the variables it uses; NULL after
 * a message. */
static pst_expr *finish(parser *ps)
{
    pst_expr *e = malloc(sizeof *e + ps->n * sizeof *ps->code);
    if (!e) {
        fail(ps, NULL, "out of memory");
        return NULL;
    }
    *e = (pst_expr){.n = ps->n, .nvars = ps->nvars};
    memcpy(e->code, ps->code, ps->n * sizeof *ps->code);
    size_t sp = 0;
    for (size_t i = 0; i < ps->n; ++i) {
        int a = arity(ps->code[i].code);
        sp = sp + 1 - (size_t)a;
        if (sp > e->depth)
            e->depth = sp;
        if (ps->code[i].code == OP_VAR)
            e->uses |= 1u << ps->code[i].var;
    }
    if (e->depth > STACK_MAX) { /* cannot happen within the nesting limit; kept as a guard */
        fail(ps, NULL, "expression too complex");
        free(e);
        return NULL;
    }
    return e;
}

pst_expr *pst_expr_parse(const char *text, const char *const *vars, int nvars, char *err,
                         size_t errlen)
{
    parser ps = {.text = text, .cur = text, .vars = vars, .nvars = nvars, .err = err,
                 .errlen = errlen};
    if (err && errlen)
        err[0] = '\0';
    check_vars(&ps);
    if (!ps.failed)
        compile(&ps);
    pst_expr *e = ps.failed ? NULL : finish(&ps);
    free(ps.code);
    return e;
}
